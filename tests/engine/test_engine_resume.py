"""Resuming rocks from their recorded state at a station continues their paths exactly."""

from __future__ import annotations

import numpy as np
import pytest

from rockfall_design.engine import Material, columns, run_ensemble
from rockfall_design.project import load_project
from rockfall_design.run.releases import draw_releases, engine_key, section_from_project

from ..engine_helpers import one_rock, run_one, section


@pytest.fixture(scope="module")
def quarry():
    from pathlib import Path

    p = load_project(Path(__file__).resolve().parents[2] / "projects" / "quarry_road.yaml")
    return section_from_project(p), draw_releases(p, 800, 7), engine_key(7)


def test_resume_reproduces_the_full_run(quarry):
    sec, rel, key = quarry
    full = run_ensemble(sec, rel, key=key, restart_stations=[95.0], grid=[100.0, 110.0])
    crossed = np.isfinite(full.restart_state[:, 0, columns.RS_X])
    assert crossed.sum() > 500
    again = run_ensemble(
        sec, rel, key=key, grid=[100.0, 110.0],
        resume=(crossed, full.restart_state[:, 0], full.restart_rng[:, 0]),
    )
    same_end = np.isclose(again.x_end, full.x_end, rtol=0, atol=1e-6) & (
        again.status == full.status)
    # Round-off at the restart point can only tip a rare chaotic bounce.
    assert same_end[crossed].mean() > 0.99
    assert np.all(again.n_events[crossed] >= full.restart_state[crossed, 0, columns.RS_NEV])
    cols = np.searchsorted(full.grid, again.grid)  # full also has the restart station
    h_full, h_again = full.grid_height[crossed][:, cols], again.grid_height[crossed]
    both = np.isfinite(h_full) & np.isfinite(h_again)
    assert both.sum() > 100  # the grid must be where the rocks pass
    assert np.isclose(h_full[both], h_again[both], atol=1e-4).mean() > 0.99


def test_resume_onto_an_edited_section_equals_a_full_run_there(quarry):
    """Downslope changes do not alter the path upslope: resume == full run on the edit."""
    sec, rel, key = quarry
    full = run_ensemble(sec, rel, key=key, restart_stations=[95.0])
    crossed = np.isfinite(full.restart_state[:, 0, columns.RS_X])
    # Dig a 2 m deep pit between 122 and 130 m.
    x = np.concatenate([sec.x[sec.x < 122], [122, 124, 128, 130], sec.x[sec.x > 130]])
    y = np.interp(x, sec.x, sec.y)
    y[(x > 122) & (x < 130)] -= 2.0
    seg = np.zeros(x.size - 1, dtype=np.int64)
    mids = 0.5 * (x[1:] + x[:-1])
    seg[:] = sec.segment_material[np.searchsorted(sec.x, mids) - 1]
    from rockfall_design.engine import Section

    edited = Section(x, y, seg, sec.materials)
    direct = run_ensemble(edited, rel, key=key)
    resumed = run_ensemble(
        edited, rel, key=key,
        resume=(crossed, full.restart_state[:, 0], full.restart_rng[:, 0]),
    )
    agree = np.isclose(resumed.x_end, direct.x_end, atol=1e-6) & (
        resumed.status == direct.status)
    assert agree[crossed].mean() > 0.99


def test_resume_of_a_rolling_rock_is_exact():
    sec = section([[0, 10], [30, 0], [100, 0]], Material(friction=0.9, rolling_resistance=0.1))
    rel = one_rock(r=0.4, x=1.0, rolling=True)
    full = run_one(sec, rel, restart_stations=[20.0])
    st = full.restart_state[:, 0]
    assert st[0, columns.RS_MODE] == columns.CONTACT
    again = run_one(sec, rel, resume=(np.array([True]), st, full.restart_rng[:, 0]))
    np.testing.assert_allclose(again.x_end, full.x_end, rtol=1e-12)
    np.testing.assert_allclose(again.duration, full.duration, rtol=1e-12)

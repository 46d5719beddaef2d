"""Later looks of a ground edit through the screening decide as the exact runs do.

Issue 37, item 1: a ditch's looks after the first resume the rocks at the
restart station above it (one chain of look screenings per station) instead
of running the whole section again. The decision must be the exact runs':
the same verdict, at the same look, with the same values, and an exact run
only to confirm an admission. The resumed paths agree with the full run's to
round-off (about 1e-13 m on this slope), so values are compared to 1e-9.
"""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rockfall_design.judge.sequential import Verdict
from rockfall_design.optimiser.decide import (
    CHAIN_REACH_M,
    EDIT_CHAINS_KEPT,
    Decider,
    Decision,
)
from rockfall_design.optimiser.scenario import set_up
from rockfall_design.plugins import guard, load_registry
from rockfall_design.project import load_project_text
from rockfall_design.studies.sampling import ScenarioRun

PROJECTS = Path(__file__).resolve().parents[2] / "projects"
#: Ditches (x, width, depth) on the meadow, from clearly short to clearly enough,
#: at three stations (so that chains are made, reused and dropped).
DITCHES = [(107.5, 3.0, 1.0), (107.5, 5.0, 1.5), (112.5, 3.0, 1.0), (112.5, 4.0, 1.5),
           (112.5, 6.0, 2.0), (116.5, 3.5, 1.0), (116.5, 8.0, 2.5)]


def _scenario(seed: int):
    """The driver's screening and decider (:func:`~rockfall_design.optimiser.scenario.set_up`)
    of the ditch project, with a target a few hundred rocks can show, so that looks of
    300 to 2,400 rocks decide some ditches and leave others to the next look."""
    name = "design_ditch_or_fence.yaml"
    text = (PROJECTS / name).read_text()
    for cat in ("catalogue_products.yaml", "catalogue_costs.yaml"):
        text = text.replace(cat, str(PROJECTS / cat))
    text = text.replace("residual: {fraction: 0.001}", "residual: {fraction: 0.02}")
    text = text.replace("  max_measures: 1", "  max_measures: 1\n  max_rocks: 2400")
    project = load_project_text(text, name, base_dir=PROJECTS)
    return set_up(ScenarioRun(0, {}, seed, project), load_registry(), 300)


def _same_values(a: Decision, b: Decision) -> None:
    assert (a.values is None) == (b.values is None)
    if a.values is None:
        return
    assert a.values.rocks == b.values.rocks
    assert a.values.residual == b.values.residual
    assert len(a.values.checks) == len(b.values.checks)
    for ca, cb in zip(a.values.checks, b.values.checks, strict=True):
        assert (ca.measure, ca.name, ca.target) == (cb.measure, cb.name, cb.target)
        for f in ("value", "bound", "optimistic"):
            va, vb = getattr(ca, f), getattr(cb, f)
            assert (va is None) == (vb is None), f
            if va is not None:
                assert math.isclose(va, vb, rel_tol=1e-9, abs_tol=1e-12), (f, va, vb)


@pytest.mark.parametrize("seed", [4, 17])
def test_a_ditch_decided_through_the_screening_is_the_exact_decision(seed: int) -> None:
    sc = _scenario(seed)
    s0, screened = sc.screen, sc.decider
    assert sc.looks.sizes == (300, 600, 1200, 2400)
    (ci,) = sorted(s0.edit_candidates)
    exact = Decider(s0, sc.looks, screened.margin)
    exact.edits_by_exact = True
    later = saved = 0
    for x, w, d in DITCHES:
        measures = s0.measures([(ci, {"x": x, "width": w, "depth": d})])
        first = s0.screen(measures)
        if not (first.feasible or first.near):
            continue  # rejected by the search's screening: never decided
        a, b = screened.decide(measures, first), exact.decide(measures, first)
        assert (a.verdict, a.rocks, a.looks) == (b.verdict, b.rocks, b.looks), (x, w, d)
        assert a.reason == b.reason
        _same_values(a, b)
        # An exact run only to confirm an admission (one run of the deciding look).
        assert a.exact == (1 if a.verdict is Verdict.ADMITTED else 0)
        if a.verdict is Verdict.ADMITTED:
            ra, rb = a.evaluation.residual, b.evaluation.residual
            assert ra.reaching == rb.reaching
        later += a.looks > 1
        saved += b.exact - a.exact
        # Every rock counted: the resumed ones of each look, and the exact run's.
        assert a.simulated > 0 or a.looks == 1
    # The screened path was taken: ditches went to later looks, with fewer exact runs.
    assert later >= 2 and saved >= 2
    assert len(screened._chains) <= EDIT_CHAINS_KEPT + 1  # the barriers' chain beside them
    assert screened.simulated > 0 and exact.simulated == 0


def test_the_restart_station_holds_for_the_largest_look() -> None:
    sc = _scenario(3)
    s0, dec = sc.screen, sc.decider
    (ci,) = sorted(s0.edit_candidates)
    (m,) = s0.measures([(ci, {"x": 112.5, "width": 4.0, "depth": 1.5})])
    edit = guard(s0.registry).measure(m).footprint(s0.section)
    xs = dec.restart_for([edit])
    assert xs is not None and xs in s0.restart_x
    last = dec._screening(len(sc.looks.sizes) - 1, [], xs)
    assert np.array_equal(last.restart_x, [xs])
    assert xs <= edit.x_start - last.margin  # its own rocks' margin holds too


@pytest.fixture(scope="module")
def search3():
    return _scenario(3)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(starts=st.lists(st.floats(0.0, 180.0), min_size=1, max_size=4),
       kept=st.lists(st.integers(0, 40), max_size=3))
def test_a_design_resumes_above_its_edits(search3, starts, kept) -> None:
    """The station is the search's, upslope of the first edit by the margin of the last
    look's rocks, and at most CHAIN_REACH_M above the last such station."""
    s0 = search3.screen
    dec = Decider(s0, search3.looks)
    rx = s0.restart_x
    for k in kept:  # chains already kept (made empty: nothing runs)
        dec._chain(float(rx[min(k, rx.size - 1)]))
    assert len(dec._chains) <= EDIT_CHAINS_KEPT + 1 and None in dec._chains
    xs = dec.restart_for([SimpleNamespace(x_start=x) for x in starts])
    limit = min(starts) - dec._restart_margin
    assert dec._restart_margin >= s0.margin
    own = rx[rx <= limit]
    if own.size == 0:
        assert xs is None
        return
    assert xs in rx and xs <= limit
    assert own[-1] - CHAIN_REACH_M <= xs <= own[-1]
    assert xs == own[-1] or xs in dec._chains

"""Results at every barrier and station: distributions, barriers.csv, the stops figure."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import rockfall_design as rd
from rockfall_design.project import load_project_text
from rockfall_design.report.tables import PASSAGE_COLUMNS, passages_frame
from rockfall_design.run.passages import QUANTITIES, barrier_values, property_marks

ROOT = Path(__file__).resolve().parents[2]
PROJECTS = ROOT / "projects"


@settings(max_examples=200, deadline=None)
@given(m=st.floats(1.0, 1e5), r=st.floats(0.05, 3.0), v=st.floats(0.0, 60.0),
       w=st.floats(0.0, 200.0), h=st.floats(0.0, 20.0), slope=st.floats(-60.0, 80.0))
def test_a_barrier_meeting_gives_back_the_sphere_s_state(m, r, v, w, h, slope):
    # What the engine records (height, speed, total energy) and the rock's mass and
    # radius determine its energies and the magnitude of its spin (I = 2/5 m r^2).
    e_tr = 0.5 * m * v**2 / 1e3
    e_rot = 0.2 * m * r**2 * w**2 / 1e3
    out = barrier_values(np.array([h]), np.array([v]), np.array([e_tr + e_rot]),
                         np.array([m]), np.array([r]), slope)
    assert set(out) == {k for k, _, _ in QUANTITIES}
    assert out["translational_energy_kj"][0] == pytest.approx(e_tr, rel=1e-9)
    assert out["rotational_energy_kj"][0] == pytest.approx(e_rot, rel=1e-6,
                                                           abs=1e-9 * (e_tr + e_rot) + 1e-12)
    assert out["energy_kj"][0] == pytest.approx(e_tr + e_rot)
    # The spin is lost in the rounding of E - E_tr only where it carries no energy.
    assert out["angular_speed_rads"][0] >= 0.0
    if e_rot > 1e-6 * (e_tr + e_rot):
        assert out["angular_speed_rads"][0] == pytest.approx(w, rel=1e-3)
    assert out["passing_height_normal_m"][0] == pytest.approx(h * math.cos(math.radians(slope)))
    assert out["passing_height_normal_m"][0] <= h + 1e-12


def test_marks_are_read_from_the_property_names_units():
    marks = property_marks({"height_m": 4.0, "capacity_kj": 3000.0, "mel_kj": 3000.0,
                            "residual_height_m": 2.4, "max_elongation_m": 6.0,
                            "width_m": 5.0})
    on = {(m.quantity, m.label.split(" (")[0]) for m in marks}
    assert ("passing_height_m", "height") in on and ("passing_height_normal_m", "height") in on
    assert ("passing_height_m", "residual height") in on
    assert ("energy_kj", "capacity") in on and ("energy_kj", "MEL") in on
    assert not any("elongation" in m.label or "width" in m.label for m in marks)


@pytest.fixture(scope="module")
def checked():
    return rd.check(PROJECTS / "quarry_fence_ditch.yaml", rocks=300, seed=3)


def test_every_station_and_barrier_has_its_distributions(checked):
    s = checked.summary
    fence, ditch = s["measures"]
    assert fence["passing"]["rocks"] == fence["met"] > 0
    assert ditch["passing"] is None  # a ground edit: no passage at a station
    for key, _, _ in QUANTITIES:
        assert fence["passing"][key]["p95"] is not None
        for station in s["stations"]:
            assert key in station
    labels = {m["label"] for m in fence["passing"]["marks"]}
    assert any(label.startswith("height") for label in labels)
    assert any(label.startswith("capacity") for label in labels)
    frame = passages_frame(s)
    assert list(frame.columns) == PASSAGE_COLUMNS
    assert len(frame) == (len(s["stations"]) + 1) * len(QUANTITIES)
    energy = frame[(frame.place == "measure") & (frame.quantity == "energy_kj")].iloc[0]
    assert "capacity" in energy.figures
    names = set(checked.figures())
    assert {"passing_measure_1", "passing_station_1", "envelopes", "stops"} <= names
    # The fence's energies add up and its translational speed is the recorded one.
    p = checked.evaluation.passages()[0]
    np.testing.assert_allclose(p.values["translational_energy_kj"]
                               + p.values["rotational_energy_kj"], p.values["energy_kj"],
                               rtol=1e-9, atol=1e-9)
    assert p.rocks == fence["met"]


def test_the_envelopes_have_the_speed(checked):
    env = checked.envelopes
    assert {"speed_max_ms", "speed_p95_ms"} <= set(env.columns)
    ok = env["crossings"] > 0
    assert (env.loc[ok, "speed_max_ms"] >= env.loc[ok, "speed_p95_ms"] - 1e-9).all()


def test_the_stops_figure_shows_caught_rocks_and_says_where_the_others_went(checked):
    fig = checked.plot_stops()
    title = fig.axes[0].get_title()
    assert "caught by a barrier" in title
    labels = fig.axes[0].get_legend_handles_labels()[1]
    assert any(label.startswith("held by fence") for label in labels)
    # The standard slope with little rolling resistance: every rock leaves downslope.
    slope = PROJECTS / "standard_slope.yaml"
    text = slope.read_text().replace("rolling_resistance: 0.3   # mu_r",
                                     "rolling_resistance: 0.05  # mu_r")
    gone = rd.simulate(load_project_text(text, str(slope)), rocks=200, seed=3)
    assert gone.summary["stops"]["exit_downslope"] == 200
    fig = gone.plot_stops()
    assert "200 left downslope" in fig.axes[0].get_title()
    bars = [p for p in fig.axes[0].patches if p.get_height() > 0]
    assert bars, "a run where every rock leaves is not an empty plot"

"""A forest on the ground: stems met as a Poisson stand, the energy they take.

Closed form: a rock rolling at constant speed over a stretch L of a stand of
N stems/m^2 with mean diameter D meets no stem with probability
exp(-N (D + 2r) L) (engine/forest.py); checked within Clopper-Pearson bounds
at three seeds. Properties: a stem never adds energy; a forest never makes
rocks run farther (stems that take every rock's energy stop each rock at its
first stem, which no rock passes); a dense stand of thick stems stops the
rocks inside it.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rockfall_design.engine import Material, Releases, Section, run_ensemble
from rockfall_design.engine.columns import STOPPED
from rockfall_design.engine.forest import stem_energy
from rockfall_design.judge.bounds import fraction_lower_bound, fraction_upper_bound

#: A flat run where a rolling sphere keeps its speed (no rolling resistance).
_FREE = Material(restitution=0.0, friction=0.8, rolling_resistance=0.0)


def _flat(stand: dict | None, x_from: float = 20.0, x_to: float = 70.0,
          length: float = 100.0) -> Section:
    """Flat ground from 0 to ``length`` m, the stand on [x_from, x_to]."""
    xs = np.array([0.0, x_from, x_to, length])
    ys = np.zeros(4)
    mats = (_FREE, _FREE if stand is None else Material(
        restitution=0.0, friction=0.8, rolling_resistance=0.0, **stand))
    return Section(xs, ys, np.array([0, 1, 0]), mats)


def _rolling(n: int, r: float, v: float, x0: float = 1.0) -> Releases:
    """n rocks of radius r rolling on the ground from x0 at speed v (m/s)."""
    return Releases(radius=np.full(n, r), density=2700.0, x=np.full(n, x0),
                    height=np.zeros(n), vx=np.full(n, v), vy=np.zeros(n), spin=np.zeros(n),
                    spin_rolling=np.ones(n, dtype=bool))


def test_energy_law_of_dorren_and_berger() -> None:
    """E_max = 38.7 DBH^2.31 J (DBH in cm): 30 cm takes about 100 kJ."""
    assert stem_energy(0.30) == pytest.approx(38.7 * 30.0 ** 2.31)
    assert 95e3 < stem_energy(0.30) < 105e3


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_share_meeting_no_stem_is_poisson(seed: int) -> None:
    """P(no stem over L) = exp(-N (D + 2r) L), within 99.9 % Clopper-Pearson bounds."""
    n, r, length = 4000, 0.3, 50.0
    # Thin stems (1 cm, 39 J) that no rolling rock of 300 kg at 15 m/s notices.
    stand = {"stems_per_ha": 400.0, "dbh_mean_cm": 1.0, "dbh_sd_cm": 0.0,
             "tree_height_m": 5.0}
    res = run_ensemble(_flat(stand), _rolling(n, r, 15.0), key=seed)
    assert (res.x_end > 70.0).all(), "every rock crosses the stand"
    expected = np.exp(-400.0 / 1e4 * (0.01 + 2 * r) * length)
    none = int((res.stems_met == 0).sum())
    # Two-sided 99.9 %: each one-sided bound at 99.95 %.
    lo, hi = fraction_lower_bound(none, n, 0.9995), fraction_upper_bound(none, n, 0.9995)
    assert lo <= expected <= hi, (none / n, expected)
    # And the mean number met is the stand's rate times the stretch.
    mean = 400.0 / 1e4 * (0.01 + 2 * r) * length
    assert abs(res.stems_met.mean() - mean) < 4.0 * np.sqrt(mean / n)


def test_no_forest_draws_nothing() -> None:
    """A section without forest meets no stem and stops nothing by it."""
    res = run_ensemble(_flat(None), _rolling(200, 0.3, 10.0), key=5)
    assert (res.stems_met == 0).all() and not res.stopped_by_forest.any()


def test_above_the_stems_no_stem_is_met() -> None:
    """Stems lower than the rolling rock's centre are never met."""
    stand = {"stems_per_ha": 2000.0, "dbh_mean_cm": 30.0, "dbh_sd_cm": 5.0,
             "tree_height_m": 0.2}
    res = run_ensemble(_flat(stand), _rolling(300, 0.3, 10.0), key=7)
    assert (res.stems_met == 0).all()


@pytest.mark.parametrize("seed", [11, 12, 13])
def test_dense_thick_stand_stops_rocks_inside(seed: int) -> None:
    """A dense stand of thick stems stops every rock inside it."""
    stand = {"stems_per_ha": 1500.0, "dbh_mean_cm": 40.0, "dbh_sd_cm": 10.0,
             "tree_height_m": 10.0}
    res = run_ensemble(_flat(stand), _rolling(500, 0.3, 12.0), key=seed)
    assert (res.status == STOPPED).all()
    assert res.stopped_by_forest.all()
    assert ((res.x_end >= 20.0) & (res.x_end <= 70.0)).all()


@settings(max_examples=25, deadline=None)
@given(r=st.floats(0.1, 1.0), v=st.floats(2.0, 25.0), dbh=st.floats(2.0, 60.0),
       seed=st.integers(0, 2**32))
def test_a_stem_never_adds_energy(r: float, v: float, dbh: float, seed: int) -> None:
    """Energy at the stand's far edge is at most the energy at its near edge."""
    stand = {"stems_per_ha": 800.0, "dbh_mean_cm": dbh, "dbh_sd_cm": dbh / 3.0,
             "tree_height_m": 5.0}
    res = run_ensemble(_flat(stand), _rolling(50, r, v), key=seed, grid=[19.0, 71.0])
    e_in, e_out = res.grid_energy[:, 0], res.grid_energy[:, 1]
    crossed = ~np.isnan(e_out)
    assert (e_out[crossed] <= e_in[crossed] * (1 + 1e-5) + 1e-6).all()


def _slope_with_stand(stand: dict | None) -> Section:
    """A 35-degree slope to 60 m, then a 10-degree run-out; the stand on 30-90 m."""
    xs = np.array([0.0, 30.0, 60.0, 90.0, 200.0])
    t35, t10 = np.tan(np.radians(35.0)), np.tan(np.radians(10.0))
    ys = np.array([0.0, -30 * t35, -60 * t35, -60 * t35 - 30 * t10, -60 * t35 - 140 * t10])
    soil = Material(restitution=0.3, friction=0.5, rolling_resistance=0.25,
                    roughness_deg=5.0)
    mats = (soil, soil if stand is None else Material(
        restitution=0.3, friction=0.5, rolling_resistance=0.25, roughness_deg=5.0, **stand))
    return Section(xs, ys, np.array([0, 1, 1, 0]), mats)


@settings(max_examples=10, deadline=None)
@given(seed=st.integers(0, 2**32), sd=st.floats(0.0, 5.0))
def test_stems_that_take_every_energy_shorten_every_path(seed: int, sd: float) -> None:
    """With stems that take all of any rock's energy, no rock runs farther.

    Each rock stops at its first stem in the stand or, if it met none, runs
    exactly as it would without the forest up to the stand's far edge: its
    stop is never beyond the stop of the same rock without the forest.
    """
    n = 200
    rel = Releases(radius=np.full(n, 0.25), density=2700.0, x=np.full(n, 1.0),
                   height=np.full(n, 2.0), vx=np.full(n, 2.0), vy=np.zeros(n),
                   spin=np.zeros(n), spin_rolling=np.zeros(n, dtype=bool))
    # 100 cm stems take 3.3 MJ, far beyond a 180 kg rock's energy here.
    stand = {"stems_per_ha": 300.0, "dbh_mean_cm": 100.0, "dbh_sd_cm": sd,
             "tree_height_m": 100.0}
    bare = run_ensemble(_slope_with_stand(None), rel, key=seed)
    wood = run_ensemble(_slope_with_stand(stand), rel, key=seed)
    assert (wood.max_x <= bare.max_x + 1e-9).all()
    stopped = wood.stopped_by_forest
    assert (wood.stems_met[stopped] == 1).all()

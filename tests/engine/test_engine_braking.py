"""A net carries the rock it catches on by its braking distance (EAD 340059 figures)."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from rockfall_design.engine import G, Material, barrier_table, columns
from rockfall_design.engine.barriers import braking_distance
from rockfall_design.judge.outcomes import braking_distances
from rockfall_design.plugins.measure import Barrier, BarrierBehaviour

from ..engine_helpers import one_rock, run_one, section

FLAT = [[-50, 0], [200, 0]]
MAT = Material(restitution=0.3, friction=0.5, rolling_resistance=0.2)


def _energy_at(xb: float, m: float, h0=10.0, vx=5.0, r=0.3, w=2.0) -> float:
    t = xb / vx
    return 0.5 * m * (vx**2 + (G * t) ** 2) + 0.2 * m * r**2 * w**2


def test_braking_distance_interpolates_between_the_sel_and_mel_tests():
    sel, mel, d_sel, d_mel = 100e3, 300e3, 3.0, 5.0
    assert braking_distance(50e3, sel, d_sel, mel, d_mel) == d_sel  # below the SEL: its test
    assert braking_distance(200e3, sel, d_sel, mel, d_mel) == 4.0  # half way
    assert braking_distance(400e3, sel, d_sel, mel, d_mel) == d_mel
    assert braking_distance(200e3, sel, 0.0, mel, d_mel) == d_mel  # no SEL test given
    assert braking_distance(200e3, sel, d_sel, mel, 0.0) == 0.0  # no MEL test: none


@settings(max_examples=200, deadline=None)
@given(e=st.floats(0.0, 1e4), frac=st.floats(0.05, 0.95), d_sel=st.floats(0.0, 8.0),
       d_mel=st.floats(0.0, 10.0), cap=st.floats(1.0, 9000.0))
def test_the_screening_brakes_as_the_engine_does(e, frac, d_sel, d_mel, cap):
    """judge.outcomes.braking_distances (arrays, kJ) is the engine's rule (scalars, J)."""
    fp = Barrier(x=0.0, height_m=3.0, capacity_kj=cap, behaviour=BarrierBehaviour.NET,
                 sel_kj=frac * cap, elongation_sel_m=d_sel if d_sel > 0 else math.nan,
                 elongation_mel_m=d_mel if d_mel > 0 else math.nan)
    array = braking_distances(fp, np.array([e]))[0]
    scalar = braking_distance(e * 1e3, frac * cap * 1e3, d_sel, cap * 1e3, d_mel)
    assert_allclose(array, scalar, rtol=1e-12, atol=1e-12)
    assert 0.0 <= array <= max(d_sel, d_mel)


def test_a_caught_rock_rests_its_braking_distance_downslope():
    xb = 6.0
    sec = section(FLAT, MAT)
    probe = run_one(sec, one_rock(r=0.3, x=0.0, h=10.0, vx=5.0, vy=0.0, w=2.0))
    e = _energy_at(xb, probe.mass[0])
    # SEL below and MEL above the rock's energy: linear between 2 and 6 m.
    sel, mel = 0.5 * e, 2.0 * e
    bar = barrier_table(xb, 5.0, mel, columns.B_NET, sel_j=sel, elongation_sel_m=2.0,
                        elongation_mel_m=6.0)
    res = run_one(sec, one_rock(r=0.3, x=0.0, h=10.0, vx=5.0, vy=0.0, w=2.0), barriers=[bar])
    assert res.barrier_outcome[0, 0] == columns.O_CAUGHT
    d = 2.0 + 4.0 * (e - sel) / (mel - sel)
    assert_allclose(res.x_end[0], xb + d, rtol=1e-10)
    assert_allclose(res.max_x[0], xb + d, rtol=1e-10)
    assert_allclose(res.y_end[0], 0.3, rtol=1e-10)  # at rest on the ground (centre path)


@settings(max_examples=200, deadline=None)
@given(h_nominal=st.floats(0.5, 10.0), slope_deg=st.floats(0.0, 70.0),
       h_vertical=st.floats(0.0, 40.0))
def test_a_nominal_height_normal_to_the_slope_intercepts_what_passes_within_it(
        h_nominal, slope_deg, h_vertical):
    """A centre h_vertical above a plane of slope beta is h_vertical cos(beta) from it."""
    cos = math.cos(math.radians(slope_deg))
    fp = Barrier(x=0.0, height_m=h_nominal, capacity_kj=1e9, behaviour=BarrierBehaviour.NET,
                 slope_cos=cos, height_normal=True)
    normal = h_vertical * cos
    if abs(normal - h_nominal) > 1e-9 * h_nominal:
        assert (h_vertical > fp.vertical_height_m) == (normal > h_nominal)
    assert fp.vertical_height_m >= h_nominal  # never lower than the nominal height

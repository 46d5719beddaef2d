"""Barriers in the engine: met at the exact passing height, in both directions."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from rockfall_design.engine import G, Material, barrier_table, columns
from rockfall_design.engine.columns import T_VX, T_VY, T_W, T_X, T_Y

from ..engine_helpers import one_rock, run_one, section

RTOL = 1e-10
FLAT = [[-50, 0], [200, 0]]


def _flight(h0=10.0, vx=5.0, vy=0.0, r=0.3, w=2.0):
    """A rock launched horizontally from height h0 above flat ground at x = 0."""
    return one_rock(r=r, x=0.0, h=h0, vx=vx, vy=vy, w=w)


def _height_at(xb, h0=10.0, vx=5.0, vy=0.0, r=0.3):
    t = xb / vx
    return r + h0 + vy * t - 0.5 * G * t**2, t


def _energy(m, r, vx, vy, w):
    return 0.5 * m * (vx**2 + vy**2) + 0.2 * m * r**2 * w**2


MAT = Material(restitution=0.3, friction=0.5, rolling_resistance=0.2)


@pytest.mark.parametrize("h_fence,expect", [(2.0, "passed_over"), (5.0, "caught")])
def test_fence_in_flight_catches_below_and_lets_over_above(h_fence, expect):
    xb = 6.0
    h, t = _height_at(xb)  # 10.3 - 4.905 * 1.2^2 = 3.24 m above ground
    assert 2.0 < h < 5.0
    bar = barrier_table(xb, h_fence, np.inf, columns.B_NET)
    res = run_one(section(FLAT, MAT), _flight(), barriers=[bar])
    out = res.barrier_outcome[0, 0]
    hb, vb, eb, tb = res.barrier_meeting[0, 0]
    assert_allclose([hb, tb], [h, t], rtol=RTOL)
    m = res.mass[0]
    assert_allclose(eb, _energy(m, 0.3, 5.0, -G * t, 2.0), rtol=RTOL)
    if expect == "caught":
        assert out == columns.O_CAUGHT
        assert columns.STATUS_NAMES[res.status[0]] == "caught"
        assert res.caught_by[0] == 0
        assert_allclose(res.x_end[0], xb, rtol=RTOL)
        assert_allclose(res.y_end[0], h, rtol=RTOL)  # flat ground at y = 0
    else:
        assert out == columns.O_PASSED_OVER
        assert res.caught_by[0] == -1
        assert res.max_x[0] > xb


def test_fence_with_too_little_capacity_is_broken_through_with_the_surplus():
    xb = 6.0
    h, t = _height_at(xb)
    sec = section(FLAT, MAT)
    probe = run_one(sec, _flight())
    m = probe.mass[0]
    e = _energy(m, 0.3, 5.0, -G * t, 2.0)
    cap = 0.4 * e
    res = run_one(sec, _flight(), barriers=[barrier_table(xb, 9.0, cap, columns.B_NET)])
    assert res.barrier_outcome[0, 0] == columns.O_BROKEN_THROUGH
    tr = res.trajectories[0]
    row = tr[np.flatnonzero(np.isclose(tr[:, T_X], xb))[0]]
    f = np.sqrt((e - cap) / e)
    assert_allclose([row[T_VX], row[T_VY], row[T_W]], [f * 5.0, -f * G * t, f * 2.0], rtol=RTOL)
    assert_allclose(_energy(m, 0.3, row[T_VX], row[T_VY], row[T_W]), e - cap, rtol=RTOL)
    assert_allclose(row[T_Y], h, rtol=RTOL)
    assert res.max_x[0] > xb + 1.0


def test_wall_rebounds_the_rock_upslope():
    xb = 6.0
    h, t = _height_at(xb)
    e_w = 0.4
    res = run_one(
        section(FLAT, MAT), _flight(),
        barriers=[barrier_table(xb, 9.0, np.inf, columns.B_RIGID, e_w)],
    )
    assert res.barrier_outcome[0, 0] == columns.O_REBOUNDED
    tr = res.trajectories[0]
    row = tr[np.flatnonzero(np.isclose(tr[:, T_X], xb))[0]]
    assert_allclose([row[T_VX], row[T_VY], row[T_W]], [-e_w * 5.0, -G * t, 2.0], rtol=RTOL)
    assert res.max_x[0] == pytest.approx(xb)
    assert res.x_end[0] < xb
    assert columns.STATUS_NAMES[res.status[0]] == "stopped"


def test_rolling_rock_meets_a_barrier_at_its_rolling_height_both_ways():
    """Rolling towards -x (upslope direction) into a fence: caught, at height r."""
    r = 0.4
    res = run_one(
        section(FLAT, MAT),
        one_rock(r=r, x=50.0, vx=-6.0, rolling=True),
        barriers=[barrier_table(45.0, 1.0, np.inf, columns.B_NET)],
    )
    assert res.barrier_outcome[0, 0] == columns.O_CAUGHT
    hb, vb, eb, tb = res.barrier_meeting[0, 0]
    # Rolling decelerates at 5/7 g mu_r: v^2 = v0^2 - 2 a d over d = 5 m.
    a = 5 / 7 * G * 0.2
    assert_allclose(hb, r, rtol=RTOL)
    assert_allclose(vb, np.sqrt(36.0 - 2 * a * 5.0), rtol=RTOL)
    assert_allclose(res.x_end[0], 45.0, rtol=RTOL)


def test_a_rock_bigger_than_the_barrier_rolls_over_it():
    res = run_one(
        section(FLAT, MAT),
        one_rock(r=1.5, x=10.0, vx=6.0, rolling=True),
        barriers=[barrier_table(15.0, 1.0, np.inf, columns.B_NET)],
    )
    assert res.barrier_outcome[0, 0] == columns.O_PASSED_OVER


def test_boulder_row_gaps_pass_the_expected_fraction_of_small_rocks():
    gap, spacing, n = 1.2, 3.0, 4000
    r = 0.2
    res = run_one(
        section(FLAT, MAT),
        one_rock(r=r, x=10.0, vx=6.0, rolling=True, n=n),
        barriers=[barrier_table(15.0, 1.0, np.inf, columns.B_BLOCKS, gap_m=gap, spacing_m=spacing)],
    )
    through = np.mean(res.barrier_outcome[:, 0] == columns.O_PASSED_THROUGH_GAP)
    p = (gap - 2 * r) / spacing
    assert abs(through - p) < 4 * np.sqrt(p * (1 - p) / n)
    caught = res.barrier_outcome[:, 0] == columns.O_CAUGHT
    assert np.all(caught | (res.barrier_outcome[:, 0] == columns.O_PASSED_THROUGH_GAP))
    # Rocks wider than the gap never pass.
    big = run_one(
        section(FLAT, MAT),
        one_rock(r=0.7, x=10.0, vx=6.0, rolling=True, n=200),
        barriers=[barrier_table(15.0, 2.0, np.inf, columns.B_BLOCKS, gap_m=gap, spacing_m=spacing)],
    )
    assert np.all(big.barrier_outcome[:, 0] == columns.O_CAUGHT)


def test_barriers_are_reported_in_the_given_order():
    bars = [
        barrier_table(30.0, 9.0, np.inf, columns.B_NET),
        barrier_table(20.0, 0.1, np.inf, columns.B_NET),
    ]
    res = run_one(section(FLAT, MAT), one_rock(r=0.3, x=10.0, vx=10.0, rolling=True), barriers=bars)
    # The low barrier at x = 20 (second in the list) is passed over; the fence at 30 catches.
    assert res.barrier_outcome[0].tolist() == [columns.O_CAUGHT, columns.O_PASSED_OVER]
    assert res.caught_by[0] == 0

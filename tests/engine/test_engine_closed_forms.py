"""The engine against closed-form solutions (PHYSICS.md), to round-off."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from rockfall_design.engine import EngineSettings, G, Material, columns
from rockfall_design.engine.columns import T_MODE, T_T, T_VX, T_VY, T_X, T_Y
from rockfall_design.engine.impact import impact

from ..engine_helpers import one_rock, run_one, section

RTOL = 1e-10


def test_free_flight_parabola_landing_and_station():
    """Free flight: landing point and time, and the passing height at a station."""
    r, h0, vx, vy, w = 0.3, 10.0, 3.0, 2.0, -1.5
    sec = section([[-20, 0], [100, 0]], Material(restitution=0.0, friction=0.5))
    res = run_one(sec, one_rock(r=r, x=0.0, h=h0, vx=vx, vy=vy, w=w), stations=[2.0])
    tr = res.trajectories[0]
    t_land = (vy + np.sqrt(vy**2 + 2 * G * h0)) / G
    # Row 1 is the state after the first landing (position and time exact).
    assert tr[0, T_MODE] == columns.FLIGHT
    assert_allclose(tr[1, T_X], vx * t_land, rtol=RTOL)
    assert_allclose(tr[1, T_Y], r, rtol=RTOL)
    assert_allclose(tr[1, T_T], t_land, rtol=RTOL)
    # Station at x = 2 crossed in flight.
    ts = 2.0 / vx
    yc = r + h0 + vy * ts - 0.5 * G * ts**2
    h, cvx, cvy, cw, ct = res.crossings[0, 0]
    assert_allclose([h, cvx, cvy, cw, ct], [yc, vx, vy - G * ts, w, ts], rtol=RTOL)
    m = 4 / 3 * np.pi * r**3 * 2650
    e_tr = 0.5 * m * (vx**2 + (vy - G * ts) ** 2)
    e_rot = 0.5 * 0.4 * m * r**2 * w**2
    j = np.searchsorted(res.grid, 2.0)
    assert_allclose(res.grid_height[0, j], yc, rtol=1e-6)  # float32 record
    assert_allclose(res.grid_energy[0, j], e_tr + e_rot, rtol=1e-6)


def test_vertical_bounce_series():
    """Dropped vertically, the k-th rebound reaches h_k = e^(2k) h0."""
    e, h0, r = 0.6, 5.0, 0.2
    sec = section([[-10, 0], [10, 0]], Material(restitution=e, friction=0.5))
    res = run_one(sec, one_rock(r=r, x=0.0, h=h0))
    tr = res.trajectories[0]
    # Rows after landings in flight mode carry the rebound velocity.
    rebounds = tr[1:][tr[1:, T_MODE] == columns.FLIGHT]
    assert len(rebounds) >= 3
    for k, row in enumerate(rebounds, start=1):
        assert row[T_VX] == 0.0
        assert_allclose(row[T_VY] ** 2 / (2 * G), e ** (2 * k) * h0, rtol=RTOL)
    # It stops bouncing once the hop would be below h_c = kappa r (no
    # roughness height; PHYSICS.md, "The transition to contact"), then rests:
    # hops 5 m x 0.36^k, the last of 0.030 m >= 0.02 m, the next 0.011 m.
    h_c = columns.CONTACT_HOP_RATIO * r
    h_last = rebounds[-1, T_VY] ** 2 / (2 * G)
    assert len(rebounds) == 5 and h_last >= h_c and e * e * h_last < h_c
    assert columns.STATUS_NAMES[res.status[0]] == "stopped"
    assert_allclose(res.x_end[0], 0.0, atol=1e-12)


@pytest.mark.parametrize(("rough_h", "v_contact", "hops"),
                         [(0.1, 0.05, 3), (0.1, 0.5, 3), (0.0, 0.02, 5), (0.3, 0.05, 2)])
def test_the_bounce_series_ends_at_the_contact_height(rough_h, v_contact, hops):
    """Hops 5 m x 0.36^k end at the first below max(h_r, kappa r), whatever v_contact.

    h_c = max(h_r, 0.1 x 0.2 m): 0.1 m ends after the hop of 0.233 m (3 hops),
    0.02 m after 0.030 m (5), 0.3 m after 0.648 m (2); v_contact 0.05 or 0.5 m/s
    (hops of 0.13 mm and 13 mm) does not enter (PHYSICS.md, "The transition").
    A vertical drop meets no tilt from the roughness height (it turns the
    normal against a tangential velocity, and there is none).
    """
    e, h0, r = 0.6, 5.0, 0.2
    sec = section([[-10, 0], [10, 0]],
                  Material(restitution=e, friction=0.5, roughness_height_m=rough_h))
    res = run_one(sec, one_rock(r=r, x=0.0, h=h0),
                  settings=EngineSettings(v_contact=v_contact))
    tr = res.trajectories[0]
    rebounds = tr[1:][tr[1:, T_MODE] == columns.FLIGHT]
    assert len(rebounds) == hops
    assert columns.STATUS_NAMES[res.status[0]] == "stopped"


@pytest.mark.parametrize("v", [2.0, 7.5])
def test_horizontal_launch_from_cliff_edge(v):
    """A rock rolling off a cliff edge lands v * sqrt(2H/g) further on."""
    H, r = 20.0, 0.25
    sec = section(
        [[0, H], [10, H], [10.0005, 0], [60, 0]],
        Material(restitution=0.3, friction=0.5, rolling_resistance=0.0),
    )
    res = run_one(sec, one_rock(r=r, x=2.0, vx=v, rolling=True))
    tr = res.trajectories[0]
    flights = np.flatnonzero(tr[:, T_MODE] == columns.FLIGHT)
    launch, land = tr[flights[0]], tr[flights[0] + 1]
    # The centre leaves where the arc's first (tangent) edge ends, horizontally.
    assert_allclose(launch[T_VY], 0.0, atol=1e-12)
    assert_allclose(launch[T_VX], v, rtol=RTOL)
    assert_allclose(land[T_X] - launch[T_X], v * np.sqrt(2 * H / G), rtol=RTOL)
    assert_allclose(land[T_Y], r, rtol=RTOL)


@pytest.mark.parametrize("beta_deg", [10.0, 30.0])
def test_rolling_down_incline(beta_deg):
    """Rolling without slip: a = 5/7 g sin(beta) (mu_r = 0)."""
    b = np.radians(beta_deg)
    L = 50.0
    sec = section([[0, L * np.tan(b)], [L, 0]], Material(friction=0.9, rolling_resistance=0.0))
    res = run_one(sec, one_rock(r=0.4, x=1.0, rolling=True), stations=[31.0])
    a = 5 / 7 * G * np.sin(b)
    s = 30.0 / np.cos(b)
    h, cvx, cvy, cw, ct = res.crossings[0, 0]
    v = np.hypot(cvx, cvy)
    assert_allclose(v, np.sqrt(2 * a * s), rtol=RTOL)
    assert_allclose(ct, np.sqrt(2 * s / a), rtol=RTOL)
    assert_allclose(cw, -v / 0.4, rtol=RTOL)  # rolling: w = -v / r
    assert_allclose(h, 0.4 / np.cos(b), rtol=RTOL)  # centre above ground, vertically


def test_rolling_with_rolling_resistance_on_incline():
    """a = 5/7 g (sin(beta) - mu_r cos(beta))."""
    b = np.radians(25.0)
    mur = 0.2
    sec = section([[0, 50 * np.tan(b)], [50, 0]], Material(friction=0.9, rolling_resistance=mur))
    res = run_one(sec, one_rock(r=0.4, x=1.0, rolling=True), stations=[21.0])
    a = 5 / 7 * G * (np.sin(b) - mur * np.cos(b))
    s = 20.0 / np.cos(b)
    _, cvx, cvy, _, ct = res.crossings[0, 0]
    assert_allclose(np.hypot(cvx, cvy), np.sqrt(2 * a * s), rtol=RTOL)
    assert_allclose(ct, np.sqrt(2 * s / a), rtol=RTOL)


def test_sliding_on_slope_too_steep_to_roll():
    """tan(beta) > (7 mu - 5 mu_r)/2: a = g (sin(beta) - mu cos(beta)) and the spin grows."""
    b = np.radians(50.0)
    mu = 0.25  # 3.5 mu = 0.875 < tan(50 deg) = 1.19
    r = 0.5
    sec = section([[0, 60 * np.tan(b)], [60, 0]], Material(friction=mu, rolling_resistance=0.1))
    res = run_one(sec, one_rock(r=r, x=1.0), stations=[21.0])
    a = G * (np.sin(b) - mu * np.cos(b))
    s = 20.0 / np.cos(b)
    _, cvx, cvy, cw, ct = res.crossings[0, 0]
    assert_allclose(np.hypot(cvx, cvy), np.sqrt(2 * a * s), rtol=RTOL)
    assert_allclose(ct, np.sqrt(2 * s / a), rtol=RTOL)
    # r ds/dt = 5/2 g cos(beta) (mu - mu_r), s = -w for motion towards +x. The
    # physics changed (issue 14): the rolling-resistance moment now acts while
    # the contact slips too, where this used to be 5/2 mu g cos(beta).
    assert_allclose(-cw * r, 2.5 * (mu - 0.1) * G * np.cos(b) * ct, rtol=RTOL)


def test_slide_to_roll_on_flat_reaches_five_sevenths():
    """A rock launched sliding without spin on level ground ends rolling at 5/7 v0."""
    v0, mu, r = 6.0, 0.4, 0.3
    sec = section([[0, 0], [100, 0]], Material(friction=mu, rolling_resistance=0.0))
    res = run_one(sec, one_rock(r=r, x=1.0, vx=v0), stations=[90.0])
    _, cvx, cvy, cw, ct = res.crossings[0, 0]
    assert_allclose(cvx, 5 / 7 * v0, rtol=RTOL)
    assert_allclose(cw, -5 / 7 * v0 / r, rtol=RTOL)
    # Slip ends at t1 = 2 v0 / (7 mu g), after d1 = v0 t1 - mu g t1^2 / 2.
    t1 = 2 * v0 / (7 * mu * G)
    d1 = v0 * t1 - 0.5 * mu * G * t1**2
    assert_allclose(ct, t1 + (89.0 - d1) / (5 / 7 * v0), rtol=RTOL)


@pytest.mark.parametrize("v0,mur", [(3.0, 0.1), (8.0, 0.35)])
def test_rolling_stop_distance(v0, mur):
    """On level ground a rolling rock stops after v0^2 / (2 * 5/7 g mu_r)."""
    sec = section([[0, 0], [200, 0]], Material(friction=0.6, rolling_resistance=mur))
    res = run_one(sec, one_rock(r=0.5, x=1.0, vx=v0, rolling=True))
    assert columns.STATUS_NAMES[res.status[0]] == "stopped"
    assert_allclose(res.x_end[0] - 1.0, v0**2 / (2 * 5 / 7 * G * mur), rtol=RTOL)
    assert_allclose(res.duration[0], v0 / (5 / 7 * G * mur), rtol=RTOL)


def _impact(
    vx,
    vy,
    w,
    n=(0.0, 1.0),
    r=0.5,
    model=columns.MODEL_SPANG,
    e=0.5,
    rt=1.0,
    mu=0.5,
    vscale=False,
    k=9.144,
):
    rng = np.zeros(1, dtype=np.uint64)
    return np.array(impact(vx, vy, w, n[0], n[1], r, model, e, rt, mu, vscale, k, 0.0, rng))


def test_impact_spang_stick_branch():
    # |u| = 1 <= 7/2 mu p_n = 3.5 * 0.5 * 3: slip stops; the rock leaves rolling.
    vx, vy, w = _impact(1.0, -2.0, 0.0, r=0.5, e=0.5, mu=0.5)
    assert_allclose([vx, vy, w], [5 / 7, 1.0, -5 / 7 / 0.5], rtol=RTOL)


def test_impact_spang_slip_branch():
    # |u| = 5 > 7/2 mu p_n = 3.5 * 0.1 * 1.3: slides through the impact.
    vx, vy, w = _impact(5.0, -1.0, 0.0, r=0.4, e=0.3, mu=0.1)
    pn = 1.3
    assert_allclose([vx, vy, w], [5.0 - 0.1 * pn, 0.3, -2.5 * 0.1 * pn / 0.4], rtol=RTOL)


def test_impact_is_frame_independent():
    """The same impact on a slope of 30 degrees, rotated back, gives the same result."""
    a = np.radians(30.0)
    rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    n = rot @ [0.0, 1.0]
    v = rot @ [5.0, -1.0]
    out = _impact(v[0], v[1], 2.0, n=n, r=0.4, e=0.3, mu=0.1)
    flat = _impact(5.0, -1.0, 2.0, r=0.4, e=0.3, mu=0.1)
    assert_allclose(rot.T @ out[:2], flat[:2], rtol=RTOL, atol=1e-12)
    assert_allclose(out[2], flat[2], rtol=RTOL)


def test_impact_rn_rt_law():
    vx, vy, w = _impact(4.0, -3.0, -2.0, model=columns.MODEL_RN_RT, e=0.4, rt=0.8)
    assert_allclose([vx, vy, w], [0.8 * 4.0, 0.4 * 3.0, 0.8 * -2.0], rtol=RTOL)


def test_pfeiffer_bowen_velocity_scaling():
    vn = -12.0
    for model in (columns.MODEL_SPANG, columns.MODEL_RN_RT):
        out = _impact(0.0, vn, 0.0, model=model, e=0.5, mu=0.5, vscale=True)
        assert_allclose(out[1], 0.5 / (1 + (12.0 / 9.144) ** 2) * 12.0, rtol=RTOL)


def test_counter_slope_rolls_back():
    """A rock running up a counter-slope comes back and settles in the trough."""
    sec = section(
        [[0, 10], [20, 0], [30, 5]],
        Material(friction=0.8, rolling_resistance=0.05, restitution=0.2),
    )
    res = run_one(sec, one_rock(r=0.3, x=1.0, rolling=True))
    tr = res.trajectories[0]
    assert (tr[:, T_VX] < 0).any(), "the rock never moved back upslope"
    assert columns.STATUS_NAMES[res.status[0]] == "stopped"
    assert 19.0 < res.x_end[0] < 21.0
    assert res.max_x[0] > 21.0


def test_event_cap_reports_unresolved():
    sec = section([[0, 10], [20, 0], [30, 5]], Material(friction=0.8, rolling_resistance=0.05))
    res = run_one(sec, one_rock(r=0.3, x=1.0, rolling=True), settings=EngineSettings(max_events=10))
    assert columns.STATUS_NAMES[res.status[0]] == "unresolved"
    assert res.n_events[0] == 10


def test_rock_resting_on_gentle_slope_does_not_move():
    sec = section([[0, 1], [10, 0]], Material(friction=0.5, rolling_resistance=0.2))
    res = run_one(sec, one_rock(r=0.3, x=5.0))
    assert columns.STATUS_NAMES[res.status[0]] == "stopped"
    assert res.x_end[0] == 5.0
    assert res.n_events[0] == 1


@pytest.mark.parametrize("shape", ["V", "trapezoid"])
@pytest.mark.parametrize("side", ["left", "right"])
@pytest.mark.parametrize("model", ["spang", "rn_rt"])
def test_rock_released_in_a_hollow_comes_to_rest_inside(shape, side, model):
    """Whichever side it starts on, a rock released in a hollow stays in it."""
    pts = (
        [[0, 10], [20, 0], [40, 10]]
        if shape == "V"
        else [[0, 10], [15, 0], [25, 0], [40, 10]]
    )
    mat = Material(impact_model=model, restitution=0.4, tangential_restitution=0.85,
                   friction=0.6, rolling_resistance=0.1, roughness_deg=5.0,
                   sd_restitution=0.05, sd_friction=0.05)
    x0 = 3.0 if side == "left" else 37.0
    res = run_one(section(pts, mat), one_rock(r=0.4, x=x0, h=1.0, n=20), key=9)
    assert np.all(res.status == columns.STOPPED)
    lo, hi = (15.0, 25.0) if shape == "V" else (14.0, 26.0)
    assert np.all((res.x_end > lo) & (res.x_end < hi)), res.x_end

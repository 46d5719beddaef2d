"""Motion in contact as PHYSICS.md states it since issue 14, against closed forms.

Rolling resistance acts whenever the rock spins (also while it slips), pure
rolling is bounded by Coulomb on both sides, -(7 mu + 5 mu_r)/2 <= tan(beta)
<= (7 mu - 5 mu_r)/2, and no path ever takes an event of zero length.
"""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from rockfall_design.engine import EngineSettings, G, Material, Releases, columns, run_ensemble
from rockfall_design.engine import contact as engine_contact
from rockfall_design.engine.columns import T_T, T_VX, T_VY, T_W, T_Y
from rockfall_design.engine.impact import impact

from ..engine_helpers import one_rock, run_one, section

RTOL = 1e-10


def _mass(r: float, rho: float = 2650.0) -> float:
    return 4.0 / 3.0 * np.pi * r**3 * rho


def test_rolling_resistance_acts_while_slipping_40_degrees():
    """Issue 14: 40 deg incline, mu 0.3, mu_r 0.2, rock (r 0.5 m) from rest at x = 1 m.

    tan 40 deg = 0.839 > (7 mu - 5 mu_r)/2 = 0.55, so the rock slips from the
    start: a = g (sin b - mu cos b) and r ds/dt = 5/2 g cos b (mu - mu_r). At
    x = 51 m the rotational energy is 1/5 m (r s)^2 = 31.6 kJ (the engine gave
    146.8 kJ before, holding the slip at zero with friction at its limit).
    """
    b, mu, mur, r = np.radians(40.0), 0.3, 0.2, 0.5
    sec = section([[0, 100 * np.tan(b)], [100, 0]], Material(friction=mu, rolling_resistance=mur))
    res = run_one(sec, one_rock(r=r, x=1.0), stations=[51.0])
    _, cvx, cvy, cw, ct = res.crossings[0, 0]
    d = 50.0 / np.cos(b)
    a = G * (np.sin(b) - mu * np.cos(b))
    t = np.sqrt(2 * d / a)
    rs = 2.5 * G * np.cos(b) * (mu - mur) * t
    m = _mass(r)
    assert_allclose(ct, t, rtol=RTOL)
    assert_allclose(np.hypot(cvx, cvy), a * t, rtol=RTOL)
    assert_allclose(-cw * r, rs, rtol=RTOL)
    e_rot = 0.2 * m * (r * cw) ** 2
    assert_allclose(e_rot, 0.2 * m * rs**2, rtol=RTOL)
    assert_allclose(e_rot / 1e3, 31.6, atol=0.05)


def test_rolling_into_a_steep_rise_slips_with_spin_ahead():
    """Issue 14: rolling at 12 m/s into a 60 deg rise (mu 0.3, e 0) climbs 4.24 m, not 4.90 m.

    The concave vertex is an impact: v_t = 12 cos 60, r w = -12, slip
    |u| = 6 <= 7/2 mu p_n, so the rock leaves it rolling at
    v' = (5 v_t - 2 r w) / 7 = 54/7 m/s. tan 60 deg = 1.73 is below the lower
    limit -(7 mu + 5 mu_r)/2 = -1.05 (moving uphill), so it slips at once with
    its spin ahead (sigma < 0): dv/dt = g (sin b + mu cos b), b = -60 deg, and
    it climbs v'^2 / (2 g (sin 60 - mu cos 60)) along the rise.
    """
    mu, r = 0.3, 0.4
    th = np.radians(60.0)
    sec = section(
        [[-60, 0], [0, 0], [10, 10 * np.tan(th)]],
        Material(restitution=0.0, friction=mu, rolling_resistance=0.0),
    )
    res = run_one(sec, one_rock(r=r, x=-50.0, vx=12.0, rolling=True))
    tr = res.trajectories[0]
    v1 = (5 * 12 * np.cos(th) + 2 * 12) / 7
    climb = v1**2 / (2 * G * (np.sin(th) - mu * np.cos(th)))
    assert_allclose(climb, 4.236, atol=5e-4)
    # The centre path's corner is at height r; it climbs along the offset line.
    assert_allclose((tr[:, T_Y].max() - r) / np.sin(th), climb, rtol=1e-9)
    # Rolling all the way up would have reached 4.90 m.
    assert v1**2 / (2 * 5 / 7 * G * np.sin(th)) == pytest.approx(4.903, abs=5e-4)


def test_rolling_uphill_within_the_lower_limit_keeps_rolling():
    """Moving up a 30 deg rise with mu 0.5: tan 30 > -(7 mu + 5 mu_r)/2, it rolls."""
    mu, mur, r, v0 = 0.5, 0.1, 0.3, 6.0
    b = np.radians(30.0)
    sec = section([[0, 0], [40, 40 * np.tan(b)]], Material(friction=mu, rolling_resistance=mur))
    rel = one_rock(r=r, x=1.0, vx=v0 * np.cos(b), vy=v0 * np.sin(b), rolling=True)
    res = run_one(sec, rel)
    tr = res.trajectories[0]
    a = 5 / 7 * G * (np.sin(b) + mur * np.cos(b))
    top = np.argmax(tr[:, T_Y])
    assert_allclose(tr[top, T_Y] - tr[0, T_Y], v0**2 / (2 * a) * np.sin(b), rtol=1e-9)
    assert_allclose(tr[top, T_T], v0 / a, rtol=1e-9)


def test_spin_held_at_zero_when_resistance_beats_friction():
    """mu <= mu_r: a rock sliding without spin keeps w = 0 (PHYSICS.md)."""
    b, mu, mur, r = np.radians(60.0), 0.2, 0.3, 0.5
    sec = section([[0, 60 * np.tan(b)], [60, 0]], Material(friction=mu, rolling_resistance=mur))
    res = run_one(sec, one_rock(r=r, x=1.0), stations=[21.0])
    _, cvx, cvy, cw, ct = res.crossings[0, 0]
    a = G * (np.sin(b) - mu * np.cos(b))
    d = 20.0 / np.cos(b)
    assert cw == 0.0
    assert_allclose(np.hypot(cvx, cvy), np.sqrt(2 * a * d), rtol=RTOL)


def test_backspin_reverses_through_a_spin_zero_event():
    """Backspin (s < 0) on a steep slope: r ds/dt = 5/2 g cos b (mu + mu_r) until s = 0.

    After the spin-zero event the resistance moment turns with the spin:
    r ds/dt = 5/2 g cos b (mu - mu_r).
    """
    b, mu, mur, r, v0, s0 = np.radians(55.0), 0.25, 0.1, 0.5, 2.0, -3.0
    sec = section([[0, 80 * np.tan(b)], [80, 0]], Material(friction=mu, rolling_resistance=mur))
    t_dir = np.array([np.cos(b), -np.sin(b)])
    rel = one_rock(r=r, x=1.0, vx=v0 * t_dir[0], vy=v0 * t_dir[1], w=-s0)
    res = run_one(sec, rel, stations=[41.0])
    _, cvx, cvy, cw, ct = res.crossings[0, 0]
    a = G * (np.sin(b) - mu * np.cos(b))
    d = 40.0 / np.cos(b)
    t = (-v0 + np.sqrt(v0**2 + 2 * a * d)) / a
    k1 = 2.5 * G * np.cos(b) * (mu + mur)
    k2 = 2.5 * G * np.cos(b) * (mu - mur)
    t0 = -r * s0 / k1
    assert t > t0
    assert_allclose(ct, t, rtol=RTOL)
    assert_allclose(np.hypot(cvx, cvy), v0 + a * t, rtol=RTOL)
    assert_allclose(-cw * r, k2 * (t - t0), rtol=1e-9)


@pytest.mark.parametrize("rt", [0.0, 0.6, 0.85, 1.0])
def test_rn_rt_spin_rule_keeps_a_rolling_rock_rolling(rt):
    """rn_rt (PHYSICS.md "Lumped-mass law"): w' = Rt w, so w' = -v_t' / r if w = -v_t / r."""
    a = np.radians(25.0)
    n = np.array([np.sin(a), np.cos(a)])
    t = np.array([n[1], -n[0]])
    r, vt, vn = 0.7, 5.0, -2.0
    v = vt * t + vn * n
    rng = np.zeros(1, dtype=np.uint64)
    vx, vy, w = impact(v[0], v[1], -vt / r, n[0], n[1], r, columns.MODEL_RN_RT, 0.35, rt,
                            0.5, False, 9.144, 0.0, rng)
    vt2 = vx * t[0] + vy * t[1]
    assert_allclose(vt2, rt * vt, rtol=RTOL, atol=1e-12)
    assert_allclose(w, rt * (-vt / r), rtol=RTOL)
    assert_allclose(w, -vt2 / r, rtol=RTOL, atol=1e-15)


@pytest.mark.parametrize("side", [+1, -1])
@pytest.mark.parametrize("offset", [0.0, 1e-12, -1e-12, 9e-10, -9e-10])
def test_slip_at_tolerance_starts_in_the_sense_of_its_rate(side, offset):
    """A slip within tolerance of zero on a piece that cannot hold rolling.

    Above the upper limit it grows positive, below the lower limit (moving
    uphill) negative, and in both cases its rate is bounded away from zero.
    """
    mu, mur, r, v = 0.3, 0.1, 0.5, 3.0
    beta = np.radians(45.0 if side > 0 else -65.0)
    s = (v - offset) / r
    a, dsig, ds, sg, s_zero = engine_contact.contact_accel(
        np.sin(beta), np.cos(beta), v, s, mu, mur, r
    )
    assert not np.isnan(ds) and not s_zero
    assert sg == side
    assert dsig * side > 0.1
    assert_allclose(dsig, G * np.cos(beta) * (np.tan(beta) - 3.5 * mu * sg + 2.5 * mur))


@pytest.mark.parametrize("deg", [-80.0, -40.0, -15.0, 0.0, 10.0, 20.5, 28.0, 60.0])
def test_slip_decays_exactly_where_rolling_can_hold(deg):
    """d(sigma)/dt has the sign that drives slip to zero iff rolling holds (no band)."""
    mu, mur, r, v = 0.3, 0.15, 0.5, 3.0
    beta = np.radians(deg)
    lo, hi = -(7 * mu + 5 * mur) / 2, (7 * mu - 5 * mur) / 2
    holds = lo <= np.tan(beta) <= hi
    _, d_pos, _, _, _ = engine_contact.contact_accel(np.sin(beta), np.cos(beta), v, (v - 0.1) / r,
                                            mu, mur, r)
    _, d_neg, _, _, _ = engine_contact.contact_accel(np.sin(beta), np.cos(beta), v, (v + 0.1) / r,
                                            mu, mur, r)
    assert holds == (d_pos < 0 and d_neg > 0)


def _near_rolling(deg: float, n: int, direction: int, seed: int) -> Releases:
    """Rocks on an incline, moving along it, with spins within 1e-9 of rolling."""
    b = np.radians(deg)
    rng = np.random.default_rng(seed)
    r = 0.5
    v = rng.uniform(0.0, 4.0, n)
    t = direction * np.array([np.cos(b), -np.sin(b)])
    rel_off = rng.choice([-1.0, 1.0], n) * 10.0 ** rng.uniform(-16, -9, n)
    w = -direction * (v / r) * (1 + rel_off) + rng.uniform(-1e-9, 1e-9, n)
    return Releases(
        radius=np.full(n, r),
        density=2650.0,
        x=rng.uniform(5.0, 55.0, n),
        height=np.zeros(n),
        vx=v * t[0],
        vy=v * t[1],
        spin=w,
        spin_rolling=np.zeros(n, bool),
    )


def _assert_no_zero_length_event(res) -> None:
    """Every event but the final stop decision advances the clock."""
    for i, tr in enumerate(res.trajectories):
        dt = np.diff(tr[:, T_T])
        ne = int(res.n_events[i])
        moving = dt[: ne - 1] if res.status[i] == columns.STOPPED else dt[:ne]
        assert np.all(moving > 0.0), (i, np.flatnonzero(moving <= 0.0)[:5])


@pytest.mark.parametrize("deg", [20, 30, 35, 40, 45, 50, 60, 70])
def test_scan_of_spins_near_rolling_leaves_no_rock_unresolved(deg):
    """Issue 14: an incline with a flat runout, mu 0.3 (sd 0.05), mu_r 0.1.

    Before the fix, 215 of 2,000 such rocks ended unresolved at 45 degrees
    (zero-length events up to the event limit).
    """
    b = np.radians(deg)
    mat = Material(restitution=0.3, friction=0.3, sd_friction=0.05, rolling_resistance=0.1)
    sec = section([[0, 60 * np.tan(b)], [60, 0], [120, 0]], mat)
    for direction in (1, -1):
        rel = _near_rolling(deg, 150, direction, seed=deg)
        res = run_ensemble(sec, rel, key=deg, settings=EngineSettings(max_events=2000),
                           n_trajectories=len(rel), max_trajectory_points=2001)
        assert np.all(res.status != columns.UNRESOLVED)
        _assert_no_zero_length_event(res)


PROP = settings(
    max_examples=int(os.environ.get("RF_EXAMPLES", "60")),
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)


@PROP
@given(
    deg=st.floats(1.0, 85.0),
    mu=st.floats(0.0, 1.2),
    mur=st.floats(0.0, 0.6),
    limit=st.sampled_from(["upper", "lower", "slope"]),
    log_off=st.floats(-16.0, -6.0),
    off_sign=st.sampled_from([-1.0, 1.0]),
    direction=st.sampled_from([1, -1]),
    v0=st.floats(0.0, 8.0),
)
def test_no_zero_length_event_near_the_coulomb_limits(
    deg, mu, mur, limit, log_off, off_sign, direction, v0
):
    """Slopes at and beside each Coulomb limit, spins within a hair of rolling.

    ``limit`` puts the incline on the upper limit (7 mu - 5 mu_r)/2, on the
    lower one (the rock moves uphill at -(7 mu + 5 mu_r)/2), or at ``deg``.
    """
    if limit == "upper" and 7 * mu - 5 * mur > 0:
        deg = np.degrees(np.arctan((7 * mu - 5 * mur) / 2)) * (1 + off_sign * 10.0**log_off)
    elif limit == "lower":
        deg = np.degrees(np.arctan((7 * mu + 5 * mur) / 2)) * (1 + off_sign * 10.0**log_off)
        direction = -1
    deg = float(np.clip(deg, 0.5, 85.0))
    b = np.radians(deg)
    mat = Material(restitution=0.2, friction=mu, rolling_resistance=mur)
    sec = section([[-40, 40 * np.tan(b)], [0, 0], [60, -60 * np.tan(b)], [90, -60 * np.tan(b)]],
                  mat)
    r = 0.4
    t = direction * np.array([np.cos(b), -np.sin(b)])
    n = 6
    offs = np.array([0.0, 1e-15, -1e-15, 1e-10, -1e-10, off_sign * 10.0**log_off])
    v = np.full(n, v0)
    rel = Releases(
        radius=np.full(n, r), density=2650.0, x=np.full(n, 30.0), height=np.zeros(n),
        vx=v * t[0], vy=v * t[1], spin=-direction * (v + offs) / r,
        spin_rolling=np.zeros(n, bool),
    )
    res = run_ensemble(sec, rel, key=3, settings=EngineSettings(max_events=2000),
                       n_trajectories=n, max_trajectory_points=2001)
    assert np.all(res.status != columns.UNRESOLVED), res.n_events
    _assert_no_zero_length_event(res)
    # Energy never grows on the way either.
    for i, tr in enumerate(res.trajectories):
        m = res.mass[i]
        e = 0.5 * m * (tr[:, T_VX] ** 2 + tr[:, T_VY] ** 2) + 0.2 * m * r * r * tr[:, T_W] ** 2
        e = e + m * G * tr[:, T_Y]
        scale = m * (G * (np.abs(tr[:, T_Y]).max() + 1.0) + v0**2 + 1.0)
        assert np.all(np.diff(e) <= 1e-9 * scale)

"""The rough_soft law and the resistance in an impact (docs/PHYSICS.md).

Closed forms: the resistance impulse of a rolling rock that sticks; the
drag of an impact on the translation; the terminal speed on a uniform slope,
V_s sqrt(tan(beta) / mu_0 - 1) rolling and V_s sqrt((tan(beta) - mu) / mu_0)
sliding, from above and below, whatever the release height; the slip's
zero against the integrated equations. Properties: no impact adds energy;
no contact phase has zero length or adds energy, and the slip reaches zero
continuously; runout grows with the block's size on rough ground and not
on smooth.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp
from scipy.stats import spearmanr

import rockfall_design as rd
from rockfall_design.engine import columns, contact
from rockfall_design.engine.columns import G
from rockfall_design.engine.impact import impact

RS = columns.MODEL_ROUGH_SOFT


def _impact(vx, vy, w, r, model, e, mu, mur, vdrag, vscale=False):
    rng = np.zeros(1, dtype=np.uint64)
    return impact(vx, vy, w, 0.0, 1.0, r, model, e, 1.0, mu, vscale, 9.144, 0.0, rng,
                  0.0, mur, vdrag)


def _energy(vx, vy, w, r):
    """Kinetic energy per unit mass of a solid sphere (J/kg)."""
    return 0.5 * (vx * vx + vy * vy) + 0.2 * r * r * w * w


def test_a_rolling_rock_that_sticks_loses_five_sevenths_mu_r_p_n():
    # Rolling at 4 m/s (w = -v/r), normal speed 2 m/s, e 0.5: p_n = 3 m/s.
    r, e, mur = 0.5, 0.5, 0.2
    vx, vy, w = _impact(4.0, -2.0, -4.0 / r, r, RS, e, 0.8, mur, 0.0)
    assert vx == pytest.approx(4.0 - 5.0 / 7.0 * mur * 3.0, rel=1e-12)
    assert vy == pytest.approx(1.0, rel=1e-12)
    assert w == pytest.approx(-vx / r, rel=1e-12)


@pytest.mark.parametrize("model", [columns.MODEL_SPANG, columns.MODEL_RN_RT])
def test_spang_and_rn_rt_impacts_take_no_rolling_resistance(model):
    # Issue 35, second attempt: only rough_soft's impacts feel the resistance.
    without = _impact(4.0, -2.0, -4.0 / 0.5, 0.5, model, 0.5, 0.8, 0.0, 0.0)
    assert _impact(4.0, -2.0, -4.0 / 0.5, 0.5, model, 0.5, 0.8, 0.7, 6.0) == without


def test_without_resistance_spang_is_unchanged():
    a = _impact(3.0, -2.0, 1.5, 0.4, columns.MODEL_SPANG, 0.4, 0.3, 0.0, 0.0)
    rng = np.zeros(1, dtype=np.uint64)
    b = impact(3.0, -2.0, 1.5, 0.0, 1.0, 0.4, columns.MODEL_SPANG, 0.4, 1.0, 0.3, False,
               9.144, 0.0, rng)
    assert a == b


def test_the_drag_of_an_impact_takes_translation_not_spin():
    # No spin, e = 0: p_n = 3 m/s. The drag integrates dv_t/dp = -mu_0 v_t^2 / V_s^2
    # over p_n (v_t / (1 + mu_0 p_n v_t / V_s^2)), then the rock sticks (5/7).
    r, e, mur, vs = 0.5, 0.0, 0.1, 5.0
    slow = _impact(4.0, -3.0, 0.0, r, RS, e, 0.8, mur, 0.0)
    fast = _impact(4.0, -3.0, 0.0, r, RS, e, 0.8, mur, vs)
    assert slow[0] == pytest.approx(5.0 / 7.0 * 4.0, rel=1e-12)
    assert fast[0] == pytest.approx(5.0 / 7.0 * 4.0 / (1.0 + mur * 3.0 * 4.0 / vs**2), rel=1e-12)
    # Without friction the spin feels the moment mu_0 r p_n alone, not the drag.
    spin = _impact(4.0, -3.0, -2.0, r, RS, e, 0.0, mur, vs)
    assert spin[0] == pytest.approx(4.0 / (1.0 + mur * 3.0 * 4.0 / vs**2), rel=1e-12)
    assert spin[2] == pytest.approx(-2.0 + 2.5 * mur * 3.0 / r, rel=1e-12)


@settings(max_examples=300, deadline=None)
@given(
    vx=st.floats(-30.0, 30.0), vy=st.floats(-30.0, -1e-3), w=st.floats(-80.0, 80.0),
    r=st.floats(0.05, 3.0), e=st.floats(0.0, 1.0), mu=st.floats(0.0, 2.0),
    mur=st.floats(0.0, 3.0), vdrag=st.sampled_from([0.0, 0.5, 3.0, 10.0]),
    model=st.sampled_from([columns.MODEL_SPANG, RS]), vscale=st.booleans(),
)
def test_no_impact_adds_energy(vx, vy, w, r, e, mu, mur, vdrag, model, vscale):
    before = _energy(vx, vy, w, r)
    after = _energy(*_impact(vx, vy, w, r, model, e, mu, mur, vdrag, vscale), r)
    assert after <= before * (1.0 + 1e-12) + 1e-12


SLOPE = """\
name: Uniform slope
description: a uniform soft slope
slope:
  points: [[0, 240], [400, {y_end}]]
  materials: [ground]
materials:
  ground: {{impact_model: rough_soft, restitution: 0.25, friction: 0.6,
           rolling_resistance: 0.3, obstacle_height_m: {ho}, drag_speed_ms: 6}}
rocks:
  count: 20
  seed: 1
  radius: {r}
  release: {{x: [1, 2], height: {h}, velocity: [0.5, 0]}}
analysis: {{stations: [300, 390]}}
protect: {{x: 399}}
"""


def _run(tmp_path, text, rocks, seed=1):
    path = tmp_path / "p.yaml"
    path.write_text(text)
    return rd.simulate(path, rocks=rocks, seed=seed, trajectories=0)


@pytest.mark.parametrize("h", [1.0, 20.0])
def test_terminal_speed_on_a_uniform_soft_slope(tmp_path, h):
    beta = math.atan((240.0 - 9.06) / 400.0)         # 30 degrees
    r, ho = 0.4, 0.1
    mu0 = 0.3 + ho / (ho + r)
    vt = 6.0 * math.sqrt(math.tan(beta) / mu0 - 1.0)
    res = _run(tmp_path, SLOPE.format(y_end=9.06, ho=ho, r=r, h=h), rocks=20)
    cross = res.crossings
    assert cross["crossed"].all() and len(cross) == 40    # every rock passes both stations
    speeds = cross["velocity_ms"].to_numpy()
    np.testing.assert_allclose(speeds, vt, rtol=1e-6)


RUNOUT = """\
name: Slope onto flat ground
description: a 30 degree slope onto level ground of the same class
slope:
  points: [[0, 60], [80, 13.8], [300, 13.8]]
  materials: [ground, ground]
materials:
  ground: {{impact_model: rough_soft, restitution: 0.3, friction: 0.6,
           rolling_resistance: 0.3, obstacle_height_m: {ho}, drag_speed_ms: 6,
           roughness_deg: 4}}
rocks:
  count: 300
  seed: 1
  volume: {{lognormal: [0.3, 0.8]}}
  release: {{x: [1, 3], height: 1, velocity: [0.5, 0]}}
protect: {{x: 299}}
"""


@pytest.mark.parametrize("seed", [1, 2])
def test_runout_grows_with_size_on_rough_ground_and_not_on_smooth(tmp_path, seed):
    # Measured (with the hop criterion, contact_hop_ratio 0.1): Spearman
    # 0.41 / 0.44 / 0.34 on rough ground (h_o 0.2 m) at seeds 1 / 2 / 3, and
    # -0.07 / -0.02 / -0.10 (p 0.22 / 0.78 / 0.09) on smooth.
    rough = _run(tmp_path, RUNOUT.format(ho=0.2), rocks=300, seed=seed).rocks
    smooth = _run(tmp_path, RUNOUT.format(ho=0.0), rocks=300, seed=seed).rocks
    rho_rough = spearmanr(rough["mass_kg"], rough["end_x_m"])
    rho_smooth = spearmanr(smooth["mass_kg"], smooth["end_x_m"])
    assert rho_rough.statistic > 0.3 and rho_rough.pvalue < 1e-6
    assert abs(rho_smooth.statistic) < 0.2 and rho_smooth.pvalue > 0.01


STEEP = """\
name: Uniform steep slope
description: a uniform soft slope on which a rock slips
slope:
  points: [[0, 400], [400, {y_end}]]
  materials: [ground]
materials:
  ground: {{impact_model: rough_soft, restitution: 0.25, friction: {mu},
           rolling_resistance: {mus}, obstacle_height_m: 0, drag_speed_ms: 6}}
rocks:
  count: 10
  seed: 1
  radius: 0.4
  release: {{x: [1, 2], height: {h}, velocity: [{vx}, {vy}]}}
analysis: {{stations: [300, 390]}}
protect: {{x: 399}}
"""


def _uniform_slope_speeds(tmp_path, deg, mu, mus, h, v0):
    tanb = math.tan(math.radians(deg))
    y_end = 400.0 - 400.0 * tanb
    # From above: released on the ground at v0 along the slope.
    vx, vy = v0 * math.cos(math.radians(deg)), -v0 * math.sin(math.radians(deg))
    text = STEEP.format(y_end=y_end, mu=mu, mus=mus, h=h, vx=f"{vx:.12f}", vy=f"{vy:.12f}")
    cross = _run(tmp_path, text, rocks=10).crossings
    assert cross["crossed"].all() and len(cross) == 20
    return tanb, cross["velocity_ms"].to_numpy()


@pytest.mark.parametrize(("h", "v0"), [(1.0, 0.5), (30.0, 0.5), (0.0, 12.0)])
def test_a_sliding_rock_has_a_terminal_speed_too(tmp_path, h, v0):
    # 40 degrees, friction 0.4 below mu_0 = 0.6: rolling cannot hold at any
    # speed (mu_0 > mu), the spin is held at zero and the rock slides at
    # V_s sqrt((tan beta - mu) / mu_0) = 5.13 m/s, from below (released
    # above the slope) and from above (on the ground at 12 m/s).
    tanb, speeds = _uniform_slope_speeds(tmp_path, 40.0, 0.4, 0.6, h, v0)
    vt = 6.0 * math.sqrt((tanb - 0.4) / 0.6)
    np.testing.assert_allclose(speeds, vt, rtol=1e-6)


@pytest.mark.parametrize(("h", "v0"), [(1.0, 0.5), (30.0, 0.5), (0.0, 14.0)])
def test_a_rock_that_slips_when_slow_rolls_at_its_terminal_speed(tmp_path, h, v0):
    # 45 degrees, friction 0.6, mu_0 0.5: rolling holds only above
    # q* = (2 tan beta - 7 mu + 5 mu_0) / (2 mu_0) = 0.3 (3.29 m/s), so a
    # slow rock slips, then rolls, at V_s sqrt(tan beta / mu_0 - 1) = 6 m/s.
    tanb, speeds = _uniform_slope_speeds(tmp_path, 45.0, 0.6, 0.5, h, v0)
    np.testing.assert_allclose(speeds, 6.0 * math.sqrt(tanb / 0.5 - 1.0), rtol=1e-6)


def _slip_ode(v0, s0, r, sinb, cosb, mu, mus, vs, t):
    """Speed and spin of a slipping rock (sigma > 0, s > 0), integrated numerically."""
    def rhs(_, y):
        return [G * (sinb - mu * cosb) - G * cosb * mus * y[0] ** 2 / vs**2,
                2.5 * G * cosb * (mu - mus) / r]
    sol = solve_ivp(rhs, [0.0, t], [v0, s0], rtol=1e-12, atol=1e-12)
    return sol.y[0, -1], sol.y[1, -1]


@pytest.mark.parametrize(("deg", "v0", "s0"), [(45.0, 1.0, 1.0), (30.0, 9.0, 2.0), (5.0, 6.0, 0.5)])
def test_the_slip_reaches_zero_where_the_equations_say(deg, v0, s0):
    r, mu, mus, vs = 0.4, 0.6, 0.3, 4.0
    sinb, cosb = math.sin(math.radians(deg)), math.cos(math.radians(deg))
    q = v0 * v0 / vs**2
    a, _, dsp, sg, _ = contact.contact_accel(sinb, cosb, v0, s0, mu, mus, r, q)
    assert sg == 1.0
    c = G * cosb * mus / vs**2
    ev, tm, _, v1, s1 = contact.drag_phase(v0, s0, v0 - r * s0, sg, a, dsp, c, vs, 1e4, sinb,
                                           cosb, mu, mus, r)
    assert ev == 2 and tm > 0.0
    v_ode, s_ode = _slip_ode(v0, s0, r, sinb, cosb, mu, mus, vs, tm)
    assert v1 == pytest.approx(v_ode, rel=1e-8)
    # Continuous: the spin the slip ends with is the rolling spin v1 / r.
    assert r * (s0 + dsp * tm) == pytest.approx(v1, rel=1e-12, abs=1e-12)
    assert r * s_ode == pytest.approx(v1, rel=1e-8)


def _phases(deg, v, s, mu, mus, vs, r, n=40):
    """Follow a rock on a long uniform piece with drag, phase by phase."""
    sinb, cosb = math.sin(math.radians(deg)), math.cos(math.radians(deg))
    x, out = 0.0, []
    for _ in range(n):
        a, _, dsp, sg, s_zero = contact.contact_accel(sinb, cosb, v, s, mu, mus, r,
                                                       v * v / vs**2)
        rolling = sg == 0.0
        sigma = 0.0 if (rolling or abs(v - r * s) <= contact.SLIP_TOL) else v - r * s
        if s_zero and not rolling:
            s = 0.0
        c = (5.0 / 7.0 if rolling else 1.0) * G * cosb * mus / vs**2
        ev, tm, ds, v1, s1 = contact.drag_phase(v, s, sigma, sg, a, dsp, c, vs, 200.0 - x,
                                                sinb, cosb, mu, mus, r)
        gap = abs(r * (s + dsp * tm) - v1) if (ev == 2 and not rolling) else 0.0
        out.append((ev, tm, ds, v, s, v1, s1, gap, sinb))
        v, s, x = v1, s1, x + ds
        if ev in (0, 1) or tm == np.inf:
            break
    return out


@settings(max_examples=150, deadline=None)
@given(deg=st.floats(-30.0, 70.0), v=st.floats(0.05, 25.0), w=st.floats(-2.0, 2.0),
       mu=st.floats(0.05, 1.2), mus=st.floats(0.02, 1.0), vs=st.sampled_from([1.0, 3.0, 8.0]))
def test_contact_phases_with_drag_are_never_empty_and_never_gain_energy(deg, v, w, mu, mus, vs):
    r = 0.4
    e0 = None
    x = 0.0
    for ev, tm, ds, v0, s0, v1, s1, gap, sinb in _phases(deg, v, w * v / r, mu, mus, vs, r):
        assert tm > 0.0 or ev == 1                    # no event of zero length
        assert gap <= 1e-9 * (1.0 + v1)              # the slip reaches zero continuously
        if e0 is None:
            e0 = 0.5 * v0 * v0 + 0.2 * r * r * s0 * s0
        x += ds
        e1 = 0.5 * v1 * v1 + 0.2 * r * r * s1 * s1 - G * sinb * x
        assert e1 <= e0 + 1e-9 * (1.0 + abs(e0))
        e0 = e1

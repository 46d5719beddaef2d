"""The closed forms of rolling with a resistance growing as v^2 (engine/drag.py)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rockfall_design.engine import drag


def _ode(a: float, c: float, v0: float, t: float) -> tuple[float, float]:
    """Speed and distance after ``t`` from dv/dt = a - c v^2, integrated numerically."""
    sol = solve_ivp(lambda _, y: [y[1], a - c * y[1] ** 2], [0.0, t], [0.0, v0],
                    rtol=1e-11, atol=1e-12)
    return float(sol.y[1, -1]), float(sol.y[0, -1])


@pytest.mark.parametrize(("a", "c", "v0"), [
    (3.0, 0.1, 1.0),    # accelerating towards the terminal speed from below
    (3.0, 0.1, 9.0),    # braking towards it from above
    (-2.0, 0.1, 5.0),   # braking to a stop
    (0.0, 0.1, 4.0),    # level with no other loss: v0 / (1 + c v0 t)
    (1e-3, 0.05, 2.0),  # nearly level
])
def test_state_speed_and_time_agree_with_the_equation(a, c, v0):
    t = 1.5
    if a < 0.0:
        t = 0.9 * drag.drag_stop(v0, a, c)[0]
    v_ode, s_ode = _ode(a, c, v0, t)
    v, s = drag.drag_state(v0, a, c, t)
    assert v == pytest.approx(v_ode, rel=1e-8, abs=1e-9)
    assert s == pytest.approx(s_ode, rel=1e-8, abs=1e-9)
    v1 = drag.drag_speed_at(v0, a, c, s_ode)
    assert v1 == pytest.approx(v_ode, rel=1e-8, abs=1e-9)
    assert drag.drag_time(v0, v1, a, c, s_ode) == pytest.approx(t, rel=1e-8)
    assert drag.along(v0, a, c, s_ode)[1] == pytest.approx(t, rel=1e-8)


def test_stop_time_and_distance_are_where_the_speed_is_zero():
    a, c, v0 = -2.0, 0.1, 5.0
    ts, ds = drag.drag_stop(v0, a, c)
    v, s = drag.drag_state(v0, a, c, ts)
    assert v == pytest.approx(0.0, abs=1e-12)
    assert s == pytest.approx(ds, rel=1e-12)
    assert drag.drag_speed_at(v0, a, c, 1.01 * ds) < 0.0     # never gets there
    assert drag.drag_stop(v0, 1.0, c) == (np.inf, np.inf)    # never stops


def test_a_long_piece_reaches_the_terminal_speed_in_finite_time():
    # 400 m at a terminal speed of 2.36 m/s: v(s) equals it to round-off, and
    # the time must still be finite and about the distance over that speed.
    a, c, v0, d = 0.47, 0.0843, 8.43, 400.0
    v1 = drag.drag_speed_at(v0, a, c, d)
    t = drag.drag_time(v0, v1, a, c, d)
    assert v1 == pytest.approx(np.sqrt(a / c), rel=1e-12)
    assert np.isfinite(t) and t == pytest.approx(d / np.sqrt(a / c), rel=0.05)


def test_without_growth_along_is_constant_acceleration():
    vs, ts = drag.along(3.0, -1.0, 0.0, 2.0)
    assert vs == pytest.approx(np.sqrt(9.0 - 4.0))
    assert ts == pytest.approx(4.0 / (3.0 + vs))


@pytest.mark.parametrize("c", [1e-12, 1e-9, 1e-6])
@pytest.mark.parametrize(("a", "v0"), [(8.255, 0.5), (8.255, 0.0), (-2.0, 6.0), (1e-3, 2.0)])
def test_a_drag_near_zero_gives_the_constant_acceleration_forms(a, c, v0):
    """A tiny c is a tiny change, not round-off noise (hypothesis found c = 1.3e-12).

    v^2 = a/c + (v0^2 - a/c) exp(-2 c s) cancelled a/c (6e12) and gave a
    speed 2e-5 too high, an energy gained; ln cosh of a tiny angle, formed as
    x + ln(1 + exp(-2x)) - ln 2, lost the distance the same way. With c near
    zero both must be the constant-acceleration forms to within c's own
    effect (a relative change of about c times the distance).
    """
    t = 0.67
    if a < 0.0:
        t = min(t, 0.9 * v0 / -a)
    v_plain, s_plain = v0 + a * t, v0 * t + 0.5 * a * t * t
    tol = 1e-13 + 10.0 * c * (s_plain + v0 * v0 / max(abs(a), 1e-3))
    v, s = drag.drag_state(v0, a, c, t)
    assert v == pytest.approx(v_plain, rel=tol, abs=1e-12)
    assert s == pytest.approx(s_plain, rel=tol, abs=1e-12)
    v1 = drag.drag_speed_at(v0, a, c, s_plain)
    assert v1 == pytest.approx(np.sqrt(v0 * v0 + 2.0 * a * s_plain), rel=tol, abs=1e-12)


@pytest.mark.parametrize("c", [1e-7, 1e-6, 1e-5, 1e-4, 1e-2, 0.1])
@pytest.mark.parametrize("v0", [0.0, 0.5, 3.0])
def test_the_time_to_a_distance_keeps_its_digits_for_a_small_drag(c, v0):
    """drag_time below the terminal speed against the same closed form in long double.

    arccosh(exp(y)) read a small y through 1 + y: 3e-10 of the time lost at
    c = 1e-7 over 2 m. The reckoning here takes arccosh(1 + u) as
    ln(1 + u + sqrt(u (2 + u))) in numpy's long double (x87 extended on x86).
    """
    L = np.longdouble
    a, d = 8.255, 2.0
    aa, cc, vv, dd = L(a), L(c), L(v0), L(d)
    vt = np.sqrt(aa / cc)
    th0 = np.arctanh(vv / vt)
    u = np.expm1(np.log1p(2 * np.sinh(th0 / 2) ** 2) + cc * dd)
    exact = (np.log1p(u + np.sqrt(u * (2 + u))) - th0) / (cc * vt)
    t = drag.drag_time(v0, drag.drag_speed_at(v0, a, c, d), a, c, d)
    assert abs(float((L(t) - exact) / exact)) < 1e-14


def _state_in_long_double(v0: float, a: float, c: float, t: float) -> tuple[float, float]:
    """drag_state's closed form (a > 0) in numpy's long double, by sum-to-product forms."""
    L = np.longdouble
    aa, cc, vv, tt = L(a), L(c), L(v0), L(t)
    vt = np.sqrt(aa / cc)
    kt = cc * vt * tt
    if vv < vt:
        th0 = np.arctanh(vv / vt)
        d = np.log1p(2 * np.sinh(th0 + kt / 2) * np.sinh(kt / 2) / np.cosh(th0)) / cc
        return vt * np.tanh(th0 + kt), d
    th0 = np.arctanh(vt / vv)
    d = np.log1p(2 * np.cosh(th0 + kt / 2) * np.sinh(kt / 2) / np.sinh(th0)) / cc
    return vt / np.tanh(th0 + kt), d


@pytest.mark.parametrize("a", [8.0, 0.5, 1e-3, 1e-6])
@pytest.mark.parametrize("c", [1e-9, 1e-7, 1e-5, 1e-3, 0.1])
@pytest.mark.parametrize("v0", [0.0, 0.5, 3.0, 20.0])
def test_speed_and_distance_after_a_time_keep_their_digits(a, c, v0):
    """drag_state against its own closed form in long double, short and long times.

    The distance was a difference of two logarithms of cosh (sinh above the
    terminal speed): 8e-8 of it lost on nearly level ground.
    """
    for t in (0.01, 0.5, 3.0, 30.0):  # 30 s at c = 0.1, a = 8: th > 20, the far branch
        v, d = drag.drag_state(v0, a, c, t)
        v_ld, d_ld = _state_in_long_double(v0, a, c, t)
        assert abs(float((np.longdouble(d) - d_ld) / d_ld)) < 1e-13, t
        if v_ld > 0:
            assert abs(float((np.longdouble(v) - v_ld) / v_ld)) < 1e-13, t

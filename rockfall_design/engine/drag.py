"""Motion against a drag that grows with the square of the speed: closed forms.

PHYSICS.md, "The `rough_soft` law" and "Rolling and slipping with the
ploughing drag": on a piece, a rock rolling or slipping on soft ground has
dv/dt = a - c v^2 with a (m/s^2) and c (1/m) constant over the piece. Speed
at a distance, time between two speeds, and speed and distance after a time
are all closed forms, and a slipping rock's spin is linear in time, so the
slip's zero is the root of a closed form (:func:`slip_zero_time`): the event
loop keeps jumping from event to event without a time step.
"""

from __future__ import annotations

import numpy as np

from .jit import hot

_LN2 = np.log(2.0)


@hot
def _logcosh(x):
    """ln cosh x without overflow, and to its last digits near 0.

    Near 0, as ln(1 + 2 sinh^2(x / 2)) (cosh x = 1 + 2 sinh^2(x / 2)): the sum
    x + ln(1 + exp(-2x)) - ln 2 forms a value of about x^2 / 2 from terms of
    about 0.7, and lost it to round-off for a tiny angle (a drag near zero).
    """
    ax = abs(x)
    if ax < 0.5:
        sh = np.sinh(0.5 * ax)
        return np.log1p(2.0 * sh * sh)
    return ax + np.log1p(np.exp(-2.0 * ax)) - _LN2


@hot
def _logsinh(x):
    """ln sinh x for x > 0 without overflow (nor, for x near 0, ln 0)."""
    if x < 0.5:  # exp(-2 x) rounds to 1 for a tiny x; sinh itself is exact there
        return np.log(np.sinh(x))
    return x + np.log1p(-np.exp(-2.0 * x)) - _LN2


@hot
def drag_speed_at(v, a, c, d):
    """Speed (m/s) after rolling a distance ``d`` (m), or -1 if the rock stops first.

    Notes
    -----
    From d(v^2)/ds = 2 (a - c v^2): v^2(s) = a/c + (v0^2 - a/c) exp(-2 c s),
    formed as v0^2 exp(-2 c s) - a expm1(-2 c s) / c: the first form cancels
    a/c, which is 6e12 for c = 1.3e-12 (hypothesis found such a drag), and gave
    a speed too high by a relative 2e-5, an energy the rock never had. The
    second tends to v0^2 + 2 a s as c tends to 0, with no cancellation.
    """
    em1 = np.expm1(-2.0 * c * d)
    q = v * v * (1.0 + em1) - a * (em1 / c)
    if q <= 0.0:
        return -1.0
    return np.sqrt(q)


@hot
def _arc_from_log(y, hyper_sin):
    """th with ln sinh th = y (``hyper_sin``) or ln cosh th = y, without overflow."""
    if y > 30.0:
        return y + _LN2
    if hyper_sin:
        return np.arcsinh(np.exp(y))
    # arccosh(1 + u) = ln(1 + u + sqrt(u (2 + u))), u = exp(y) - 1 as expm1: for a
    # small y (a drag near zero) arccosh(exp(y)) read y through 1 + y, and lost
    # a relative 3e-10 of the time at c = 1e-7 (against a long-double reckoning).
    u = np.expm1(y)
    return np.log1p(u + np.sqrt(u * (2.0 + u)))


@hot
def drag_time(v0, v1, a, c, d):
    """Time (s) to roll a distance ``d`` (m) from speed ``v0`` to ``v1`` (m/s).

    Notes
    -----
    With V = sqrt(a/c) and k = c V (a > 0): v(t) = V tanh(th) below V and
    V coth(th) above it, th = k t + th0, and the distance is
    ln(cosh th / cosh th0) / c (ln(sinh th / sinh th0) / c), so th follows
    from d without ever forming v = V (which a long piece reaches to round-off);
    with W = sqrt(-a/c), k = c W (a < 0): v(t) = W tan(th0 - k t), distance
    ln(cos th / cos th0) / c, so t = arctan((v0 - v1) W / (W^2 + v0 v1)) / k
    (the difference of the two angles as one); with a = 0: v = v0 / (1 + c v0 t),
    t = (exp(c d) - 1) / (c v0). Over a short distance the mean speed is
    exact enough and better conditioned.
    """
    if c * d < 1e-7 or abs(v1 - v0) <= 1e-9 * (v0 + v1):
        return 2.0 * d / (v0 + v1) if v0 + v1 > 0.0 else 0.0
    if a > 0.0:
        vt = np.sqrt(a / c)
        k = c * vt
        if v0 < vt:
            th0 = np.arctanh(v0 / vt)
            return (_arc_from_log(_logcosh(th0) + c * d, False) - th0) / k
        th0 = np.arctanh(vt / v0)
        return (_arc_from_log(_logsinh(th0) + c * d, True) - th0) / k
    if a < 0.0:
        # th0 - th = arctan(v0 / W) - arctan(v1 / W), written as one arctan (the
        # difference formula; v0, v1 >= 0): with W far below the speed (a Coulomb
        # friction near zero: hypothesis found mu = 7e-129) both angles round to
        # pi / 2 and their difference, and so the time, came out 0 or negative.
        wt = np.sqrt(-a / c)
        return np.arctan((v0 - v1) * wt / (wt * wt + v0 * v1)) / (c * wt)
    return np.expm1(c * d) / (c * v0)


@hot
def drag_stop(v0, a, c):
    """Time (s) and distance (m) to a stop, (inf, inf) where the rock never stops (a >= 0)."""
    if a >= 0.0:
        return np.inf, np.inf
    wt = np.sqrt(-a / c)
    return np.arctan(v0 / wt) / (c * wt), np.log1p(c * v0 * v0 / -a) / (2.0 * c)


@hot
def drag_state(v0, a, c, t):
    """Speed (m/s) and distance (m) after rolling for a time ``t`` (s)."""
    if a > 0.0:
        vt = np.sqrt(a / c)
        k = c * vt
        # The distance ln(cosh th / cosh th0) / c (ln(sinh th / sinh th0) / c above
        # V) as ln(1 + 2 sinh(th0 + kt/2) sinh(kt/2) / cosh th0) (cosh(...) and
        # sinh th0 above V): the sum-to-product form, with th - th0 = kt never
        # formed by a subtraction. The difference of two logarithms lost a
        # relative 8e-8 of the distance on nearly level ground (a = 1e-6,
        # c = 1e-7, 0.01 s; against a long-double reckoning). Far out (th > 20,
        # the terminal speed reached) the difference is large and exact enough,
        # and sinh and cosh would overflow.
        kt = k * t
        if v0 < vt:
            th0 = np.arctanh(v0 / vt)
            th = th0 + kt
            if th < 20.0:
                d = np.log1p(2.0 * np.sinh(th0 + 0.5 * kt) * np.sinh(0.5 * kt) / np.cosh(th0))
            else:
                d = _logcosh(th) - _logcosh(th0)
            return vt * np.tanh(th), d / c
        if v0 > vt:
            th0 = np.arctanh(vt / v0)
            th = th0 + kt
            if th < 20.0:
                d = np.log1p(2.0 * np.cosh(th0 + 0.5 * kt) * np.sinh(0.5 * kt) / np.sinh(th0))
            else:
                d = _logsinh(th) - _logsinh(th0)
            return vt / np.tanh(th), d / c
        return vt, vt * t
    if a < 0.0:
        # v = W tan(th0 - k t) and cos(th0 - k t) / cos th0 by the sum formulas
        # (tan th0 = v0 / W): no angle near pi / 2 is formed, which lost v0
        # where W is far below it (both tend to the a = 0 forms below).
        t_stop, d_stop = drag_stop(v0, a, c)
        if t >= t_stop:  # at rest by then
            return 0.0, d_stop
        wt = np.sqrt(-a / c)
        kt = c * wt * t
        tk = np.tan(kt)
        v = wt * (v0 - wt * tk) / (wt + v0 * tk)
        half = np.sin(0.5 * kt)
        return max(v, 0.0), np.log1p(v0 * np.sin(kt) / wt - 2.0 * half * half) / c
    return v0 / (1.0 + c * v0 * t), np.log1p(c * v0 * t) / c


@hot
def along(v, a, c, d):
    """Speed (m/s) and time (s) of a rock in contact when it has moved ``d`` (m).

    With ``c`` = 0 the constant-acceleration forms of PHYSICS.md
    (v_d^2 = v^2 + 2 a d, t = 2 d / (v + v_d)); otherwise those of
    :func:`drag_speed_at` and :func:`drag_time`.
    """
    if c > 0.0:
        vs = drag_speed_at(v, a, c, d)
        if vs < 0.0:
            vs = 0.0
        return vs, drag_time(v, vs, a, c, d)
    q = v * v + 2.0 * a * d
    vs = np.sqrt(q) if q > 0.0 else 0.0
    ts = 2.0 * d / (v + vs) if v + vs > 0.0 else 0.0
    return vs, ts


@hot
def _slip_at(v0, sig0, a, c, rds, t):
    """Slip sigma (m/s) and its rate (m/s^2) a time ``t`` (s) into a phase.

    The speed follows dv/dt = a - c v^2 (:func:`drag_state`) and the spin's
    part r s of the slip falls linearly, at ``rds`` = r ds/dt (m/s^2), so
    sigma(t) = v(t) - (v0 - sig0) - rds t.
    """
    v = drag_state(v0, a, c, t)[0]
    return v - (v0 - sig0) - rds * t, a - c * v * v - rds


@hot
def _slip_root(v0, sig0, sg, a, c, rds, lo, hi):
    """The zero of the slip in [lo, hi] (s), where sg * sigma goes from > 0 to <= 0.

    Newton's step where it stays inside the bracket and halves it at least as
    fast as bisection would, bisection otherwise (the safeguarded Newton of
    Press et al. 2007, section 9.4): the bracket always holds the root, so it
    converges whatever the start, to the resolution of a double.
    """
    t = 0.5 * (lo + hi)
    dx_old = hi - lo
    dx = dx_old
    f, df = _slip_at(v0, sig0, a, c, rds, t)
    f *= sg
    df *= sg
    for _ in range(200):
        if f == 0.0:
            return t
        if f > 0.0:
            lo = t
        else:
            hi = t
        if hi - lo <= 4.0 * np.finfo(np.float64).eps * hi:
            return hi
        tn = t - f / df if df != 0.0 else lo - 1.0
        if lo < tn < hi and abs(2.0 * f) <= abs(dx_old * df):
            dx_old = dx
            dx = t - tn
        else:
            dx_old = dx
            dx = 0.5 * (hi - lo)
            tn = lo + dx
        if tn == t:
            return t
        t = tn
        f, df = _slip_at(v0, sig0, a, c, rds, t)
        f *= sg
        df *= sg
    return hi


@hot
def slip_zero_time(v0, sig0, sg, a, c, rds, t_max):
    """First time (s) in (0, ``t_max``] at which a slipping rock's slip reaches zero.

    Parameters
    ----------
    v0 : float
        Speed at the start of the phase (m/s).
    sig0 : float
        Slip sigma = v - r s at the start (m/s); 0 if it has just left zero.
    sg : float
        Sense of the slip in this phase (+1 or -1).
    a, c : float
        dv/dt = a - c v^2 (m/s^2, 1/m), c > 0.
    rds : float
        r ds/dt, the rate of the spin's part of the slip (m/s^2), constant.
    t_max : float
        End of the search (s): the phase's first other event, finite.

    Returns
    -------
    float
        The time of the zero, or inf if the slip keeps its sense up to
        ``t_max``.

    Notes
    -----
    d(sigma)/dt = a - c v^2 - rds changes sign at most once, where
    v^2 = (a - rds) / c, since v(t) is monotone (towards sqrt(a / c), or to
    a stop). Split there, sigma is monotone on each part, so a change of its
    sign on a part brackets exactly one zero, which :func:`_slip_root` finds.
    A slip that starts at zero (``sig0`` = 0) leaves it in the sense ``sg``
    on the first part: only a return on the second part is a zero, so no
    phase ends at its own start.
    """
    if not (t_max > 0.0 and t_max < np.inf):
        return np.inf
    split = t_max
    q = (a - rds) / c
    if q > 0.0:
        vm = np.sqrt(q)
        v1 = drag_state(v0, a, c, t_max)[0]
        if (v0 - vm) * (v1 - vm) < 0.0:
            # The rate changes sign inside: split at the speed vm.
            d = np.log((v0 * v0 - a / c) / (q - a / c)) / (2.0 * c)
            split = min(max(drag_time(v0, vm, a, c, d), 0.0), t_max)
    ta = 0.0
    fa = sg * sig0
    for part in range(2):
        tb = split if part == 0 else t_max
        if tb > ta:
            fb = sg * _slip_at(v0, sig0, a, c, rds, tb)[0]
            if fa > 0.0 and fb <= 0.0:
                return _slip_root(v0, sig0, sg, a, c, rds, ta, tb)
            fa = fb
            ta = tb
    return np.inf

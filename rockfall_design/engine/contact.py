"""Motion in contact: rolling, sliding and both at once on one piece (PHYSICS.md).

With the rough_soft law's ploughing drag the phase is :func:`drag_phase`, in
closed form like the phases of constant acceleration (:func:`constant_phase`).
"""

from __future__ import annotations

import numpy as np

from .columns import G
from .drag import drag_speed_at, drag_state, drag_stop, drag_time, slip_zero_time
from .flight import unit_tangent
from .jit import hot

SLIP_TOL = 1e-9
"""Slip sigma = v - r s (m/s), or spin r s (m/s), within which it counts as zero."""


@hot
def contact_accel(sinb, cosb, v, s, mu, mur, r, q=0.0):
    """Accelerations of a rock in contact, moving along a piece.

    Parameters
    ----------
    sinb, cosb : float
        Sine and cosine of the piece angle, beta > 0 where the motion goes downhill.
    v : float
        Speed along the piece (m/s), >= 0.
    s : float
        Spin (rad/s) in the rolling sense: rolling without slip is v = r s.
    mu, mur : float
        Friction and rolling-resistance coefficients (-).
    r : float
        Radius (m).
    q : float
        (v / V_s)^2 of the rough_soft law's ploughing drag, which takes
        mu_r q N from the translation (PHYSICS.md, "The rough_soft law"); 0
        for none. The drag widens the range of slopes rolling holds on.

    Returns
    -------
    a : float
        dv/dt (m/s^2).
    dsig : float
        d(sigma)/dt (m/s^2) of the slip sigma = v - r s; 0 while rolling.
    ds : float
        ds/dt (rad/s^2); nan while the rock rolls without slip (then s = v / r).
    sig_sign : float
        Sense of the slip this phase has (+1 or -1; 0 while rolling). A slip
        within ``SLIP_TOL`` of zero is zero, and this is the sense it starts in.
    s_zero : bool
        True if the spin counts as zero at the start of the phase.

    Notes
    -----
    PHYSICS.md, "Motion in contact". Rolling without slip holds while
    -(7 mu + 5 mu_r) / 2 <= tan beta <= (7 mu - 5 mu_r) / 2, with
    a = 5/7 g (sin beta - mu_r cos beta). With slip, the rolling-resistance
    moment mu_r N r still opposes the spin:

        dv/dt   = g (sin beta - mu cos beta sgn sigma),
        r ds/dt = 5/2 g cos beta (mu sgn sigma - mu_r sgn s),
        d(sigma)/dt = g cos beta (tan beta - 7/2 mu sgn sigma + 5/2 mu_r sgn s).

    A slip within tolerance of zero on a piece that cannot hold rolling
    starts in the sense d(sigma)/dt gives: above the upper limit the rate with
    sgn sigma = +1 is positive, below the lower one the rate with -1 is
    negative, so the slip leaves zero at once and no event of zero length
    follows. A spin of zero is held by the resistance moment while
    mu sgn(sigma) <= mu_r; otherwise friction turns it in the sense of sgn sigma.

    With the rough_soft law's drag (q > 0) the returned a and d(sigma)/dt are
    the parts without it (the caller adds -c v^2), and the bounds of rolling
    are those of :func:`_rolls_with_drag`.
    """
    sigma = v - r * s
    if abs(sigma) <= SLIP_TOL:
        sg = _rolls_with_drag(sinb, cosb, mu, mur, q) if q > 0.0 else _rolls(sinb, cosb, mu, mur)
        if sg == 0.0:
            return 5.0 / 7.0 * G * (sinb - mur * cosb), 0.0, np.nan, 0.0, False
    elif sigma > 0.0:
        sg = 1.0
    else:
        sg = -1.0
    s_zero = abs(r * s) <= SLIP_TOL
    if s_zero:
        if mu * sg <= mur:
            # The resistance moment holds the spin at zero (PHYSICS.md).
            ss = 0.0
        else:
            ss = sg
    else:
        ss = 1.0 if s > 0.0 else -1.0
    a = G * (sinb - mu * cosb * sg)
    rds = 0.0 if (s_zero and ss == 0.0) else 2.5 * G * cosb * (mu * sg - mur * ss)
    return a, a - rds, rds / r, sg, s_zero


@hot
def _first_event(t_end, t_zero, t_slip, t_other):
    """The first of four event times (s), and its number (0 to 3); ties go to the lower."""
    ev = 0
    tm = t_end
    if t_zero < tm:
        ev = 1
        tm = t_zero
    if t_slip < tm:
        ev = 2
        tm = t_slip
    if t_other < tm:
        ev = 3
        tm = t_other
    return ev, tm


@hot
def _rolls(sinb, cosb, mu, mur):
    """0 if a rock without slip rolls on, else the sense (+1, -1) its slip takes.

    Both bounds of rolling (PHYSICS.md, "Rolling without slip"), times
    2 cos beta (cos beta > 0 on every piece): spin ahead of speed below the
    lower, behind it above the upper.
    """
    lo = -(7.0 * mu + 5.0 * mur) * cosb
    hi = (7.0 * mu - 5.0 * mur) * cosb
    if lo <= 2.0 * sinb <= hi:
        return 0.0
    return 1.0 if 2.0 * sinb > hi else -1.0


@hot
def constant_phase(v, s, sigma, rolling, a, dsig, dsp, dist, r):
    """The next event of a contact phase with constant accelerations.

    Parameters
    ----------
    v, s, sigma : float
        Speed (m/s), spin (rad/s, rolling sense) and slip (m/s) at the start.
    rolling : bool
        True while the rock rolls without slip.
    a, dsig, dsp : float
        dv/dt, d(sigma)/dt (m/s^2) and ds/dt (rad/s^2), of :func:`contact_accel`.
    dist : float
        Distance to the end of the piece (m).
    r : float
        Radius (m).

    Returns
    -------
    ev : int
        0 end of the piece, 1 speed zero, 2 slip zero, 3 spin zero.
    tm, ds, v1, s1 : float
        Duration (s), distance (m), speed (m/s) and spin (rad/s) at the event;
        ``tm`` is inf if no event ever comes (a rock at rest, held).
    """
    t_end = np.inf
    if dist <= 0.0:
        t_end = 0.0
    elif a == 0.0:
        if v > 0.0:
            t_end = dist / v
    else:
        disc = v * v + 2.0 * a * dist
        if disc >= 0.0 and v + np.sqrt(disc) > 0.0:
            t_end = 2.0 * dist / (v + np.sqrt(disc))
    t_zero = v / -a if a < 0.0 else np.inf
    t_slip = -sigma / dsig if (not rolling and sigma * dsig < 0.0) else np.inf
    t_spin = -s / dsp if (not rolling and s * dsp < 0.0) else np.inf
    ev, tm = _first_event(t_end, t_zero, t_slip, t_spin)
    if tm == np.inf:
        return ev, tm, 0.0, 0.0, 0.0
    ds = v * tm + 0.5 * a * tm * tm
    if ds < 0.0:
        ds = 0.0
    if ds > dist:
        ds = dist
    v1 = v + a * tm
    if v1 < 0.0 or ev == 1:
        v1 = 0.0
    if rolling or ev == 2:
        s1 = v1 / r
    elif ev == 3:
        s1 = 0.0
    else:
        s1 = s + dsp * tm
    return ev, tm, ds, v1, s1


@hot
def _rolls_with_drag(sinb, cosb, mu, mur, q):
    """0 if a rock without slip rolls on, else the sense (+1, -1) its slip takes.

    Notes
    -----
    With the drag mu_r q N on the translation (PHYSICS.md, "Rolling with the
    ploughing drag") rolling needs the friction F / m = g cos beta
    (2/7 tan beta + 5/7 mu_r - 2/7 mu_r q), within mu g cos beta:

        -(7 mu + 5 mu_r - 2 mu_r q) <= 2 tan beta <= 7 mu - 5 mu_r + 2 mu_r q.

    Both bounds move with q. At a bound (within a relative 1e-9, where the
    phase before ended on it) the rock rolls on only if q moves it inside:
    the upper bound tightens as the rock slows, the lower one as it speeds
    up, so a rock exactly at a bound and moving out of it slips at once and
    no phase of zero length follows.
    """
    hi = (7.0 * mu - 5.0 * mur + 2.0 * mur * q) * cosb
    lo = -(7.0 * mu + 5.0 * mur - 2.0 * mur * q) * cosb
    tol = 1e-9 * (7.0 * mu + 5.0 * mur + 2.0 * mur * q) * cosb
    # Rolling's acceleration at this speed: q falls where it is negative.
    slowing = sinb - mur * cosb * (1.0 + q) < 0.0
    if 2.0 * sinb > hi - (tol if slowing else -tol):
        return 1.0
    if 2.0 * sinb < lo + (tol if not slowing else -tol):
        return -1.0
    return 0.0


@hot
def drag_phase(v, s, sigma, sg, a, dsp, c, vdr, dist, sinb, cosb, mu, mur, r):
    """The next event of a contact phase with the ploughing drag, in closed form.

    Parameters
    ----------
    v, s, sigma : float
        Speed (m/s), spin (rad/s, rolling sense) and slip (m/s) at the start.
    sg : float
        Sense of the slip (+1, -1), 0 while the rock rolls.
    a : float
        The constant part of dv/dt (m/s^2): 5/7 g (sin beta - mu_r cos beta)
        rolling, g (sin beta - mu cos beta sg) slipping.
    dsp : float
        ds/dt (rad/s^2) while slipping (the drag takes no spin); unused rolling.
    c : float
        dv/dt = a - c v^2 (1/m), c > 0.
    vdr : float
        V_s (m/s).
    dist : float
        Distance to the end of the piece (m).
    sinb, cosb, mu, mur, r : float
        As :func:`contact_accel`.

    Returns
    -------
    ev : int
        0 end of the piece, 1 speed zero, 2 slip zero (the rock rolls on),
        3 spin zero, 5 a rolling rock reaches a bound of rolling and slips.
    tm, ds, v1, s1 : float
        Duration (s), distance (m), speed (m/s) and spin (rad/s) at the event;
        ``tm`` is inf if no event ever comes (a rock at rest, held).

    Notes
    -----
    PHYSICS.md, "Rolling and slipping with the ploughing drag". Speed and
    distance are the closed forms of dv/dt = a - c v^2 (``drag.py``); the spin
    of a slipping rock is linear in t, so the slip's zero is the root of a
    closed form, bracketed (:func:`.drag.slip_zero_time`); the bound of
    rolling is reached at a speed in closed form.
    """
    rolling = sg == 0.0
    t_end = 0.0
    v_end = drag_speed_at(v, a, c, dist)
    if dist > 0.0:
        t_end = drag_time(v, v_end, a, c, dist) if v_end >= 0.0 else np.inf
    t_zero, d_zero = drag_stop(v, a, c)
    t_other = np.inf
    v_lim = -1.0
    if rolling:
        v_lim = _rolling_bound_speed(v, a, c, vdr, sinb, cosb, mu, mur)
        if v_lim >= 0.0:
            d = np.log((v * v - a / c) / (v_lim * v_lim - a / c)) / (2.0 * c)
            t_other = drag_time(v, v_lim, a, c, d)
    elif s * dsp < 0.0:
        t_other = -s / dsp
    t_first = min(t_end, t_zero, t_other)
    t_slip = np.inf
    if not rolling:
        t_slip = slip_zero_time(v, sigma, sg, a, c, r * dsp, t_first)
    ev, tm = _first_event(t_end, t_zero, t_slip, t_other)
    if ev == 3 and rolling:
        ev = 5
    if ev == 0:
        ds, v1 = dist, max(v_end, 0.0)
    elif ev == 1:
        ds, v1 = min(d_zero, dist), 0.0
    elif ev == 5:
        v1 = v_lim
        ds = min(np.log((v * v - a / c) / (v1 * v1 - a / c)) / (2.0 * c), dist)
    else:
        v1, ds = drag_state(v, a, c, tm)
        ds = min(ds, dist)
    # Rolling on, or just rolling: the spin of rolling; else as it ran.
    s1 = v1 / r if (rolling or ev == 2 or ev == 5) else (0.0 if ev == 3 else s + dsp * tm)
    return ev, tm, ds, v1, s1


@hot
def _rolling_bound_speed(v, a, c, vdr, sinb, cosb, mu, mur):
    """Speed (m/s) at which a rolling rock reaches a bound of rolling, or -1 if never.

    The bounds of :func:`_rolls_with_drag` are reached where q = (v / V_s)^2
    is q_hi = (2 tan beta - 7 mu + 5 mu_r) / (2 mu_r) (the upper, while the
    rock slows) or q_lo = (2 tan beta + 7 mu + 5 mu_r) / (2 mu_r) (the lower,
    while it speeds up), if that speed lies between v and where the rock
    tends to (its terminal speed sqrt(a / c), or 0).
    """
    tanb = sinb / cosb
    v_inf = np.sqrt(a / c) if a > 0.0 else 0.0
    if v > v_inf:
        qb = (2.0 * tanb - 7.0 * mu + 5.0 * mur) / (2.0 * mur)
    else:
        qb = (2.0 * tanb + 7.0 * mu + 5.0 * mur) / (2.0 * mur)
    if qb <= 0.0:
        return -1.0
    vb = vdr * np.sqrt(qb)
    if min(v, v_inf) < vb < max(v, v_inf):
        return vb
    return -1.0


@hot
def start_from_rest(px, py, k, x, y, w, r, mu, mur):
    """Choose piece and direction for a rock at (almost) zero speed.

    Returns (k, dirn) with dirn = +1 or -1 for the direction in which the
    rock accelerates, or dirn = 0 if the ground holds it in both directions.
    On a vertex the piece ahead in each direction is used, so a rock at the
    bottom of a V is held and one on a crest rolls off the steeper side.
    """
    npc = px.shape[0] - 1
    scale = 1e-9 * max(1.0, abs(x))
    kp = k
    if abs(x - px[k + 1]) <= scale and k + 1 < npc:
        kp = k + 1
    km = k
    if abs(x - px[k]) <= scale and k > 0:
        km = k - 1
    best_a = 1e-9
    best_k = k
    best_d = 0
    for dirn in (1, -1):
        kk = kp if dirn > 0 else km
        tx, ty = unit_tangent(px, py, kk)
        sinb = -dirn * ty
        cosb = tx
        s = -w * dirn
        a = contact_accel(sinb, cosb, 0.0, s, mu, mur, r)[0]
        if a > best_a:
            best_a = a
            best_k = kk
            best_d = dirn
    return best_k, best_d

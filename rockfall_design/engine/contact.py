"""Motion in contact: rolling, sliding and both at once on one piece (PHYSICS.md)."""

from __future__ import annotations

import numpy as np

from .columns import G
from .flight import unit_tangent
from .jit import hot

SLIP_TOL = 1e-9
"""Slip sigma = v - r s (m/s), or spin r s (m/s), within which it counts as zero."""


@hot
def contact_accel(sinb, cosb, v, s, mu, mur, r):
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
    """
    sigma = v - r * s
    if abs(sigma) <= SLIP_TOL:
        # Both bounds, times 2 cos beta (cos beta > 0 on every piece).
        lo = -(7.0 * mu + 5.0 * mur) * cosb
        hi = (7.0 * mu - 5.0 * mur) * cosb
        if lo <= 2.0 * sinb <= hi:
            return 5.0 / 7.0 * G * (sinb - mur * cosb), 0.0, np.nan, 0.0, False
        # Spin ahead of speed below the lower limit, behind it above the upper.
        sg = 1.0 if 2.0 * sinb > hi else -1.0
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

"""Event-to-event motion of a rigid sphere on the centre path (PHYSICS.md).

The rock is in one of two modes:

* FLIGHT: a parabola, solved exactly for the next contact with the centre
  path (one quadratic per piece walked);
* CONTACT: rolling, sliding, or rolling with sliding on one straight piece
  of the centre path, with constant accelerations between events (end of the
  piece, speed reaching zero, slip reaching zero, spin reaching zero), all
  closed forms. Rolling resistance opposes the spin whether or not the
  contact slips, and no event ever has zero length (see ``_contact_accel``).

Impacts apply Newton restitution with Coulomb friction and spin (``spang``) or
the lumped-mass law (``rn_rt``). There is no time step anywhere.

All functions are compiled with numba and take plain arrays. Sign conventions:
x downslope, y up, angular velocity ``w`` counter-clockwise positive; a rock
rolling towards +x without slip has ``w = -v / r``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._jit import CACHE
from .rng import next_normal, next_uniform, truncated_normal

G = 9.81
"""Acceleration of gravity (m/s^2)."""

# Columns of the material table (one row per material).
M_MODEL = 0  #: impact model: 0 = spang, 1 = rn_rt
M_E = 1  #: e (spang) or Rn (rn_rt), mean
M_RT = 2  #: Rt (rn_rt)
M_MU = 3  #: Coulomb friction coefficient mu, mean
M_MUR = 4  #: rolling-resistance coefficient mu_r, mean
M_VSCALE = 5  #: 1 = Pfeiffer & Bowen velocity scaling of the normal restitution
M_VSK = 6  #: K of the velocity scaling (m/s)
M_ROUGH = 7  #: standard deviation of the tilt of the impact normal (rad)
M_SD_E = 8  #: standard deviation of e / Rn
M_SD_MU = 9  #: standard deviation of mu
M_SD_MUR = 10  #: standard deviation of mu_r
M_ROUGH_H = 11  #: roughness height h_r (m): one-sided tilt up to atan(h_r / r)
N_MAT_COLS = 12

MODEL_SPANG = 0
MODEL_RN_RT = 1

# Columns of the settings vector.
S_V_CONTACT = 0  #: outgoing normal speed below which the rock stays in contact (m/s)
S_V_STOP = 1  #: speed below which a rock that can be held is stopped (m/s)
S_MAX_EVENTS = 2  #: event limit per rock
N_SETTINGS = 3

# How a path ends.
RUNNING = 0
STOPPED = 1
EXIT_UPSLOPE = 2  #: left the section at its upslope end (x < x_first)
EXIT_DOWNSLOPE = 3  #: left the section at its downslope end (x > x_last)
UNRESOLVED = 4  #: reached the event limit
CAUGHT = 5  #: stopped by a barrier (fence net, block of a boulder row)
STATUS_NAMES = ("running", "stopped", "exit_upslope", "exit_downslope", "unresolved", "caught")

# Barrier behaviours (see rockfall_design.measures.BarrierBehaviour).
B_NET = 0
B_RIGID = 1
B_BLOCKS = 2

# Columns of the barrier table (one row per barrier, sorted by x).
BR_X = 0  #: station (m)
BR_YG = 1  #: ground height at the station (m)
BR_H = 2  #: height of the top above ground (m)
BR_CAP = 3  #: energy capacity (J)
BR_BEH = 4  #: behaviour code
BR_E = 5  #: restitution of a rigid barrier
BR_GAP = 6  #: clear gap between blocks (m)
BR_SPACING = 7  #: block spacing (m)
N_BARRIER_COLS = 8

# Outcome of a rock's first meeting with a barrier (rockfall_design.measures.Outcome).
O_NOT_MET = 0
O_CAUGHT = 1
O_PASSED_OVER = 2
O_BROKEN_THROUGH = 3
O_REBOUNDED = 4
O_PASSED_THROUGH_GAP = 5

# Columns of a rock's state at the first downslope passage of a restart station,
# enough to resume the path there exactly as it would have gone on (with the
# rock's random stream, saved apart as uint64).
RS_MODE, RS_X, RS_Y, RS_VX, RS_VY, RS_W, RS_T = 0, 1, 2, 3, 4, 5, 6
RS_SEG, RS_E, RS_MU, RS_MUR, RS_NIMP, RS_NEV, RS_MAXX = 7, 8, 9, 10, 11, 12, 13
N_RESTART_COLS = 14

# Columns of the record of a rock's first meeting with a barrier.
BM_H, BM_V, BM_E, BM_T = 0, 1, 2, 3
N_BMEET_COLS = 4

FLIGHT = 0
CONTACT = 1

# Columns of a recorded trajectory point.
T_X, T_Y, T_VX, T_VY, T_W, T_T, T_MODE = 0, 1, 2, 3, 4, 5, 6
N_TRAJ_COLS = 7

# Columns of the per-station detail record.
C_H, C_VX, C_VY, C_W, C_T = 0, 1, 2, 3, 4
N_CROSS_COLS = 5


@njit(cache=CACHE)
def locate(px: np.ndarray, x: float, vx: float) -> int:
    """Index of the centre-path piece under ``x``, on the side ``vx`` moves to."""
    npc = px.shape[0] - 1
    k = np.searchsorted(px, x, side="right") - 1
    if k < 0:
        k = 0
    if k > npc - 1:
        k = npc - 1
    # On a vertex, the piece ahead in the direction of travel.
    if vx < 0.0 and k > 0 and x <= px[k]:
        k -= 1
    return k


@njit(cache=CACHE)
def path_height(px: np.ndarray, py: np.ndarray, k: int, x: float) -> float:
    """Height (m) of piece ``k`` of the centre path at ``x``."""
    return py[k] + (py[k + 1] - py[k]) * (x - px[k]) / (px[k + 1] - px[k])


@njit(cache=CACHE)
def next_landing(px, py, x0, y0, vx, vy, k):
    """Time and piece of the next contact of a free flight with the centre path.

    Parameters
    ----------
    px, py : ndarray
        Centre path vertices (m).
    x0, y0 : float
        Start of the flight (m); on or above the path.
    vx, vy : float
        Initial velocity (m/s).
    k : int
        Piece under ``x0`` on the side of travel (see :func:`locate`).

    Returns
    -------
    leaves : bool
        True if the rock leaves the section before landing.
    t : float
        Flight time (s) to the landing, or to the section end if ``leaves``.
    k : int
        Piece landed on (or the last one walked).

    Notes
    -----
    On a piece with slope ``c`` the height of the centre above it is the
    concave quadratic h(t) = C + B t - g t^2 / 2, C = y0 - Y(x0),
    B = vy - c vx. The flight is above the piece at both ends of its time
    window [t_in, t_out] exactly when no landing lies within it (a concave
    function is above the smaller of its end values), so the walk tests only
    h(t_out) and, on the piece where it is <= 0, takes the descending root
    t = (B + sqrt(B^2 + 2 g C)) / g, written without cancellation.
    """
    npc = px.shape[0] - 1
    t_in = 0.0
    while True:
        c = (py[k + 1] - py[k]) / (px[k + 1] - px[k])
        if vx > 0.0:
            t_out = (px[k + 1] - x0) / vx
        elif vx < 0.0:
            t_out = (px[k] - x0) / vx
        else:
            t_out = np.inf
        cc = y0 - (py[k] + c * (x0 - px[k]))
        bb = vy - c * vx
        if t_out < np.inf:
            h_out = cc + t_out * (bb - 0.5 * G * t_out)
            if h_out > 0.0:
                k = k + 1 if vx > 0.0 else k - 1
                if k < 0 or k >= npc:
                    return True, t_out, k
                t_in = t_out
                continue
        disc = bb * bb + 2.0 * G * cc
        sq = np.sqrt(disc) if disc > 0.0 else 0.0
        if bb >= 0.0:
            t = (bb + sq) / G
        elif sq - bb > 0.0:
            t = 2.0 * cc / (sq - bb)
        else:
            t = 0.0
        if t < t_in:
            t = t_in
        if t > t_out:
            t = t_out
        return False, t, k


@njit(cache=CACHE)
def impact(vx, vy, w, nx, ny, r, model, e, rt, mu, vscale, vsk, rough, rng, tilt_max=0.0):
    """Velocity and spin after an impact on ground of outward normal (nx, ny).

    Parameters
    ----------
    vx, vy : float
        Velocity before the impact (m/s).
    w : float
        Angular velocity before (rad/s), counter-clockwise positive.
    nx, ny : float
        Unit outward normal of the ground (centre path piece).
    r : float
        Rock radius (m).
    model : int
        ``MODEL_SPANG`` or ``MODEL_RN_RT``.
    e : float
        Coefficient of restitution e (spang) or Rn (rn_rt), this impact's draw.
    rt : float
        Tangential restitution Rt (rn_rt only).
    mu : float
        Coulomb friction coefficient, this impact's draw.
    vscale : bool
        Apply the Pfeiffer & Bowen (1989) scaling e / (1 + (|v_n| / K)^2).
    vsk : float
        K of that scaling (m/s), 9.144 m/s in CRSP.
    rough : float
        Standard deviation of the tilt of the impact normal (rad).
    rng : ndarray of uint64, shape (1,)
        The rock's random stream (for the tilt).
    tilt_max : float
        Largest one-sided tilt of the normal (rad), atan(h_r / r) for a
        roughness height h_r; 0 for none.

    Returns
    -------
    vx, vy, w : float
        Velocity (m/s) and angular velocity (rad/s) after the impact.

    Notes
    -----
    With v_n = v.n < 0, v_t = v.t, slip u = v_t + r w, normal impulse per
    unit mass p_n = (1 + e)|v_n| (Spang & Rautenstrauch 1988; PHYSICS.md):

    * spang, stick (|u| <= 7/2 mu p_n): v_t' = (5 v_t - 2 r w) / 7,
      w' = -v_t' / r;
    * spang, slip: v_t' = v_t - mu p_n sgn(u), w' = w - 5/2 mu p_n sgn(u) / r;
    * rn_rt: v_n' = -Rn v_n, v_t' = Rt v_t and w' = Rt w (PHYSICS.md,
      "Lumped-mass law"): the spin scales with the tangential speed, so a
      rolling rock stays rolling and no energy is gained.

    A tilted normal that would make the rock arrive from below is drawn again
    (at most 64 times, then the untilted normal is used).

    Roughness as a height (PlatRock's convention, PHYSICS.md "Options"): the
    normal also turns by an angle drawn uniformly from [0, ``tilt_max``],
    always against the tangential velocity, as if the rock met the face of an
    asperity of height h_r turned towards it; larger rocks (larger r) feel a
    smaller tilt. Turning against the motion makes the arrival steeper, so it
    never makes the rock arrive from below.
    """
    mx = nx
    my = ny
    # One-sided tilt: counter-clockwise turns the normal towards -t, against
    # a rock moving along +t (t = (n_y, -n_x)).
    th_h = 0.0
    if tilt_max > 0.0:
        vt0 = vx * ny - vy * nx
        if vt0 != 0.0:
            th_h = tilt_max * next_uniform(rng) * (1.0 if vt0 > 0.0 else -1.0)
            c = np.cos(th_h)
            s = np.sin(th_h)
            mx = c * nx - s * ny
            my = s * nx + c * ny
    if rough > 0.0:
        for _ in range(64):
            th = th_h + rough * next_normal(rng)
            c = np.cos(th)
            s = np.sin(th)
            ax = c * nx - s * ny
            ay = s * nx + c * ny
            if vx * ax + vy * ay < 0.0:
                mx = ax
                my = ay
                break
    tx = my
    ty = -mx
    vn = vx * mx + vy * my
    vt = vx * tx + vy * ty
    if vn >= 0.0:
        return vx, vy, w
    ee = e
    if vscale:
        q = vn / vsk
        ee = e / (1.0 + q * q)
    vn2 = -ee * vn
    if model == MODEL_SPANG:
        pn = -(1.0 + ee) * vn
        u = vt + r * w
        if abs(u) <= 3.5 * mu * pn:
            vt2 = (5.0 * vt - 2.0 * r * w) / 7.0
            w2 = -vt2 / r
        else:
            sg = 1.0 if u > 0.0 else -1.0
            vt2 = vt - mu * pn * sg
            w2 = w - 2.5 * mu * pn * sg / r
    else:
        vt2 = rt * vt
        w2 = rt * w
    return vn2 * mx + vt2 * tx, vn2 * my + vt2 * ty, w2


@njit(cache=CACHE)
def _draw(mats, mat, rng, drawn):
    """Draw this contact's e, mu and mu_r for material ``mat`` into ``drawn``."""
    drawn[0] = truncated_normal(rng, mats[mat, M_E], mats[mat, M_SD_E], 0.0, 1.0)
    drawn[1] = truncated_normal(rng, mats[mat, M_MU], mats[mat, M_SD_MU], 0.0, np.inf)
    drawn[2] = truncated_normal(rng, mats[mat, M_MUR], mats[mat, M_SD_MUR], 0.0, np.inf)


@njit(cache=CACHE)
def _unit_tangent(px, py, k):
    dx = px[k + 1] - px[k]
    dy = py[k + 1] - py[k]
    ln = np.hypot(dx, dy)
    return dx / ln, dy / ln


@njit(cache=CACHE)
def _collide(vx, vy, w, k, px, py, pseg, seg_mat, mats, r, v_contact, rng, drawn):
    """Impact on piece ``k``, then decide between flight and contact.

    Draws the material parameters of the piece (per impact), applies
    :func:`impact`, and returns (vx, vy, w, mode, seg). If the outgoing normal
    speed against the true piece is below ``v_contact`` the normal component
    is removed and the rock continues in contact.
    """
    seg = pseg[k]
    mat = seg_mat[seg]
    _draw(mats, mat, rng, drawn)
    tx, ty = _unit_tangent(px, py, k)
    nx = -ty
    ny = tx
    vx, vy, w = impact(
        vx,
        vy,
        w,
        nx,
        ny,
        r,
        int(mats[mat, M_MODEL]),
        drawn[0],
        mats[mat, M_RT],
        drawn[1],
        mats[mat, M_VSCALE] > 0.5,
        mats[mat, M_VSK],
        mats[mat, M_ROUGH],
        rng,
        np.arctan(mats[mat, M_ROUGH_H] / r),
    )
    vn = vx * nx + vy * ny
    if vn >= v_contact:
        return vx, vy, w, FLIGHT, seg
    vt = vx * tx + vy * ty
    return vt * tx, vt * ty, w, CONTACT, seg


SLIP_TOL = 1e-9
"""Slip sigma = v - r s (m/s), or spin r s (m/s), within which it counts as zero."""


@njit(cache=CACHE)
def _contact_accel(sinb, cosb, v, s, mu, mur, r):
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


@njit(cache=CACHE)
def _start_from_rest(px, py, k, x, y, w, r, mu, mur):
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
        tx, ty = _unit_tangent(px, py, kk)
        sinb = -dirn * ty
        cosb = tx
        s = -w * dirn
        a = _contact_accel(sinb, cosb, 0.0, s, mu, mur, r)[0]
        if a > best_a:
            best_a = a
            best_k = kk
            best_d = dirn
    return best_k, best_d


@njit(cache=CACHE, inline="always")
def _record(j, h, vx, vy, w, t, m, r, st_user, grid_h, grid_e, grid_v, cross):
    """Record the first downslope passage of station ``j``; True if it was the first.

    Hot path: takes only the arrays it writes (passing more arrays to a
    compiled call costs reference counting on every call).
    """
    if not np.isnan(grid_h[j]):
        return False
    grid_h[j] = h
    grid_e[j] = 0.5 * m * (vx * vx + vy * vy) + 0.2 * m * r * r * w * w
    grid_v[j] = np.hypot(vx, vy)
    u = st_user[j]
    if u >= 0:
        cross[u, C_H] = h
        cross[u, C_VX] = vx
        cross[u, C_VY] = vy
        cross[u, C_W] = w
        cross[u, C_T] = t
    return True


@njit(cache=CACHE, inline="always")
def _traj_row(traj, n, x, y, vx, vy, w, t, mode):
    """Append the state at an event to ``traj`` if there is room; the new count."""
    if n >= traj.shape[0]:
        return n
    traj[n, T_X] = x
    traj[n, T_Y] = y
    traj[n, T_VX] = vx
    traj[n, T_VY] = vy
    traj[n, T_W] = w
    traj[n, T_T] = t
    traj[n, T_MODE] = mode
    return n + 1


@njit(cache=CACHE)
def _record_restart(q, srec, srng, rng, drawn, ctx, mode, xs, yabs, vx, vy, w, t):
    """The full state of a rock at the first passage of restart station row ``q``.

    ``ctx`` holds (cur_seg, n_imp, n_ev, max_x) at the start of the phase.
    """
    srec[q, RS_MODE] = mode
    srec[q, RS_X] = xs
    srec[q, RS_Y] = yabs
    srec[q, RS_VX] = vx
    srec[q, RS_VY] = vy
    srec[q, RS_W] = w
    srec[q, RS_T] = t
    srec[q, RS_SEG] = ctx[0]
    srec[q, RS_E] = drawn[0]
    srec[q, RS_MU] = drawn[1]
    srec[q, RS_MUR] = drawn[2]
    srec[q, RS_NIMP] = ctx[1]
    srec[q, RS_NEV] = ctx[2]
    srec[q, RS_MAXX] = max(ctx[3], xs)
    srng[q] = rng[0]


@njit(cache=CACHE)
def _barrier_hit(bars, j, h, vx, vy, w, r, m, rng):
    """What barrier ``j`` does to a rock reaching its station.

    Parameters
    ----------
    bars : ndarray, shape (B, N_BARRIER_COLS)
        Barrier table.
    j : int
        Barrier row.
    h : float
        Passing height of the rock centre above the ground at the station (m).
    vx, vy, w : float
        Velocity (m/s) and angular velocity (rad/s) on arrival.
    r, m : float
        Radius (m) and mass (kg).
    rng : ndarray of uint64
        The rock's random stream (gap passage of a boulder row).

    Returns
    -------
    outcome : int
        ``O_*`` code.
    vx, vy, w : float
        State after the barrier (unchanged if passed; zero if caught).

    Notes
    -----
    A rock whose centre passes above the top (h > height) passes over. Below:
    a net catches it if E <= capacity; a rigid barrier returns it with its
    horizontal velocity reversed and scaled by the restitution; a boulder row
    lets it through a gap with probability max(0, gap - 2r) / spacing, else
    stops it. Beyond capacity the barrier gives way and the rock goes on with
    the surplus energy E - capacity (velocity and spin scaled by
    sqrt((E - capacity) / E)).
    """
    if h > bars[j, BR_H]:
        return O_PASSED_OVER, vx, vy, w
    beh = int(bars[j, BR_BEH])
    if beh == B_BLOCKS:
        p = (bars[j, BR_GAP] - 2.0 * r) / bars[j, BR_SPACING]
        if p > 0.0 and next_uniform(rng) < p:
            return O_PASSED_THROUGH_GAP, vx, vy, w
    e = 0.5 * m * (vx * vx + vy * vy) + 0.2 * m * r * r * w * w
    cap = bars[j, BR_CAP]
    if e > cap:
        f = np.sqrt((e - cap) / e)
        return O_BROKEN_THROUGH, f * vx, f * vy, f * w
    if beh == B_RIGID:
        return O_REBOUNDED, -bars[j, BR_E] * vx, vy, w
    return O_CAUGHT, 0.0, 0.0, 0.0


@njit(cache=CACHE)
def _meet(bar_out, bar_rec, j, code, h, vx, vy, w, t, m, r):
    """Record the first meeting of barrier ``j``."""
    if bar_out[j] != O_NOT_MET:
        return
    bar_out[j] = code
    bar_rec[j, BM_H] = h
    bar_rec[j, BM_V] = np.hypot(vx, vy)
    bar_rec[j, BM_E] = 0.5 * m * (vx * vx + vy * vy) + 0.2 * m * r * r * w * w
    bar_rec[j, BM_T] = t


@njit(cache=CACHE)
def simulate_rock(
    px,
    py,
    pseg,
    seg_mat,
    mats,
    settings,
    r,
    m,
    x0,
    h0,
    vx0,
    vy0,
    w0,
    spin_rolling,
    rng,
    st_x,
    st_yg,
    st_user,
    grid_h,
    grid_e,
    cross,
    traj,
    bars,
    bar_out,
    bar_rec,
    grid_v,
    st_srow,
    srec,
    srng,
    resume,
    state0,
):
    """Follow one rock from its release to the end of its path.

    Parameters
    ----------
    px, py : ndarray of float
        Centre path of this rock's radius (m), see ``profile.centre_path``.
    pseg : ndarray of int
        Ground segment under each piece of the centre path.
    seg_mat : ndarray of int
        Material index of each ground segment.
    mats : ndarray of float, shape (n_materials, N_MAT_COLS)
        Material table (columns ``M_*``).
    settings : ndarray of float, shape (N_SETTINGS,)
        ``v_contact`` (m/s), ``v_stop`` (m/s), ``max_events``.
    r, m : float
        Radius (m) and mass (kg).
    x0 : float
        Release x of the centre (m).
    h0 : float
        Clearance above the centre path at release (m); 0 = on the ground.
    vx0, vy0 : float
        Initial velocity (m/s).
    w0 : float
        Initial angular velocity (rad/s), ignored if ``spin_rolling``.
    spin_rolling : bool
        Start with the spin of rolling without slip along the ground.
    rng : ndarray of uint64, shape (1,)
        The rock's random stream.
    st_x, st_yg : ndarray of float, shape (S,)
        Stations (m), sorted, and the ground height there (m).
    st_user : ndarray of int, shape (S,)
        Row of ``cross`` for each station, or -1 (envelope-only station).
    grid_h, grid_e : ndarray of float, shape (S,)
        Out: passing height (m) and total kinetic energy (J) at the first
        downslope passage of each station; must come in as NaN.
    cross : ndarray of float, shape (U, N_CROSS_COLS)
        Out: detail of the first downslope passage of each user station.
    traj : ndarray of float, shape (T, N_TRAJ_COLS)
        Out: the state at each event (T may be 0 to record nothing).
    bars : ndarray of float, shape (B, N_BARRIER_COLS)
        Barriers (columns ``BR_*``), sorted by x; B may be 0.
    bar_out : ndarray of int8, shape (B,)
        Out: outcome of the first meeting with each barrier (``O_*``); must
        come in as ``O_NOT_MET``.
    bar_rec : ndarray of float, shape (B, N_BMEET_COLS)
        Out: passing height (m), speed (m/s), total kinetic energy (J) and
        time (s) of that first meeting.
    grid_v : ndarray of float, shape (S,)
        Out: speed (m/s) at the first downslope passage of each station.
    st_srow : ndarray of int, shape (S,)
        Row of ``srec`` for each restart station, or -1.
    srec : ndarray of float, shape (R, N_RESTART_COLS)
        Out: the rock's full state at the first downslope passage of each
        restart station (columns ``RS_*``); must come in as NaN.
    srng : ndarray of uint64, shape (R,)
        Out: the rock's random stream there.
    resume : bool
        Start from ``state0`` (a row of ``srec``, with ``rng`` set to the
        matching ``srng``) instead of the release.
    state0 : ndarray of float, shape (N_RESTART_COLS,)
        The state to resume from.

    Returns
    -------
    status : int
        How the path ended (``STOPPED``, ``EXIT_*``, ``UNRESOLVED``).
    x, y : float
        Final position of the centre (m).
    n_impacts : int
        Number of landings from flight.
    n_events : int
        Number of events.
    max_x : float
        Largest x reached by the centre (m).
    t : float
        Duration of the path (s).
    n_traj : int
        Number of rows written to ``traj``.
    caught_by : int
        Barrier row that caught the rock, or -1.
    """
    v_contact = settings[S_V_CONTACT]
    v_stop = settings[S_V_STOP]
    max_events = int(settings[S_MAX_EVENTS])
    npc = px.shape[0] - 1
    drawn = np.empty(3)
    cur_seg = -1

    x = x0
    vx = vx0
    vy = vy0
    k = locate(px, x, vx)
    y = path_height(px, py, k, x)
    tx, ty = _unit_tangent(px, py, k)
    w = -(vx * tx + vy * ty) / r if spin_rolling else w0
    t = 0.0
    n_imp = 0
    n_ev = 0
    n_traj = 0
    max_x = x
    status = RUNNING
    caught_by = -1
    nbar = bars.shape[0]
    # Barrier results, defined up front for the compiler.
    code = O_NOT_MET
    nvx = 0.0
    nvy = 0.0
    nw = 0.0
    vs = 0.0
    ctx = np.zeros(4)
    if resume:
        # Continue a path from its state at a restart station.
        mode = int(state0[RS_MODE])
        x = state0[RS_X]
        y = state0[RS_Y]
        vx = state0[RS_VX]
        vy = state0[RS_VY]
        w = state0[RS_W]
        t = state0[RS_T]
        cur_seg = int(state0[RS_SEG])
        drawn[0] = state0[RS_E]
        drawn[1] = state0[RS_MU]
        drawn[2] = state0[RS_MUR]
        n_imp = int(state0[RS_NIMP])
        n_ev = int(state0[RS_NEV])
        max_x = state0[RS_MAXX]
        k = locate(px, x, vx)
        if mode == CONTACT:
            # Back onto the path (the record is exact up to round-off).
            y = path_height(px, py, k, x)
    elif h0 > 0.0:
        y += h0
        mode = FLIGHT
    else:
        vn = -vx * ty + vy * tx
        if vn > 1e-9:
            mode = FLIGHT
        elif vn < -1e-9:
            vx, vy, w, mode, cur_seg = _collide(
                vx, vy, w, k, px, py, pseg, seg_mat, mats, r, v_contact, rng, drawn
            )
        else:
            mode = CONTACT
            vt = vx * tx + vy * ty
            vx = vt * tx
            vy = vt * ty

    while True:
        if n_ev >= max_events:
            status = UNRESOLVED
            break
        ctx[0] = cur_seg
        ctx[1] = n_imp
        ctx[2] = n_ev
        ctx[3] = max_x
        n_ev += 1
        n_traj = _traj_row(traj, n_traj, x, y, vx, vy, w, t, mode)

        if mode == FLIGHT:
            k = locate(px, x, vx)
            leaves, tf, k = next_landing(px, py, x, y, vx, vy, k)
            x1 = x + vx * tf
            # Barriers crossed by this flight, in the order of travel; the
            # first that changes the path ends the flight there.
            hit = -1
            if nbar > 0 and vx != 0.0:
                if vx > 0.0:
                    j = np.searchsorted(bars[:, BR_X], x, side="right")
                    jstep = 1
                else:
                    j = np.searchsorted(bars[:, BR_X], x, side="left") - 1
                    jstep = -1
                while 0 <= j < nbar and (bars[j, BR_X] - x1) * jstep <= 0.0:
                    ts = (bars[j, BR_X] - x) / vx
                    yb = y + vy * ts - 0.5 * G * ts * ts
                    vyb = vy - G * ts
                    hb = yb - bars[j, BR_YG]
                    code, nvx, nvy, nw = _barrier_hit(bars, j, hb, vx, vyb, w, r, m, rng)
                    _meet(bar_out, bar_rec, j, code, hb, vx, vyb, w, t + ts, m, r)
                    if code == O_PASSED_OVER or code == O_PASSED_THROUGH_GAP:
                        j += jstep
                        continue
                    hit = j
                    break
            if hit >= 0:
                xb = bars[hit, BR_X]
                if vx > 0.0:
                    j = np.searchsorted(st_x, x, side="right")
                    while j < st_x.shape[0] and st_x[j] <= xb:
                        ts = (st_x[j] - x) / vx
                        ys = y + vy * ts - 0.5 * G * ts * ts
                        if _record(j, ys - st_yg[j], vx, vy - G * ts, w, t + ts, m, r,
                                   st_user, grid_h, grid_e, grid_v, cross) and st_srow[j] >= 0:
                            _record_restart(st_srow[j], srec, srng, rng, drawn, ctx, FLIGHT,
                                            st_x[j], ys, vx, vy - G * ts, w, t + ts)
                        j += 1
                tb = (xb - x) / vx
                t += tb
                y = y + vy * tb - 0.5 * G * tb * tb
                x = xb
                max_x = max(max_x, x)
                if code == O_CAUGHT:
                    status = CAUGHT
                    caught_by = hit
                    vx = 0.0
                    vy = 0.0
                    w = 0.0
                    break
                vx = nvx
                vy = nvy
                w = nw
                continue
            if vx > 0.0:
                # Stations crossed downslope by this flight, in (x, x1].
                j = np.searchsorted(st_x, x, side="right")
                while j < st_x.shape[0] and st_x[j] <= x1:
                    ts = (st_x[j] - x) / vx
                    ys = y + vy * ts - 0.5 * G * ts * ts
                    if (
                        _record(j, ys - st_yg[j], vx, vy - G * ts, w, t + ts, m, r,
                                st_user, grid_h, grid_e, grid_v, cross)
                        and st_srow[j] >= 0
                    ):
                        _record_restart(st_srow[j], srec, srng, rng, drawn, ctx, FLIGHT,
                                        st_x[j], ys, vx, vy - G * ts, w, t + ts)
                    j += 1
            t += tf
            if leaves:
                x = px[npc] if vx > 0.0 else px[0]
                y = y + vy * tf - 0.5 * G * tf * tf
                vy -= G * tf
                max_x = max(max_x, x)
                status = EXIT_DOWNSLOPE if vx > 0.0 else EXIT_UPSLOPE
                break
            x = x1
            y = path_height(px, py, k, x)
            vy -= G * tf
            max_x = max(max_x, x)
            n_imp += 1
            vx, vy, w, mode, cur_seg = _collide(
                vx, vy, w, k, px, py, pseg, seg_mat, mats, r, v_contact, rng, drawn
            )
            continue

        # ---- CONTACT: rolling and/or sliding on piece k ----
        seg = pseg[k]
        if seg != cur_seg:
            _draw(mats, seg_mat[seg], rng, drawn)
            cur_seg = seg
        mu = drawn[1]
        mur = drawn[2]
        tx, ty = _unit_tangent(px, py, k)
        vt = vx * tx + vy * ty
        v = abs(vt)
        if v < v_stop:
            # Slow enough to be held, if the ground can hold it.
            k2, d2 = _start_from_rest(px, py, k, x, y, w, r, mu, mur)
            if d2 == 0:
                status = STOPPED
                vx = 0.0
                vy = 0.0
                w = 0.0
                break
            if v <= 1e-12:
                k = k2
                tx, ty = _unit_tangent(px, py, k)
                dirn = d2
                v = 0.0
            else:
                dirn = 1 if vt > 0.0 else -1
        else:
            dirn = 1 if vt > 0.0 else -1
        dx = dirn * tx
        dy = dirn * ty
        sinb = -dy
        cosb = tx
        s = -w * dirn
        a, dsig, dsp, _, s_zero = _contact_accel(sinb, cosb, v, s, mu, mur, r)
        rolling = np.isnan(dsp)
        sigma = v - r * s
        if rolling or abs(sigma) <= SLIP_TOL:
            # Zero slip has no event of its own: it rolls, or the slip has
            # already been given the sense in which it grows.
            sigma = 0.0
        if s_zero and not rolling:
            s = 0.0
        if dirn > 0:
            dist = np.hypot(px[k + 1] - x, py[k + 1] - y)
        else:
            dist = np.hypot(x - px[k], y - py[k])
        # Event times: end of piece, speed zero, slip zero, spin zero.
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
        ev = 0
        tm = t_end
        if t_zero < tm:
            ev = 1
            tm = t_zero
        if t_slip < tm:
            ev = 2
            tm = t_slip
        if t_spin < tm:
            ev = 3
            tm = t_spin
        if tm == np.inf:
            status = STOPPED
            break
        ds_ = v * tm + 0.5 * a * tm * tm
        if ds_ < 0.0:
            ds_ = 0.0
        if ds_ > dist:
            ds_ = dist
        v1 = v + a * tm
        if v1 < 0.0 or ev == 1:
            v1 = 0.0
        if rolling or ev == 2:
            s1 = v1 / r
        elif ev == 3:
            s1 = 0.0
        else:
            s1 = s + dsp * tm
        if ev == 0:
            xn = px[k + 1] if dirn > 0 else px[k]
            yn = py[k + 1] if dirn > 0 else py[k]
        else:
            xn = x + dx * ds_
            yn = y + dy * ds_
        # Barriers met in this phase, in the order of travel.
        hit = -1
        if nbar > 0:
            if dirn > 0:
                j = np.searchsorted(bars[:, BR_X], x, side="right")
            else:
                j = np.searchsorted(bars[:, BR_X], x, side="left") - 1
            while 0 <= j < nbar and (bars[j, BR_X] - xn) * dirn <= 0.0:
                dd = (bars[j, BR_X] - x) / dx
                q = v * v + 2.0 * a * dd
                vs = np.sqrt(q) if q > 0.0 else 0.0
                ts = 2.0 * dd / (v + vs) if v + vs > 0.0 else 0.0
                ss = vs / r if rolling else s + dsp * ts
                hb = y + dy * dd - bars[j, BR_YG]
                code, nvx, nvy, nw = _barrier_hit(
                    bars, j, hb, vs * dx, vs * dy, -ss * dirn, r, m, rng)
                _meet(bar_out, bar_rec, j, code, hb, vs * dx, vs * dy, -ss * dirn, t + ts, m, r)
                if code == O_PASSED_OVER or code == O_PASSED_THROUGH_GAP:
                    j += dirn
                    continue
                hit = j
                # The phase ends at the barrier.
                xn = bars[j, BR_X]
                yn = y + dy * dd
                tm = ts
                break
        if dirn > 0 and st_x.shape[0] > 0:
            j = np.searchsorted(st_x, x, side="right")
            while j < st_x.shape[0] and st_x[j] <= xn:
                dd = (st_x[j] - x) / dx
                q = v * v + 2.0 * a * dd
                vs = np.sqrt(q) if q > 0.0 else 0.0
                ts = 2.0 * dd / (v + vs) if v + vs > 0.0 else 0.0
                ss = vs / r if rolling else s + dsp * ts
                if (
                    _record(j, y + dy * dd - st_yg[j], vs * dx, vs * dy, -ss * dirn, t + ts,
                            m, r, st_user, grid_h, grid_e, grid_v, cross)
                    and st_srow[j] >= 0
                ):
                    _record_restart(st_srow[j], srec, srng, rng, drawn, ctx, CONTACT, st_x[j],
                                    y + dy * dd, vs * dx, vs * dy, -ss * dirn, t + ts)
                j += 1
        x = xn
        y = yn
        t += tm
        max_x = max(max_x, x)
        if hit >= 0:
            if code == O_CAUGHT:
                status = CAUGHT
                caught_by = hit
                vx = 0.0
                vy = 0.0
                w = 0.0
                break
            if code == O_REBOUNDED:
                # On the ground the rebound reverses the velocity along it.
                f = bars[hit, BR_E]
                vx = -f * vs * dx
                vy = -f * vs * dy
                w = nw
                if f * vs < v_stop:
                    # Too slow to leave: the rock comes to rest against the barrier.
                    status = STOPPED
                    vx = 0.0
                    vy = 0.0
                    w = 0.0
                    break
            else:
                vx = nvx
                vy = nvy
                w = nw
            continue
        vx = v1 * dx
        vy = v1 * dy
        w = -s1 * dirn
        if ev != 0:
            continue
        # End of the piece: leave the section, fly off a convex vertex, or
        # meet the next piece (impact at a concave vertex).
        k2 = k + dirn
        if k2 < 0 or k2 >= npc:
            status = EXIT_DOWNSLOPE if dirn > 0 else EXIT_UPSLOPE
            break
        kl = k if dirn > 0 else k2
        cl = (py[kl + 1] - py[kl]) / (px[kl + 1] - px[kl])
        cr = (py[kl + 2] - py[kl + 1]) / (px[kl + 2] - px[kl + 1])
        tol = 1e-9 * (1.0 + abs(cl) + abs(cr))
        if cr < cl - tol:
            mode = FLIGHT
            continue
        k = k2
        if cr > cl + tol:
            t2x, t2y = _unit_tangent(px, py, k)
            if vx * -t2y + vy * t2x < 0.0:
                vx, vy, w, mode, cur_seg = _collide(
                    vx, vy, w, k, px, py, pseg, seg_mat, mats, r, v_contact, rng, drawn
                )
                continue
        t2x, t2y = _unit_tangent(px, py, k)
        vt = vx * t2x + vy * t2y
        vx = vt * t2x
        vy = vt * t2y

    n_traj = _traj_row(traj, n_traj, x, y, vx, vy, w, t, mode)
    return status, x, y, n_imp, n_ev, max_x, t, n_traj, caught_by

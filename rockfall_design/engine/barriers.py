"""Barriers: what a fence, wall or boulder row does to a rock that reaches it."""

from __future__ import annotations

import numpy as np

from .columns import (
    B_BLOCKS,
    B_RIGID,
    BM_E,
    BM_H,
    BM_T,
    BM_V,
    BR_BEH,
    BR_CAP,
    BR_D_MEL,
    BR_D_SEL,
    BR_E,
    BR_GAP,
    BR_H,
    BR_SEL,
    BR_SPACING,
    BR_X,
    O_BROKEN_THROUGH,
    O_CAUGHT,
    O_NOT_MET,
    O_PASSED_OVER,
    O_PASSED_THROUGH_GAP,
    O_REBOUNDED,
)
from .flight import locate, path_height
from .jit import hot
from .rng import next_uniform


@hot
def barrier_hit(bars, j, h, vx, vy, w, r, m, rng):
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


@hot
def meet_barrier(bar_out, bar_rec, j, code, h, vx, vy, w, t, m, r):
    """Record the first meeting of barrier ``j``."""
    if bar_out[j] != O_NOT_MET:
        return
    bar_out[j] = code
    bar_rec[j, BM_H] = h
    bar_rec[j, BM_V] = np.hypot(vx, vy)
    bar_rec[j, BM_E] = 0.5 * m * (vx * vx + vy * vy) + 0.2 * m * r * r * w * w
    bar_rec[j, BM_T] = t


@hot
def braking_distance(e, sel, d_sel, mel, d_mel):
    """How far a net carries a rock of energy ``e`` that it catches (m).

    Parameters
    ----------
    e : float
        Kinetic energy of the rock when it meets the net (J).
    sel, mel : float
        The kit's service and maximum energy levels, SEL and MEL (J).
    d_sel, d_mel : float
        Its elongation in the SEL test and its maximum elongation in the MEL
        test (m); 0 (or less) for not given.

    Returns
    -------
    float
        The braking distance (m): 0 without an MEL elongation; the MEL
        elongation for every rock without an SEL elongation; else the SEL
        elongation up to the SEL, the MEL elongation from the MEL on, and
        linear in ``e`` between the two tests.

    Notes
    -----
    EAD 340059 (formerly ETAG 027) measures the elongation of a kit in its
    SEL and MEL tests only. Between them the rule interpolates linearly in
    the energy; below the SEL it keeps the SEL elongation rather than
    extrapolate to zero (no test measured it, and a net's elongation falls
    more slowly than the energy it absorbs); with only the MEL elongation
    given it takes that for every caught rock. Both choices err towards a
    longer braking distance. ``judge.outcomes.braking_distances`` applies
    the same rule to arrays (the optimiser's screening).

    References
    ----------
    .. [1] EOTA (2018). EAD 340059-00-0106, Falling rock protection kits.
    .. [2] Peila, D. and Ronco, C. (2009). Technical note: Design of rockfall
       net fences and the new ETAG 027 European guideline. Natural Hazards
       and Earth System Sciences 9, 1291-1298.
    """
    if not d_mel > 0.0:
        return 0.0
    if not d_sel > 0.0 or not mel > sel:
        return d_mel
    if e <= sel:
        return d_sel
    if e >= mel:
        return d_mel
    return d_sel + (d_mel - d_sel) * (e - sel) / (mel - sel)


@hot
def braked_stop(bars, j, e, vx, x, y, px, py):
    """Where a rock that barrier ``j`` caught at ``x``, ``y`` with energy ``e`` (J) rests.

    Its braking distance (:func:`braking_distance`) on from the station in
    the direction it moved (``vx``), taken horizontally (the elongation is
    measured along the slope: its horizontal projection is shorter, so this
    errs towards the protected zone), on the centre path ``px``, ``py`` and
    within the section. Without a braking distance the rock stays where the
    net caught it (``x``, ``y``). Returns x, y (m).
    """
    d = braking_distance(e, bars[j, BR_SEL], bars[j, BR_D_SEL], bars[j, BR_CAP],
                         bars[j, BR_D_MEL])
    if not d > 0.0:
        return x, y
    x = bars[j, BR_X] + (d if vx >= 0.0 else -d)
    x = min(max(x, px[0]), px[px.shape[0] - 1])
    k = locate(px, x, vx)
    return x, path_height(px, py, k, x)

"""Barriers: what a fence, wall or boulder row does to a rock that reaches it."""

from __future__ import annotations

import numpy as np

from ._jit import hot
from .columns import (
    B_BLOCKS,
    B_RIGID,
    BM_E,
    BM_H,
    BM_T,
    BM_V,
    BR_BEH,
    BR_CAP,
    BR_E,
    BR_GAP,
    BR_H,
    BR_SPACING,
    O_BROKEN_THROUGH,
    O_CAUGHT,
    O_NOT_MET,
    O_PASSED_OVER,
    O_PASSED_THROUGH_GAP,
    O_REBOUNDED,
)
from .rng import next_uniform


@hot
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


@hot
def _meet(bar_out, bar_rec, j, code, h, vx, vy, w, t, m, r):
    """Record the first meeting of barrier ``j``."""
    if bar_out[j] != O_NOT_MET:
        return
    bar_out[j] = code
    bar_rec[j, BM_H] = h
    bar_rec[j, BM_V] = np.hypot(vx, vy)
    bar_rec[j, BM_E] = 0.5 * m * (vx * vx + vy * vy) + 0.2 * m * r * r * w * w
    bar_rec[j, BM_T] = t

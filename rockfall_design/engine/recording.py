"""What a rock leaves behind: station passages, event states, restart states."""

from __future__ import annotations

import numpy as np

from .columns import (
    C_H,
    C_T,
    C_VX,
    C_VY,
    C_W,
    RS_E,
    RS_MAXX,
    RS_MODE,
    RS_MU,
    RS_MUR,
    RS_NEV,
    RS_NIMP,
    RS_SEG,
    RS_T,
    RS_VX,
    RS_VY,
    RS_W,
    RS_X,
    RS_Y,
    T_MODE,
    T_T,
    T_VX,
    T_VY,
    T_W,
    T_X,
    T_Y,
)
from .jit import hot


@hot
def record_passage(j, h, vx, vy, w, t, m, r, st_user, grid_h, grid_e, grid_v, cross):
    """Record the first downslope passage of station ``j``; True if it was the first.

    Hot path, compiled without reference counting (:func:`~.jit.hot`).
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


@hot
def traj_row(traj, n, x, y, vx, vy, w, t, mode):
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


@hot
def record_restart(q, srec, srng, rng, drawn, ctx, mode, xs, yabs, vx, vy, w, t):
    """The full state of a rock at the first passage of restart station row ``q``.

    ``ctx`` holds (cur_seg, n_imp, n_ev, max_x) at the start of the phase.
    The forest's state is not kept: a resumed rock draws its next stem afresh
    and counts the stems it meets from there.
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

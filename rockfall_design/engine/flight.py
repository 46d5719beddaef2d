"""Free flight: where on the centre path a parabola lands (PHYSICS.md, 'Free flight')."""

from __future__ import annotations

import numpy as np

from ._jit import hot
from .columns import G


@hot
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


@hot
def path_height(px: np.ndarray, py: np.ndarray, k: int, x: float) -> float:
    """Height (m) of piece ``k`` of the centre path at ``x``."""
    return py[k] + (py[k + 1] - py[k]) * (x - px[k]) / (px[k + 1] - px[k])


@hot
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


@hot
def _unit_tangent(px, py, k):
    dx = px[k + 1] - px[k]
    dy = py[k + 1] - py[k]
    ln = np.hypot(dx, dy)
    return dx / ln, dy / ln

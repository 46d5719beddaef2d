"""Free flight: where on the centre path a parabola lands (PHYSICS.md, 'Free flight')."""

from __future__ import annotations

import numpy as np

from .columns import G
from .jit import compiled, hot


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


LINEAR_PIECES = 8
"""Pieces a flight walks one by one before it looks for whole blocks to skip.

Most flights on a section of a few pieces land within a few of them: the
tree of :func:`path_tree` is used only for the longer walks of a dense
survey, so the short ones cost what they did.
"""

#: Relative size of the margin by which a flight must clear a block of the
#: centre path to skip it: the round-off of the piece-by-piece test is below
#: 1e-13 of the magnitudes involved, so a skipped piece is one the exact test
#: would also have passed, and the landing found is bit-identical.
_SKIP_REL = 1e-10


@hot
def _flight_height(x0, y0, vx, vy, x):
    """Height (m) of the flight from (x0, y0) with velocity (vx, vy) at abscissa ``x``."""
    t = (x - x0) / vx
    return y0 + t * (vy - 0.5 * G * t)


@hot
def _clears(px, tree, nv, node, a, b, x0, y0, vx, vy, slack):
    """True if the flight clears every vertex ``a .. b`` under ``node`` by a margin.

    A parabola is concave, so over ``[px[a], px[b]]`` it is lowest at an
    end: it clears every vertex there (and so every piece between them,
    which are straight) when both ends are above the highest vertex,
    ``tree[node]`` (see :func:`path_tree`). The margin is far above the
    round-off of the piece-by-piece test of :func:`next_landing`.
    """
    if a >= nv:
        return True  # padding only
    if b > nv - 1:
        b = nv - 1
    ya = _flight_height(x0, y0, vx, vy, px[a])
    yb = _flight_height(x0, y0, vx, vy, px[b])
    low = min(ya, yb)
    far = max(abs(px[a] - x0), abs(px[b] - x0))
    tf = far / abs(vx)
    top = tree[node]
    margin = _SKIP_REL * (1.0 + abs(y0) + abs(top) + abs(low) + abs(vy) * tf + G * tf * tf
                          + slack * far)
    return low > top + margin


@hot
def first_not_cleared(px, tree, nv, v, dirn, x0, y0, vx, vy):
    """First vertex from ``v`` on, in direction ``dirn``, that the flight may not clear.

    A walk over the heap-ordered tree of :func:`path_tree`: a block cleared
    whole is skipped and the walk climbs to the next larger block along; a
    block not cleared is split. O(log n) blocks per call. Returns ``nv``
    (moving right) or -1 (moving left) if every vertex is cleared.
    """
    size = tree.shape[0] // 2
    slack = tree[0]
    node = size + v
    a = v  # first leaf under node
    w = 1  # leaves under node
    while True:
        if _clears(px, tree, nv, node, a, a + w - 1, x0, y0, vx, vy, slack):
            # Up while this node is the last child in the direction of travel,
            # then to the next block along.
            if dirn > 0:
                while node & 1:
                    a -= w
                    w *= 2
                    node >>= 1
                if node == 0:
                    return nv
                node += 1
                a += w
            else:
                while node > 1 and not node & 1:
                    w *= 2
                    node >>= 1
                if node == 1:
                    return -1
                node -= 1
                a -= w
        elif node >= size:
            return a
        else:
            w //= 2
            node *= 2
            if dirn < 0:
                node += 1
                a += w


@hot
def next_landing(px, py, tree, x0, y0, vx, vy, k):
    """Time and piece of the next contact of a free flight with the centre path.

    Parameters
    ----------
    px, py : ndarray
        Centre path vertices (m).
    tree : ndarray
        The path's tree of highest vertices (:func:`path_tree`).
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

    After ``LINEAR_PIECES`` pieces the walk skips every block of pieces that
    the flight clears by a margin (:func:`first_not_cleared`), so a flight
    over a survey of n vertices costs O(log n), not O(n). Only pieces that
    the test above would have passed are skipped, and the piece where it
    fails is tested exactly as before: the landing is the same to the bit.
    """
    npc = px.shape[0] - 1
    t_in = 0.0
    walked = 0
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
                walked += 1
                if walked >= LINEAR_PIECES:
                    # Skip to the piece whose far end the flight may not clear.
                    if vx > 0.0:
                        v = first_not_cleared(px, tree, npc + 1, k + 1, 1, x0, y0, vx, vy)
                        if v > npc:
                            return True, (px[npc] - x0) / vx, npc
                        if v - 1 > k:
                            k = v - 1
                            t_in = (px[k] - x0) / vx
                    else:
                        v = first_not_cleared(px, tree, npc + 1, k, -1, x0, y0, vx, vy)
                        if v < 0:
                            return True, (px[0] - x0) / vx, -1
                        if v < k:
                            k = v
                            t_in = (px[k + 1] - x0) / vx
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


@compiled
def path_tree(px, py):
    """Tree of the highest vertex of the centre path over blocks of vertices.

    Parameters
    ----------
    px, py : ndarray of float, shape (nv,)
        Centre path vertices (m).

    Returns
    -------
    ndarray of float, shape (2 P,)
        A heap-ordered segment tree over ``P >= nv`` leaves (a power of two):
        ``tree[P + i] = py[i]`` (``-inf`` beyond ``nv``), and each node
        ``j`` in ``1 .. P - 1`` holds the larger of its children ``2j`` and
        ``2j + 1``. ``tree[0]``, which no node uses, holds the largest
        absolute slope of the pieces (it bounds the round-off of the test of
        a piece, see :func:`_clears`). O(nv) to build.

    See Also
    --------
    next_landing : skips the blocks a flight clears.
    """
    nv = py.shape[0]
    size = 1
    while size < nv:
        size *= 2
    tree = np.empty(2 * size)
    tree[size : size + nv] = py
    tree[size + nv :] = -np.inf
    for j in range(size - 1, 0, -1):
        tree[j] = max(tree[2 * j], tree[2 * j + 1])
    smax = 0.0
    for i in range(nv - 1):
        c = abs((py[i + 1] - py[i]) / (px[i + 1] - px[i]))
        if c > smax:
            smax = c
    tree[0] = smax
    return tree


@hot
def unit_tangent(px, py, k):
    """Unit vector along segment ``k`` of the polyline ``(px, py)`` (from vertex k to k + 1)."""
    dx = px[k + 1] - px[k]
    dy = py[k + 1] - py[k]
    ln = np.hypot(dx, dy)
    return dx / ln, dy / ln

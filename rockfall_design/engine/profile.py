"""Slope section geometry: the ground polyline and the centre path of a sphere.

A sphere of radius ``r`` touches the ground when its centre lies at distance
``r`` from it, so its centre moves on or above the *centre path*: the upper
boundary of the ground dilated by a disc of radius ``r``. Because the ground
is the graph of a function of x, so is the centre path,

    Y(x) = max over ground points (x', y') with |x - x'| <= r of
           y' + sqrt(r^2 - (x - x')^2),

and it is the upper envelope of (a) every ground segment offset by ``r``
along its outward normal and (b) at every convex vertex, the arc of radius
``r`` about the vertex between the normals of its two segments (PHYSICS.md,
"The slope section"). The arcs are replaced by polygons *circumscribed* about
them, with edges turning by at most ``max_chord`` each: a circumscribed edge
never comes closer to the vertex than ``r``, so the rock never enters the
ground, and each edge is tangent to the arc at its middle, so its normal is an
exact normal of the arc.

Everything here is compiled with numba and works on plain arrays.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._jit import CACHE

#: Relative tolerance used to merge breakpoints and collinear pieces.
_EPS_X = 1e-12


@njit(cache=CACHE)
def ground_height(gx: np.ndarray, gy: np.ndarray, x: float) -> float:
    """Height of the ground at ``x`` (m), linear between vertices.

    Outside the section the end segments are extended.
    """
    n = gx.shape[0]
    k = np.searchsorted(gx, x, side="right") - 1
    if k < 0:
        k = 0
    if k > n - 2:
        k = n - 2
    return gy[k] + (gy[k + 1] - gy[k]) * (x - gx[k]) / (gx[k + 1] - gx[k])


@njit(cache=CACHE)
def _arc_edges(t1x, t1y, t2x, t2y, max_chord):
    """Angles of the two normals at a vertex and the number of polygon corners."""
    phi1 = np.arctan2(t1x, -t1y)
    phi2 = np.arctan2(t2x, -t2y)
    m = max(int(np.ceil((phi1 - phi2) / max_chord - 1e-9)), 1)
    return phi1, phi2, m


@njit(cache=CACHE)
def _raw_pieces(gx, gy, seg_id, r, max_chord):
    """Offset segments and circumscribed vertex arcs of an extended profile.

    Returns arrays (xa, ya, xb, yb, sid) of straight pieces, each with
    ``xa < xb``, in the order of the raw offset curve.
    """
    n = gx.shape[0]
    nseg = n - 1
    tx = np.empty(nseg)
    ty = np.empty(nseg)
    for i in range(nseg):
        dx = gx[i + 1] - gx[i]
        dy = gy[i + 1] - gy[i]
        ln = np.hypot(dx, dy)
        tx[i] = dx / ln
        ty[i] = dy / ln
    # A convex vertex (the ground turns clockwise) carries an arc of m + 1 edges.
    cap = nseg
    for j in range(1, nseg):
        if tx[j - 1] * ty[j] - ty[j - 1] * tx[j] < -1e-12:
            cap += _arc_edges(tx[j - 1], ty[j - 1], tx[j], ty[j], max_chord)[2] + 1
    xa = np.empty(cap)
    ya = np.empty(cap)
    xb = np.empty(cap)
    yb = np.empty(cap)
    sid = np.empty(cap, dtype=np.int64)
    p = 0
    for i in range(nseg):
        # Collinear neighbours (|cross| ~ round-off) need no arc.
        if i > 0 and tx[i - 1] * ty[i] - ty[i - 1] * tx[i] < -1e-12:
            # Circumscribed polygon about the arc at vertex i: from the tangent
            # point of the upslope normal (angle phi1) through m corners at the
            # mid angles (radius r / cos(delta/2)) to the tangent point of the
            # downslope normal (phi2). The angle decreases, so x increases.
            phi1, phi2, m = _arc_edges(tx[i - 1], ty[i - 1], tx[i], ty[i], max_chord)
            delta = (phi2 - phi1) / m
            rc = r / np.cos(0.5 * delta)
            x_prev = gx[i] + r * np.cos(phi1)
            y_prev = gy[i] + r * np.sin(phi1)
            for q in range(m + 1):
                if q < m:
                    ang = phi1 + (q + 0.5) * delta
                    x_next = gx[i] + rc * np.cos(ang)
                    y_next = gy[i] + rc * np.sin(ang)
                else:
                    x_next = gx[i] + r * np.cos(phi2)
                    y_next = gy[i] + r * np.sin(phi2)
                xa[p] = x_prev
                ya[p] = y_prev
                xb[p] = x_next
                yb[p] = y_next
                # Edge q is tangent at phi1 + q*delta: the first half of the arc
                # takes the material of the upslope segment.
                sid[p] = seg_id[i - 1] if 2 * q < m else seg_id[i]
                p += 1
                x_prev = x_next
                y_prev = y_next
        nx = -ty[i]
        ny = tx[i]
        xa[p] = gx[i] + r * nx
        ya[p] = gy[i] + r * ny
        xb[p] = gx[i + 1] + r * nx
        yb[p] = gy[i + 1] + r * ny
        sid[p] = seg_id[i]
        p += 1
    return xa, ya, xb, yb, sid


@njit(cache=CACHE)
def _grow(a, cap):
    b = np.empty(cap, dtype=a.dtype)
    b[: a.shape[0]] = a
    return b


@njit(cache=CACHE)
def _line_at(xa, ya, xb, yb, i, x):
    """Value of the line through piece i at x (extrapolated)."""
    return ya[i] + (yb[i] - ya[i]) * (x - xa[i]) / (xb[i] - xa[i])


@njit(cache=CACHE)
def _slope(xa, ya, xb, yb, i):
    return (yb[i] - ya[i]) / (xb[i] - xa[i])


#: Vertices on each side of a piece among which :func:`_hidden` looks for one
#: whose circle hides the piece.
_HIDE_WINDOW = 32


@njit(cache=CACHE)
def _hidden(xa, ya, xb, yb, ex, ey, r, tol):
    """Pieces that lie below the circle of radius ``r`` about some ground vertex.

    The centre path is at or above the circle about every ground vertex
    within ``r`` (the sphere touching that vertex), so a piece below such a
    circle over its whole extent, by a margin, is never on the path: the
    sweep of :func:`centre_path` need not consider it. The circle minus a
    straight piece is concave, so the piece is below it everywhere when it
    is below at both ends. The vertices tried are the ``_HIDE_WINDOW`` on
    either side of the foot of the piece's normal (the ground point that made
    it), nearest first. On a dense, noisy survey most pieces are hidden so
    (the offsets and arcs of the points in the noise's hollows), and the
    sweep does a few lines per interval instead of hundreds.

    The margin keeps the sweep's choices exactly as without the test: a
    hidden piece is below the path by far more than the sweep's tie
    tolerances (1e-13 m in height, ``tol`` in x times slopes up to 1e5), so
    it would never have been chosen; pieces steeper than 100 are never
    hidden. The path is bit-identical (tests/engine/test_engine_survey.py).
    """
    npc = xa.shape[0]
    n = ex.shape[0]
    out = np.zeros(npc, dtype=np.bool_)
    r2 = r * r
    for i in range(npc):
        dx = xb[i] - xa[i]
        dy = yb[i] - ya[i]
        if dx <= 0.0 or abs(dy) > 100.0 * dx:
            continue
        ln = np.hypot(dx, dy)
        m = 1e-9 * (1.0 + abs(ya[i]) + abs(yb[i])) + 1e5 * tol
        # Vertices tried outwards from the foot of the piece's normal (the
        # ground point that made it); the first whose circle hides it will do.
        j = np.searchsorted(ex, 0.5 * (xa[i] + xb[i]) + r * dy / ln)
        for d in range(2 * _HIDE_WINDOW):
            w = j + (d + 1) // 2 if d % 2 else j - d // 2 - 1
            if w < 0 or w >= n:
                continue
            # Both ends of the piece within r of the vertex, in x.
            da = xa[i] - ex[w]
            db = xb[i] - ex[w]
            if abs(da) >= r or abs(db) >= r:
                continue
            if ey[w] + np.sqrt(r2 - da * da) > ya[i] + m and \
                    ey[w] + np.sqrt(r2 - db * db) > yb[i] + m:
                out[i] = True
                break
    return out


@njit(cache=CACHE)
def centre_path(gx, gy, seg_mat, r, max_chord):
    """Centre path of a sphere of radius ``r`` on the ground polyline (see :func:`_centre_path`)."""
    return _centre_path(gx, gy, seg_mat, r, max_chord, True)


@njit(cache=CACHE)
def _centre_path(gx, gy, seg_mat, r, max_chord, prune):
    """Centre path of a sphere of radius ``r`` on the ground polyline.

    Parameters
    ----------
    gx, gy : ndarray of float, shape (n,)
        Ground vertices (m), ``gx`` strictly increasing, ``n >= 2``.
    seg_mat : ndarray of int, shape (n - 1,)
        Material index of each ground segment (carried to the pieces).
    r : float
        Sphere radius (m), > 0.
    max_chord : float
        Largest turn of a circumscribed arc edge (rad).
    prune : bool
        Leave out of the sweep the pieces that a vertex's circle hides
        (:func:`_hidden`); the result is the same, found faster on dense
        surveys. False only to test that.

    Returns
    -------
    px, py : ndarray of float, shape (m + 1,)
        Vertices of the centre path (m), ``px[0] == gx[0]``,
        ``px[-1] == gx[-1]``, strictly increasing.
    pseg : ndarray of int, shape (m,)
        Ground segment index under each piece (for its material).

    Notes
    -----
    The profile is first extended level beyond both ends so that the path is
    complete over the whole section; the path is then clipped
    to ``[gx[0], gx[-1]]``. The upper envelope is found by a sweep over the
    breakpoints of the pieces; within each elementary interval the lines of the
    covering pieces are walked from the top line at its left end, always
    switching to the line whose crossing comes first (the envelope of lines is
    convex). Pieces hidden below a vertex's circle (:func:`_hidden`) are
    left out of the walk; every piece's ends stay breakpoints.
    """
    n = gx.shape[0]
    ext = 2.0 * r + 1.0
    ex = np.empty(n + 2)
    ey = np.empty(n + 2)
    eseg = np.empty(n + 1, dtype=np.int64)
    ex[1 : n + 1] = gx
    ey[1 : n + 1] = gy
    # Beyond its ends the ground is taken as level: a level extension of
    # length 2r + 1 always covers the section ends, whatever the end slopes.
    ex[0] = gx[0] - ext
    ey[0] = gy[0]
    ex[n + 1] = gx[n - 1] + ext
    ey[n + 1] = gy[n - 1]
    eseg[0] = 0
    for i in range(n - 1):
        eseg[i + 1] = i
    eseg[n] = n - 2

    xa, ya, xb, yb, sid = _raw_pieces(ex, ey, eseg, r, max_chord)
    npc = xa.shape[0]

    # Breakpoints: all piece ends inside the section, and the section ends.
    bp = np.empty(2 * npc + 2)
    nb = 0
    for i in range(npc):
        if gx[0] < xa[i] < gx[n - 1]:
            bp[nb] = xa[i]
            nb += 1
        if gx[0] < xb[i] < gx[n - 1]:
            bp[nb] = xb[i]
            nb += 1
    bp[nb] = gx[0]
    bp[nb + 1] = gx[n - 1]
    nb += 2
    bp = np.sort(bp[:nb])
    # Remove breakpoints closer than round-off.
    scale = max(abs(gx[0]), abs(gx[n - 1]), 1.0)
    tol = _EPS_X * scale
    ub = np.empty(nb)
    nu = 0
    for i in range(nb):
        if nu == 0 or bp[i] - ub[nu - 1] > tol:
            ub[nu] = bp[i]
            nu += 1
    ub[nu - 1] = gx[n - 1]

    hidden = _hidden(xa, ya, xb, yb, ex, ey, r, tol) if prune else np.zeros(npc, np.bool_)
    order = np.argsort(xa)
    active = np.empty(npc, dtype=np.int64)
    nact = 0
    nxt = 0  # next piece (in order of xa) not yet activated

    cap = 4 * nu + 16
    ox = np.empty(cap)
    oy = np.empty(cap)
    oseg = np.empty(cap, dtype=np.int64)
    no = 0

    for b in range(nu - 1):
        x0 = ub[b]
        x1 = ub[b + 1]
        xm = 0.5 * (x0 + x1)
        # Activate pieces starting at or before the midpoint; drop those ended.
        while nxt < npc and xa[order[nxt]] <= xm:
            # A piece of no width (round-off on a collinear arc) has no slope.
            if xb[order[nxt]] > xa[order[nxt]] and not hidden[order[nxt]]:
                active[nact] = order[nxt]
                nact += 1
            nxt += 1
        k = 0
        for q in range(nact):
            if xb[active[q]] > xm:
                active[k] = active[q]
                k += 1
        nact = k
        if nact == 0:
            # The raw offset curve covers the extended section, so a gap can only
            # be round-off wide: bridge it. A real gap would be a bug.
            if x1 - x0 <= 1e-9 * scale:
                continue
            raise ValueError("centre path has a gap; check the profile")
        # Top line at the left end (ties: the steeper one is above just right of x0).
        top = active[0]
        vtop = _line_at(xa, ya, xb, yb, top, x0)
        for q in range(1, nact):
            i = active[q]
            v = _line_at(xa, ya, xb, yb, i, x0)
            if v > vtop + 1e-13 or (
                abs(v - vtop) <= 1e-13 and _slope(xa, ya, xb, yb, i) > _slope(xa, ya, xb, yb, top)
            ):
                top = i
                vtop = v
        if no + nact + 2 >= cap:
            cap = 2 * cap + nact + 4
            ox = _grow(ox, cap)
            oy = _grow(oy, cap)
            oseg = _grow(oseg, cap)
        ox[no] = x0
        oy[no] = vtop
        oseg[no] = sid[top]
        no += 1
        xc = x0
        # Walk the upper envelope of the active lines across [x0, x1].
        for _ in range(nact):
            kt = _slope(xa, ya, xb, yb, top)
            best = -1
            bx = np.inf
            for q in range(nact):
                i = active[q]
                ki = _slope(xa, ya, xb, yb, i)
                if ki <= kt:
                    continue
                # Crossing of line i with the top line.
                d = _line_at(xa, ya, xb, yb, top, xc) - _line_at(xa, ya, xb, yb, i, xc)
                xi = xc + d / (ki - kt)
                # The first crossing wins; on a tie the steeper line is above after it.
                if (
                    best < 0
                    or xi < bx - tol
                    or (abs(xi - bx) <= tol and ki > _slope(xa, ya, xb, yb, best))
                ):
                    bx = xi
                    best = i
            if best < 0 or bx >= x1 - tol:
                break
            if bx > xc + tol:
                ox[no] = bx
                oy[no] = _line_at(xa, ya, xb, yb, top, bx)
                oseg[no] = sid[best]
                no += 1
            else:
                oseg[no - 1] = sid[best]
            top = best
            xc = max(bx, xc)
    # Last point: the value at the right end of the section.
    xe = ub[nu - 1]
    ve = -np.inf
    for q in range(nact):
        v = _line_at(xa, ya, xb, yb, active[q], xe)
        if v > ve:
            ve = v
    ox[no] = xe
    oy[no] = ve
    no += 1

    # Merge consecutive collinear pieces of the same ground segment.
    px = np.empty(no)
    py = np.empty(no)
    pseg = np.empty(no - 1, dtype=np.int64)
    px[0] = ox[0]
    py[0] = oy[0]
    m = 0  # number of pieces so far
    for i in range(1, no):
        if m > 0 and oseg[i - 1] == pseg[m - 1]:
            # Is the new point on the line of the last piece?
            k_prev = (py[m] - py[m - 1]) / (px[m] - px[m - 1])
            pred = py[m] + k_prev * (ox[i] - px[m])
            if abs(pred - oy[i]) <= 1e-11 * max(1.0, abs(oy[i])):
                px[m] = ox[i]
                py[m] = oy[i]
                continue
        m += 1
        px[m] = ox[i]
        py[m] = oy[i]
        pseg[m - 1] = oseg[i - 1]
    return px[: m + 1].copy(), py[: m + 1].copy(), pseg[:m].copy()

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

from .jit import compiled, hot, writable

#: Relative tolerance used to merge breakpoints and collinear pieces.
_EPS_X = 1e-12


@compiled
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


@compiled
def _arc_edges(t1x, t1y, t2x, t2y, max_chord):
    """Angles of the two normals at a vertex and the number of polygon corners."""
    phi1 = np.arctan2(t1x, -t1y)
    phi2 = np.arctan2(t2x, -t2y)
    m = max(int(np.ceil((phi1 - phi2) / max_chord - 1e-9)), 1)
    return phi1, phi2, m


@compiled
def raw_pieces(gx, gy, seg_id, r, max_chord, elems):
    """Offset segments and circumscribed vertex arcs of an extended profile.

    Returns arrays (xa, ya, xb, yb, sid) of straight pieces, each with
    ``xa < xb``, in the order of the raw offset curve. Only the elements
    ``elems`` are made (sorted codes: ``2 i`` the arc at vertex ``i``,
    ``2 i + 1`` the offset of segment ``i``; ``np.arange(2 * len(gx) - 1)``
    for all, see :func:`element_codes`). :func:`_piece_units` and
    :func:`_scaled_pieces`: what does not depend on ``r`` made once.
    """
    return _scaled_pieces(gx, gy, _piece_units(gx, gy, seg_id, max_chord, elems), r)


@compiled
def _unit_tangents(gx, gy, elems):
    """Unit tangents (tx, ty) of the ground segments the elements ``elems`` need.

    An arc needs the segments on both sides of its vertex, an offset its own
    (sorted codes, :func:`element_codes`); each is computed once. The other
    entries are left unset.
    """
    nseg = gx.shape[0] - 1
    tx = np.empty(nseg)
    ty = np.empty(nseg)
    last = -1  # segments up to this one have their tangents (elems are sorted)
    for c in elems:
        for i in range(max(c // 2 - 1 + c % 2, last + 1), c // 2 + 1):
            if 0 <= i < nseg:
                dx = gx[i + 1] - gx[i]
                dy = gy[i + 1] - gy[i]
                ln = np.hypot(dx, dy)
                tx[i] = dx / ln
                ty[i] = dy / ln
                last = i
    return tx, ty


@compiled
def _convex(tx, ty, i):
    """Whether the ground turns clockwise at inner vertex ``i``: it carries an arc.

    Collinear neighbours (a cross product of round-off size) need none.
    """
    return 0 < i < tx.shape[0] and tx[i - 1] * ty[i] - ty[i - 1] * tx[i] < -1e-12


@compiled
def _piece_units(gx, gy, seg_id, max_chord, elems):
    """What the pieces of :func:`raw_pieces` are made of, whatever the radius.

    Each end of a piece is a ground vertex plus a radius times a unit
    vector: the segment's normal for an offset (radius ``r``), the normal at
    an angle of the arc's polygon for a tangent point (``r``) or a corner
    (``r / ch``, ``ch`` the cosine of half the polygon's turn). Those units,
    angles and cosines cost the trigonometry of a path; a rock of a size of
    its own then needs only :func:`_scaled_pieces` (its path is the same to
    the bit: the same expressions of the same numbers). A level extension's
    length does not change them (its direction is (1, 0) exactly).

    Returns
    -------
    tuple
        ``(va, uax, uay, ka, vb, ubx, uby, kb, ch, sid)`` per piece: the
        vertex of each end, its unit vector, whether it is a corner (1) or not
        (0), the cosine ``ch`` of the piece's arc (1 for an offset) and the
        ground segment of its material.
    """
    tx, ty = _unit_tangents(gx, gy, elems)
    # A convex vertex carries an arc of m + 1 edges.
    cap = 0
    for c in elems:
        j = c // 2
        if c % 2:
            cap += 1
        elif _convex(tx, ty, j):
            cap += _arc_edges(tx[j - 1], ty[j - 1], tx[j], ty[j], max_chord)[2] + 1
    va = np.empty(cap, dtype=np.int64)
    vb = np.empty(cap, dtype=np.int64)
    uax = np.empty(cap)
    uay = np.empty(cap)
    ubx = np.empty(cap)
    uby = np.empty(cap)
    ka = np.zeros(cap, dtype=np.int8)
    kb = np.zeros(cap, dtype=np.int8)
    ch = np.ones(cap)
    sid = np.empty(cap, dtype=np.int64)
    p = 0
    for c in elems:
        i = c // 2
        if c % 2 == 0:
            if not _convex(tx, ty, i):
                continue
            # Circumscribed polygon about the arc at vertex i: from the tangent
            # point of the upslope normal (angle phi1) through m corners at the
            # mid angles (radius r / cos(delta/2)) to the tangent point of the
            # downslope normal (phi2). The angle decreases, so x increases.
            phi1, phi2, m = _arc_edges(tx[i - 1], ty[i - 1], tx[i], ty[i], max_chord)
            delta = (phi2 - phi1) / m
            half = np.cos(0.5 * delta)
            cx = np.cos(phi1)
            cy = np.sin(phi1)
            corner = 0
            for q in range(m + 1):
                if q < m:
                    ang = phi1 + (q + 0.5) * delta
                    nxq = np.cos(ang)
                    nyq = np.sin(ang)
                    nk = 1
                else:
                    nxq = np.cos(phi2)
                    nyq = np.sin(phi2)
                    nk = 0
                va[p] = i
                vb[p] = i
                uax[p] = cx
                uay[p] = cy
                ka[p] = corner
                ubx[p] = nxq
                uby[p] = nyq
                kb[p] = nk
                ch[p] = half
                # Edge q is tangent at phi1 + q*delta: the first half of the arc
                # takes the material of the upslope segment.
                sid[p] = seg_id[i - 1] if 2 * q < m else seg_id[i]
                p += 1
                cx = nxq
                cy = nyq
                corner = nk
            continue
        va[p] = i
        vb[p] = i + 1
        uax[p] = -ty[i]
        uay[p] = tx[i]
        ubx[p] = -ty[i]
        uby[p] = tx[i]
        sid[p] = seg_id[i]
        p += 1
    return va, uax, uay, ka, vb, ubx, uby, kb, ch, sid


@compiled
def _scaled_pieces(gx, gy, units, r):
    """The pieces of :func:`raw_pieces` for radius ``r`` (m) from :func:`_piece_units`."""
    va, uax, uay, ka, vb, ubx, uby, kb, ch, sid = units
    npc = va.shape[0]
    xa = np.empty(npc)
    ya = np.empty(npc)
    xb = np.empty(npc)
    yb = np.empty(npc)
    for p in range(npc):
        # A corner of an arc's polygon is at r / cos(delta / 2) from its vertex.
        sa = r / ch[p] if ka[p] else r
        sb = r / ch[p] if kb[p] else r
        xa[p] = gx[va[p]] + sa * uax[p]
        ya[p] = gy[va[p]] + sa * uay[p]
        xb[p] = gx[vb[p]] + sb * ubx[p]
        yb[p] = gy[vb[p]] + sb * uby[p]
    return xa, ya, xb, yb, sid


def element_codes(n: int) -> np.ndarray:
    """Codes of every element of a ground of ``n`` vertices (see :func:`raw_pieces`).

    ``2 i``: the arc at vertex ``i`` (none at the two ends of the ground
    itself, but :func:`sweep_centre_path` extends it); ``2 i + 1``: the offset of
    segment ``i``. In the order of the raw offset curve.
    """
    return np.arange(2 * n - 1, dtype=np.int64)


@compiled
def _grow(a, cap):
    b = np.empty(cap, dtype=a.dtype)
    b[: a.shape[0]] = a
    return b


@compiled
def _line_at(xa, ya, xb, yb, i, x):
    """Value of the line through piece i at x (extrapolated)."""
    return ya[i] + (yb[i] - ya[i]) * (x - xa[i]) / (xb[i] - xa[i])


@compiled
def _slope(xa, ya, xb, yb, i):
    return (yb[i] - ya[i]) / (xb[i] - xa[i])


#: Vertices on each side of a piece among which :func:`hidden_pieces` looks for one
#: whose circle hides the piece.
HIDE_WINDOW = 32


@compiled
def hidden_pieces(xa, ya, xb, yb, ex, ey, r, tol):
    """Pieces that lie below the circle of radius ``r`` about some ground vertex.

    The centre path is at or above the circle about every ground vertex
    within ``r`` (the sphere touching that vertex), so a piece below such a
    circle over its whole extent, by a margin, is never on the path: the
    sweep of :func:`centre_path` need not consider it. The circle minus a
    straight piece is concave, so the piece is below it everywhere when it
    is below at both ends. The vertices tried are the ``HIDE_WINDOW`` on
    either side of the foot of the piece's normal (the ground point that made
    it), nearest first (:func:`_hides`). On a dense, noisy survey most pieces
    are hidden so (the offsets and arcs of the points in the noise's
    hollows), and the sweep does a few lines per interval instead of hundreds.

    The margin keeps the sweep's choices exactly as without the test: a
    hidden piece is below the path by far more than the sweep's tie
    tolerances (1e-13 m in height, ``tol`` in x times slopes up to 1e5), so
    it would never have been chosen; pieces steeper than 100 are never
    hidden. The path is bit-identical (tests/engine/test_engine_survey.py).
    """
    npc = xa.shape[0]
    out = np.zeros(npc, dtype=np.bool_)
    j = 0
    for i in range(npc):
        out[i], j = _hides(xa[i], ya[i], xb[i], yb[i], ex, ey, r, tol, j)
    return out


@hot
def _search_from(a, v, j):
    """``np.searchsorted(a, v)`` (side left; ``a`` sorted, no NaN), looked for from index ``j``.

    Galloping out from ``j`` and then halving: a few steps when ``v`` falls
    near ``j``, as the feet of consecutive pieces do, where numba's
    searchsorted took about 40 ns a call.
    """
    n = a.shape[0]
    j = min(max(j, 0), n)
    step = 1
    if j < n and a[j] < v:
        # The index is above j.
        lo = j + 1
        while True:
            k = lo + step - 1
            if k >= n:
                hi = n
                break
            if a[k] < v:
                lo = k + 1
                step *= 2
            else:
                hi = k
                break
    else:
        # The index is j or below.
        hi = j
        while True:
            k = hi - step
            if k < 0:
                lo = 0
                break
            if a[k] < v:
                lo = k + 1
                break
            hi = k
            step *= 2
    # a[:lo] < v <= a[hi:]
    while lo < hi:
        mid = (lo + hi) >> 1
        if a[mid] < v:
            lo = mid + 1
        else:
            hi = mid
    return lo


@hot
def _hides(xa, ya, xb, yb, ex, ey, r, tol, j0):
    """Whether the piece from (xa, ya) to (xb, yb) (m) is below a vertex's circle.

    See :func:`hidden_pieces`.

    Returns that and ``j`` (below), to start the next piece's search from
    (``j0``: a guess, any index).

    ``ex``, ``ey``: the vertices (m), sorted by x. Those tried are the
    ``HIDE_WINDOW`` on each side of ``j``, the index where the foot of the
    piece's normal falls among them, nearest first: ``j - 1`` down to
    ``j - HIDE_WINDOW`` and ``j + 1`` up to ``j + HIDE_WINDOW`` (``j``
    itself is not tried, as it never was: the hidden pieces, and so the
    paths, stay what they were to the bit). A side is left at the first
    vertex that is ``r`` or more away from the piece's near end, in x: every
    vertex beyond is further (the differences are rounded monotonically), so
    none of them could hide it, and the answer is the one the whole window
    gives. On a noisy survey the pieces on the path, which nothing hides,
    used to try all 64 vertices; now the 10 to 20 within ``r``.
    """
    dx = xb - xa
    dy = yb - ya
    if dx <= 0.0 or abs(dy) > 100.0 * dx:
        return False, j0
    n = ex.shape[0]
    ln = np.hypot(dx, dy)
    m = 1e-9 * (1.0 + abs(ya) + abs(yb)) + 1e5 * tol
    r2 = r * r
    j = _search_from(ex, 0.5 * (xa + xb) + r * dy / ln, j0)
    lo_end = max(j - HIDE_WINDOW, 0)
    hi_end = min(j + HIDE_WINDOW, n - 1)
    ya_m = ya + m
    yb_m = yb + m
    # A vertex whose circle's top is not above both ends hides nothing (as
    # rounded: each root below is at most sqrt(r2), and a rounded sum grows
    # with its terms): no roots for it.
    top = max(ya_m, yb_m)
    sr = np.sqrt(r2)
    # The nearest two on each side first (where a hidden piece's vertex
    # mostly is), then the rest of each side in turn: the answer is whether
    # any hides it, whatever the order.
    for d in range(4):
        w = j - 1 - d // 2 if d % 2 == 0 else j + 1 + d // 2
        if lo_end <= w <= hi_end and _under(xa, xb, ex[w], ey[w], ya_m, yb_m, top, sr, r, r2):
            return True, j
    for w in range(j - 3, lo_end - 1, -1):
        if xb - ex[w] >= r:
            break  # the vertices further left are further from xb
        if _under(xa, xb, ex[w], ey[w], ya_m, yb_m, top, sr, r, r2):
            return True, j
    for w in range(j + 3, hi_end + 1):
        if xa - ex[w] <= -r:
            break  # the vertices further right are further from xa
        if _under(xa, xb, ex[w], ey[w], ya_m, yb_m, top, sr, r, r2):
            return True, j
    return False, j


@hot
def _under(xa, xb, vx, vy, ya_m, yb_m, top, sr, r, r2):
    """The test of :func:`_hides` for one vertex (vx, vy) (m)."""
    if vy + sr <= top:
        return False
    da = xa - vx
    db = xb - vx
    return abs(da) < r and abs(db) < r and vy + np.sqrt(r2 - da * da) > ya_m and \
        vy + np.sqrt(r2 - db * db) > yb_m


#: Most edges of a vertex arc for which :func:`visible_pieces` finds the
#: corners by turning a vector (the rounding it adds grows with the turns).
_MAX_TURNS = 100_000


@hot
def _surely_hidden(xa, ya, xb, yb, s, ex, ey, r, tol, j0):
    """Whether :func:`_hides` holds, for sure, for a piece near (xa, ya)-(xb, yb).

    True only if :func:`_hides` gives True for every piece whose ends are
    within ``s`` (m) of these in each coordinate, as rounded in floating
    point (:func:`_surely_under`). Tries the two nearest vertices on each
    side (where a hidden piece's vertex is, 99 % of the time on a noisy
    survey); False means "not known", not "not hidden". Also returns where
    the foot falls among ``ex`` (from ``j0``, as :func:`_hides`).
    """
    if not _surely_gentle(xa, ya, xb, yb, s):
        return False, j0
    n = ex.shape[0]
    dx = xb - xa
    dy = yb - ya
    ln = np.sqrt(dx * dx + dy * dy)
    # The foot of the normal moves by s and by r times the turn of the piece
    # (at most 3 s / ln rad); the window is the one of every foot in between.
    foot = 0.5 * (xa + xb) + r * dy / ln
    sf = 2.0 * s + 8.0 * r * s / ln
    jlo = _search_from(ex, foot - sf, j0)
    jhi = _search_from(ex, foot + sf, jlo)
    mp = _surely_margin(ya, yb, s, tol)
    r2 = r * r
    for d in range(4):
        w = _candidate(d, jlo, jhi, n)
        if w >= 0 and _surely_under(xa, ya, xb, yb, s, ex[w], ey[w], r, r2, mp):
            return True, jlo
    return False, jlo


@hot
def _surely_gentle(xa, ya, xb, yb, s):
    """Whether a piece with ends within ``s`` of these passes :func:`_hides`'s first test.

    That is, runs to the right (``dx > 0``) and is no steeper than 100.
    """
    dxl = (xb - xa) - 4.0 * s
    dyh = abs(yb - ya) + 4.0 * s
    return dxl > 0.0 and dyh <= 100.0 * dxl


@hot
def _surely_margin(ya, yb, s, tol):
    """At least :func:`_hides`'s margin ``m`` for a piece with ends within ``s`` of these."""
    return 1e-9 * (1.0 + (abs(ya) + 2.0 * s) + (abs(yb) + 2.0 * s)) + 1e5 * tol


@hot
def _candidate(d, jlo, jhi, n):
    """The ``d``-th nearest vertex to the feet's range ``[jlo, jhi]``, or -1.

    Even ``d`` on the left, odd on the right (:func:`_surely_hidden` tries
    ``d`` 0 to 3), if in the window of :func:`_hides` for every ``j`` in the
    range (and not ``j`` itself).
    """
    w = jlo - 1 - d // 2 if d % 2 == 0 else jhi + 1 + d // 2
    if w < 0 or w >= n or w < jhi - HIDE_WINDOW or w > jlo + HIDE_WINDOW:
        return -1
    return w


@hot
def _surely_under(xa, ya, xb, yb, s, vx, vy, r, r2, mp):
    """Whether :func:`_under` holds for every piece with ends within ``s`` (m) of these.

    Each quantity of its test is taken at its least favourable (``2 s``
    more or less: the ends' error and the roundings, which are far below
    ``s``), with ``mp`` at least its margin (:func:`_surely_margin`), and
    every step of the test rounds monotonically (a rounded sum, product or
    root grows with its terms), so what holds here holds there.
    """
    dah = abs(xa - vx) + 2.0 * s
    dbh = abs(xb - vx) + 2.0 * s
    return dah < r and dbh < r and vy + np.sqrt(r2 - dah * dah) > (ya + 2.0 * s) + mp and \
        vy + np.sqrt(r2 - dbh * dbh) > (yb + 2.0 * s) + mp


#: Most vertices an arc's middle edges are tried against (:func:`visible_pieces`).
_ARC_CANDIDATES = 6


@hot
def _surely_by(xa, ya, xb, yb, s, hx, hy, r, r2, mp, cand, nc):
    """Whether one of the vertices ``cand[:nc]`` surely hides the piece (:func:`_surely_under`)."""
    for k in range(nc):
        w = cand[k]
        if _surely_under(xa, ya, xb, yb, s, hx[w], hy[w], r, r2, mp):
            return True
    return False


@hot
def _highest_within(hx, hy, cx, r, jlo, jhi, side):
    """The highest of the nearest 16 vertices on a side of ``[jlo, jhi]`` within ``r`` of ``cx``.

    ``side`` 0 left, 1 right; only vertices in the window of :func:`_hides`
    for every foot in the range (:func:`_candidate`); -1 if none. Where an
    arc is in a hollow of the noise, the top beside it whose circle hides it.
    """
    n = hx.shape[0]
    w = -1
    for k in range(16):
        v = _candidate(2 * k + side, jlo, jhi, n)
        if v < 0 or abs(hx[v] - cx) >= r:
            break
        if w < 0 or hy[v] > hy[w]:
            w = v
    return w


@compiled
def visible_pieces(gx, gy, seg_id, r, max_chord, elems, prune, tol):
    """The pieces of :func:`raw_pieces` that :func:`hidden_pieces` does not hide.

    The same arrays, to the bit, as ``raw_pieces(gx, gy, seg_id, r,
    max_chord, elems)`` less the pieces ``hidden_pieces`` marks (tried against the
    vertices whose arcs are in ``elems``), in the same order; every piece if
    not ``prune``. On a dense noisy survey most pieces are the edges of the
    arcs of vertices in the noise's hollows, hidden by their neighbours'
    circles (93 % of 176,790 pieces on 100,000 points): making them took a
    cosine and a sine a corner. Here an arc's corners are first found
    roughly, by turning a unit vector through the arc's angle step (a
    rounding of about 1e-16 a turn, far below ``s`` = 1e-9 (1 + |x| + |y| +
    r) m), and an edge that is hidden even so, for sure
    (:func:`_surely_under`), is left out without its exact corners: whatever
    they are, ``hidden_pieces`` hides it. The others are made exactly as
    ``raw_pieces`` makes them and tried exactly (:func:`_hides`).

    The edges between two corners are tangent to the circle of radius ``r``
    about the vertex at their middles, so the foot of their normals is the
    vertex itself (to round-off): the vertices tried for them are found once
    an arc.
    """
    tx, ty = _unit_tangents(gx, gy, elems)
    nh = 0
    for c in elems:
        nh += 1 - c % 2
    # The vertices whose circles hide pieces: those whose arcs are given.
    hx = np.empty(nh)
    hy = np.empty(nh)
    # Each arc's angles and edges, found once.
    aphi1 = np.empty(nh)
    aphi2 = np.empty(nh)
    am = np.zeros(nh, dtype=np.int64)  # 0: no arc (not convex)
    nh = 0
    cap = 0
    for c in elems:
        i = c // 2
        if c % 2:
            cap += 1
            continue
        hx[nh] = gx[i]
        hy[nh] = gy[i]
        if _convex(tx, ty, i):
            aphi1[nh], aphi2[nh], am[nh] = _arc_edges(tx[i - 1], ty[i - 1], tx[i], ty[i],
                                                      max_chord)
            cap += am[nh] + 1
        nh += 1
    xa = np.empty(cap)
    ya = np.empty(cap)
    xb = np.empty(cap)
    yb = np.empty(cap)
    sid = np.empty(cap, dtype=np.int64)
    p = 0
    j = 0  # where the last piece's foot fell among hx
    hid = False
    r2 = r * r
    kv = -1  # the arc's index among hx
    cand = np.empty(_ARC_CANDIDATES, dtype=np.int64)
    for c in elems:
        i = c // 2
        if c % 2 == 1:
            nx = -ty[i]
            ny = tx[i]
            x0 = gx[i] + r * nx
            y0 = gy[i] + r * ny
            x1 = gx[i + 1] + r * nx
            y1 = gy[i + 1] + r * ny
            if prune:
                hid, j = _hides(x0, y0, x1, y1, hx, hy, r, tol, j)
            if not (prune and hid):
                xa[p] = x0
                ya[p] = y0
                xb[p] = x1
                yb[p] = y1
                sid[p] = seg_id[i]
                p += 1
            continue
        kv += 1
        m = am[kv]
        if m == 0:
            continue
        # The arc's polygon as raw_pieces makes it: from the tangent point at
        # phi1 through m corners at phi1 + (q + 0.5) delta, radius rc, to the
        # tangent point at phi2.
        phi1 = aphi1[kv]
        phi2 = aphi2[kv]
        delta = (phi2 - phi1) / m
        rc = r / np.cos(0.5 * delta)
        cx = gx[i]
        cy = gy[i]
        s = 1e-9 * (1.0 + abs(cx) + abs(cy) + rc)
        rough = prune and m <= _MAX_TURNS and abs(delta) < 1.0
        nc = 0
        tops = False  # the highest vertices on each side are among the candidates
        if rough and m >= 2:
            # The feet of the middle edges are within h of the vertex (the
            # rounding of their ends, over their length of at least r |delta|):
            # the vertices in the window of every one of them are tried, the
            # nearest two on each side first.
            h = 2.0 * s + 16.0 * s / abs(delta)
            jlo = _search_from(hx, cx - h, kv)
            jhi = _search_from(hx, cx + h, jlo)
            for d in range(4):
                w = _candidate(d, jlo, jhi, nh)
                if w >= 0:
                    cand[nc] = w
                    nc += 1
        cd = np.cos(delta)
        sd = np.sin(delta)
        # The corner ahead, roughly (exact for the first): its unit vector.
        cu = np.cos(phi1 + (0 + 0.5) * delta)
        su = np.sin(phi1 + (0 + 0.5) * delta)
        # The start of the edge: exact (x_prev, y_prev) if known, else rough.
        x_prev = cx + r * np.cos(phi1)
        y_prev = cy + r * np.sin(phi1)
        exact_prev = True
        for q in range(m + 1):
            if q < m:
                x_next = cx + rc * cu
                y_next = cy + rc * su
                exact_next = q == 0
                cu, su = cu * cd - su * sd, su * cd + cu * sd
            else:
                x_next = cx + r * np.cos(phi2)
                y_next = cy + r * np.sin(phi2)
                exact_next = True
            hid = False
            if rough:
                if 0 < q < m:
                    if _surely_gentle(x_prev, y_prev, x_next, y_next, s):
                        mp = _surely_margin(y_prev, y_next, s, tol)
                        hid = _surely_by(x_prev, y_prev, x_next, y_next, s, hx, hy, r, r2, mp,
                                         cand, nc)
                        if not hid and not tops:
                            # Then the highest within reach on each side,
                            # tried first from now on: they hide the arc's
                            # edges beyond the neighbours' reach.
                            tops = True
                            n0 = nc
                            for side in range(2):
                                w = _highest_within(hx, hy, cx, r, jlo, jhi, side)
                                for k in range(nc):
                                    if cand[k] == w:
                                        w = -1
                                if w >= 0:
                                    cand[nc] = cand[nc - n0]
                                    cand[nc - n0] = w
                                    nc += 1
                            hid = _surely_by(x_prev, y_prev, x_next, y_next, s, hx, hy, r, r2,
                                             mp, cand, nc - n0)
                else:
                    hid, j = _surely_hidden(x_prev, y_prev, x_next, y_next, s, hx, hy, r,
                                            tol, j)
            if hid:
                x_prev = x_next
                y_prev = y_next
                exact_prev = exact_next
                continue
            if not exact_prev:
                ang = phi1 + ((q - 1) + 0.5) * delta
                x_prev = cx + rc * np.cos(ang)
                y_prev = cy + rc * np.sin(ang)
            if not exact_next:
                ang = phi1 + (q + 0.5) * delta
                x_next = cx + rc * np.cos(ang)
                y_next = cy + rc * np.sin(ang)
            if prune:
                hid, j = _hides(x_prev, y_prev, x_next, y_next, hx, hy, r, tol, j)
            if not hid:
                xa[p] = x_prev
                ya[p] = y_prev
                xb[p] = x_next
                yb[p] = y_next
                sid[p] = seg_id[i - 1] if 2 * q < m else seg_id[i]
                p += 1
            x_prev = x_next
            y_prev = y_next
            exact_prev = True
    return xa[:p].copy(), ya[:p].copy(), xb[:p].copy(), yb[:p].copy(), sid[:p].copy()


@compiled
def stable_order(a):
    """``np.argsort(a, kind="mergesort")`` (stable), fast when ``a`` is nearly sorted.

    An insertion sort, whose work is the number of pairs out of order: the
    pieces of a function graph's offset, and their ends, come nearly in
    order of x (numba's merge sort took about 30 ns an element on them). If
    the pairs out of order pass 16 per element, the merge sort instead.
    Ties keep their order, as in any stable sort, so the result is the
    merge sort's.
    """
    n = a.shape[0]
    idx = np.empty(n, dtype=np.int64)
    key = np.empty(n)
    budget = 16 * n + 64
    for i in range(n):
        v = a[i]
        k = i
        while k > 0 and key[k - 1] > v:
            key[k] = key[k - 1]
            idx[k] = idx[k - 1]
            k -= 1
        key[k] = v
        idx[k] = i
        budget -= i - k
        if budget < 0:
            return _merge_order(a)
    return idx


@compiled
def _merge_order(a):
    """``np.argsort(a, kind="mergesort")``: a bottom-up merge sort of the indices.

    Stable (of two equal keys the earlier comes first), so for keys without
    NaN the order is the one ``np.argsort`` gives with any stable kind
    (tests/engine/test_engine_survey.py). Written out rather than numba's
    own: its merge sort cost about a tenth of the centre path's first
    compile (2.3 s of CPU of 42.7, numba's compile events, docs/speed.md).
    """
    n = a.shape[0]
    idx = np.arange(n)
    tmp = np.empty(n, dtype=np.int64)
    # Runs of 16 sorted by insertion first (stable: only a strictly greater
    # key moves up), as numba's and numpy's merge sorts do: small merges
    # cost more than they save.
    width = 16
    for lo in range(0, n, width):
        for i in range(lo + 1, min(lo + width, n)):
            v = idx[i]
            k = i
            while k > lo and a[idx[k - 1]] > a[v]:
                idx[k] = idx[k - 1]
                k -= 1
            idx[k] = v
    while width < n:
        for lo in range(0, n, 2 * width):
            mid = min(lo + width, n)
            hi = min(lo + 2 * width, n)
            i = lo
            j = mid
            for k in range(lo, hi):
                # The right one only if strictly smaller: ties keep their order.
                if j < hi and (i >= mid or a[idx[j]] < a[idx[i]]):
                    tmp[k] = idx[j]
                    j += 1
                else:
                    tmp[k] = idx[i]
                    i += 1
        idx, tmp = tmp, idx
        width *= 2
    return idx


@compiled
def centre_path(gx, gy, seg_mat, r, max_chord):
    """Centre path of a sphere of radius ``r`` on the ground (:func:`sweep_centre_path`)."""
    return sweep_centre_path(gx, gy, seg_mat, r, max_chord, True,
                             np.arange(2 * gx.shape[0] - 1), False)


@compiled(nogil=True)
def survey_path(gx, gy, seg_mat, r, max_chord, elems):
    """Centre path of radius ``r`` (m) made of the ground elements ``elems`` only.

    The path of :func:`centre_path`, from the offsets of the segments and
    the arcs of the vertices in ``elems`` (sorted codes, see
    :func:`element_codes`), with crossings found from the pieces alone
    (``canon`` of :func:`sweep_centre_path`). When ``elems`` holds every element
    that can be on the path (:func:`path_elements`), it is the same, to the
    bit, as this function over every element
    (tests/engine/test_engine_survey.py): on a dense noisy survey a rock of a
    size of its own then costs the sweep over the tops of the noise instead
    of over every point.
    """
    return sweep_centre_path(gx, gy, seg_mat, r, max_chord, True, elems, True)


def path_elements(gx: np.ndarray, gy: np.ndarray, r_min: float, r_max: float,
                  max_chord: float) -> np.ndarray:
    """The ground elements the centre path of any radius in [r_min, r_max] can lie on.

    Parameters
    ----------
    gx, gy : ndarray of float, shape (n,)
        Ground vertices (m).
    r_min, r_max : float
        Smallest and largest rock radius (m), ``0 < r_min <= r_max``.
    max_chord : float
        Largest turn (rad) of an edge of a vertex arc, as in :func:`centre_path`.

    Returns
    -------
    ndarray of int64
        Sorted codes (:func:`element_codes`) of the segment offsets and vertex
        arcs to give :func:`survey_path`.

    Notes
    -----
    Let ``U_r`` be the union of the discs of radius ``r`` above the ground
    whose inside is free of it (where rocks of radius ``r`` reach). A disc of
    radius ``R > r`` free of ground is the union of discs of radius ``r``
    free of ground, so ``U_R`` lies in ``U_r``, and a ground point's distance
    to ``U_r`` is at most its distance to ``U_R`` (the inclusion of openings
    by growing discs, Serra 1982). A segment's offset is on the path of
    radius ``R`` only where a free disc touches the segment (distance 0 to
    ``U_R``), and an edge of a vertex's arc only if a free disc comes
    within ``R (s - 1)`` of the vertex (the edges are circumscribed, their
    corners at ``R s`` from it, ``s = 1 / cos(max_chord / 2)``); so either
    happens only for ground within ``0`` resp. ``r_max (s - 1)`` of
    ``U_{r_min}``, that is, within ``r_min`` resp. ``r_min + r_max (s - 1)``
    of the free centres of radius ``r_min``. Those lie above the path of
    radius ``r_min / s`` (whose arcs are at most ``r_min`` from their
    vertices), so the offsets kept are those of the segments within
    ``r_min`` of that path, and the arcs those of the vertices within
    ``r_min + r_max (s - 1)`` of it, with a margin for round-off, and all
    near the section's ends (where the nearest free centre may lie beyond
    them). This keeps every element that can be on the path of any radius
    in the range, though not only those, for the circumscribed arcs as for
    true circles: choosing by the path of ``r_min`` alone misses some where
    an arc's corners stand out (tests/engine/test_engine_survey.py).

    References
    ----------
    Serra, J. (1982). Image Analysis and Mathematical Morphology. Academic
    Press (openings by discs; granulometries).
    """
    # One compiled variant of near_path for every caller (read-only or
    # strided arrays would each compile one of their own, see jit.writable).
    gx, gy = writable(gx, np.float64), writable(gy, np.float64)
    n = gx.shape[0]
    s = 1.0 / np.cos(0.5 * max_chord)
    every = element_codes(n)
    px, py, _ = survey_path(gx, gy, np.arange(n - 1), r_min / s, max_chord, every)
    scale = max(abs(gx[0]), abs(gx[-1]), abs(gy).max(), 1.0)
    margin = 1e-9 * (scale + r_max)
    reach_vtx = r_min + r_max * (s - 1.0) + margin
    keep = near_path(gx, gy, px, py, r_min + margin, reach_vtx)
    # Every element near the ends: the vertices within reach_vtx of them,
    # and the segments that start (end) there.
    first = np.flatnonzero(gx <= gx[0] + reach_vtx)[-1]
    last = np.flatnonzero(gx >= gx[-1] - reach_vtx)[0]
    keep[: 2 * first + 2] = True
    keep[max(2 * last - 1, 0):] = True
    return every[keep]


@compiled(nogil=True)
def near_path(gx, gy, px, py, reach_seg, reach_vtx):
    """Which elements (:func:`element_codes`) are near the polyline (px, py).

    A vertex within ``reach_vtx`` of it (m), its arc; a segment within
    ``reach_seg``, its offset. See :func:`path_elements`.
    """
    n = gx.shape[0]
    npc = px.shape[0] - 1
    keep = np.zeros(2 * n - 1, dtype=np.bool_)
    # A piece of the path higher than a ground point by more than the reach
    # (and the roundings of _dist2, far less than eps) is further from it: no
    # distance to work out. Most ground points of a noisy survey are in
    # hollows, below a few tens of pieces of the path (100,000 points).
    eps = 1e-9 * (1.0 + reach_seg + reach_vtx + np.abs(gy).max() + np.abs(py).max())
    rv2 = reach_vtx * reach_vtx
    k0 = 0
    for v in range(n):
        lo = max(_search_from(px, gx[v] - reach_vtx, k0) - 1, 0)
        hi = min(_search_from(px, gx[v] + reach_vtx, lo), npc)
        k0 = lo
        far = gy[v] + (reach_vtx + eps)
        for k in range(lo, hi):
            if min(py[k], py[k + 1]) > far:
                continue
            if _dist2(gx[v], gy[v], px[k], py[k], px[k + 1], py[k + 1]) <= rv2:
                keep[2 * v] = True
                break
    r2 = reach_seg * reach_seg
    k0 = 0
    for i in range(n - 1):
        lo = max(_search_from(px, gx[i] - reach_seg, k0) - 1, 0)
        hi = min(_search_from(px, gx[i + 1] + reach_seg, lo), npc)
        k0 = lo
        far = max(gy[i], gy[i + 1]) + (reach_seg + eps)
        for k in range(lo, hi):
            if min(py[k], py[k + 1]) > far:
                continue
            # Two segments that do not cross (the path is above the ground):
            # their distance is that of an end of one to the other.
            if (_dist2(px[k], py[k], gx[i], gy[i], gx[i + 1], gy[i + 1]) <= r2
                    or _dist2(px[k + 1], py[k + 1], gx[i], gy[i], gx[i + 1], gy[i + 1]) <= r2
                    or _dist2(gx[i], gy[i], px[k], py[k], px[k + 1], py[k + 1]) <= r2
                    or _dist2(gx[i + 1], gy[i + 1], px[k], py[k], px[k + 1], py[k + 1]) <= r2):
                keep[2 * i + 1] = True
                break
    return keep


@compiled
def _dist2(x, y, ax, ay, bx, by):
    """Squared distance (m^2) of the point (x, y) to the segment from (ax, ay) to (bx, by)."""
    dx = bx - ax
    dy = by - ay
    ln2 = dx * dx + dy * dy
    t = 0.0 if ln2 <= 0.0 else min(max(((x - ax) * dx + (y - ay) * dy) / ln2, 0.0), 1.0)
    ex = ax + t * dx - x
    ey = ay + t * dy - y
    return ex * ex + ey * ey


@compiled
def sweep_centre_path(gx, gy, seg_mat, r, max_chord, prune, elems, canon):
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
        (:func:`hidden_pieces`); the result is the same, found faster on dense
        surveys. False only to test that.
    elems : ndarray of int
        Sorted codes of the ground elements (segment offsets, vertex arcs;
        :func:`element_codes`) that make the path: every one
        (``np.arange(2 n - 1)``) but in :func:`survey_path`.
    canon : bool
        Find where two pieces' lines cross from the two pieces alone, not
        from where the sweep stands: the path then does not depend on
        pieces that are not on it (their ends are breakpoints of the sweep),
        so that :func:`survey_path` over fewer segments gives it to the bit.
        False keeps the crossings of earlier versions (the results of
        sections of few points stay as they were).

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
    convex). Pieces hidden below a vertex's circle (:func:`hidden_pieces`) are
    left out of the walk; every piece's ends stay breakpoints.
    """
    return centre_path_of(gx, gy, seg_mat, r, max_chord, prune, elems, canon, no_units())


@compiled
def _extended(gx, gy, r, elems):
    """The profile extended level beyond both ends by ``2 r + 1`` (m), and its elements.

    Returns ``ex, ey`` (n + 2 vertices), ``eseg`` (the ground segment of
    each of its n + 1 segments) and ``ecodes``: the offsets of the two level
    extensions and ``elems`` (a vertex and a segment further on: code + 2).
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
    ecodes = np.empty(elems.shape[0] + 2, dtype=np.int64)
    ecodes[0] = 1
    ecodes[1:-1] = elems + 2
    ecodes[-1] = 2 * n + 1
    return ex, ey, eseg, ecodes


@compiled
def no_units():
    """Empty :func:`_piece_units`: :func:`centre_path_of` makes them itself."""
    e = np.empty(0, dtype=np.int64)
    f = np.empty(0)
    k = np.empty(0, dtype=np.int8)
    return e, f, f, k, e, f, f, k, f, e


@compiled(nogil=True)
def every_piece_units(gx, gy, max_chord):
    """:func:`_piece_units` of the whole extended profile, for every radius at once.

    A run's rocks of sizes of their own on a section of few points each make
    their path from these (:func:`centre_path_of`), made once per batch: the
    trigonometry of the arcs is most of a small section's path.
    """
    ex, ey, eseg, ecodes = _extended(gx, gy, 1.0, np.arange(2 * gx.shape[0] - 1))
    return _piece_units(ex, ey, eseg, max_chord, ecodes)


@compiled
def centre_path_of(gx, gy, seg_mat, r, max_chord, prune, elems, canon, units):
    """:func:`sweep_centre_path`, from the pieces' ``units`` when given (not ``canon``).

    ``units``: :func:`every_piece_units` of this ground and ``max_chord``
    (``elems`` then every element), or :func:`no_units`.
    """
    n = gx.shape[0]
    ex, ey, eseg, ecodes = _extended(gx, gy, r, elems)
    scale = max(abs(gx[0]), abs(gx[n - 1]), 1.0)
    tol = _EPS_X * scale
    if canon:
        # Only the pieces not hidden (by the circles of the vertices whose
        # arcs are given: any ground vertex's circle is below the path, and
        # the path does not depend on which pieces are hidden when canon). Of
        # the elements path_elements keeps, those are the tops the path
        # touches, which hide a piece within a vertex or two, where among
        # every vertex the nearest would be those in the hollows between.
        xa, ya, xb, yb, sid = visible_pieces(ex, ey, eseg, r, max_chord, ecodes, prune, tol)
        npc = xa.shape[0]
        hidden = np.zeros(npc, np.bool_)
    else:
        if units[0].shape[0] == 0:
            units = _piece_units(ex, ey, eseg, max_chord, ecodes)
        xa, ya, xb, yb, sid = _scaled_pieces(ex, ey, units, r)
        npc = xa.shape[0]
        hidden = hidden_pieces(xa, ya, xb, yb, ex, ey, r, tol) if prune else np.zeros(npc, np.bool_)

    # Breakpoints: all piece ends inside the section (canon: of the pieces not
    # hidden, since the path does not depend on the others'), and the section ends.
    bp = np.empty(2 * npc + 2)
    nb = 0
    for i in range(npc):
        if canon and hidden[i]:
            continue
        if gx[0] < xa[i] < gx[n - 1]:
            bp[nb] = xa[i]
            nb += 1
        if gx[0] < xb[i] < gx[n - 1]:
            bp[nb] = xb[i]
            nb += 1
    bp[nb] = gx[0]
    bp[nb + 1] = gx[n - 1]
    nb += 2
    # numba's np.sort (quicksort) takes ~1 us per element on these nearly
    # sorted breakpoints with many repeats; a stable sort gives the same values.
    bp = bp[:nb]
    bp = bp[stable_order(bp)]
    # Remove breakpoints closer than round-off.
    ub = np.empty(nb)
    nu = 0
    for i in range(nb):
        if nu == 0 or bp[i] - ub[nu - 1] > tol:
            ub[nu] = bp[i]
            nu += 1
    ub[nu - 1] = gx[n - 1]

    if canon:
        # The pieces (none hidden) in order of xa; stable, so that pieces that
        # start at the same x keep the order of the raw offset curve whatever
        # other pieces are there.
        order = stable_order(xa)
    else:
        order = np.argsort(xa)
    nord = order.shape[0]
    active = np.empty(npc, dtype=np.int64)
    nact = 0
    nxt = 0  # next piece (in order of xa) not yet activated

    cap = 4 * nu + 16
    ox = np.empty(cap)
    oy = np.empty(cap)
    oseg = np.empty(cap, dtype=np.int64)
    otop = np.empty(cap, dtype=np.int64)  # the piece each stretch lies on
    no = 0

    for b in range(nu - 1):
        x0 = ub[b]
        x1 = ub[b + 1]
        xm = 0.5 * (x0 + x1)
        # Activate pieces starting at or before the midpoint; drop those ended.
        while nxt < nord and xa[order[nxt]] <= xm:
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
            otop = _grow(otop, cap)
        ox[no] = x0
        oy[no] = vtop
        oseg[no] = sid[top]
        otop[no] = top
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
                # Crossing of line i with the top line, from where the sweep
                # stands, or (canon) from where both pieces begin.
                xr = max(xa[top], xa[i]) if canon else xc
                d = _line_at(xa, ya, xb, yb, top, xr) - _line_at(xa, ya, xb, yb, i, xr)
                xi = xr + d / (ki - kt)
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
                otop[no] = best
                no += 1
            else:
                oseg[no - 1] = sid[best]
                otop[no - 1] = best
            top = best
            xc = max(bx, xc)
    # Last point: the value at the right end of the section.
    xe = ub[nu - 1]
    ve = -np.inf
    for q in range(nact):
        v = _line_at(xa, ya, xb, yb, active[q], xe)
        if v > ve:
            ve = v
    if canon and nact > 0:
        # The last top line's value (another line may be up to round-off higher).
        ve = _line_at(xa, ya, xb, yb, top, xe)
    ox[no] = xe
    oy[no] = ve
    no += 1

    if canon:
        # Stretches of one piece, cut by the ends of other pieces, made one
        # first: the test of slopes below then sees whole pieces, and does
        # not depend on where pieces that are not on the path end (a short
        # stretch just past a corner would pass it).
        k = 1
        for i in range(1, no):
            if i < no - 1 and otop[i] == otop[i - 1]:
                continue
            ox[k] = ox[i]
            oy[k] = oy[i]
            oseg[k] = oseg[i]
            otop[k] = otop[i]
            k += 1
        no = k

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

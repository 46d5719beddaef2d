"""The engine on dense surveys (issue 27, item 8).

``flight.next_landing`` skips the blocks of the centre path that a flight
clears (``flight.path_tree``), ``profile.centre_path`` leaves out of its
sweep the pieces a vertex's circle hides (``profile.hidden_pieces``), and the
path of a rock of a size of its own is made from the ground elements that
the paths of the run's radii can lie on (``profile.path_elements``,
``profile.survey_path``); these tests hold them to the plain versions over
random noisy surveys: the same piece, time and path, to the bit.
"""

from __future__ import annotations

import os

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rockfall_design.engine import G, Material, Releases, Section, run_ensemble
from rockfall_design.engine.batching import BATCH_SECONDS, Batches
from rockfall_design.engine.flight import (
    LINEAR_PIECES,
    first_not_cleared,
    locate,
    next_landing,
    path_tree,
)
from rockfall_design.engine.profile import (
    HIDE_WINDOW,
    centre_path,
    element_codes,
    hidden_pieces,
    near_path,
    path_elements,
    raw_pieces,
    stable_order,
    survey_path,
    sweep_centre_path,
    visible_pieces,
)

SETTINGS = settings(
    max_examples=int(os.environ.get("RF_EXAMPLES", "40")),
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)

STANDARD = np.array([(0, 100), (30, 60), (60, 30), (80, 20), (120, 15), (200, 12)], float)


def noisy_survey(n: int, noise: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """``n`` points of the standard slope, heights with N(0, noise) errors (m)."""
    rng = np.random.default_rng(seed)
    x = np.linspace(0.0, 200.0, n)
    return x, np.interp(x, STANDARD[:, 0], STANDARD[:, 1]) + rng.normal(0.0, noise, n)


def walk(px, py, x0, y0, vx, vy, k):
    """The landing by the plain walk, piece by piece (the engine before the tree)."""
    with np.errstate(all="ignore"):  # a vx of 1e-300 overflows, as in the engine
        return _walk(px, py, x0, y0, vx, vy, k)


def _walk(px, py, x0, y0, vx, vy, k):
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
        return False, min(max(t, t_in), t_out), k


def _path(n: int, noise: float, seed: int, r: float):
    x, y = noisy_survey(n, noise, seed)
    px, py, _ = centre_path(x, y, np.arange(n - 1), r, np.radians(5.0))
    return px, py, path_tree(px, py)


@SETTINGS
@given(
    n=st.sampled_from([6, 40, 300, 3000]),
    noise=st.sampled_from([0.0, 0.01, 0.3]),
    seed=st.integers(0, 2**16),
    r=st.sampled_from([0.05, 0.5, 2.0]),
    flights=st.lists(
        st.tuples(st.floats(0.0, 1.0), st.floats(0.0, 30.0), st.floats(-40.0, 40.0),
                  st.floats(-30.0, 30.0)),
        min_size=1, max_size=20),
)
def test_the_tree_finds_the_landing_of_the_plain_walk(n, noise, seed, r, flights):
    px, py, tree = _path(n, noise, seed, r)
    for u, h, vx, vy in flights:
        x0 = px[0] + u * (px[-1] - px[0])
        k = locate(px, x0, vx)
        y0 = py[k] + (py[k + 1] - py[k]) * (x0 - px[k]) / (px[k + 1] - px[k]) + h
        assert next_landing(px, py, tree, x0, y0, vx, vy, k) == walk(px, py, x0, y0, vx, vy, k)


@SETTINGS
@given(
    seed=st.integers(0, 2**16),
    v=st.integers(0, 2999),
    dirn=st.sampled_from([1, -1]),
    x0=st.floats(0.0, 200.0),
    y0=st.floats(0.0, 140.0),
    vx=st.floats(0.5, 40.0),
    vy=st.floats(-20.0, 20.0),
)
def test_the_first_vertex_not_cleared_is_the_first_by_brute_force(seed, v, dirn, x0, y0, vx,
                                                                  vy):
    # Every vertex the tree skips is cleared, and the one it stops at is not
    # cleared by the margin (or is the first not cleared at all).
    px, py, tree = _path(3000, 0.01, seed, 0.5)
    nv = px.size
    v = min(v, nv - 1)
    vx = vx * dirn
    got = first_not_cleared(px, tree, nv, v, dirn, x0, y0, vx, vy)
    t = (px - x0) / vx
    above = y0 + t * (vy - 0.5 * G * t) > py
    skipped = range(v, got) if dirn > 0 else range(got + 1, v + 1)
    assert all(above[j] for j in skipped)
    if 0 <= got < nv:
        # Not cleared by a margin: the exact test decides there.
        assert (y0 + t[got] * (vy - 0.5 * G * t[got])) - py[got] < 1e-6 * (1 + abs(py[got]))


def test_flights_over_a_dense_survey_walk_blocks_not_pieces():
    # A long flight over 30,000 survey points passes thousands of pieces; it
    # must still land where the plain walk lands.
    px, py, tree = _path(30_000, 0.01, 1, 0.5)
    assert px.size > 50 * LINEAR_PIECES
    x0, vx, vy = 1.0, 25.0, 5.0
    k = locate(px, x0, vx)
    y0 = py[k] + 20.0
    fast = next_landing(px, py, tree, x0, y0, vx, vy, k)
    assert fast == walk(px, py, x0, y0, vx, vy, k)
    assert fast[2] - k > 1000


def test_runs_on_a_noisy_survey_are_the_same_on_one_and_two_threads():
    x, y = noisy_survey(5000, 0.01, 3)
    sec = Section(x, y, np.zeros(x.size - 1, dtype=int),
                  (Material(impact_model="rn_rt", restitution=0.35,
                            tangential_restitution=0.85, friction=0.58,
                            rolling_resistance=0.3, roughness_deg=5),))
    n = 64
    g = np.random.default_rng(0)
    rel = Releases(radius=g.choice([0.4, 0.5], n), density=2650.0, x=np.full(n, 1.0),
                   height=np.zeros(n), vx=np.full(n, 0.6), vy=np.full(n, -0.8),
                   spin=np.zeros(n), spin_rolling=np.zeros(n, dtype=bool))
    one = run_ensemble(sec, rel, key=5, threads=1, batch_size=7)
    two = run_ensemble(sec, rel, key=5, threads=2, batch_size=16)
    for name in ("status", "x_end", "y_end", "n_events", "max_x", "grid_height"):
        np.testing.assert_array_equal(getattr(one, name), getattr(two, name))
    assert (one.x_end > 100.0).any()


@SETTINGS
@given(
    n=st.sampled_from([8, 200, 1500]),
    noise=st.sampled_from([0.0, 0.003, 0.01, 0.3]),
    seed=st.integers(0, 2**16),
    r=st.sampled_from([0.01, 0.05, 0.5, 2.0]),
    chord=st.sampled_from([1.0, 5.0, 20.0]),
    canon=st.booleans(),
)
def test_leaving_hidden_pieces_out_keeps_the_centre_path_to_the_bit(n, noise, seed, r, chord,
                                                                   canon):
    # The sweep leaves out the pieces a vertex's circle hides (profile.hidden_pieces),
    # and (canon) their ends as breakpoints; the path must be the one the
    # sweep over every piece gives.
    x, y = noisy_survey(n, noise, seed)
    seg = np.arange(n - 1)
    every = element_codes(n)
    fast = sweep_centre_path(x, y, seg, r, np.radians(chord), True, every, canon)
    full = sweep_centre_path(x, y, seg, r, np.radians(chord), False, every, canon)
    for a, b in zip(fast, full, strict=True):
        np.testing.assert_array_equal(a, b)


def _hidden_by_the_window(xa, ya, xb, yb, ex, ey, r, tol):
    """profile.hidden_pieces as it was: every vertex of the whole window tried, for every piece.

    Written with arrays (a piece per row, a vertex of its window per column,
    in the order the kernel tries them), not as the kernel's loop with its
    early exits: a piece is hidden if any vertex of its window hides both
    ends. The plain-Python loop it replaces took 25 s of the suite.
    """
    dx = xb - xa
    dy = yb - ya
    tried = (dx > 0.0) & (np.abs(dy) <= 100.0 * dx)
    m = 1e-9 * (1.0 + np.abs(ya) + np.abs(yb)) + 1e5 * tol
    with np.errstate(divide="ignore", invalid="ignore"):
        j = np.searchsorted(ex, 0.5 * (xa + xb) + r * dy / np.hypot(dx, dy))
    d = np.arange(2 * HIDE_WINDOW)
    step = np.where(d % 2 == 1, (d + 1) // 2, -(d // 2) - 1)
    w = j[:, None] + step[None, :]
    inside = (w >= 0) & (w < ex.size)
    wc = np.clip(w, 0, ex.size - 1)
    da = xa[:, None] - ex[wc]
    db = xb[:, None] - ex[wc]
    near = inside & (np.abs(da) < r) & (np.abs(db) < r)
    with np.errstate(invalid="ignore"):
        over_a = ey[wc] + np.sqrt(r * r - da * da) > (ya + m)[:, None]
        over_b = ey[wc] + np.sqrt(r * r - db * db) > (yb + m)[:, None]
    return tried & (near & over_a & over_b).any(axis=1)


def test_path_elements_of_read_only_or_strided_arrays_compile_no_variant_of_their_own():
    # numba types a read-only or strided array apart from a plain one and
    # compiles a function anew for it; path_elements gives its compiled parts
    # (survey_path, near_path) plain arrays whatever it is given.
    x, y = noisy_survey(400, 0.01, 3)
    plain = path_elements(x, y, 0.3, 0.7, np.radians(5.0))
    before = {d: len(d.signatures) for d in (survey_path, near_path)}
    read_only = x.copy()
    read_only.flags.writeable = False
    strided = np.stack([y, y], axis=1)[:, 0]
    np.testing.assert_array_equal(
        path_elements(read_only, strided, 0.3, 0.7, np.radians(5.0)), plain)
    assert {d: len(d.signatures) for d in before} == before


@SETTINGS
@given(
    n=st.sampled_from([8, 60, 400, 3000]),
    noise=st.sampled_from([0.0, 0.003, 0.01, 0.05, 0.3, 3.0]),
    seed=st.integers(0, 2**16),
    r=st.sampled_from([0.01, 0.05, 0.45, 2.0]),
    chord=st.sampled_from([0.5, 5.0, 20.0, 45.0]),
    keep=st.sampled_from(["every", "kept", "random"]),
)
def test_the_visible_pieces_are_the_raw_pieces_that_are_not_hidden(n, noise, seed, r, chord,
                                                                   keep):
    # visible_pieces leaves out arc edges that a rough, slack test finds
    # hidden for sure, without making them, and stops looking along a side
    # of the window at the first vertex out of reach: the pieces must be
    # raw_pieces' less those the whole window hides, to the bit, and in order.
    x, y = noisy_survey(n, noise, seed)
    mc = np.radians(chord)
    if keep == "kept":
        elems = path_elements(x, y, r, 1.5 * r, mc)
    elif keep == "random":
        g = np.random.default_rng(seed)
        elems = np.flatnonzero(g.random(2 * n - 1) < 0.5)
    else:
        elems = element_codes(n)
    ext = 2 * r + 1
    ex = np.r_[x[0] - ext, x, x[-1] + ext]
    ey = np.r_[y[0], y, y[-1]]
    eseg = np.r_[0, np.arange(n - 1), n - 2]
    ecodes = np.r_[1, elems + 2, 2 * n + 1]
    tol = 1e-12 * 200.0
    xa, ya, xb, yb, sid = raw_pieces(ex, ey, eseg, r, mc, ecodes)
    hv = ecodes[ecodes % 2 == 0] // 2
    hidden = hidden_pieces(xa, ya, xb, yb, ex[hv], ey[hv], r, tol)
    np.testing.assert_array_equal(hidden,
                                  _hidden_by_the_window(xa, ya, xb, yb, ex[hv], ey[hv], r, tol))
    vis = visible_pieces(ex, ey, eseg, r, mc, ecodes, True, tol)
    for a, b in zip(vis, (xa, ya, xb, yb, sid), strict=True):
        assert a.tobytes() == b[~hidden].tobytes()
    for a, b in zip(visible_pieces(ex, ey, eseg, r, mc, ecodes, False, tol),
                    (xa, ya, xb, yb, sid), strict=True):
        assert a.tobytes() == b.tobytes()


@SETTINGS
@given(
    n=st.integers(0, 300),
    shuffle=st.integers(0, 400),
    ties=st.booleans(),
    seed=st.integers(0, 2**16),
)
def test_the_stable_order_is_the_merge_sorts(n, shuffle, ties, seed):
    # Nearly sorted (a few swaps) up to shuffled past the insertion sort's
    # budget, with and without repeated values.
    g = np.random.default_rng(seed)
    a = np.sort(g.integers(0, max(n // 4, 1), n).astype(float) if ties else g.random(n))
    for _ in range(shuffle):
        if n > 1:
            i, j = g.integers(0, n, 2)
            a[i], a[j] = a[j], a[i]
    np.testing.assert_array_equal(stable_order(a), np.argsort(a, kind="stable"))


def _dist2_to_pieces(x, y, px, py):
    """Squared distances (m^2) of the points (x, y) to each piece of the polyline (px, py)."""
    ax, ay, dx, dy = px[:-1], py[:-1], np.diff(px), np.diff(py)
    x = np.asarray(x, dtype=float)[:, None]
    y = np.asarray(y, dtype=float)[:, None]
    t = np.clip(((x - ax) * dx + (y - ay) * dy) / (dx * dx + dy * dy), 0.0, 1.0)
    return (ax + t * dx - x) ** 2 + (ay + t * dy - y) ** 2


@SETTINGS
@given(
    n=st.sampled_from([8, 60, 400, 1500]),
    noise=st.sampled_from([0.0, 0.003, 0.01, 0.3]),
    seed=st.integers(0, 2**16),
    r=st.sampled_from([0.01, 0.05, 0.5, 2.0]),
    spread=st.floats(1.0, 3.0),
)
def test_the_elements_near_the_path_are_those_within_reach_of_some_piece(n, noise, seed, r,
                                                                           spread):
    # near_path skips the pieces higher than a ground point by more than the
    # reach: it must keep what the distances to every piece keep.
    x, y = noisy_survey(n, noise, seed)
    px, py, _ = survey_path(x, y, np.arange(n - 1), r, np.radians(5.0), element_codes(n))
    reach_seg, reach_vtx = r * spread, r * spread * 1.001
    keep = near_path(x, y, px, py, reach_seg, reach_vtx)
    to_pieces = _dist2_to_pieces(x, y, px, py)  # ground point i, path piece k
    to_segments = _dist2_to_pieces(px, py, x, y)  # path point k, ground segment i
    # A segment and a piece: the nearer of the four end-to-other distances.
    seg = np.minimum.reduce([to_pieces[:-1], to_pieces[1:], to_segments[:-1].T,
                             to_segments[1:].T])
    np.testing.assert_array_equal(keep[::2], (to_pieces <= reach_vtx**2).any(axis=1))
    np.testing.assert_array_equal(keep[1::2], (seg <= reach_seg**2).any(axis=1))


def test_most_pieces_of_a_dense_noisy_survey_are_hidden():
    x, y = noisy_survey(30_000, 0.01, 4)
    r = 0.5
    ext = 2 * r + 1
    ex = np.r_[x[0] - ext, x, x[-1] + ext]
    ey = np.r_[y[0], y, y[-1]]
    xa, ya, xb, yb, _ = raw_pieces(ex, ey, np.arange(x.size + 1), r, np.radians(5.0),
                                    element_codes(ex.size))
    hidden = hidden_pieces(xa, ya, xb, yb, ex, ey, r, 1e-12 * 200.0)
    assert hidden.mean() > 0.9


@SETTINGS
@given(
    n=st.sampled_from([8, 60, 400, 3000]),
    noise=st.sampled_from([0.0, 0.003, 0.01, 0.05, 0.3]),
    seed=st.integers(0, 2**16),
    r_min=st.floats(0.01, 1.0),
    spread=st.floats(1.0, 3.0),
    chord=st.sampled_from([1.0, 5.0, 20.0, 45.0]),
    u=st.lists(st.floats(0.0, 1.0), min_size=1, max_size=3),
)
def test_the_path_from_the_elements_kept_is_the_path_from_every_element(n, noise, seed, r_min,
                                                                        spread, chord, u):
    # For every radius in [r_min, r_max] the path made of the elements that
    # path_elements keeps is the one made of every element, to the bit; the
    # coarse chords (whose circumscribed arcs stand out of the circle by up to
    # 8 % of r) are where a choice by the path of r_min alone fails.
    x, y = noisy_survey(n, noise, seed)
    r_max = r_min * spread
    mc = np.radians(chord)
    kept = path_elements(x, y, r_min, r_max, mc)
    every = element_codes(n)
    assert np.all(np.diff(kept) > 0) and kept[0] == 0 and kept[-1] == every[-1]
    seg = np.arange(n - 1)
    for r in (r_min, r_max, *(r_min + f * (r_max - r_min) for f in u)):
        part = survey_path(x, y, seg, r, mc, kept)
        full = survey_path(x, y, seg, r, mc, every)
        for a, b in zip(part, full, strict=True):
            np.testing.assert_array_equal(a, b)


@SETTINGS
@given(
    n=st.sampled_from([8, 60, 400, 3000]),
    noise=st.sampled_from([0.0, 0.003, 0.01, 0.3]),
    seed=st.integers(0, 2**16),
    r=st.sampled_from([0.01, 0.05, 0.5, 2.0]),
    chord=st.sampled_from([1.0, 5.0, 20.0]),
)
def test_survey_path_is_the_centre_path(n, noise, seed, r, chord):
    # survey_path finds crossings from the pieces and merges a piece's
    # stretches before testing slopes; the curve is the centre_path's to
    # round-off (centre_path may cut a piece in two where a stretch of it is
    # short, so the number of pieces may differ).
    x, y = noisy_survey(n, noise, seed)
    seg = np.arange(n - 1)
    px, py, pseg = survey_path(x, y, seg, r, np.radians(chord), element_codes(n))
    cx, cy, _ = centre_path(x, y, seg, r, np.radians(chord))
    assert px[0] == x[0] and px[-1] == x[-1] and np.all(np.diff(px) > 0)
    assert pseg.size == px.size - 1 and pseg.min() >= 0 and pseg.max() <= n - 2
    xs = np.concatenate([px, cx, np.linspace(x[0], x[-1], 2000)])
    np.testing.assert_allclose(np.interp(xs, px, py), np.interp(xs, cx, cy), rtol=0,
                               atol=1e-9 * (1.0 + np.abs(y).max()))


def test_a_dense_noisy_survey_keeps_few_elements_for_rocks_of_several_sizes():
    # The paths of rocks of 0.3 to 0.7 m touch the tops of the noise only.
    x, y = noisy_survey(100_000, 0.01, 2)
    kept = path_elements(x, y, 0.3, 0.7, np.radians(5.0))
    assert kept.size < 0.1 * element_codes(x.size).size


def test_batches_hold_as_many_paths_as_fit_in_their_time():
    # Rock 0 has the shared radius; the others each a path of their own, of
    # 0.04 s: 2 per batch (BATCH_SECONDS 0.1), however cheap the rocks were.
    radius = np.r_[0.5, 0.5, np.linspace(0.3, 0.7, 20)]
    b = Batches(radius.size, 4096, radius, 0.5, 0.4 * BATCH_SECONDS)
    a0, b0 = b.take()
    b.done(a0, b0, 1e-4)
    spans = []
    while (span := b.take()) is not None:
        spans.append(span)
        b.done(*span, 0.4 * BATCH_SECONDS * b._paths(*span) + 1e-5)
    assert spans[0][0] == 1 and spans[-1][1] == radius.size
    assert all(b._paths(*sp) <= 2 for sp in spans)
    assert max(b._paths(*sp) for sp in spans) == 2
    # The rocks' own cost leaves the paths out.
    assert b.seconds / b.rocks < 1e-3


def test_runs_of_several_sizes_on_a_noisy_survey_do_not_depend_on_chunks():
    # A run cut into chunks (first_index) has other smallest and largest radii
    # per chunk, so other elements kept, and must give the same rocks.
    x, y = noisy_survey(3000, 0.01, 5)
    sec = Section(x, y, np.zeros(x.size - 1, dtype=int),
                  (Material(impact_model="rn_rt", restitution=0.35,
                            tangential_restitution=0.85, friction=0.58,
                            rolling_resistance=0.3, roughness_deg=5),))
    n = 24
    g = np.random.default_rng(1)

    def rel(radius):
        m = radius.size
        return Releases(radius=radius, density=2650.0, x=np.full(m, 1.0), height=np.zeros(m),
                        vx=np.full(m, 0.6), vy=np.full(m, -0.8), spin=np.zeros(m),
                        spin_rolling=np.zeros(m, dtype=bool))

    radius = g.uniform(0.3, 0.7, n)
    radius[12:16] = radius[12]  # a chunk of one size
    whole = run_ensemble(sec, rel(radius), key=9, threads=1)
    parts = [run_ensemble(sec, rel(radius[a:b]), key=9, threads=1, first_index=a)
             for a, b in ((0, 12), (12, 16), (16, n))]
    for name in ("status", "x_end", "y_end", "n_events", "max_x", "grid_height"):
        np.testing.assert_array_equal(getattr(whole, name),
                                      np.concatenate([getattr(p, name) for p in parts]))

"""Run many rocks through the engine: plain inputs in, plain arrays out.

This is the boundary of the numeric core: it knows nothing of project files,
plugins or reports. Every random number of a rock comes from that rock's own
counter-based stream (``rng.stream_start(key, index)``), so rock *i* gives
the same path whatever batch it runs in and whatever the other rocks do.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from typing import Any

import numpy as np

from . import columns, first_compile, native_code
from .batching import FIRST_BATCH, FIRST_BATCH_FEW_POINTS, Batches, default_threads
from .flight import path_tree
from .forest import F_N, F_STOP
from .jit import DIGEST, compile_notice, compiled, writable
from .problem import (
    EngineSettings,
    EnsembleResult,
    Material,
    Releases,
    Section,
    barrier_table,
    rock_mass,
)
from .profile import (
    centre_path_of,
    element_codes,
    every_piece_units,
    no_units,
    path_elements,
)
from .records import (
    N_REL_COLS,
    N_WORK,
    REL_H,
    REL_M,
    REL_R,
    REL_ROLLING,
    REL_VX,
    REL_VY,
    REL_W,
    REL_X,
    WORK_CTX,
    BatchOut,
    Ground,
    Path,
    Resume,
    RockOut,
    Stations,
)
from .rng import forest_stream, stream_start
from .rock import simulate_rock

__all__ = [
    "Material",
    "Section",
    "Releases",
    "EngineSettings",
    "EnsembleResult",
    "run_ensemble",
    "rock_mass",
    "barrier_table",
    "STATUS_NAMES",
    "default_threads",
]


STATUS_NAMES = columns.STATUS_NAMES


SHARED_PATH_VERTICES = 256
"""Sections of more vertices than this have the centre path of a run's first radius
made once per run rather than once per batch, and, with rocks of several sizes, the
ground elements the paths of the others can lie on (see :func:`run_ensemble`)."""


@compiled(nogil=True)
def rock_path(ground, r, max_chord, elems):
    """The ground as a rock of radius ``r`` (m) meets it (``records.Path``).

    Its centre path (``profile.centre_path``) and the tree of its highest
    vertices (``flight.path_tree``); ``max_chord`` (rad) as in ``centre_path``.
    ``elems``: empty, or the ground elements (segment offsets and vertex
    arcs) that the path can lie on (``profile.path_elements``), of which
    ``profile.survey_path`` makes it.
    """
    return _path(ground, r, max_chord, elems, no_units())


@compiled(nogil=True)
def rock_path_of(ground, r, max_chord, units):
    """:func:`rock_path` from every element, from ``units`` (``profile.every_piece_units``).

    The same path, to the bit; what does not depend on the radius (the arcs'
    trigonometry, most of a small section's path) made once per batch, or
    here if ``units`` is ``profile.no_units()``.
    """
    return _path(ground, r, max_chord, np.empty(0, dtype=np.int64), units)


@compiled(nogil=True)
def _path(ground, r, max_chord, elems, units):
    """:func:`rock_path` (``elems`` given) or :func:`rock_path_of` (``elems`` empty).

    The one function the kernel calls for a rock's path, and the one call of
    the sweep (``profile.centre_path_of``) in it: numba compiles every
    function between the kernel and the sweep with the sweep's code linked
    in and optimised again, and a chain of three such wrappers cost about a
    tenth of the first compile. ``units`` is used with every element only
    (``elems`` empty), as ``profile.centre_path_of`` wants.
    """
    n = ground.x.shape[0]
    if elems.shape[0] == 0:
        # Leaving hidden pieces out of the sweep (profile.hidden_pieces) pays on a
        # survey of many points; on a section of few it costs more than it
        # saves, and there every rock of a size of its own makes its path
        # (the optimiser's ground edits: about 8 us a rock, twice their
        # engine time). The path is the same either way, to the bit.
        prune = n > SHARED_PATH_VERTICES
        codes = np.arange(2 * n - 1)
        canon = False
        pieces = units
    else:
        # survey_path (``elems``): what profile.sweep_centre_path does with them.
        prune = True
        codes = elems
        canon = True
        pieces = no_units()
    px, py, pseg = centre_path_of(ground.x, ground.y, np.arange(n - 1), r, max_chord, prune,
                                   codes, canon, pieces)
    return Path(px, py, pseg, ground.seg_mat, ground.mats, path_tree(px, py))


# nogil: batches of rocks run on several Python threads at once; every rock
# writes only its own rows, and draws from its own stream, so the results do
# not depend on how the rocks are shared among threads.
@compiled(nogil=True)
def _run_batch(ground, path0, r0, elems, settings, max_chord, key, first_index, rows, rel,
               resume, stations, bars, out):
    """Run the rocks of one batch (``rows`` of ``rel``) and write their rows of ``out``.

    Parameters
    ----------
    ground : Ground
        The section (``records.Ground``).
    path0 : Path
        The ground as rocks of radius ``r0`` meet it (:func:`rock_path`),
        made once per run: the rocks of that radius use it, the others have
        theirs made here.
    r0 : float
        The radius of ``path0`` (m).
    elems : ndarray of int
        Empty, or the ground elements that the paths of every radius of the
        run can lie on (:func:`rock_path`).
    settings : ndarray of float, shape (N_SETTINGS,)
    max_chord : float
        Largest turn (rad) of a chord of the centre path at a convex vertex.
    key : uint64
        Key of the run's random streams.
    first_index : int
        Index in the whole run of the call's first rock: rock ``i`` (row ``i``
        of ``rel``) draws from stream ``first_index + i``.
    rows : ndarray of int64, shape (M,)
        The rocks of the batch, in the order they run (rows of ``rel``,
        ``resume`` and ``out``): rocks of one radius one after another share
        their centre path (:func:`run_ensemble` groups them by size on a
        survey). Which rows and in what order does not change any result.
    rel : ndarray of float, shape (N, N_REL_COLS)
        Release table of the call (columns ``records.REL_*``).
    resume : Resume
        Which rocks resume, from which state and stream (``records.Resume``).
    stations : Stations
        The recorded stations (``records.Stations``).
    bars : ndarray of float, shape (B, N_BARRIER_COLS)
        Barrier table, sorted by x.
    out : BatchOut
        Every output of the call (``records.BatchOut``), of which the batch
        writes its ``rows``.
    """
    n = rel.shape[0]
    path = path0
    r_prev = r0
    ns = stations.x.shape[0]
    gh = np.empty(ns)
    ge = np.empty(ns)
    # The rock's stream and its forest's (rng.forest_stream).
    rng = np.empty(2, dtype=np.uint64)
    work = np.zeros(N_WORK)  # each rock's scratch (RockOut.work): no allocation per rock
    empty_traj = np.empty((0, columns.N_TRAJ_COLS))
    ntr = out.traj.shape[0]
    # Paths from every element (a section of few points): the radius-free part
    # of their pieces once for the batch, when a rock first needs it (rocks of
    # one size on a survey never do: they share path0).
    units = no_units()
    # Serial on purpose: a prange version measured slower here (per-rock
    # allocations), and compiles for much longer.
    for j in range(rows.shape[0]):
        i = rows[j]
        r = rel[i, REL_R]
        if r != r_prev:
            # Rocks of one size share their centre path.
            if r == r0:
                path = path0
            else:
                if elems.shape[0] == 0 and units[0].shape[0] == 0:
                    units = every_piece_units(ground.x, ground.y, max_chord)
                path = _path(ground, r, max_chord, elems, units)
            r_prev = r
        if resume.mask[i]:
            rng[0] = resume.rngs[i]
        else:
            rng[0] = stream_start(key, first_index + i)
        forest_stream(rng)
        gh[:] = np.nan
        ge[:] = np.nan
        # Without speed recording grid_v is one scratch row shared by all rocks.
        gv = out.grid_v[i] if out.grid_v.shape[0] == n else out.grid_v[0]
        gv[:] = np.nan
        sr = out.srec[i]
        sr[:, :] = np.nan
        cr = out.cross[i]
        cr[:, :] = np.nan
        bo = out.bar_out[i]
        bo[:] = columns.O_NOT_MET
        br = out.bar_rec[i]
        br[:, :] = np.nan
        rock_out = RockOut(gh, ge, gv, cr, out.traj[i] if i < ntr else empty_traj, bo, br, sr,
                           out.srng[i], work)
        st, xe, ye, ni, ne, mx, tt, nt, cb = simulate_rock(
            path, settings, rel[i], rng, stations, bars, rock_out, resume.mask[i],
            resume.states[i],
        )
        out.caught_by[i] = cb
        out.n_stems[i] = work[WORK_CTX + F_N]
        out.forest_stop[i] = work[WORK_CTX + F_STOP] > 0.5
        out.status[i] = st
        out.x_end[i] = xe
        out.y_end[i] = ye
        out.n_imp[i] = ni
        out.n_ev[i] = ne
        out.max_x[i] = mx
        out.dur[i] = tt
        # Element by element, not out.grid_h[i, :] = gh: numba compiles an
        # array-to-array slice assignment with its shape check's error path,
        # which formats a message (about a twentieth of the first compile).
        for s in range(ns):
            out.grid_h[i, s] = gh[s]
            out.grid_e[i, s] = ge[s]
        if i < ntr:
            out.n_traj[i] = nt


def run_ensemble(
    section: Section,
    releases: Releases,
    *,
    key: int,
    stations: np.ndarray | list[float] = (),
    grid: np.ndarray | list[float] = (),
    settings: EngineSettings | None = None,
    barriers: np.ndarray | None = None,
    restart_stations: np.ndarray | list[float] = (),
    record_speed: bool = False,
    resume: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    n_trajectories: int = 0,
    max_trajectory_points: int = 4000,
    batch_size: int = 4096,
    progress: Callable[[int], None] | None = None,
    first_index: int = 0,
    threads: int | None = None,
) -> EnsembleResult:
    """Simulate every rock of ``releases`` on ``section``.

    Parameters
    ----------
    section : Section
    releases : Releases
    key : int
        64-bit key of the run's random streams (derive it from the seed).
    stations : array_like
        Analysis stations (m) with full crossing detail.
    grid : array_like
        Further envelope stations (m) with passing height and energy only.
    settings : EngineSettings, optional
    barriers : ndarray, shape (B, columns.N_BARRIER_COLS), optional
        Barrier table (columns ``columns.BR_*``; the ground-height column is
        filled in here), any order. See :func:`barrier_table`.
    record_speed : bool
        Keep the speed at every envelope station too (``grid_speed``; the
        optimiser needs it), at 4 bytes per rock and station.
    restart_stations : array_like
        Stations (m), each also an envelope station, at whose first downslope
        passage every rock's full state is kept (``restart_state``,
        ``restart_rng``), so that a later run can resume the rocks there.
    resume : (mask, states, rngs), optional
        Per rock: whether to resume, the state (a row of ``restart_state``)
        and the random stream (of ``restart_rng``). A resumed rock continues
        exactly as it would have from that point, on this run's section.
    n_trajectories : int
        Record the event states of the first ``n_trajectories`` rocks.
    max_trajectory_points : int
        Rows kept per recorded trajectory.
    batch_size : int
        Most rocks per compiled call (memory and progress granularity only;
        the results do not depend on it). Batches are smaller where rocks are
        costly, so that each takes about :data:`~.batching.BATCH_SECONDS`.
    progress : callable, optional
        Called with the number of rocks done after each batch.
    first_index : int
        Index of the first rock of ``releases`` in the whole run: rock ``i``
        draws from the random stream of rock ``first_index + i``, so a run cut
        into chunks gives exactly the rocks of the run in one piece.
    threads : int, optional
        Threads that run batches at once (default :func:`default_threads`).
        The results are bit-identical whatever the number.

    Returns
    -------
    EnsembleResult
    """
    settings = settings or EngineSettings()
    n = len(releases)
    user = np.asarray(stations, dtype=float).ravel()
    rs_x = np.unique(np.asarray(restart_stations, dtype=float).ravel())
    stations_rec = _stations(section, user, np.asarray(grid, dtype=float).ravel(), rs_x)
    grid_all = stations_rec.x
    rel = _release_table(releases)
    radius, mass = rel[:, REL_R].copy(), rel[:, REL_M].copy()

    ntr = min(n_trajectories, n)
    bars, bar_order = _sorted_barriers(section, barriers)
    out = _outputs(n, grid_all.size, user.size, ntr, max_trajectory_points, bars.shape[0],
                   rs_x.size, record_speed)
    # numba wants a uint64 scalar; Python ints above 2**63 need the wrap.
    k64 = np.uint64(int(key) % (1 << 64))
    max_chord = float(np.radians(settings.max_chord_deg))
    ground = Ground(*(writable(a) for a in (section.x, section.y, section.segment_material,
                                              section.material_table())))
    path0, r0, elems, path_seconds = _shared_path(ground, radius, max_chord)

    survey = ground.x.size > SHARED_PATH_VERTICES
    order = _run_order(radius, survey)
    batch_args = _batch_slicer(
        (ground, path0, r0, elems, settings.vector(), max_chord, k64), int(first_index), order,
        rel, _resume(resume, n), stations_rec, bars, out)
    first = FIRST_BATCH if survey else FIRST_BATCH_FEW_POINTS
    _run_all(batch_args, Batches(n, batch_size, radius[order], r0, path_seconds, first), n,
             threads, progress)

    return EnsembleResult(
        radius=radius,
        mass=mass,
        status=out.status,
        x_end=out.x_end,
        y_end=out.y_end,
        max_x=out.max_x,
        n_impacts=out.n_imp,
        n_events=out.n_ev,
        duration=out.dur,
        stations=user,
        crossings=out.cross,
        grid=grid_all,
        grid_height=out.grid_h,
        grid_energy=out.grid_e,
        trajectories=[out.traj[i, : out.n_traj[i]].copy() for i in range(ntr)],
        # Back to the caller's barrier order.
        barrier_outcome=_unsort(out.bar_out, bar_order),
        barrier_meeting=_unsort(out.bar_rec, bar_order),
        caught_by=_caught_in_given_order(out.caught_by, bar_order),
        grid_speed=out.grid_v if record_speed else np.zeros((n, 0), dtype=np.float32),
        restart_x=rs_x,
        restart_state=out.srec,
        restart_rng=out.srng,
        stems_met=out.n_stems,
        stopped_by_forest=out.forest_stop,
    )


def _outputs(n: int, n_grid: int, n_user: int, n_traj: int, max_points: int, n_bars: int,
             n_restart: int, record_speed: bool) -> BatchOut:
    """The arrays the compiled batches write into, for ``n`` rocks (see :class:`BatchOut`)."""
    return BatchOut(
        status=np.empty(n, dtype=np.int8), x_end=np.empty(n), y_end=np.empty(n),
        n_imp=np.empty(n, dtype=np.int64), n_ev=np.empty(n, dtype=np.int64),
        max_x=np.empty(n), dur=np.empty(n), caught_by=np.empty(n, dtype=np.int64),
        n_stems=np.empty(n, dtype=np.int32), forest_stop=np.empty(n, dtype=np.bool_),
        grid_h=np.empty((n, n_grid), dtype=np.float32),
        grid_e=np.empty((n, n_grid), dtype=np.float32),
        grid_v=np.empty((n if record_speed else 1, n_grid), dtype=np.float32),
        cross=np.empty((n, n_user, columns.N_CROSS_COLS)),
        traj=np.zeros((n_traj, max_points, columns.N_TRAJ_COLS)),
        n_traj=np.zeros(n_traj, dtype=np.int64),
        bar_out=np.zeros((n, n_bars), dtype=np.int8),
        bar_rec=np.empty((n, n_bars, columns.N_BMEET_COLS)),
        srec=np.empty((n, n_restart, columns.N_RESTART_COLS)),
        srng=np.zeros((n, n_restart), dtype=np.uint64))


def _shared_path(ground: Ground, radius: np.ndarray,
                 max_chord: float) -> tuple[Path, float, np.ndarray, float]:
    """What every batch is given to make the rocks' centre paths.

    Returns
    -------
    path0 : Path
        The centre path of the first rock's radius (an empty one if none).
    r0 : float
        Its radius (m), -1 if none.
    elems : ndarray of int64
        On a survey of many points, the ground elements (segment offsets,
        vertex arcs) the paths of the run's radii can lie on
        (``profile.path_elements``; all of them if the rocks have one size),
        of which ``profile.survey_path`` makes each path, the same whichever
        radii a run (or a chunk of one) has. Empty on a few points: each
        rock's path from every element (``profile.centre_path``, as before).
    path_seconds : float
        Measured cost (s) of one path (0 on a few points).

    Notes
    -----
    On a survey of many points, the centre path of the first rock's radius
    is made once for the whole run (on a fixed size, for every rock): it
    costs more than many rocks, and the batches stay short (see
    ``batch_size``). With rocks of several sizes, the ground elements their
    paths can lie on are found once too (from the path of the smallest
    radius), and each path is made from those: on a dense noisy survey, the
    tops of the noise. On a few points each batch makes
    its own paths from every segment, which costs less than loading numba's
    compiler to call :func:`rock_path` from here. The calls here run on a
    thread of their own (:func:`_off_the_main_thread`): an interrupt is
    taken at once.
    """
    every = np.empty(0, dtype=np.int64)
    if radius.size and ground.x.size > SHARED_PATH_VERTICES:
        r0 = float(radius[0])
        r_min, r_max = float(radius.min()), float(radius.max())
        if r_min == r_max:
            elems = element_codes(ground.x.size)
        else:
            elems = _off_the_main_thread(path_elements, ground.x, ground.y, r_min, r_max,
                                         max_chord)
        t0 = time.perf_counter()
        path0 = _off_the_main_thread(rock_path, ground, r0, max_chord, elems)
        return path0, r0, elems, time.perf_counter() - t0
    # no rock has radius -1: every batch makes its paths
    return (Path(np.empty(0), np.empty(0), np.empty(0, dtype=np.int64), ground.seg_mat,
                 ground.mats, np.empty(0)), -1.0, every, 0.0)


def _batch_slicer(fixed: tuple, first_index: int, order: np.ndarray, rel: np.ndarray,
                  resume: Resume, stations: Stations, bars: np.ndarray,
                  out: BatchOut) -> Callable[[int, int], tuple]:
    """The arguments of the compiled call for the rocks ``order[a:b]`` (no copies).

    ``fixed`` holds the arguments every batch shares, in the kernel's order:
    ground, shared path, its radius, the elements paths are made of, settings,
    chord limit and run key. Every batch is given the whole release table
    and outputs, and writes the rows of its rocks.
    """
    def batch_args(a: int, b: int) -> tuple:
        return (*fixed, first_index, order[a:b], rel, resume, stations, bars, out)

    return batch_args


def _run_order(radius: np.ndarray, survey: bool) -> np.ndarray:
    """The order the rocks run in: by radius on a survey, else as given.

    On a survey (more than :data:`SHARED_PATH_VERTICES` points) a rock's
    centre path costs milliseconds; rocks of one radius one after another
    share it (:func:`_run_batch`), so a run of size classes
    (``run.releases.size_classes``) makes about one path per class rather
    than one per rock (a decision of the project). A stable sort: rocks of one radius
    keep their order. The results do not depend on the order.
    """
    n = radius.size
    if not survey or n < 2 or np.all(radius == radius[0]):
        return np.arange(n, dtype=np.int64)
    return np.argsort(radius, kind="stable").astype(np.int64)


def _stations(section: Section, user: np.ndarray, grid: np.ndarray,
              restart_x: np.ndarray) -> Stations:
    """Every envelope station (m), sorted, with its ground height and the user's rows.

    Rows of ``crossings`` follow the user's order; duplicates share a grid
    slot. Restart stations are envelope stations too.
    """
    grid_all = np.unique(np.concatenate([user, grid, restart_x]))
    st_srow = np.full(grid_all.size, -1, dtype=np.int64)
    st_srow[np.searchsorted(grid_all, restart_x)] = np.arange(restart_x.size)
    st_user = np.full(grid_all.size, -1, dtype=np.int64)
    for u, xs in enumerate(user):
        st_user[np.searchsorted(grid_all, xs)] = u
    return Stations(grid_all, section.ground_height(grid_all).astype(float), st_user, st_srow)


def _release_table(releases: Releases) -> np.ndarray:
    """The release table: one row per rock, built once (columns ``records.REL_*``)."""
    n = len(releases)
    radius = np.ascontiguousarray(np.broadcast_to(releases.radius, (n,)), dtype=float)
    rel = np.empty((n, N_REL_COLS))
    rel[:, REL_R] = radius
    rel[:, REL_M] = rock_mass(radius, releases.density) * np.ones(n)
    for col, values in ((REL_X, releases.x), (REL_H, releases.height), (REL_VX, releases.vx),
                        (REL_VY, releases.vy), (REL_W, releases.spin),
                        (REL_ROLLING, np.asarray(releases.spin_rolling, dtype=bool))):
        rel[:, col] = np.broadcast_to(np.asarray(values, dtype=float), (n,))
    return rel


def _sorted_barriers(section: Section,
                     barriers: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """The barrier table sorted by station, with its ground heights, and the order used."""
    if barriers is None:
        barriers = np.zeros((0, columns.N_BARRIER_COLS))
    bars = np.array(barriers, dtype=float, ndmin=2).reshape(-1, columns.N_BARRIER_COLS)
    bar_order = np.argsort(bars[:, columns.BR_X], kind="stable")
    bars = np.ascontiguousarray(bars[bar_order])
    bars[:, columns.BR_YG] = section.ground_height(bars[:, columns.BR_X])
    return bars, bar_order


def _resume(resume: tuple[np.ndarray, np.ndarray, np.ndarray] | None, n: int) -> Resume:
    """Per rock: whether it resumes, from which state and random stream."""
    if resume is None:
        return Resume(np.zeros(n, dtype=bool), np.zeros((n, columns.N_RESTART_COLS)),
                      np.zeros(n, dtype=np.uint64))
    return Resume(writable(resume[0], bool), writable(resume[1], float),
                  writable(resume[2], np.uint64))


def _run_all(batch_args: Callable[[int, int], tuple], batches: Batches, n: int,
             threads: int | None, progress: Callable[[int], None] | None) -> int:
    """Run every batch of the compiled kernel, on one thread or a pool; rocks done.

    The kernel is its kept machine code where that fits the arguments
    (:mod:`.native_code`: no numba compiler to load), else numba's dispatcher,
    whose code is then kept for the next process. The first batch runs alone
    if it compiles the kernel (said on stderr).
    """
    native = native_code.load(_run_batch, DIGEST) if n else None

    def run(a: int, b: int) -> int:
        t0 = time.perf_counter()
        args = batch_args(a, b)
        if native is not None and native.accepts(args):
            native(*args)
        else:
            _run_batch(*args)
            if native is None:
                # Kept for the next process; not over a valid copy that only
                # these arguments' types do not fit (read-only arrays, say).
                native_code.export(_run_batch, args, DIGEST)
        batches.done(a, b, time.perf_counter() - t0)
        return b - a

    n_done = 0
    first = batches.take()
    if first is not None:
        args0 = batch_args(*first)
        compiled = (None if native is not None and native.accepts(args0)
                    else compile_notice(_run_batch, args0))
        if compiled is not None:
            first_compile.start(_path, args0)
            n_done += run(*first)
            compiled()
            if progress is not None:
                progress(n_done)
            first = batches.take()
    left = n - (first[0] if first is not None else n)
    nthreads = min(threads if threads is not None else default_threads(),
                   -(-left // batches.size))
    if nthreads <= 1:
        span = first
        while span is not None:
            n_done += run(*span)
            if progress is not None:
                progress(n_done)
            span = batches.take()
    else:
        with ThreadPoolExecutor(max_workers=nthreads) as pool:
            # One batch per thread at a time, each cut when a thread is free,
            # so that its size follows the measured cost of a rock.
            pending = set()
            span = first
            while span is not None and len(pending) < nthreads:
                pending.add(pool.submit(run, *span))
                span = batches.take() if len(pending) < nthreads else None
            try:
                while pending:
                    finished, pending = wait(pending, return_when=FIRST_COMPLETED)
                    for f in finished:
                        n_done += f.result()
                        nxt = batches.take()
                        if nxt is not None:
                            pending.add(pool.submit(run, *nxt))
                    if progress is not None:
                        progress(n_done)
            except BaseException:
                # An interrupt or a failing callback: start no further batch.
                for f in pending:
                    f.cancel()
                raise

    return n_done


def _off_the_main_thread(fn: Callable[..., Any], *args: Any) -> Any:
    """``fn(*args)`` run on a thread of its own, waited for here.

    For a compiled call that takes seconds (the centre path of a survey of
    100,000 points): an interrupt is raised here at once instead of after
    the call (the call itself runs on, on a daemon thread that does not hold
    the process at exit), and never while numba turns the call's result into
    Python objects, which an exception at that moment can crash (measured: a
    segmentation fault on Ctrl-C during the centre path of such a survey).
    """
    box: dict[str, Any] = {}

    def target() -> None:
        try:
            box["value"] = fn(*args)
        except BaseException as exc:  # noqa: BLE001 - handed to the caller below
            box["error"] = exc

    th = threading.Thread(target=target, name="rockfall-design centre path", daemon=True)
    th.start()
    while th.is_alive():
        th.join(0.05)
    if "error" in box:
        raise box["error"]
    return box["value"]


def _caught_in_given_order(caught: np.ndarray, order: np.ndarray) -> np.ndarray:
    out = np.full(caught.shape, -1, dtype=np.int64)
    hit = caught >= 0
    out[hit] = order[caught[hit]]
    return out


def _unsort(a: np.ndarray, order: np.ndarray) -> np.ndarray:
    out = np.empty_like(a)
    out[:, order] = a
    return out



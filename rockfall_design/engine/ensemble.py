"""Run many rocks through the engine: plain inputs in, plain arrays out.

This is the boundary of the numeric core: it knows nothing of project files,
plugins or reports. Every random number of a rock comes from that rock's own
counter-based stream (``rng.stream_start(key, index)``), so rock *i* gives
the same path whatever batch it runs in and whatever the other rocks do.
"""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from contextvars import ContextVar
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numba import njit

from . import _native, core
from ._jit import CACHE, DIGEST, compile_notice
from .flight import path_tree
from .profile import centre_path
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
    BatchOut,
    Ground,
    Path,
    Resume,
    RockOut,
    Stations,
)
from .rng import stream_start

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

THREADS_ENV = "ROCKFALL_DESIGN_THREADS"
"""Environment variable that sets the number of engine threads (default: every core)."""


#: Engine threads for runs started in this context (a thread of a study's
#: scenario pool sets 1); None: :data:`THREADS_ENV` or the usable cores.
#: A context variable, not the environment: several scenarios run at once in
#: one process, and the caller's other runs keep every core.
ENGINE_THREADS: ContextVar[int | None] = ContextVar("rockfall_design_engine_threads",
                                                    default=None)


def default_threads() -> int:
    """Threads the engine runs on.

    :data:`ENGINE_THREADS` if set in this context, else
    ``ROCKFALL_DESIGN_THREADS``, else the usable cores.
    """
    own = ENGINE_THREADS.get()
    if own is not None:
        return max(1, int(own))
    env = os.environ.get(THREADS_ENV, "").strip()
    if env:
        try:
            return max(1, int(env))
        except ValueError:
            pass
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)

STATUS_NAMES = core.STATUS_NAMES

BATCH_SECONDS = 0.1
"""Work per batch that the batch sizes aim at (s of one thread).

A batch runs to its end once started (compiled code does not look at
signals), so an interrupt takes effect within about this time after the
running batches end, whatever the cost of a rock (issue 27, item 2). The
size adapts to the measured cost per rock: 4096 rocks of the standard slope
take about 0.02 s, one rock of a size of its own on a survey of 100,000
points about a second (its centre path).
"""

FIRST_BATCH = 1
"""Rocks in the first batch, before the cost of a rock is known (a rock of a survey of
100,000 points and a size of its own costs seconds; batches grow 8-fold from there)."""

SHARED_PATH_VERTICES = 256
"""Sections of more vertices than this have the centre path of a run's first radius
made once per run rather than once per batch (see :func:`run_ensemble`)."""


class _Batches:
    """Cuts rocks 0..n-1 into consecutive batches sized to :data:`BATCH_SECONDS`.

    Thread-safe. The results do not depend on where the cuts fall (each rock
    draws from its own stream), so sizing them by measured time is harmless.
    """

    def __init__(self, n: int, most: int) -> None:
        self.n = n
        self.most = max(1, int(most))
        self.next = 0
        self.size = min(self.most, FIRST_BATCH)
        self.rocks = 0
        self.seconds = 0.0
        self.lock = threading.Lock()

    def take(self) -> tuple[int, int] | None:
        """The next batch (first rock, end), or None when every rock is given out."""
        with self.lock:
            if self.next >= self.n:
                return None
            a = self.next
            self.next = min(self.n, a + self.size)
            return a, self.next

    def done(self, rocks: int, seconds: float) -> None:
        """Record that ``rocks`` rocks took ``seconds`` (one thread); size the next batches."""
        with self.lock:
            self.rocks += rocks
            self.seconds += seconds
            per_rock = self.seconds / max(self.rocks, 1)
            fit = int(BATCH_SECONDS / per_rock) if per_rock > 0.0 else self.most
            # Grow at most 8-fold per batch: the first batches may be cheap ones.
            self.size = max(1, min(self.most, fit, 8 * self.size))


@dataclass(frozen=True)
class Material:
    """Impact and contact parameters of one ground material.

    Attributes
    ----------
    impact_model : str
        ``"spang"`` (restitution e, friction mu, spin) or ``"rn_rt"``
        (lumped-mass v_n' = -Rn v_n, v_t' = Rt v_t).
    restitution : float
        e (spang) or Rn (rn_rt), in [0, 1].
    friction : float
        Coulomb friction coefficient mu (-), >= 0.
    rolling_resistance : float
        Rolling-resistance coefficient mu_r (-), >= 0.
    tangential_restitution : float
        Rt (rn_rt only), in [0, 1].
    velocity_scaling : bool
        Pfeiffer & Bowen (1989) scaling of the normal restitution.
    velocity_scaling_k : float
        K of that scaling (m/s).
    roughness_deg : float
        Standard deviation of the tilt of the impact normal (degrees).
    roughness_height_m : float
        Roughness as a height h_r (m), PlatRock's convention: the normal tilts
        against the motion by an angle uniform in [0, atan(h_r / r)].
    sd_restitution, sd_friction, sd_rolling_resistance : float
        Standard deviations of the per-impact draws.
    """

    impact_model: str = "spang"
    restitution: float = 0.35
    friction: float = 0.5
    rolling_resistance: float = 0.0
    tangential_restitution: float = 1.0
    velocity_scaling: bool = False
    velocity_scaling_k: float = 9.144
    roughness_deg: float = 0.0
    sd_restitution: float = 0.0
    sd_friction: float = 0.0
    sd_rolling_resistance: float = 0.0
    roughness_height_m: float = 0.0

    def row(self) -> np.ndarray:
        """This material as a row of the engine's material table."""
        out = np.zeros(core.N_MAT_COLS)
        out[core.M_MODEL] = core.MODEL_SPANG if self.impact_model == "spang" else core.MODEL_RN_RT
        out[core.M_E] = self.restitution
        out[core.M_RT] = self.tangential_restitution
        out[core.M_MU] = self.friction
        out[core.M_MUR] = self.rolling_resistance
        out[core.M_VSCALE] = 1.0 if self.velocity_scaling else 0.0
        out[core.M_VSK] = self.velocity_scaling_k
        out[core.M_ROUGH] = np.radians(self.roughness_deg)
        out[core.M_SD_E] = self.sd_restitution
        out[core.M_SD_MU] = self.sd_friction
        out[core.M_SD_MUR] = self.sd_rolling_resistance
        out[core.M_ROUGH_H] = self.roughness_height_m
        return out


@dataclass(frozen=True)
class Section:
    """A slope section: ground polyline and the material of each segment.

    Attributes
    ----------
    x, y : ndarray of float
        Ground vertices (m), x strictly increasing, at least two.
    segment_material : ndarray of int
        Index into ``materials`` for each of the ``len(x) - 1`` segments.
    materials : tuple of Material
    """

    x: np.ndarray
    y: np.ndarray
    segment_material: np.ndarray
    materials: tuple[Material, ...]

    def __post_init__(self) -> None:
        x = np.ascontiguousarray(self.x, dtype=float)
        y = np.ascontiguousarray(self.y, dtype=float)
        sm = np.ascontiguousarray(self.segment_material, dtype=np.int64)
        if x.ndim != 1 or x.shape != y.shape or x.size < 2:
            raise ValueError("a section needs at least two (x, y) vertices")
        if not np.all(np.diff(x) > 0):
            raise ValueError("section x must be strictly increasing")
        if sm.shape != (x.size - 1,):
            raise ValueError("one material index per segment is needed")
        if sm.min() < 0 or sm.max() >= len(self.materials):
            raise ValueError("material index out of range")
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "y", y)
        object.__setattr__(self, "segment_material", sm)

    def material_table(self) -> np.ndarray:
        return np.vstack([m.row() for m in self.materials])

    def ground_height(self, x: np.ndarray | float) -> np.ndarray:
        """Ground height (m) at ``x``, linear between vertices."""
        return np.interp(x, self.x, self.y)

    def centre_path(self, radius: float, max_chord_deg: float = 5.0):
        """Centre path (px, py, pseg) of a sphere of ``radius`` (m)."""
        return centre_path(
            self.x, self.y, np.arange(self.x.size - 1), float(radius), np.radians(max_chord_deg)
        )


@dataclass(frozen=True)
class Releases:
    """Per-rock initial conditions (all arrays of one length N).

    Attributes
    ----------
    radius : ndarray
        Rock radius (m).
    density : float or ndarray
        Rock density (kg/m^3).
    x : ndarray
        Release x of the rock centre (m).
    height : ndarray
        Clearance above the ground at release (m), >= 0.
    vx, vy : ndarray
        Initial velocity (m/s).
    spin : ndarray
        Initial angular velocity (rad/s), counter-clockwise positive.
    spin_rolling : ndarray of bool
        Start with the spin of rolling along the ground instead of ``spin``.
    zone : ndarray of int
        Index of the release zone each rock came from (for reports).
    """

    radius: np.ndarray
    density: float | np.ndarray
    x: np.ndarray
    height: np.ndarray
    vx: np.ndarray
    vy: np.ndarray
    spin: np.ndarray
    spin_rolling: np.ndarray
    zone: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))

    def __len__(self) -> int:
        return int(np.asarray(self.radius).size)

    @property
    def mass(self) -> np.ndarray:
        return rock_mass(np.asarray(self.radius), self.density)


def rock_mass(radius: np.ndarray | float, density: np.ndarray | float) -> np.ndarray:
    """Mass (kg) of a solid sphere: m = 4/3 pi r^3 rho."""
    return 4.0 / 3.0 * np.pi * np.asarray(radius) ** 3 * np.asarray(density)


@dataclass(frozen=True)
class EngineSettings:
    """Numerical parameters of the engine (PHYSICS.md).

    Attributes
    ----------
    v_contact : float
        Outgoing normal speed (m/s) below which a rock stays in contact.
    v_stop : float
        Speed (m/s) below which a rock that the ground can hold is stopped.
    max_events : int
        Event limit per rock; a rock reaching it is reported as unresolved.
    max_chord_deg : float
        Largest turn (degrees) of an edge of the polygon replacing the arc of
        the centre path at a convex vertex.
    """

    v_contact: float = 0.5
    v_stop: float = 0.05
    max_events: int = 10_000
    max_chord_deg: float = 5.0

    def vector(self) -> np.ndarray:
        out = np.zeros(core.N_SETTINGS)
        out[core.S_V_CONTACT] = self.v_contact
        out[core.S_V_STOP] = self.v_stop
        out[core.S_MAX_EVENTS] = self.max_events
        return out


@dataclass
class EnsembleResult:
    """Per-rock outcomes of an ensemble run.

    Attributes
    ----------
    radius, mass : ndarray, shape (N,)
        Rock radius (m) and mass (kg).
    status : ndarray of int8, shape (N,)
        How each path ended, index into ``STATUS_NAMES``.
    x_end, y_end : ndarray, shape (N,)
        Final position of the rock centre (m).
    max_x : ndarray, shape (N,)
        Largest x reached (m).
    n_impacts, n_events : ndarray of int, shape (N,)
    duration : ndarray, shape (N,)
        Duration of each path (s).
    stations : ndarray, shape (U,)
        The user's analysis stations (m).
    crossings : ndarray, shape (N, U, 5)
        First downslope passage of each station: passing height (m),
        vx, vy (m/s), w (rad/s), time (s); NaN where not crossed.
    grid : ndarray, shape (S,)
        Envelope stations (m), sorted, including the user stations.
    grid_height : ndarray of float32, shape (N, S)
        Passing height (m) at the first downslope passage, NaN if none.
    grid_energy : ndarray of float32, shape (N, S)
        Total kinetic energy (J) there.
    trajectories : list of ndarray
        Event states (columns x, y, vx, vy, w, t, mode) of the first rocks.
    barrier_outcome : ndarray of int8, shape (N, B)
        Outcome of each rock's first meeting with each barrier (``core.O_*``),
        barriers in the order given.
    barrier_meeting : ndarray, shape (N, B, 4)
        Passing height (m), speed (m/s), total kinetic energy (J) and time (s)
        of that meeting; NaN if not met.
    caught_by : ndarray of int, shape (N,)
        Barrier that caught each rock (order given), or -1.
    grid_speed : ndarray of float32, shape (N, S), or (N, 0)
        Speed (m/s) at the first downslope passage of each envelope station
        (only with ``record_speed``).
    restart_x : ndarray, shape (R,)
        Restart stations (m), sorted.
    restart_state : ndarray, shape (N, R, core.N_RESTART_COLS)
        Each rock's state at the first downslope passage of each restart
        station; NaN where it never passed.
    restart_rng : ndarray of uint64, shape (N, R)
        Each rock's random stream there.
    """

    radius: np.ndarray
    mass: np.ndarray
    status: np.ndarray
    x_end: np.ndarray
    y_end: np.ndarray
    max_x: np.ndarray
    n_impacts: np.ndarray
    n_events: np.ndarray
    duration: np.ndarray
    stations: np.ndarray
    crossings: np.ndarray
    grid: np.ndarray
    grid_height: np.ndarray
    grid_energy: np.ndarray
    trajectories: list[np.ndarray]
    barrier_outcome: np.ndarray
    barrier_meeting: np.ndarray
    caught_by: np.ndarray
    grid_speed: np.ndarray
    restart_x: np.ndarray
    restart_state: np.ndarray
    restart_rng: np.ndarray

    @property
    def n(self) -> int:
        return int(self.status.size)

    @property
    def events_total(self) -> int:
        return int(self.n_events.sum())


@njit(cache=CACHE, nogil=True)
def rock_path(ground, r, max_chord):
    """The ground as a rock of radius ``r`` (m) meets it (``records.Path``).

    Its centre path (``profile.centre_path``) and the tree of its highest
    vertices (``flight.path_tree``); ``max_chord`` (rad) as in ``centre_path``.
    """
    px, py, pseg = centre_path(ground.x, ground.y, np.arange(ground.x.shape[0] - 1), r,
                               max_chord)
    return Path(px, py, pseg, ground.seg_mat, ground.mats, path_tree(px, py))


# nogil: batches of rocks run on several Python threads at once; every rock
# writes only its own rows, and draws from its own stream, so the results do
# not depend on how the rocks are shared among threads.
@njit(cache=CACHE, nogil=True)
def _run_batch(ground, path0, r0, settings, max_chord, key, first_index, rel, resume,
               stations, bars, out):
    """Run the rocks of one batch (rows of ``rel``) and write their rows of ``out``.

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
    settings : ndarray of float, shape (N_SETTINGS,)
    max_chord : float
        Largest turn (rad) of a chord of the centre path at a convex vertex.
    key : uint64
        Key of the run's random streams.
    first_index : int
        Index in the whole run of the batch's first rock (its stream).
    rel : ndarray of float, shape (N, N_REL_COLS)
        Release table (columns ``records.REL_*``).
    resume : Resume
        Which rocks resume, from which state and stream (``records.Resume``).
    stations : Stations
        The recorded stations (``records.Stations``).
    bars : ndarray of float, shape (B, N_BARRIER_COLS)
        Barrier table, sorted by x.
    out : BatchOut
        The batch's rows of every output (``records.BatchOut``).
    """
    n = rel.shape[0]
    path = path0
    r_prev = r0
    ns = stations.x.shape[0]
    gh = np.empty(ns)
    ge = np.empty(ns)
    rng = np.empty(1, dtype=np.uint64)
    work = np.zeros(N_WORK)  # each rock's scratch (RockOut.work): no allocation per rock
    empty_traj = np.empty((0, core.N_TRAJ_COLS))
    ntr = out.traj.shape[0]
    # Serial on purpose: a prange version measured slower here (per-rock
    # allocations), and compiles for much longer.
    for i in range(n):
        r = rel[i, REL_R]
        if r != r_prev:
            # Rocks of one size share their centre path.
            path = path0 if r == r0 else rock_path(ground, r, max_chord)
            r_prev = r
        if resume.mask[i]:
            rng[0] = resume.rngs[i]
        else:
            rng[0] = stream_start(key, first_index + i)
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
        bo[:] = core.O_NOT_MET
        br = out.bar_rec[i]
        br[:, :] = np.nan
        rock_out = RockOut(gh, ge, gv, cr, out.traj[i] if i < ntr else empty_traj, bo, br, sr,
                           out.srng[i], work)
        st, xe, ye, ni, ne, mx, tt, nt, cb = core.simulate_rock(
            path, settings, rel[i], rng, stations, bars, rock_out, resume.mask[i],
            resume.states[i],
        )
        out.caught_by[i] = cb
        out.status[i] = st
        out.x_end[i] = xe
        out.y_end[i] = ye
        out.n_imp[i] = ni
        out.n_ev[i] = ne
        out.max_x[i] = mx
        out.dur[i] = tt
        out.grid_h[i, :] = gh
        out.grid_e[i, :] = ge
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
    barriers : ndarray, shape (B, core.N_BARRIER_COLS), optional
        Barrier table (columns ``core.BR_*``; the ground-height column is
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
        costly, so that each takes about :data:`BATCH_SECONDS`.
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
    grid_all = np.unique(
        np.concatenate([user, np.asarray(grid, dtype=float).ravel(), rs_x])
    )
    st_srow = np.full(grid_all.size, -1, dtype=np.int64)
    st_srow[np.searchsorted(grid_all, rs_x)] = np.arange(rs_x.size)
    st_user = np.full(grid_all.size, -1, dtype=np.int64)
    # Rows of `crossings` follow the user's order; duplicates share a grid slot.
    for u, xs in enumerate(user):
        st_user[np.searchsorted(grid_all, xs)] = u
    st_yg = section.ground_height(grid_all).astype(float)
    radius = np.ascontiguousarray(np.broadcast_to(releases.radius, (n,)), dtype=float)
    mass = np.ascontiguousarray(rock_mass(radius, releases.density) * np.ones(n), dtype=float)
    # The release table: one row per rock, built once (columns records.REL_*).
    rel = np.empty((n, N_REL_COLS))
    rel[:, REL_R] = radius
    rel[:, REL_M] = mass
    for col, values in ((REL_X, releases.x), (REL_H, releases.height), (REL_VX, releases.vx),
                        (REL_VY, releases.vy), (REL_W, releases.spin),
                        (REL_ROLLING, np.asarray(releases.spin_rolling, dtype=bool))):
        rel[:, col] = np.broadcast_to(np.asarray(values, dtype=float), (n,))

    status = np.empty(n, dtype=np.int8)
    x_end = np.empty(n)
    y_end = np.empty(n)
    n_imp = np.empty(n, dtype=np.int64)
    n_ev = np.empty(n, dtype=np.int64)
    max_x = np.empty(n)
    dur = np.empty(n)
    grid_h = np.empty((n, grid_all.size), dtype=np.float32)
    grid_e = np.empty((n, grid_all.size), dtype=np.float32)
    cross = np.empty((n, user.size, core.N_CROSS_COLS))
    ntr = min(n_trajectories, n)
    traj = np.zeros((ntr, max_trajectory_points, core.N_TRAJ_COLS))
    n_traj = np.zeros(ntr, dtype=np.int64)
    if barriers is None:
        barriers = np.zeros((0, core.N_BARRIER_COLS))
    bars = np.array(barriers, dtype=float, ndmin=2).reshape(-1, core.N_BARRIER_COLS)
    bar_order = np.argsort(bars[:, core.BR_X], kind="stable")
    bars = np.ascontiguousarray(bars[bar_order])
    bars[:, core.BR_YG] = section.ground_height(bars[:, core.BR_X])
    nb = bars.shape[0]
    bar_out_s = np.zeros((n, nb), dtype=np.int8)
    bar_rec_s = np.empty((n, nb, core.N_BMEET_COLS))
    caught_s = np.empty(n, dtype=np.int64)
    grid_v = np.empty((n if record_speed else 1, grid_all.size), dtype=np.float32)
    srec = np.empty((n, rs_x.size, core.N_RESTART_COLS))
    srng = np.zeros((n, rs_x.size), dtype=np.uint64)
    if resume is None:
        res_mask = np.zeros(n, dtype=bool)
        states0 = np.zeros((n, core.N_RESTART_COLS))
        rngs0 = np.zeros(n, dtype=np.uint64)
    else:
        res_mask = np.ascontiguousarray(resume[0], dtype=bool)
        states0 = np.ascontiguousarray(resume[1], dtype=float)
        rngs0 = np.ascontiguousarray(resume[2], dtype=np.uint64)
    mats = section.material_table()
    sv = settings.vector()
    # numba wants a uint64 scalar; Python ints above 2**63 need the wrap.
    k64 = np.uint64(int(key) % (1 << 64))
    max_chord = float(np.radians(settings.max_chord_deg))

    ground = Ground(section.x, section.y, section.segment_material, mats)
    # On a survey of many points, the centre path of the first rock's radius
    # is made once for the whole run (on a fixed size, for every rock): it
    # costs more than many rocks, and the batches stay short (see
    # batch_size). On a few points each batch makes its own, which costs
    # less than loading numba's compiler to call rock_path from here.
    if n and section.x.size > SHARED_PATH_VERTICES:
        r0 = float(radius[0])
        path0 = _off_the_main_thread(rock_path, ground, r0, max_chord)
    else:
        r0 = -1.0  # no rock has it: every batch makes its paths
        path0 = Path(np.empty(0), np.empty(0), np.empty(0, dtype=np.int64), ground.seg_mat,
                     ground.mats, np.empty(0))
    stations_rec = Stations(grid_all, st_yg, st_user, st_srow)
    resume_rec = Resume(res_mask, states0, rngs0)
    out = BatchOut(status, x_end, y_end, n_imp, n_ev, max_x, dur, caught_s, grid_h, grid_e,
                   grid_v, cross, traj, n_traj, bar_out_s, bar_rec_s, srec, srng)

    def batch_args(a: int, b: int) -> tuple:
        """The arguments of the compiled call for rocks a..b-1 (views, no copies)."""
        sl = slice(a, b)
        tr = slice(min(a, ntr), min(b, ntr))
        rows = BatchOut._make(
            getattr(out, f)[tr] if f in ("traj", "n_traj")
            else getattr(out, f) if (f == "grid_v" and not record_speed)
            else getattr(out, f)[sl]
            for f in BatchOut._fields
        )
        return (ground, path0, r0, sv, max_chord, k64, int(first_index) + a, rel[sl],
                Resume._make(x[sl] for x in resume_rec), stations_rec, bars, rows)

    batches = _Batches(n, batch_size)

    # The kernel's kept machine code if it fits these arguments (_native:
    # no numba compiler to load), else numba's dispatcher, which keeps it.
    native = _native.load(_run_batch, DIGEST) if n else None

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
                _native.export(_run_batch, args, DIGEST)
        batches.done(b - a, time.perf_counter() - t0)
        return b - a

    n_done = 0
    first = batches.take()
    if first is not None:
        # The first batch runs alone if it compiles the kernel (said on stderr).
        args0 = batch_args(*first)
        compiled = (None if native is not None and native.accepts(args0)
                    else compile_notice(_run_batch, args0))
        if compiled is not None:
            n_done += run(*first)
            compiled()
            if progress is not None:
                progress(n_done)
            first = batches.take()
    left = n - (first[0] if first is not None else n)
    nthreads = min(threads if threads is not None else default_threads(),
                   -(-left // FIRST_BATCH))
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

    return EnsembleResult(
        radius=radius,
        mass=mass,
        status=status,
        x_end=x_end,
        y_end=y_end,
        max_x=max_x,
        n_impacts=n_imp,
        n_events=n_ev,
        duration=dur,
        stations=user,
        crossings=cross,
        grid=grid_all,
        grid_height=grid_h,
        grid_energy=grid_e,
        trajectories=[traj[i, : n_traj[i]].copy() for i in range(ntr)],
        # Back to the caller's barrier order.
        barrier_outcome=_unsort(bar_out_s, bar_order),
        barrier_meeting=_unsort(bar_rec_s, bar_order),
        caught_by=_caught_in_given_order(caught_s, bar_order),
        grid_speed=grid_v if record_speed else np.zeros((n, 0), dtype=np.float32),
        restart_x=rs_x,
        restart_state=srec,
        restart_rng=srng,
    )


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


def barrier_table(
    x: float,
    height_m: float,
    capacity_j: float,
    behaviour: int,
    restitution: float = 0.0,
    gap_m: float = 0.0,
    spacing_m: float = 1.0,
) -> np.ndarray:
    """One row of the engine's barrier table (see ``core.BR_*``).

    Parameters
    ----------
    x : float
        Station (m).
    height_m : float
        Height of the top above ground (m).
    capacity_j : float
        Energy capacity (J); ``np.inf`` for none.
    behaviour : int
        ``core.B_NET``, ``core.B_RIGID`` or ``core.B_BLOCKS``.
    restitution : float
        Rebound restitution of a rigid barrier (-).
    gap_m, spacing_m : float
        Clear gap and spacing of a boulder row (m).
    """
    row = np.zeros(core.N_BARRIER_COLS)
    row[core.BR_X] = x
    row[core.BR_H] = height_m
    row[core.BR_CAP] = capacity_j
    row[core.BR_BEH] = behaviour
    row[core.BR_E] = restitution
    row[core.BR_GAP] = gap_m
    row[core.BR_SPACING] = spacing_m
    return row

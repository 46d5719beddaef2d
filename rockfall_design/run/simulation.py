"""From a validated project to an ensemble run and its statistics.

Data flow: ``Project`` -> engine inputs (section, per-rock releases drawn
from the seed) -> :func:`rockfall_design.engine.run_ensemble` ->
``SimulationRun`` (one simulation's run, its record and its statistics as
tables and JSON-ready dicts; not a parametric study, which is
:mod:`rockfall_design.studies`).

The jobs live in rooms of their own, whose names this module re-exports:
``releases`` (the engine's inputs: section, settings, rocks drawn from the
seed), ``summary`` (the JSON summary), ``streamed`` (statistics of runs too
large to keep). Here: the in-memory :class:`SimulationRun`,
:func:`run_in_memory`, and :func:`simulate`, which chooses between an exact
and a streamed run (:class:`~.streamed.StreamedRun`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from contextvars import copy_context
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..engine import EnsembleResult, Releases, Section, run_ensemble
from ..engine.columns import C_H, C_T, C_VX, C_VY, C_W, STATUS_NAMES, STOPPED
from ..engine.trajectory import centre_points, end_counts
from .histograms import LogHistogram
from .passages import slope_deg_at
from .reach import protected_zone_counts, reaches_protected_zone
from .releases import (
    ReleaseStream,
    draw_releases,
    engine_key,
    engine_settings,
    section_from_project,
)
from .streamed import REST_SAMPLE, STOP_BUCKETS, STREAM_REL_ERROR, StreamedRun
from .summary import (
    STATION_QUANTITIES,
    STATISTICS,
    RunSummary,
    percentile_label,
    run_record,
    stat_block,
)

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

    from ..project import Project

# pandas and scipy are imported where a table or a size distribution needs
# them: together they cost more than a second at start-up, and `simulate`
# with a fixed rock size writes no table unless asked.

__all__ = [
    "SimulationRun",
    "StreamedRun",
    "ReleaseStream",
    "simulate",
    "simulation_memory",
    "chunk_rocks",
    "EXACT_ROCKS",
    "section_from_project",
    "engine_settings",
    "draw_releases",
    "protected_zone_counts",
    "reaches_protected_zone",
    "run_in_memory",
    "STATISTICS",
]


@dataclass
class SimulationRun:
    """An ensemble run of a project, with what is needed to repeat it.

    Attributes
    ----------
    project : Project
    result : EnsembleResult
    releases : Releases
    seed : int
    runtime_s : float
        Wall time of the engine run (s).
    section : Section
    first_rock : int
        Index in the whole run of the first rock of this one (a chunk of a
        streamed run starts past 0); the rock column of the tables counts from it.
    stream : ReleaseStream or None
        The run's release stream past its rocks, for a run that goes on from
        them (``run_in_memory``'s ``after``) to draw the next ones without drawing
        these again; None where not kept.
    """

    project: Project
    result: EnsembleResult
    releases: Releases
    seed: int
    runtime_s: float
    section: Section
    first_rock: int = 0
    stream: ReleaseStream | None = field(default=None, repr=False)
    _cache: dict[str, Any] = field(default_factory=dict, repr=False)
    #: The engine's barrier table the rocks ran against (None: none), kept so
    #: that a run recorded without its envelope grid can draw it again.
    barriers: np.ndarray | None = field(default=None, repr=False)
    #: False where ``run_in_memory`` left the envelope grid out (``envelope``).
    envelope_recorded: bool = field(default=True, repr=False)

    #: How the statistics were obtained (recorded in the summary).
    statistics = {"method": "exact"}

    @property
    def n(self) -> int:
        return self.result.n

    # ---- what the figures need (a streamed run answers the same) -------------
    @property
    def stations(self) -> np.ndarray:
        """The user's analysis stations x (m)."""
        return self.result.stations

    @property
    def trajectories(self) -> list[np.ndarray]:
        """Event states of the first rocks (see ``EnsembleResult.trajectories``)."""
        return self.result.trajectories

    def status_counts(self) -> np.ndarray:
        """Number of rocks per end state, indexed by the engine's status codes."""
        return np.bincount(self.result.status, minlength=len(STATUS_NAMES))

    def forest_counts(self) -> tuple[int, int] | None:
        """Rocks that met at least one stem, and rocks a stem stopped; None without a forest."""
        if not self.section.forested:
            return None
        r = self.result
        return int((r.stems_met > 0).sum()), int(r.stopped_by_forest.sum())

    def ends(self) -> dict[str, int]:
        """Rocks per end state by name: ``stopped``, ``exit_downslope``, ``caught``, ...

        See :func:`rockfall_design.engine.trajectory.end_counts`.
        """
        return end_counts(self.status_counts())

    def paths(self, pts_per_flight: int = 24) -> list[tuple[np.ndarray, np.ndarray]]:
        """Points (x, y in m) along the centre paths of the rocks whose events were kept."""
        return [centre_points(tr, pts_per_flight) for tr in self.trajectories]

    def rest_positions(self) -> tuple[np.ndarray, np.ndarray]:
        """x and y (m) of the rock centres at rest (every stopped rock)."""
        stopped = self.result.status == STOPPED
        return self.result.x_end[stopped], self.result.y_end[stopped]

    def stop_counts(self, bins: int) -> np.ndarray:
        """Rocks at rest in ``bins`` equal intervals of the section's x range."""
        x0, x1 = self.section.x[0], self.section.x[-1]
        x, _ = self.rest_positions()
        return np.histogram(x, bins=np.linspace(x0, x1, bins + 1))[0]

    # ---- per-rock and per-crossing tables ------------------------------------
    def rocks_table(self) -> pd.DataFrame:
        """One row per rock: size, release, how and where its path ended."""
        import pandas as pd

        r = self.result
        stopped = r.status == STOPPED
        return pd.DataFrame(
            {
                "rock": self.first_rock + np.arange(r.n),
                "zone": self.releases.zone,
                "radius_m": r.radius,
                "mass_kg": r.mass,
                "release_x_m": self.releases.x,
                "end": np.asarray(STATUS_NAMES, dtype=object)[r.status],
                "end_x_m": r.x_end,
                "stop_x_m": np.where(stopped, r.x_end, np.nan),
                "max_x_m": r.max_x,
                "n_impacts": r.n_impacts,
                "n_events": r.n_events,
                "duration_s": r.duration,
            }
        )

    def crossing_arrays(self) -> dict[str, np.ndarray]:
        """Per rock and user station (shape (N, U)): passing height and energies.

        Energies in J; NaN where a rock did not pass the station downslope.
        ``passing_height_normal_m`` is the height normal to the slope and
        ``angular_speed_rads`` the magnitude of the spin (see
        :mod:`rockfall_design.run.passages`).
        """
        if "cross" not in self._cache:
            r = self.result
            c = r.crossings
            m = r.mass[:, None]
            speed = np.hypot(c[..., C_VX], c[..., C_VY])
            e_tr = 0.5 * m * speed**2
            e_rot = 0.2 * m * r.radius[:, None] ** 2 * c[..., C_W] ** 2
            # Normal to the slope: h cos(beta) of the segment at each station
            # (run.passages, where the convention is written down).
            cos = np.cos(np.radians([slope_deg_at(self.section, float(xs))
                                     for xs in r.stations]))
            self._cache["cross"] = {
                "passing_height_m": c[..., C_H],
                "passing_height_normal_m": c[..., C_H] * cos[None, :],
                "angular_speed_rads": np.abs(c[..., C_W]),
                "vx_ms": c[..., C_VX],
                "vy_ms": c[..., C_VY],
                "velocity_ms": speed,
                "spin_rads": c[..., C_W],
                "translational_energy_j": e_tr,
                "rotational_energy_j": e_rot,
                "energy_j": e_tr + e_rot,
                "time_s": c[..., C_T],
            }
        return self._cache["cross"]

    def crossings_table(self) -> pd.DataFrame:
        """One row per rock and station (first downslope passage)."""
        import pandas as pd

        r = self.result
        a = self.crossing_arrays()
        n, u = r.n, r.stations.size
        crossed = np.isfinite(a["passing_height_m"])
        return pd.DataFrame(
            {
                "rock": self.first_rock + np.repeat(np.arange(n), u),
                "station_x_m": np.tile(r.stations, n),
                "crossed": crossed.ravel(),
                "passing_height_m": a["passing_height_m"].ravel(),
                "velocity_ms": a["velocity_ms"].ravel(),
                "vx_ms": a["vx_ms"].ravel(),
                "vy_ms": a["vy_ms"].ravel(),
                "spin_rads": a["spin_rads"].ravel(),
                "translational_energy_kj": a["translational_energy_j"].ravel() / 1e3,
                "rotational_energy_kj": a["rotational_energy_j"].ravel() / 1e3,
                "energy_kj": a["energy_j"].ravel() / 1e3,
                "time_s": a["time_s"].ravel(),
            }
        )

    def envelopes(self) -> pd.DataFrame:
        """Envelopes along x of passing height (m) and kinetic energy (kJ).

        Columns: ``x_m``, ``ground_m``, ``crossings``, then ``height_max_m`` and
        ``height_pXX_m`` for each configured percentile, and the same for
        ``energy_*_kj`` and, where the run recorded speeds, ``speed_*_ms`` (m/s).
        Statistics are over the rocks that pass each station downslope; NaN
        where none does. ``attrs["rocks"]`` is the number of rocks they are
        over: the run's, or for a run recorded without the grid
        (``run_in_memory``'s ``envelope``) its first ``EXACT_ROCKS``, run again.
        """
        import pandas as pd

        if "env" in self._cache:
            return self._cache["env"]
        if not self.envelope_recorded:
            # Recorded without the grid (the optimiser's looks): the first rocks
            # again, each from its own stream, so on the same paths, with it.
            again = run_in_memory(self.project, rocks=min(self.n, EXACT_ROCKS), seed=self.seed,
                                  section=self.section, barriers=self.barriers)
            self._cache["env"] = again.envelopes()
            return self._cache["env"]
        r = self.result
        h = r.grid_height.astype(float)
        e = r.grid_energy.astype(float) / 1e3
        quantities = [("height", h, "m"), ("energy", e, "kj")]
        if r.grid_speed.shape == h.shape:  # recorded (record_speed): the speed envelope
            quantities.append(("speed", r.grid_speed.astype(float), "ms"))
        count = np.isfinite(h).sum(axis=0)
        out: dict[str, np.ndarray] = {
            "x_m": r.grid,
            "ground_m": self.section.ground_height(r.grid),
            "crossings": count,
        }
        pcts = list(self.project.analysis.percentiles)
        has = count > 0
        for name, arr, unit in quantities:
            mx = np.full(r.grid.size, np.nan)
            mx[has] = np.nanmax(arr[:, has], axis=0)
            out[f"{name}_max_{unit}"] = mx
            for q in pcts:
                col = np.full(r.grid.size, np.nan)
                if has.any():
                    col[has] = np.nanpercentile(arr[:, has], q, axis=0)
                out[f"{name}_p{percentile_label(q)}_{unit}"] = col
        df = pd.DataFrame(out)
        df.attrs["rocks"] = r.n
        self._cache["env"] = df
        return df

    # ---- the JSON summary ----------------------------------------------------
    def summary(self) -> dict[str, Any]:
        """The run's summary as a JSON-ready dict: :meth:`run_summary`'s ``to_json()``."""
        return self.run_summary().to_json()

    def run_summary(self) -> RunSummary:
        """The run's summary as an object (see the README for the keys of its JSON)."""
        r = self.result
        a = self.crossing_arrays()
        blocks = {
            key: [stat_block(a[arr][:, j] / scale) for j in range(r.stations.size)]
            for key, (arr, scale) in STATION_QUANTITIES.items()
        }
        crossings = np.isfinite(a["passing_height_m"]).sum(axis=0)
        stop_block = stat_block(r.x_end[r.status == STOPPED])
        protect = self.project.protect
        reaching = None if protect is None else protected_zone_counts(r.max_x, r.status, protect.x)
        return run_record(self, r.events_total, crossings, blocks, stop_block, reaching)


def _releases_after(project: Project, seed: int, n: int,
                    after: SimulationRun | None) -> tuple[int, Releases, ReleaseStream]:
    """The first rock to run, the releases of rocks ``first .. n - 1`` of a run, and the
    run's release stream past them.

    Without ``after`` the run starts at rock 0. With it, the run goes on from
    ``after``'s rocks: the rocks after them get the releases a run of all
    ``n`` rocks at once would give them, drawn from ``after``'s kept stream
    (a copy: ``after`` can be gone on from again), or else after drawing
    (and dropping) the releases of ``after``'s rocks first, in rock order.
    """
    if after is None:
        stream = ReleaseStream(project, seed)
        return 0, stream.draw(n), stream
    if after.seed != seed or after.first_rock != 0 or after.n > n:
        raise ValueError("a run goes on only from the first rocks of the same run")
    kept = after.stream
    if kept is not None and after.project is project and kept.drawn == after.n:
        stream = kept.fork()
    else:
        stream = ReleaseStream(project, seed)
        stream.draw(after.n)  # the releases of the rocks already run, in order
    return after.n, stream.draw(n - after.n), stream


def run_in_memory(
    project: Project,
    *,
    rocks: int | None = None,
    seed: int | None = None,
    n_trajectories: int = 0,
    progress: Callable[[int], None] | None = None,
    section: Section | None = None,
    barriers: np.ndarray | None = None,
    after: SimulationRun | None = None,
    record_speed: bool = False,
    envelope: bool = True,
) -> SimulationRun:
    """Run the project's rocks once, keeping every rock's result (exact statistics).

    Parameters
    ----------
    project : Project
    rocks : int, optional
        Number of rocks (default: the project's ``rocks.count``).
    seed : int, optional
        Seed (default: the project's ``rocks.seed``).
    n_trajectories : int
        Keep the event states of the first rocks, for figures.
    progress : callable, optional
        Called with the number of rocks done.
    section : Section, optional
        The ground to run on (default: the project's slope; ``check`` passes
        the slope with its ditches and berms).
    barriers : ndarray, optional
        The engine's barrier table (``check``'s fences, walls, boulder rows).
    after : SimulationRun, optional
        The first rocks of this very run (same project, seed, section and
        barriers, fewer rocks, from rock 0): only the rocks after them are
        simulated and joined on, and the result is that of a run of all the
        rocks at once, bit for bit (each rock draws from its own stream, and
        the releases are drawn in rock order). The optimiser's looks at a
        design with more rocks go on from the last look this way.
    record_speed : bool
        Keep the speed at every envelope point too, for the speed envelope
        of the figures (4 bytes per rock and point; the optimiser's runs
        leave it out).
    envelope : bool
        Record the ``analysis.envelope_points`` grid (8 bytes a rock and point;
        the optimiser's decisions leave it out, and ``envelopes()`` then runs the
        first rocks again with it). ``after`` must have been recorded alike.
    """
    n = int(project.rocks.count if rocks is None else rocks)
    s = int(project.rocks.seed if seed is None else seed)
    if section is None:
        section = section_from_project(project)
    first, releases, stream = _releases_after(project, s, n, after)
    if after is not None:
        n_trajectories = 0
    x0, x1 = section.x[0], section.x[-1]
    grid = np.linspace(x0, x1, int(project.analysis.envelope_points) if envelope else 0)
    t0 = time.perf_counter()
    result = run_ensemble(
        section,
        releases,
        key=engine_key(s),
        stations=np.asarray(project.analysis.stations, dtype=float),
        grid=grid,
        settings=engine_settings(project),
        barriers=barriers,
        n_trajectories=n_trajectories,
        progress=progress,
        first_index=first,
        record_speed=record_speed and after is None,
    )
    runtime = time.perf_counter() - t0
    if after is not None:
        result = after.result.joined(result)
        releases = after.releases.joined(releases)
        runtime += after.runtime_s
    return SimulationRun(project=project, result=result, releases=releases, seed=s,
                         runtime_s=runtime, section=section, stream=stream,
                         barriers=barriers, envelope_recorded=envelope)


# ---- large runs: statistics accumulated chunk by chunk -------------------------

#: Runs of up to this many rocks keep every result and give exact statistics;
#: larger ones are streamed (bounded memory, statistics from histograms). A
#: fixed count, not the machine's memory, so a run repeats exactly anywhere.
EXACT_ROCKS = 100_000

# Envelope values (rocks x envelope points) held per chunk: about 100 MB with
# the temporaries of the statistics.
_CHUNK_VALUES = 4_000_000


def chunk_rocks(project: Project) -> int:
    """Rocks per chunk of a streamed run (from the envelope size only)."""
    s = int(project.analysis.envelope_points) + len(project.analysis.stations)
    return int(min(EXACT_ROCKS, max(1_000, _CHUNK_VALUES // s)))


def simulation_memory(project: Project, rocks: int) -> int:
    """Memory (bytes) that ``simulate`` of ``rocks`` rocks needs at its peak.

    An exact run holds every rock's envelope values (float32 height and
    energy, and float64 copies of them while the percentiles are taken) and
    crossings; a streamed run holds one chunk of them and its histograms.
    """
    s = int(project.analysis.envelope_points) + len(project.analysis.stations)
    u = len(project.analysis.stations)
    # height, energy and speed: float32 each, float64 copies while percentiles are taken
    per_rock = 44 * s + 40 * u + 200
    if rocks <= EXACT_ROCKS:
        return rocks * per_rock
    probe = LogHistogram(1, STREAM_REL_ERROR)
    n_log = probe.n_buckets
    # The histograms, and while adding to one of them its temporaries and a
    # fresh count array of the same size (np.bincount).
    histograms = 8 * n_log * (3 * s + len(STATION_QUANTITIES) * u) + 8 * STOP_BUCKETS
    adding = probe.ADD_TEMPORARY_BYTES + 8 * n_log * s
    # The engine computes the next chunk while this one is being added: its
    # float32 envelope values and crossings are held too.
    ahead = chunk_rocks(project) * (12 * s + 40 * u + 200)
    return chunk_rocks(project) * per_rock + ahead + histograms + adding + 16 * REST_SAMPLE


def simulate(
    project: Project,
    *,
    rocks: int | None = None,
    seed: int | None = None,
    n_trajectories: int = 0,
    progress: Callable[[int], None] | None = None,
    on_chunk: Callable[[SimulationRun], None] | None = None,
    chunk: int | None = None,
    section: Section | None = None,
) -> SimulationRun | StreamedRun:
    """Run the simulation of ``simulate``: exact up to ``EXACT_ROCKS`` rocks, else streamed.

    Parameters
    ----------
    project : Project
    rocks, seed : int, optional
        As :func:`run_in_memory`.
    n_trajectories : int
        Keep the paths of the first rocks, for figures.
    progress : callable, optional
        Called with the number of rocks done.
    on_chunk : callable, optional
        Called with each chunk's :class:`SimulationRun` (the whole run's, if
        exact) in rock order, e.g. to write the per-rock tables as they come.
    chunk : int, optional
        Stream in chunks of this many rocks whatever the run's size (the
        default: exact up to ``EXACT_ROCKS``, else :func:`chunk_rocks`).
    section : Section, optional
        The project's slope section, when the caller holds it (the command's
        plan); default: built from the project.

    Returns
    -------
    SimulationRun or StreamedRun
    """
    n = int(project.rocks.count if rocks is None else rocks)
    s = int(project.rocks.seed if seed is None else seed)
    if chunk is None and n <= EXACT_ROCKS:
        run = run_in_memory(project, rocks=n, seed=s, n_trajectories=n_trajectories,
                            progress=progress, record_speed=True, section=section)
        if on_chunk is not None:
            on_chunk(run)
        return run
    size = int(chunk) if chunk is not None else chunk_rocks(project)
    return _simulate_streamed(project, n, s, size, n_trajectories, progress, on_chunk,
                              section)


def _simulate_streamed(
    project: Project, n: int, s: int, size: int, n_trajectories: int,
    progress: Callable[[int], None] | None, on_chunk: Callable[[SimulationRun], None] | None,
    section: Section | None = None,
) -> StreamedRun:
    """:func:`simulate`'s streamed run: ``n`` rocks of seed ``s`` in chunks of ``size``."""
    if section is None:
        section = section_from_project(project)
    grid = np.linspace(section.x[0], section.x[-1], int(project.analysis.envelope_points))
    stations = np.asarray(project.analysis.stations, dtype=float)
    key = engine_key(s)
    settings = engine_settings(project)
    stream = ReleaseStream(project, s)
    out: StreamedRun | None = None
    t0 = time.perf_counter()

    def compute(first: int, releases: Releases) -> EnsembleResult:
        chunk_progress = None if progress is None else (lambda k, f=first: progress(f + k))
        return run_ensemble(
            section, releases, key=key, stations=stations, grid=grid, settings=settings,
            n_trajectories=n_trajectories if first == 0 else 0, progress=chunk_progress,
            first_index=first, record_speed=True,
        )

    # The engine runs the next chunk (on its own threads, without the GIL)
    # while this thread adds the last one to the histograms: the two take
    # comparable time, so overlapping them saves about a third of a large run.
    # Releases are drawn here, in rock order, so the rocks are those of a run
    # in one piece. Each chunk runs in a copy of this thread's context, so
    # that it keeps the engine threads set for it (a scenario of a study).
    firsts = list(range(0, n, size))
    with ThreadPoolExecutor(max_workers=1) as ahead:
        releases = stream.draw(min(size, n))
        pending = ahead.submit(copy_context().run, compute, 0, releases)
        for i, first in enumerate(firsts):
            result = pending.result()
            current = releases
            if i + 1 < len(firsts):
                nxt = firsts[i + 1]
                releases = stream.draw(min(size, n - nxt))
                pending = ahead.submit(copy_context().run, compute, nxt, releases)
            part = SimulationRun(project=project, result=result, releases=current, seed=s,
                                 runtime_s=0.0, section=section, first_rock=first)
            if out is None:
                out = StreamedRun(project=project, seed=s, section=section,
                                  stations=result.stations, grid=result.grid, chunk=size)
            out.add(part)
            if on_chunk is not None:
                on_chunk(part)
    assert out is not None  # n >= 1
    out.runtime_s = time.perf_counter() - t0
    return out

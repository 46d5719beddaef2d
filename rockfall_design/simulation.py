"""From a validated project to an ensemble run and its statistics.

Data flow: ``Project`` -> engine inputs (section, per-rock releases drawn
from the seed) -> :func:`rockfall_design.engine.run_ensemble` -> ``Study``
(the run, its record and its statistics as tables and JSON-ready dicts).

Random numbers: one ``np.random.SeedSequence(seed)`` is split into
independent child sequences, one per quantity (engine streams, zone, x
within the zone, rock size). Each quantity is drawn for all rocks at once
from its own generator, so the first N rocks of a larger run are exactly the
rocks of a run of N: a run can be cut short or extended and stay comparable.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from . import __version__
from .engine import EngineSettings, EnsembleResult, Material, Releases, Section, run_ensemble
from .engine.core import (
    C_H,
    C_T,
    C_VX,
    C_VY,
    C_W,
    CAUGHT,
    EXIT_DOWNSLOPE,
    EXIT_UPSLOPE,
    STATUS_NAMES,
    STOPPED,
    UNRESOLVED,
)
from .histograms import LinearHistogram, LogHistogram
from .judge.outcomes import protected_zone_counts, reaches_protected_zone

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

    from .project import Project

# pandas and scipy are imported where a table or a size distribution needs
# them: together they cost more than a second at start-up, and `simulate`
# with a fixed rock size writes no table unless asked (issue 14).

__all__ = [
    "Study",
    "StreamedStudy",
    "ReleaseStream",
    "simulate",
    "study_memory",
    "chunk_rocks",
    "EXACT_ROCKS",
    "section_from_project",
    "engine_settings",
    "draw_releases",
    "protected_zone_counts",
    "reaches_protected_zone",
    "run_study",
    "STATISTICS",
]

#: The statistics reported for every station quantity, in this order.
STATISTICS = ("mean", "p50", "p95", "p99", "max")

# Child sequences of the run's SeedSequence, by purpose. Never reorder: that
# would change every result for a given seed.
_SEED_ENGINE, _SEED_ZONE, _SEED_X, _SEED_SIZE = range(4)
_N_SEED_CHILDREN = 4


def section_from_project(project: Project) -> Section:
    """The engine's slope section (ground polyline and materials) of a project."""
    names = list(project.materials)
    mats = []
    for name in names:
        m = project.materials[name]
        mats.append(
            Material(
                impact_model=m.impact_model,
                restitution=m.restitution,
                friction=m.friction,
                rolling_resistance=m.rolling_resistance,
                tangential_restitution=(
                    m.tangential_restitution if m.tangential_restitution is not None else 1.0
                ),
                velocity_scaling=m.velocity_scaling,
                velocity_scaling_k=m.velocity_scaling_k,
                roughness_deg=m.roughness_deg,
                roughness_height_m=m.roughness_height_m,
                sd_restitution=m.scatter.restitution,
                sd_friction=m.scatter.friction,
                sd_rolling_resistance=m.scatter.rolling_resistance,
            )
        )
    pts = np.asarray(project.slope.points, dtype=float)
    seg_mat = np.array([names.index(n) for n in project.slope.materials], dtype=np.int64)
    return Section(pts[:, 0], pts[:, 1], seg_mat, tuple(mats))


def engine_settings(project: Project) -> EngineSettings:
    e = project.engine
    return EngineSettings(
        v_contact=e.v_contact,
        v_stop=e.v_stop,
        max_events=e.max_events,
        max_chord_deg=e.max_chord_deg,
    )


def _children(seed: int) -> list[np.random.SeedSequence]:
    return np.random.SeedSequence(int(seed)).spawn(_N_SEED_CHILDREN)


def engine_key(seed: int) -> int:
    """The 64-bit key of the engine's per-rock random streams for ``seed``."""
    return int(_children(seed)[_SEED_ENGINE].generate_state(1, np.uint64)[0])


def _draw_size(
    kind: str,
    a: float,
    b: float,
    n: int,
    rng: np.random.Generator,
    upper: float = np.inf,
    lower: float = 0.0,
) -> np.ndarray:
    """Draw n values of a size quantity (radius m, volume m^3 or mass kg).

    Normal and lognormal sizes are drawn by inverting their CDF, truncated to
    (0, ``upper``]: one uniform per rock keeps the draws of the first rocks
    independent of n. Where the cut-off lies beyond float precision of the
    CDF (every realistic case) the draws are those of the whole distribution.
    Draws below ``lower`` are raised to it: a clip rather than a truncation,
    so that every draw above it stays bit for bit what it was.
    """
    return np.maximum(_draw_size_unclipped(kind, a, b, n, rng, upper), lower)


def _draw_size_unclipped(
    kind: str, a: float, b: float, n: int, rng: np.random.Generator, upper: float
) -> np.ndarray:
    if kind == "fixed":
        return np.full(n, float(a))
    u = rng.random(n)
    if kind == "uniform":
        return a + (b - a) * u
    # The standard normal CDF and its inverse (what scipy.stats.norm.cdf/ppf
    # evaluate), from scipy.special, which imports in a fraction of the time.
    from scipy.special import ndtr, ndtri

    if kind == "normal":
        if b <= 0.0:
            return np.full(n, float(a))
        lo, hi = ndtr(-a / b), ndtr((upper - a) / b)
        return np.minimum(a + b * ndtri(lo + (hi - lo) * u), upper)
    if kind == "lognormal":
        if b <= 0.0:
            return np.full(n, float(a))
        hi = ndtr(np.log(upper / a) / b)
        return np.minimum(a * np.exp(b * ndtri(hi * u)), upper)
    raise ValueError(f"unknown size distribution {kind!r}")


class ReleaseStream:
    """Draws the size and release conditions of a run's rocks, a chunk at a time.

    Each quantity has its own generator, consumed in rock order, so drawing
    the rocks in chunks gives exactly the rocks drawn all at once.

    Parameters
    ----------
    project : Project
    seed : int
        Seed of the run.
    """

    def __init__(self, project: Project, seed: int) -> None:
        ch = _children(seed)
        self._rocks = project.rocks
        zones = self._rocks.release
        w = np.array([z.weight for z in zones], dtype=float)
        self._p = w / w.sum()
        self._zone_rng = np.random.default_rng(ch[_SEED_ZONE])
        self._x_rng = np.random.default_rng(ch[_SEED_X])
        self._size_rng = np.random.default_rng(ch[_SEED_SIZE])
        self.drawn = 0

    def draw(self, n: int) -> Releases:
        """The next ``n`` rocks.

        Returns
        -------
        Releases
            Radius (m), density (kg/m^3), release x (m), clearance (m),
            velocity (m/s), spin (rad/s) and zone index of each rock.
        """
        rocks = self._rocks
        zones = rocks.release
        if len(zones) == 1:
            zone = np.zeros(n, dtype=np.int64)
        else:
            zone = self._zone_rng.choice(len(zones), size=n, p=self._p)
        lo = np.array([z.x[0] for z in zones])[zone]
        hi = np.array([z.x[1] for z in zones])[zone]
        u = self._x_rng.random(n)
        x = lo + (hi - lo) * u
        spec = rocks.size
        q = _draw_size(spec.kind, spec.a, spec.b, n, self._size_rng, rocks.max_size,
                       rocks.min_size)
        rho = float(rocks.density)
        if rocks.size_quantity == "radius":
            radius = q
        else:
            volume = q if rocks.size_quantity == "volume" else q / rho
            radius = np.cbrt(3.0 * volume / (4.0 * np.pi))
        height = np.array([z.height for z in zones], dtype=float)[zone]
        vel = np.array([z.velocity for z in zones], dtype=float).reshape(-1, 2)[zone]
        rolling = np.array([z.spin == "rolling" for z in zones])[zone]
        spin = np.array([0.0 if z.spin == "rolling" else float(z.spin) for z in zones])[zone]
        self.drawn += n
        return Releases(
            radius=radius,
            density=rho,
            x=x,
            height=height,
            vx=vel[:, 0].copy(),
            vy=vel[:, 1].copy(),
            spin=spin,
            spin_rolling=rolling,
            zone=zone,
        )


def draw_releases(project: Project, n: int, seed: int) -> Releases:
    """Draw the size and release conditions of ``n`` rocks from ``seed``.

    Parameters
    ----------
    project : Project
    n : int
        Number of rocks.
    seed : int
        Seed of the run.

    Returns
    -------
    Releases
        See :meth:`ReleaseStream.draw`.
    """
    return ReleaseStream(project, seed).draw(n)


def _stat_block(values: np.ndarray) -> dict[str, float | None]:
    """mean, p50, p95, p99, max of the finite values (None if there are none)."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return {k: None for k in STATISTICS}
    p = np.percentile(v, [50, 95, 99])
    return {
        "mean": float(v.mean()),
        "p50": float(p[0]),
        "p95": float(p[1]),
        "p99": float(p[2]),
        "max": float(v.max()),
    }


@dataclass
class Study:
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
    """

    project: Project
    result: EnsembleResult
    releases: Releases
    seed: int
    runtime_s: float
    section: Section
    first_rock: int = 0
    _cache: dict[str, Any] = field(default_factory=dict, repr=False)

    #: How the statistics were obtained (recorded in the summary).
    statistics = {"method": "exact"}

    @property
    def n(self) -> int:
        return self.result.n

    # ---- what the figures need (a streamed study answers the same) -----------
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
        """
        if "cross" not in self._cache:
            r = self.result
            c = r.crossings
            m = r.mass[:, None]
            speed = np.hypot(c[..., C_VX], c[..., C_VY])
            e_tr = 0.5 * m * speed**2
            e_rot = 0.2 * m * r.radius[:, None] ** 2 * c[..., C_W] ** 2
            self._cache["cross"] = {
                "passing_height_m": c[..., C_H],
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
        ``energy_*_kj``. Statistics are over the rocks that pass each station
        downslope; NaN where none does.
        """
        import pandas as pd

        if "env" in self._cache:
            return self._cache["env"]
        r = self.result
        h = r.grid_height.astype(float)
        e = r.grid_energy.astype(float) / 1e3
        count = np.isfinite(h).sum(axis=0)
        out: dict[str, np.ndarray] = {
            "x_m": r.grid,
            "ground_m": self.section.ground_height(r.grid),
            "crossings": count,
        }
        pcts = list(self.project.analysis.percentiles)
        has = count > 0
        for name, arr, unit in (("height", h, "m"), ("energy", e, "kj")):
            mx = np.full(r.grid.size, np.nan)
            mx[has] = np.nanmax(arr[:, has], axis=0)
            out[f"{name}_max_{unit}"] = mx
            for q in pcts:
                col = np.full(r.grid.size, np.nan)
                if has.any():
                    col[has] = np.nanpercentile(arr[:, has], q, axis=0)
                out[f"{name}_p{_pct_label(q)}_{unit}"] = col
        df = pd.DataFrame(out)
        self._cache["env"] = df
        return df

    # ---- the JSON summary ----------------------------------------------------
    def summary(self) -> dict[str, Any]:
        """The run's summary as a JSON-ready dict (see the README for the keys)."""
        r = self.result
        a = self.crossing_arrays()
        blocks = {
            key: [_stat_block(a[arr][:, j] / scale) for j in range(r.stations.size)]
            for key, (arr, scale) in _STATION_QUANTITIES.items()
        }
        crossings = np.isfinite(a["passing_height_m"]).sum(axis=0)
        stop_block = _stat_block(r.x_end[r.status == STOPPED])
        protect = self.project.protect
        reaching = None if protect is None else protected_zone_counts(r.max_x, r.status, protect.x)
        return _summary(self, r.events_total, crossings, blocks, stop_block, reaching)


# Per station: summary key -> (crossing array, divisor to the reported unit).
_STATION_QUANTITIES: dict[str, tuple[str, float]] = {
    "passing_height_m": ("passing_height_m", 1.0),
    "velocity_ms": ("velocity_ms", 1.0),
    "energy_kj": ("energy_j", 1e3),
    "translational_energy_kj": ("translational_energy_j", 1e3),
    "rotational_energy_kj": ("rotational_energy_j", 1e3),
}


def _summary(
    study: Study | StreamedStudy,
    events: int,
    crossings: np.ndarray,
    blocks: dict[str, list[dict[str, float | None]]],
    stop_block: dict[str, float | None],
    reaching: tuple[int, int] | None,
) -> dict[str, Any]:
    """The summary dict, the same for an exact and a streamed study.

    ``reaching`` is (rocks counted as reaching the protected zone, how many of
    them are unresolved paths counted so), None without a protected zone.
    """
    counts = study.status_counts()
    stations = []
    for j, xs in enumerate(study.stations):
        st: dict[str, Any] = {"x": float(xs), "crossings": int(crossings[j])}
        st.update({key: blocks[key][j] for key in _STATION_QUANTITIES})
        stations.append(st)
    out: dict[str, Any] = {
        "project": study.project.name,
        "version": __version__,
        "rocks": int(study.n),
        "seed": int(study.seed),
        "project_hash": study.project.resolved_hash(),
        "runtime_s": round(float(study.runtime_s), 6),
        "events": int(events),
        "statistics": dict(study.statistics),
        "stops": {
            "x": {k: stop_block[k] for k in ("mean", "p50", "p95", "max")},
            "stopped": int(counts[STOPPED]),
            "out_of_section": int(counts[EXIT_DOWNSLOPE] + counts[EXIT_UPSLOPE]),
            "exit_downslope": int(counts[EXIT_DOWNSLOPE]),
            "exit_upslope": int(counts[EXIT_UPSLOPE]),
            "unresolved": int(counts[UNRESOLVED]),
            "caught": int(counts[CAUGHT]),
        },
        "stations": stations,
    }
    protect = study.project.protect
    if protect is not None:
        n_reach, n_unresolved = reaching or (0, 0)
        out["protect"] = {
            "x": float(protect.x),
            "reaching": int(n_reach),
            "fraction": n_reach / study.n if study.n else 0.0,
            "unresolved": int(n_unresolved),
        }
    return out


def _pct_label(q: float) -> str:
    """'95' for 95.0, '99_9' for 99.9 (column-name safe)."""
    return f"{q:g}".replace(".", "_")


def run_study(
    project: Project,
    *,
    rocks: int | None = None,
    seed: int | None = None,
    n_trajectories: int = 0,
    progress: Callable[[int], None] | None = None,
    section: Section | None = None,
    barriers: np.ndarray | None = None,
) -> Study:
    """Run the project's rockfall study.

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
    """
    n = int(project.rocks.count if rocks is None else rocks)
    s = int(project.rocks.seed if seed is None else seed)
    if section is None:
        section = section_from_project(project)
    releases = draw_releases(project, n, s)
    x0, x1 = section.x[0], section.x[-1]
    grid = np.linspace(x0, x1, int(project.analysis.envelope_points))
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
    )
    runtime = time.perf_counter() - t0
    return Study(
        project=project,
        result=result,
        releases=releases,
        seed=s,
        runtime_s=runtime,
        section=section,
    )


# ---- large runs: statistics accumulated chunk by chunk -------------------------

#: Runs of up to this many rocks keep every result and give exact statistics;
#: larger ones are streamed (bounded memory, statistics from histograms). A
#: fixed count, not the machine's memory, so a run repeats exactly anywhere.
EXACT_ROCKS = 100_000

#: Relative error of the streamed percentiles of heights, speeds and energies.
STREAM_REL_ERROR = 0.002

#: Stopped rocks whose rest position is kept for the profile figure.
REST_SAMPLE = 20_000

# Envelope values (rocks x envelope points) held per chunk: about 100 MB with
# the temporaries of the statistics.
_CHUNK_VALUES = 4_000_000

# Buckets of the where-rocks-stop histogram: a multiple of the figure's 80 bins.
_STOP_BUCKETS = 80 * 820


def chunk_rocks(project: Project) -> int:
    """Rocks per chunk of a streamed run (from the envelope size only)."""
    s = int(project.analysis.envelope_points) + len(project.analysis.stations)
    return int(min(EXACT_ROCKS, max(1_000, _CHUNK_VALUES // s)))


def study_memory(project: Project, rocks: int) -> int:
    """Memory (bytes) that ``simulate`` of ``rocks`` rocks needs at its peak.

    An exact run holds every rock's envelope values (float32 height and
    energy, and float64 copies of them while the percentiles are taken) and
    crossings; a streamed run holds one chunk of them and its histograms.
    """
    s = int(project.analysis.envelope_points) + len(project.analysis.stations)
    u = len(project.analysis.stations)
    per_rock = 32 * s + 40 * u + 200
    if rocks <= EXACT_ROCKS:
        return rocks * per_rock
    probe = LogHistogram(1, STREAM_REL_ERROR)
    n_log = probe.n_buckets
    # The histograms, and while adding to one of them its temporaries and a
    # fresh count array of the same size (np.bincount).
    histograms = 8 * n_log * (2 * s + len(_STATION_QUANTITIES) * u) + 8 * _STOP_BUCKETS
    adding = probe.ADD_TEMPORARY_BYTES + 8 * n_log * s
    # The engine computes the next chunk while this one is being added: its
    # float32 envelope values and crossings are held too.
    ahead = chunk_rocks(project) * (8 * s + 40 * u + 200)
    return chunk_rocks(project) * per_rock + ahead + histograms + adding + 16 * REST_SAMPLE


@dataclass
class StreamedStudy:
    """The statistics of a run too large to keep: accumulated chunk by chunk.

    Answers what :class:`Study` answers for the summary, the envelopes and
    the figures (not the per-rock tables: those went to ``on_chunk``).
    Counts, means and maxima are exact; percentiles of heights, speeds and
    energies within ``STREAM_REL_ERROR`` (relative), of the stop position
    within half a bucket of the stop histogram.
    """

    project: Project
    seed: int
    section: Section
    stations: np.ndarray
    grid: np.ndarray
    chunk: int
    n: int = 0
    runtime_s: float = 0.0
    events: int = 0
    reaching: int = 0
    reaching_unresolved: int = 0
    trajectories: list[np.ndarray] = field(default_factory=list)
    _counts: np.ndarray = field(default_factory=lambda: np.zeros(len(STATUS_NAMES), np.int64))
    _rest_x: list[np.ndarray] = field(default_factory=list)
    _rest_y: list[np.ndarray] = field(default_factory=list)
    _station: dict[str, LogHistogram] = field(default_factory=dict)
    _env_h: LogHistogram | None = None
    _env_e: LogHistogram | None = None
    _stops: LinearHistogram | None = None

    def __post_init__(self) -> None:
        u, s = self.stations.size, self.grid.size
        self._station = {k: LogHistogram(u, STREAM_REL_ERROR) for k in _STATION_QUANTITIES}
        self._env_h = LogHistogram(s, STREAM_REL_ERROR)
        self._env_e = LogHistogram(s, STREAM_REL_ERROR)
        self._stops = LinearHistogram(self.section.x[0], self.section.x[-1], _STOP_BUCKETS)

    @property
    def statistics(self) -> dict[str, Any]:
        return {
            "method": "histograms",
            "chunk_rocks": int(self.chunk),
            "relative_error": STREAM_REL_ERROR,
            "stop_x_error_m": float(self._stops.width / 2),
        }

    def add(self, part: Study) -> None:
        """Add the rocks of one chunk (a :class:`Study` of consecutive rocks)."""
        r = part.result
        a = part.crossing_arrays()
        for key, (arr, scale) in _STATION_QUANTITIES.items():
            self._station[key].add(a[arr], scale)
        self._env_h.add(r.grid_height)
        self._env_e.add(r.grid_energy, 1e3)
        stopped = r.status == STOPPED
        self._stops.add(r.x_end[stopped])
        room = REST_SAMPLE - sum(x.size for x in self._rest_x)
        if room > 0:
            self._rest_x.append(r.x_end[stopped][:room].copy())
            self._rest_y.append(r.y_end[stopped][:room].copy())
        self._counts += part.status_counts()
        protect = self.project.protect
        if protect is not None:
            n_reach, n_unresolved = protected_zone_counts(r.max_x, r.status, protect.x)
            self.reaching += n_reach
            self.reaching_unresolved += n_unresolved
        self.events += r.events_total
        self.n += r.n
        if not self.trajectories:
            self.trajectories = r.trajectories

    # ---- what the figures need -------------------------------------------
    def status_counts(self) -> np.ndarray:
        return self._counts.copy()

    def rest_positions(self) -> tuple[np.ndarray, np.ndarray]:
        """x and y (m) of the first ``REST_SAMPLE`` rocks to come to rest."""
        if not self._rest_x:
            return np.zeros(0), np.zeros(0)
        return np.concatenate(self._rest_x), np.concatenate(self._rest_y)

    def stop_counts(self, bins: int) -> np.ndarray:
        if _STOP_BUCKETS % bins:
            raise ValueError(f"bins must divide {_STOP_BUCKETS}")
        return self._stops.counts[0].reshape(bins, -1).sum(axis=1)

    # ---- statistics ------------------------------------------------------
    def envelopes(self) -> pd.DataFrame:
        """As :meth:`Study.envelopes`, from the histograms."""
        import pandas as pd

        out: dict[str, np.ndarray] = {
            "x_m": self.grid,
            "ground_m": self.section.ground_height(self.grid),
            "crossings": self._env_h.n.copy(),
        }
        for name, hist, unit in (("height", self._env_h, "m"), ("energy", self._env_e, "kj")):
            out[f"{name}_max_{unit}"] = hist.maximum()
            for q in self.project.analysis.percentiles:
                out[f"{name}_p{_pct_label(q)}_{unit}"] = hist.percentile(q)
        return pd.DataFrame(out)

    def summary(self) -> dict[str, Any]:
        """As :meth:`Study.summary`, from the histograms."""
        blocks = {key: _hist_blocks(h) for key, h in self._station.items()}
        crossings = self._station["passing_height_m"].n
        stop_block = _hist_blocks(self._stops)[0]
        reaching = (None if self.project.protect is None
                    else (self.reaching, self.reaching_unresolved))
        return _summary(self, self.events, crossings, blocks, stop_block, reaching)


def _hist_blocks(h: LogHistogram | LinearHistogram) -> list[dict[str, float | None]]:
    """The statistics block of each column of a histogram (None where empty)."""
    cols = {
        "mean": h.mean(),
        "p50": h.percentile(50),
        "p95": h.percentile(95),
        "p99": h.percentile(99),
        "max": h.maximum(),
    }
    return [
        {k: (float(v[j]) if h.n[j] > 0 else None) for k, v in cols.items()}
        for j in range(h.columns)
    ]


def simulate(
    project: Project,
    *,
    rocks: int | None = None,
    seed: int | None = None,
    n_trajectories: int = 0,
    progress: Callable[[int], None] | None = None,
    on_chunk: Callable[[Study], None] | None = None,
    chunk: int | None = None,
) -> Study | StreamedStudy:
    """Run the study of ``simulate``: exact up to ``EXACT_ROCKS`` rocks, else streamed.

    Parameters
    ----------
    project : Project
    rocks, seed : int, optional
        As :func:`run_study`.
    n_trajectories : int
        Keep the paths of the first rocks, for figures.
    progress : callable, optional
        Called with the number of rocks done.
    on_chunk : callable, optional
        Called with each chunk's :class:`Study` (the whole run's, if exact)
        in rock order, e.g. to write the per-rock tables as they come.
    chunk : int, optional
        Stream in chunks of this many rocks whatever the run's size (the
        default: exact up to ``EXACT_ROCKS``, else :func:`chunk_rocks`).

    Returns
    -------
    Study or StreamedStudy
    """
    n = int(project.rocks.count if rocks is None else rocks)
    s = int(project.rocks.seed if seed is None else seed)
    if chunk is None and n <= EXACT_ROCKS:
        study = run_study(project, rocks=n, seed=s, n_trajectories=n_trajectories,
                          progress=progress)
        if on_chunk is not None:
            on_chunk(study)
        return study
    size = int(chunk) if chunk is not None else chunk_rocks(project)
    section = section_from_project(project)
    grid = np.linspace(section.x[0], section.x[-1], int(project.analysis.envelope_points))
    stations = np.asarray(project.analysis.stations, dtype=float)
    key = engine_key(s)
    settings = engine_settings(project)
    stream = ReleaseStream(project, s)
    out: StreamedStudy | None = None
    t0 = time.perf_counter()

    def compute(first: int, releases: Releases) -> EnsembleResult:
        chunk_progress = None if progress is None else (lambda k, f=first: progress(f + k))
        return run_ensemble(
            section, releases, key=key, stations=stations, grid=grid, settings=settings,
            n_trajectories=n_trajectories if first == 0 else 0, progress=chunk_progress,
            first_index=first,
        )

    # The engine runs the next chunk (on its own threads, without the GIL)
    # while this thread adds the last one to the histograms: the two take
    # comparable time, so overlapping them saves about a third of a large run.
    # Releases are drawn here, in rock order, so the rocks are those of a run
    # in one piece.
    firsts = list(range(0, n, size))
    with ThreadPoolExecutor(max_workers=1) as ahead:
        releases = stream.draw(min(size, n))
        pending = ahead.submit(compute, 0, releases)
        for i, first in enumerate(firsts):
            result = pending.result()
            current = releases
            if i + 1 < len(firsts):
                nxt = firsts[i + 1]
                releases = stream.draw(min(size, n - nxt))
                pending = ahead.submit(compute, nxt, releases)
            part = Study(project=project, result=result, releases=current, seed=s,
                         runtime_s=0.0, section=section, first_rock=first)
            if out is None:
                out = StreamedStudy(project=project, seed=s, section=section,
                                    stations=result.stations, grid=result.grid, chunk=size)
            out.add(part)
            if on_chunk is not None:
                on_chunk(part)
    assert out is not None  # n >= 1
    out.runtime_s = time.perf_counter() - t0
    return out

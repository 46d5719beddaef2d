"""Runs too large to keep: statistics accumulated chunk by chunk from histograms."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..engine.columns import STATUS_NAMES, STOPPED
from ..engine.trajectory import centre_points, end_counts
from .histograms import LinearHistogram, LogHistogram
from .reach import protected_zone_counts
from .summary import (
    STATION_QUANTITIES,
    RunSummary,
    histogram_blocks,
    percentile_label,
    run_record,
)

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

    from ..engine import Section
    from ..project import Project
    from .simulation import SimulationRun

#: Relative error of the streamed percentiles of heights, speeds and energies.
STREAM_REL_ERROR = 0.002

#: Stopped rocks whose rest position is kept for the profile figure.
REST_SAMPLE = 20_000

# Envelope values (rocks x envelope points) held per chunk: about 100 MB with
# the temporaries of the statistics.
_CHUNK_VALUES = 4_000_000

# Buckets of the where-rocks-stop histogram: a multiple of the figure's 80 bins.
STOP_BUCKETS = 80 * 820


@dataclass
class StreamedRun:
    """The statistics of a run too large to keep: accumulated chunk by chunk.

    Answers what :class:`~.simulation.SimulationRun` answers for the summary,
    the envelopes and the figures (not the per-rock tables: those went to ``on_chunk``).
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
    met_stems: int = 0
    forest_stopped: int = 0
    trajectories: list[np.ndarray] = field(default_factory=list)
    _counts: np.ndarray = field(default_factory=lambda: np.zeros(len(STATUS_NAMES), np.int64))
    _rest_x: list[np.ndarray] = field(default_factory=list)
    _rest_y: list[np.ndarray] = field(default_factory=list)
    _station: dict[str, LogHistogram] = field(default_factory=dict)
    _env_h: LogHistogram | None = None
    _env_e: LogHistogram | None = None
    _env_v: LogHistogram | None = None
    _stops: LinearHistogram | None = None

    def __post_init__(self) -> None:
        u, s = self.stations.size, self.grid.size
        self._station = {k: LogHistogram(u, STREAM_REL_ERROR) for k in STATION_QUANTITIES}
        self._env_h = LogHistogram(s, STREAM_REL_ERROR)
        self._env_e = LogHistogram(s, STREAM_REL_ERROR)
        self._env_v = LogHistogram(s, STREAM_REL_ERROR)
        self._stops = LinearHistogram(self.section.x[0], self.section.x[-1], STOP_BUCKETS)

    @property
    def statistics(self) -> dict[str, Any]:
        return {
            "method": "histograms",
            "chunk_rocks": int(self.chunk),
            "relative_error": STREAM_REL_ERROR,
            "stop_x_error_m": float(self._stops.width / 2),
        }

    def add(self, part: SimulationRun) -> None:
        """Add the rocks of one chunk (a :class:`SimulationRun` of consecutive rocks)."""
        r = part.result
        a = part.crossing_arrays()
        for key, (arr, scale) in STATION_QUANTITIES.items():
            self._station[key].add(a[arr], scale)
        self._env_h.add(r.grid_height)
        self._env_e.add(r.grid_energy, 1e3)
        if r.grid_speed.shape == r.grid_height.shape:
            self._env_v.add(r.grid_speed)
        stopped = r.status == STOPPED
        self._stops.add(r.x_end[stopped])
        room = REST_SAMPLE - sum(x.size for x in self._rest_x)
        if room > 0:
            self._rest_x.append(r.x_end[stopped][:room].copy())
            self._rest_y.append(r.y_end[stopped][:room].copy())
        self._counts += part.status_counts()
        self.met_stems += int((r.stems_met > 0).sum())
        self.forest_stopped += int(r.stopped_by_forest.sum())
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
        """Number of rocks per end state, indexed by the engine's status codes."""
        return self._counts.copy()

    def forest_counts(self) -> tuple[int, int] | None:
        """Rocks that met a stem and rocks a stem stopped.

        As :meth:`SimulationRun.forest_counts`.
        """
        return (self.met_stems, self.forest_stopped) if self.section.forested else None

    def ends(self) -> dict[str, int]:
        """Rocks per end state by name, as :meth:`SimulationRun.ends`."""
        return end_counts(self._counts)

    def paths(self, pts_per_flight: int = 24) -> list[tuple[np.ndarray, np.ndarray]]:
        """Points (x, y in m) along the centre paths of the first rocks.

        As :meth:`SimulationRun.paths`.
        """
        return [centre_points(tr, pts_per_flight) for tr in self.trajectories]

    def rest_positions(self) -> tuple[np.ndarray, np.ndarray]:
        """x and y (m) of the first ``REST_SAMPLE`` rocks to come to rest."""
        if not self._rest_x:
            return np.zeros(0), np.zeros(0)
        return np.concatenate(self._rest_x), np.concatenate(self._rest_y)

    def stop_counts(self, bins: int) -> np.ndarray:
        if STOP_BUCKETS % bins:
            raise ValueError(f"bins must divide {STOP_BUCKETS}")
        return self._stops.counts[0].reshape(bins, -1).sum(axis=1)

    # ---- statistics ------------------------------------------------------
    def envelopes(self) -> pd.DataFrame:
        """As :meth:`SimulationRun.envelopes`, from the histograms."""
        import pandas as pd

        out: dict[str, np.ndarray] = {
            "x_m": self.grid,
            "ground_m": self.section.ground_height(self.grid),
            "crossings": self._env_h.n.copy(),
        }
        hists = [("height", self._env_h, "m"), ("energy", self._env_e, "kj")]
        if self._env_v.n.any():
            hists.append(("speed", self._env_v, "ms"))
        for name, hist, unit in hists:
            out[f"{name}_max_{unit}"] = hist.maximum()
            for q in self.project.analysis.percentiles:
                out[f"{name}_p{percentile_label(q)}_{unit}"] = hist.percentile(q)
        return pd.DataFrame(out)

    def summary(self) -> dict[str, Any]:
        """As :meth:`SimulationRun.summary`, from the histograms."""
        return self.run_summary().to_json()

    def run_summary(self) -> RunSummary:
        """As :meth:`SimulationRun.run_summary`, from the histograms."""
        blocks = {key: histogram_blocks(h) for key, h in self._station.items()}
        crossings = self._station["passing_height_m"].n
        stop_block = histogram_blocks(self._stops)[0]
        reaching = (None if self.project.protect is None
                    else (self.reaching, self.reaching_unresolved))
        return run_record(self, self.events, crossings, blocks, stop_block, reaching)

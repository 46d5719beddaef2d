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
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
from scipy import stats as sps

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

if TYPE_CHECKING:  # pragma: no cover
    from .project import Project

__all__ = [
    "Study",
    "section_from_project",
    "engine_settings",
    "draw_releases",
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


def _draw_size(kind: str, a: float, b: float, n: int, rng: np.random.Generator) -> np.ndarray:
    """Draw n values of a size quantity (radius m, volume m^3 or mass kg)."""
    if kind == "fixed":
        return np.full(n, float(a))
    u = rng.random(n)
    if kind == "uniform":
        return a + (b - a) * u
    if kind == "normal":
        # Normal truncated to positive values, by inverting its CDF: one uniform
        # per rock keeps the draws of the first rocks independent of n.
        if b <= 0.0:
            return np.full(n, float(a))
        lo = sps.norm.cdf(-a / b)
        return a + b * sps.norm.ppf(lo + (1.0 - lo) * u)
    if kind == "lognormal":
        return a * np.exp(b * sps.norm.ppf(u))
    raise ValueError(f"unknown size distribution {kind!r}")


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
        Radius (m), density (kg/m^3), release x (m), clearance (m), velocity
        (m/s), spin (rad/s) and zone index of each rock.
    """
    ch = _children(seed)
    rocks = project.rocks
    zones = rocks.release
    w = np.array([z.weight for z in zones], dtype=float)
    if len(zones) == 1:
        zone = np.zeros(n, dtype=np.int64)
    else:
        zone = np.random.default_rng(ch[_SEED_ZONE]).choice(len(zones), size=n, p=w / w.sum())
    lo = np.array([z.x[0] for z in zones])[zone]
    hi = np.array([z.x[1] for z in zones])[zone]
    u = np.random.default_rng(ch[_SEED_X]).random(n)
    x = lo + (hi - lo) * u
    spec = rocks.size
    q = _draw_size(spec.kind, spec.a, spec.b, n, np.random.default_rng(ch[_SEED_SIZE]))
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
    """

    project: Project
    result: EnsembleResult
    releases: Releases
    seed: int
    runtime_s: float
    section: Section
    _cache: dict[str, Any] = field(default_factory=dict, repr=False)

    @property
    def n(self) -> int:
        return self.result.n

    # ---- per-rock and per-crossing tables ------------------------------------
    def rocks_table(self) -> pd.DataFrame:
        """One row per rock: size, release, how and where its path ended."""
        r = self.result
        stopped = r.status == STOPPED
        return pd.DataFrame(
            {
                "rock": np.arange(r.n),
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
        r = self.result
        a = self.crossing_arrays()
        n, u = r.n, r.stations.size
        crossed = np.isfinite(a["passing_height_m"])
        return pd.DataFrame(
            {
                "rock": np.repeat(np.arange(n), u),
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
        stopped = r.status == STOPPED
        stops_x = r.x_end[stopped]
        a = self.crossing_arrays()
        stations = []
        for j, xs in enumerate(r.stations):
            stations.append(
                {
                    "x": float(xs),
                    "crossings": int(np.isfinite(a["passing_height_m"][:, j]).sum()),
                    "passing_height_m": _stat_block(a["passing_height_m"][:, j]),
                    "velocity_ms": _stat_block(a["velocity_ms"][:, j]),
                    "energy_kj": _stat_block(a["energy_j"][:, j] / 1e3),
                    "translational_energy_kj": _stat_block(
                        a["translational_energy_j"][:, j] / 1e3
                    ),
                    "rotational_energy_kj": _stat_block(a["rotational_energy_j"][:, j] / 1e3),
                }
            )
        stop_block = _stat_block(stops_x)
        out: dict[str, Any] = {
            "project": self.project.name,
            "version": __version__,
            "rocks": r.n,
            "seed": int(self.seed),
            "project_hash": self.project.resolved_hash(),
            "runtime_s": round(float(self.runtime_s), 6),
            "events": r.events_total,
            "stops": {
                "x": {k: stop_block[k] for k in ("mean", "p50", "p95", "max")},
                "stopped": int(stopped.sum()),
                "out_of_section": int(
                    ((r.status == EXIT_DOWNSLOPE) | (r.status == EXIT_UPSLOPE)).sum()
                ),
                "exit_downslope": int((r.status == EXIT_DOWNSLOPE).sum()),
                "exit_upslope": int((r.status == EXIT_UPSLOPE).sum()),
                "unresolved": int((r.status == UNRESOLVED).sum()),
                "caught": int((r.status == CAUGHT).sum()),
            },
            "stations": stations,
        }
        protect = self.project.protect
        if protect is not None:
            reaching = int((r.max_x >= protect.x).sum())
            out["protect"] = {
                "x": float(protect.x),
                "reaching": reaching,
                "fraction": reaching / r.n if r.n else 0.0,
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

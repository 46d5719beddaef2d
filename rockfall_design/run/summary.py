"""The JSON summary of a run (``simulate --json``), the same for an exact and a streamed run."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..engine.columns import CAUGHT, EXIT_DOWNSLOPE, EXIT_UPSLOPE, STOPPED, UNRESOLVED
from ..version import __version__
from .histograms import LinearHistogram, LogHistogram

if TYPE_CHECKING:  # pragma: no cover
    from .simulation import Study
    from .streamed import StreamedStudy

#: The statistics reported for every station quantity, in this order.
STATISTICS = ("mean", "p50", "p95", "p99", "max")


def stat_block(values: np.ndarray) -> dict[str, float | None]:
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


# Per station: summary key -> (crossing array, divisor to the reported unit).
STATION_QUANTITIES: dict[str, tuple[str, float]] = {
    "passing_height_m": ("passing_height_m", 1.0),
    "velocity_ms": ("velocity_ms", 1.0),
    "energy_kj": ("energy_j", 1e3),
    "translational_energy_kj": ("translational_energy_j", 1e3),
    "rotational_energy_kj": ("rotational_energy_j", 1e3),
    # The height as EAD 340059 measures a fence's (normal to the
    # slope) and the angular speed, so every station has the quantities a
    # barrier's distributions show (run.passages.QUANTITIES).
    "passing_height_normal_m": ("passing_height_normal_m", 1.0),
    "angular_speed_rads": ("angular_speed_rads", 1.0),
}


def run_summary(
    study: Study | StreamedStudy,
    events: int,
    crossings: np.ndarray,
    blocks: dict[str, list[dict[str, float | None]]],
    stop_block: dict[str, float | None],
    reaching: tuple[int, int] | None,
    project_hash: str | None = None,
) -> dict[str, Any]:
    """The summary dict, the same for an exact and a streamed study.

    ``reaching`` is (rocks counted as reaching the protected zone, how many of
    them are unresolved paths counted so), None without a protected zone.
    ``project_hash``: the project's :meth:`~rockfall_design.project.Project.resolved_hash`
    if the caller has it already (it hashes the whole project: a study's
    scenario computes it once).
    """
    counts = study.status_counts()
    stations = []
    for j, xs in enumerate(study.stations):
        st: dict[str, Any] = {"x": float(xs), "crossings": int(crossings[j])}
        st.update({key: blocks[key][j] for key in STATION_QUANTITIES})
        stations.append(st)
    out: dict[str, Any] = {
        "project": study.project.name,
        "version": __version__,
        "rocks": int(study.n),
        "seed": int(study.seed),
        # The relative step of the size classes the radii were rounded to, where
        # they were (a survey, sizes that vary: run.releases.size_classes).
        **({"size_step": study.project.size_step} if study.project.size_step > 0 else {}),
        "project_hash": project_hash or study.project.resolved_hash(),
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
    forest = study.forest_counts()
    if forest is not None:
        out["forest"] = forest_block(*forest, int(study.n))
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


#: Two-sided confidence of the bounds of the forest's counts in a summary.
FOREST_CONFIDENCE = 0.95


def forest_block(met: int, stopped: int, n: int) -> dict[str, Any]:
    """The summary's ``forest``: rocks that met a stem, rocks a stem stopped, with bounds.

    Each count with its two-sided 95 % Clopper-Pearson interval of the share
    of rocks (the bounds of ``judge.bounds.fraction_bounds``, which this room
    cannot import: judge imports run), so that a report says how sure the
    share is.

    References
    ----------
    .. [1] Clopper, C.J. and Pearson, E.S. (1934). The use of confidence or
       fiducial limits illustrated in the case of the binomial. Biometrika
       26, 404-413.
    """
    from scipy.special import betaincinv  # on first use, as judge.bounds does

    tail = (1.0 - FOREST_CONFIDENCE) / 2.0

    def share(x: int) -> dict[str, float]:
        lower = 0.0 if x <= 0 or n <= 0 else float(betaincinv(x, n - x + 1, tail))
        upper = 1.0 if x >= n else float(betaincinv(x + 1, n - x, 1.0 - tail))
        return {"fraction": x / n if n else 0.0, "lower": lower, "upper": upper}

    return {"confidence": FOREST_CONFIDENCE,
            "met_stems": int(met), "met_stems_share": share(met),
            "stopped": int(stopped), "stopped_share": share(stopped)}


def percentile_label(q: float) -> str:
    """'95' for 95.0, '99_9' for 99.9 (column-name safe)."""
    return f"{q:g}".replace(".", "_")


def histogram_blocks(h: LogHistogram | LinearHistogram) -> list[dict[str, float | None]]:
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

"""The page's run: a barrier dragged along the section, judged in milliseconds.

The bare slope's rocks are kept at dense stations.

Built once per run the page asks for (:func:`build_page_run`, over
:func:`rockfall_design.api.trial_run`: the optimiser's screening on the
run's rocks); :meth:`PageRun.place` judges measures placed anywhere through
the one judgement of :mod:`rockfall_design.judge.outcomes`
(:meth:`rockfall_design.trial.placements.TrialRun.place`). This module only
turns those results into the page's JSON.
"""

from __future__ import annotations

import math
import re
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..api import trial_run
from ..errors import InputError, ProjectError
from ..plugins.measure import Barrier
from .guards import ServeError

if TYPE_CHECKING:  # pragma: no cover
    from ..optimiser.screening import Screening
    from ..plugins import Registry
    from ..project import Project
    from ..trial.placements import Trial, TrialRun
    from .workbench import ProjectEntry


#: Spacing (m) of the table stations along the whole section. A placed
#: barrier is judged at the table station nearest to it; 1 m keeps a table of
#: 10,000 rocks on a 300 m section near 75 MB.
TABLE_STEP_M = 1.0


#: Spacing (m) of the restart stations, where every rock's full state is kept
#: so that a ditch or berm re-runs only the rocks from the station above it
#: (14 numbers per rock and station: 10,000 rocks on 300 m near 35 MB).
RESTART_STEP_M = 10.0


#: Rocks whose paths are drawn on the section (the first rocks of the run).
PATHS_DRAWN = 40


#: Bins of the where-rocks-stop histogram along the section.
STOP_BINS = 120


def _finite_percentiles(a: np.ndarray, qs: Sequence[float]) -> dict[str, list[float | None]]:
    """Per column of ``a`` (rocks x stations): the percentiles and maximum of its finite values."""
    a = np.where(np.isfinite(a), a, np.nan)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # columns no rock passed
        p = np.nanpercentile(a, list(qs), axis=0) if a.shape[0] else np.full((len(qs), 0), np.nan)
        mx = np.nanmax(a, axis=0) if a.shape[0] else np.zeros(0)
    out = {f"p{q:g}": _json_list(p[i]) for i, q in enumerate(qs)}
    out["max"] = _json_list(mx)
    return out


def _json_list(v: np.ndarray) -> list[float | None]:
    return [None if not math.isfinite(float(x)) else round(float(x), 4) for x in v]


def _num(v: float | None) -> float | None:
    return None if v is None or not math.isfinite(float(v)) else float(v)


@dataclass
class PageRun:
    """One finished run of the page: the trial run's table and what the page draws from it."""

    trial_run: TrialRun
    rocks: int
    seed: int
    runtime_s: float
    envelopes: dict[str, Any]
    stops: dict[str, Any]
    paths: list[list[list[float]]]

    @property
    def screening(self) -> Screening:
        """The optimiser's screening behind the table (its rocks, allowance, confidence)."""
        return self.trial_run.screening

    def place(self, entry: ProjectEntry, raws: Sequence[Any]) -> dict[str, Any]:
        """Judge fences and walls at the given stations from the table.

        Parameters
        ----------
        entry
            The project the run belongs to.
        raws
            Measures as the project file writes them (``{"type": "fence",
            "x": 120, "height": 5, "capacity_kj": 2000}``); barriers only.

        Returns
        -------
        dict
            ``measures`` (label, station used, counts, checks with their
            bounds), ``residual`` (rocks reaching the protected zone with
            the Clopper-Pearson bounds and the target), ``verdict`` (what
            :func:`~rockfall_design.judge.verdict.verdict_of` says of these
            numbers, as ``check --json`` gives it), ``admitted`` and
            ``rejected`` as the optimiser's screening decides them, and
            ``elapsed_ms``.

        Raises
        ------
        ServeError
            400 for a measure the plugins reject or one that does not fit.

        Notes
        -----
        A ditch or berm (a measure that reshapes the ground) is judged by
        running again only the rocks that pass the restart station just
        above it, from their saved state, on the edited ground (the
        screening's own way, cached per shape and place): a fraction of a
        second, so the page sends it when the measure is let go, not on
        every move (``reshapes_ground`` in the answer says so).
        """
        t0 = time.perf_counter()
        measures = [entry.build_measure(raw, i) for i, raw in enumerate(raws)]
        try:
            trial = self.trial_run.place(entry.project, entry.registry, measures)
        except ProjectError as exc:
            raise ServeError(400, placed_message(exc.message)) from None
        except InputError as exc:  # a ditch or berm with no restart station above it
            raise ServeError(400, str(exc)) from None
        res = trial.result
        out_measures = _measure_dicts(self.trial_run, trial, raws)
        verdict = self.trial_run.verdict(
            [{k: m[k] for k in ("label", "type", "met", "checks")} for m in out_measures],
            trial.protect if entry.project.protect is not None else None)
        return {
            "measures": out_measures,
            "residual": _residual_dict(entry, self.screening, trial.protect),
            # The verdict of check (judge.verdict) on these numbers: "untested"
            # for a measure no rock meets, never "holds".
            "verdict": verdict.as_dict(),
            "admitted": bool(res.feasible), "near": bool(res.near),
            "rejected": not res.feasible and not res.near,
            "approximate": bool(res.approximate), "cost": _num(trial.cost),
            "reshapes_ground": trial.reshapes_ground,
            "rerun_rocks": trial.rerun_rocks,
            "elapsed_ms": round((time.perf_counter() - t0) * 1e3, 3),
        }


def _measure_dicts(run: TrialRun, trial: Trial, raws: Sequence[Any]) -> list[dict[str, Any]]:
    """Per placed measure: its label, station, counts and checks, for the page."""
    out = []
    res = trial.result
    for p, r, checks in zip(trial.placed, res.results, res.checks, strict=True):
        fp = p.footprint
        x = float(fp.x) if isinstance(fp, Barrier) else float(fp.x_start)
        out.append({
            "index": p.index, "label": p.label, "type": raws[p.index]["type"],
            "x": x, "x_table": run.table_station(x),
            "reshapes_ground": not isinstance(fp, Barrier),
            "met": int(r.met), "caught": int(r.caught), "passed_over": int(r.passed_over),
            "broken_through": int(r.broken_through), "rebounded": int(r.rebounded),
            "checks": [_check_dict(c) for c in checks],
            "ok": all(c.ok for c in checks),
        })
    return out


def _residual_dict(entry: ProjectEntry, sc: Screening, prot: dict[str, Any]) -> dict[str, Any]:
    """The rocks reaching the protected zone, with their Clopper-Pearson bounds and target.

    ``prot`` is :func:`~rockfall_design.judge.evaluation.protect_summary` of them.
    """
    return {
        "reaching": prot["reaching"], "rocks": sc.n, "fraction": prot["fraction"],
        "upper_bound": prot["upper_fraction"], "lower_bound": prot["lower_fraction"],
        "allowed_fraction": sc.allowed_fraction, "allowed": sc.allowed_residual,
        "confidence": sc.confidence, "x": sc.protect_x,
        # Without protect: in the project, the foot of the section stands in.
        "protected_zone": entry.project.protect is not None,
        "ok": prot["ok"], "ok_with_confidence": prot["ok_with_confidence"],
    }


def placed_message(message: str) -> str:
    """A placement error without the project file's line: the measure is the page's."""
    return re.sub(r"^.*?:\d+: ", "", message)


def _check_dict(c: Any) -> dict[str, Any]:
    d = c.as_dict()
    for k in ("value", "target", "bound", "optimistic"):
        d[k] = _num(d.get(k))
    d["holds_with_confidence"] = bool(c.holds_with_confidence)
    return d


def build_page_run(project: Project, registry: Registry, rocks: int, seed: int,
                   progress: Callable[[int], None] | None = None) -> PageRun:
    """:func:`~rockfall_design.api.trial_run` at the app's spacings, with what the page draws.

    The parameters are ``trial_run``'s; the table's and restart stations'
    spacings and the paths kept are the app's (``TABLE_STEP_M``,
    ``RESTART_STEP_M``, ``PATHS_DRAWN``). The page's run adds the envelopes, the
    stops' histogram and the first rocks' paths for the page.
    """
    run = trial_run(project, registry, rocks, seed, table_step_m=TABLE_STEP_M,
                    restart_step_m=RESTART_STEP_M, paths_drawn=PATHS_DRAWN, progress=progress)
    sc = run.screening
    qs = sorted({50.0, 95.0, *[float(q) for q in project.analysis.percentiles]})
    t = sc.bare
    envelopes = {
        "x": [round(float(v), 4) for v in run.grid],
        "ground": _json_list(run.ground),
        "crossings": [int(c) for c in np.isfinite(t.h).sum(axis=0)],
        "height": _finite_percentiles(t.h, qs),
        "energy": _finite_percentiles(t.e_kj, qs),
        "percentiles": [f"p{q:g}" for q in qs],
        # The 95th percentile's distribution-free bounds at the project's
        # confidence (the judge's order statistics), for the hover.
        "confidence": sc.confidence,
        "height_p95_bounds": [list(b) for b in run.p95_bounds(t.h)],
        "energy_p95_bounds": [list(b) for b in run.p95_bounds(t.e_kj)],
    }
    x0, x1 = float(run.section.x[0]), float(run.section.x[-1])
    stopped_x = run.stopped_x
    counts, edges = np.histogram(stopped_x, bins=STOP_BINS, range=(x0, x1))
    stops = {"edges": [round(float(e), 4) for e in edges], "counts": counts.tolist(),
             "stopped": int(stopped_x.size), "reaching": run.reaching,
             "p95_x": _num(float(np.percentile(stopped_x, 95))) if stopped_x.size else None}
    # The first rocks' paths, from the same random streams (rock i draws from
    # stream i of the run's key): the rocks of the table, drawn.
    paths = [p.round(3).tolist() for p in run.paths]
    return PageRun(run, rocks, seed, run.runtime_s, envelopes, stops, paths)

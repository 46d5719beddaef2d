"""The bench: a barrier dragged along the section, judged in milliseconds.

The bare slope's rocks are kept at dense stations.

Built once per project run (:func:`build_bench`, the screening of the
optimiser on the run's rocks); :meth:`Bench.place` judges measures placed
anywhere through the one judgement of :mod:`rockfall_design.judge.outcomes`.
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

from ..judge.evaluation import protect_summary
from ..judge.verdict import verdict_of
from .guards import ServeError

if TYPE_CHECKING:  # pragma: no cover
    from ..optimiser.screening import Screening
    from ..plugins import Registry
    from ..project import Project
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


def _p95_bounds(a: np.ndarray, confidence: float) -> list[list[float | None]]:
    """Per column of ``a``: [lower, upper] confidence bound of the 95th percentile of its
    finite values (None where too few rocks passed to bound it)."""
    from ..judge.bounds import quantile_lower_bound, quantile_upper_bound

    out = []
    for j in range(a.shape[1]):
        v = a[:, j]
        v = v[np.isfinite(v)]
        lo = quantile_lower_bound(v, 0.95, confidence) if v.size else None
        hi = quantile_upper_bound(v, 0.95, confidence) if v.size else None
        out.append([_num(lo), _num(hi)])
    return out


def _json_list(v: np.ndarray) -> list[float | None]:
    return [None if not math.isfinite(float(x)) else round(float(x), 4) for x in v]


def _num(v: float | None) -> float | None:
    return None if v is None or not math.isfinite(float(v)) else float(v)


@dataclass
class Bench:
    """One finished run: the screening table and what the page draws from it."""

    screening: Screening
    rocks: int
    seed: int
    runtime_s: float
    envelopes: dict[str, Any]
    stops: dict[str, Any]
    paths: list[list[list[float]]]

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
        from ..errors import ProjectError
        from ..judge.placing import edited_section, place_measures
        from ..plugins.measure import ProfileEdit

        t0 = time.perf_counter()
        sc = self.screening
        measures = [entry.build_measure(raw, i) for i, raw in enumerate(raws)]
        try:
            placed = place_measures(entry.project, entry.registry, measures, sc.section)
        except ProjectError as exc:
            raise ServeError(400, _placed_message(exc.message)) from None
        edits = [p.footprint for p in placed if isinstance(p.footprint, ProfileEdit)]
        table = sc.bare
        if edits:
            try:
                # The screening's table for edited ground (its private helper: the
                # one place that resumes rocks at a restart station).
                table = sc._table_for(edits, edited_section(entry.project, sc.section, placed))
            except ValueError as exc:
                raise ServeError(400, f"{' + '.join(p.label for p in placed)}: {exc}") from None
        cost = _cost(sc, placed)
        res = sc.screen_placed(placed, table, cost)
        out_measures = _measure_dicts(sc, placed, res, raws)
        # The residual as check reports it (judge.evaluation), against the
        # screening's allowance; the foot of the section stands in without protect:.
        prot = protect_summary(sc.protect_x, int(res.residual), sc.n, sc.allowed_fraction,
                               sc.confidence)
        verdict = verdict_of({
            "rocks": sc.n, "confidence": sc.confidence,
            "protect": prot if entry.project.protect is not None else None,
            "measures": [{k: m[k] for k in ("label", "type", "met", "checks")}
                         for m in out_measures]})
        return {
            "measures": out_measures, "residual": _residual_dict(entry, sc, prot),
            # The verdict of check (judge.verdict) on these numbers: "untested"
            # for a measure no rock meets, never "holds".
            "verdict": verdict.as_dict(),
            "admitted": bool(res.feasible), "near": bool(res.near),
            "rejected": not res.feasible and not res.near,
            "approximate": bool(res.approximate), "cost": _num(cost),
            "reshapes_ground": bool(edits),
            "rerun_rocks": int(table.rows.size) if table.rows is not None else 0,
            "elapsed_ms": round((time.perf_counter() - t0) * 1e3, 3),
        }


def _cost(sc: Screening, placed: Sequence[Any]) -> float:
    """The design's cost by the project's cost model; NaN without one or without a price."""
    if sc.spec.cost_model is None:
        return math.nan
    try:
        return float(sc.cost([p.measure for p in placed]))
    except (KeyError, ValueError):
        return math.nan  # the cost model has no price for it: shown as unknown


def _measure_dicts(sc: Screening, placed: Sequence[Any], res: Any,
                   raws: Sequence[Any]) -> list[dict[str, Any]]:
    """Per placed measure: its label, station, counts and checks, for the page."""
    from ..plugins.measure import Barrier

    out = []
    for p, r, checks in zip(placed, res.results, res.checks, strict=True):
        fp = p.footprint
        x = float(fp.x) if isinstance(fp, Barrier) else float(fp.x_start)
        out.append({
            "index": p.index, "label": p.label, "type": raws[p.index]["type"],
            "x": x, "x_table": float(sc.grid[sc.station(x)]),
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


def _placed_message(message: str) -> str:
    """A placement error without the project file's line: the measure is the page's."""
    return re.sub(r"^.*?:\d+: ", "", message)


def _check_dict(c: Any) -> dict[str, Any]:
    d = c.as_dict()
    for k in ("value", "target", "bound", "optimistic"):
        d[k] = _num(d.get(k))
    d["holds_with_confidence"] = bool(c.holds_with_confidence)
    return d


def default_spec(project: Project, registry: Registry) -> Any:
    """The project's design section, or targets alone for a project without one.

    Without ``design:`` the residual is judged as ``check`` judges it: against
    ``protect.allowed_fraction`` (0 without a protected zone), and nothing is
    priced.
    """
    from ..judge.design_spec import DesignSpec, resolve_design

    if project.design is not None:
        return resolve_design(project, registry)
    allowed = float(project.protect.allowed_fraction) if project.protect is not None else 0.0
    return DesignSpec(max_measures=4, residual_count=None, residual_fraction=allowed,
                      fresh_rocks=None, fresh_seed=None, length_m=1.0, candidates=(),
                      cost_model=None, products={})


def build_bench(project: Project, registry: Registry, rocks: int, seed: int,
                progress: Callable[[int], None] | None = None) -> Bench:
    """Run the rocks on the bare slope once and keep the screening table.

    Parameters
    ----------
    project, registry
        The project and its plugins.
    rocks, seed
        Rocks of the run and its seed (the same rocks as ``simulate`` and
        the optimiser's screening draw for this seed).
    progress
        Called with the rocks done; an exception it raises stops the run.
    """
    from ..engine import Releases, run_ensemble
    from ..engine.columns import STOPPED
    from ..engine.trajectory import centre_points
    from ..judge.placing import build_concept
    from ..optimiser.screening import Screening
    from ..run.releases import section_from_project

    section = section_from_project(project)
    x0, x1 = float(section.x[0]), float(section.x[-1])
    stations = np.arange(x0, x1 + 1e-9, TABLE_STEP_M)
    judged = project
    if project.protect is None:
        # The screening counts rocks reaching a protected zone; without one,
        # the foot of the section stands in (the page says there is none).
        from ..project.schema import Protect

        judged = project.model_copy(update={"protect": Protect(x=x1)})
    t0 = time.perf_counter()
    sc = Screening(judged, registry, default_spec(project, registry),
                   build_concept(project, registry), rocks=rocks, seed=seed,
                   stations=stations, rock_progress=progress,
                   restart_stations=np.arange(x0, x1 + 1e-9, RESTART_STEP_M))
    runtime = time.perf_counter() - t0
    qs = sorted({50.0, 95.0, *[float(q) for q in project.analysis.percentiles]})
    t = sc.bare
    ground = section.ground_height(sc.grid)
    envelopes = {
        "x": [round(float(v), 4) for v in sc.grid],
        "ground": _json_list(ground),
        "crossings": [int(c) for c in np.isfinite(t.h).sum(axis=0)],
        "height": _finite_percentiles(t.h, qs),
        "energy": _finite_percentiles(t.e_kj, qs),
        "percentiles": [f"p{q:g}" for q in qs],
        # The 95th percentile's distribution-free bounds at the project's
        # confidence (the judge's order statistics), for the hover.
        "confidence": sc.confidence,
        "height_p95_bounds": _p95_bounds(t.h, sc.confidence),
        "energy_p95_bounds": _p95_bounds(t.e_kj, sc.confidence),
    }
    stopped = t.status == STOPPED
    counts, edges = np.histogram(t.x_end[stopped], bins=STOP_BINS, range=(x0, x1))
    reach = 0
    if project.protect is not None:
        from ..run.reach import reaches_protected_zone

        reach = int(reaches_protected_zone(t.max_x, t.status, float(project.protect.x)).sum())
    stops = {"edges": [round(float(e), 4) for e in edges], "counts": counts.tolist(),
             "stopped": int(stopped.sum()), "reaching": reach,
             "p95_x": _num(float(np.percentile(t.x_end[stopped], 95))) if stopped.any() else None}
    # The first rocks' paths, from the same random streams (rock i draws from
    # stream i of the run's key): the rocks of the table, drawn.
    k = min(PATHS_DRAWN, rocks)
    rel = sc.releases
    sub = Releases(radius=rel.radius[:k], density=rel.density, x=rel.x[:k],
                   height=rel.height[:k], vx=rel.vx[:k], vy=rel.vy[:k], spin=rel.spin[:k],
                   spin_rolling=rel.spin_rolling[:k])
    tr = run_ensemble(section, sub, key=sc.key, settings=sc.settings, n_trajectories=k)
    paths = []
    for traj in tr.trajectories:
        px, py = centre_points(traj, 12)
        paths.append(np.column_stack([px, py]).round(3).tolist())
    return Bench(sc, rocks, seed, runtime, envelopes, stops, paths)

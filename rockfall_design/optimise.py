"""Least-cost design: search the measures of ``design.candidates`` with scipy.

How a candidate design is judged, fast and with common random numbers:

1. One run of the rocks on the bare slope keeps, at dense stations along every
   barrier candidate's range, each rock's passing height, energy and speed at
   its first passage downslope, and at restart stations upslope of every
   ground-edit candidate, each rock's full state (``engine.run_ensemble``).
2. Barriers (fence, wall, boulder row) do not change the ground, so the rocks
   a barrier meets, and how high and how fast, are read from that table; a
   barrier upslope takes the rocks it stops out of what the next one sees.
   Profile edits (ditch, berm) need a new run, but only of the rocks that pass
   the restart station just upslope of the edit, resumed there from their
   saved state with their own random streams: every candidate sees the same
   rocks (cached per edit geometry).
3. The project's safety concept checks each measure on these results; the
   cost model prices it. Infeasible designs cost a penalty that grows with how
   far they miss their targets, so ``scipy.optimize.differential_evolution``
   (with integrality for products, heights and options) walks towards the
   cheapest feasible design of every family of measures (each type alone,
   pairs, the same type twice, up to ``design.max_measures``).

The screening is exact for what it models; what it leaves out (a rock that
breaks through a barrier goes on with its bare-slope path, which overstates
what reaches the next one; a rock rolling back upslope into a barrier) is
settled by the exact check: the best design of every family is run through
``evaluate_design`` with the search rocks and again with fresh, independent
rocks, and the report says whether it holds on each.

A design that does not fit (a measure's ``footprint`` raises ValueError, two
measures stand in one place) or that the cost model has no price for (its
``cost`` raises KeyError or ValueError) is infeasible, and the reason is
reported. Any other failure of plugin code is a
:class:`~rockfall_design.errors.PluginError` that stops the search (exit 3):
it is never taken for an infeasible design.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy.optimize import differential_evolution

from .engine import Releases, Section, core, run_ensemble
from .errors import ProjectError
from .evaluate import Evaluation, edited_section, evaluate_design, place_measures
from .measures import Barrier, BarrierBehaviour, MeasureResult, ProfileEdit
from .plugins import call_plugin
from .safety import Check
from .simulation import (
    draw_releases,
    engine_key,
    engine_settings,
    reaches_protected_zone,
    section_from_project,
)

if TYPE_CHECKING:  # pragma: no cover
    from .design import CandidateSpec, DesignSpec
    from .measures import ProtectiveMeasure
    from .plugins import Registry
    from .project import Project

__all__ = ["Alternative", "OptimisationResult", "Screening", "optimise", "families"]

#: Spacing (m) of the stations where barrier candidates may stand.
STATION_STEP_M = 0.5
#: Continuous design variables take one of RANGE_STEPS + 1 values across their range.
RANGE_STEPS = 100
#: Lattice (m) of the continuous dimensions of ground edits (ditch width, ...).
EDIT_STEP_M = 0.25
#: Spacing (m) of the restart stations upslope of ground-edit candidates.
RESTART_STEP_M = 2.0


# ---- the search space of one family -------------------------------------------------


@dataclass(frozen=True)
class _Var:
    """One coordinate of the search vector."""

    slot: int  # which measure of the family
    name: str  # "x", "product", "height", or a parameter name
    low: float
    high: float
    integer: bool
    options: tuple[Any, ...] = ()
    step: float = 0.0  # lattice of a continuous variable (0: 1/RANGE_STEPS of the range)


def families(candidates: Sequence[CandidateSpec], max_measures: int) -> list[tuple[int, ...]]:
    """Every multiset of candidates with 1..max_measures members, in a stable order."""
    idx = range(len(candidates))
    out: list[tuple[int, ...]] = []
    for k in range(1, max_measures + 1):
        out.extend(itertools.combinations_with_replacement(idx, k))
    return out


def candidate_name(candidates: Sequence[CandidateSpec], i: int) -> str:
    """'fence', or 'fence 25-92 m' where several candidates share a type."""
    c = candidates[i]
    if sum(d.kind == c.kind for d in candidates) == 1:
        return c.kind
    return f"{c.kind} {c.x_range[0]:g}-{c.x_range[1]:g} m"


def family_name(candidates: Sequence[CandidateSpec], fam: tuple[int, ...]) -> str:
    """'fence + ditch', '2 x fence', 'fence 25-92 m + fence 113-280 m'."""
    counts: dict[int, int] = {}
    for i in fam:
        counts[i] = counts.get(i, 0) + 1
    names = [candidate_name(candidates, i) for i in counts]
    return " + ".join(nm if n == 1 else f"{n} x {nm}" for nm, n in zip(names, counts.values(),
                                                                        strict=True))


def _variables(
    cands: Sequence[CandidateSpec], fam: tuple[int, ...], edits: set[int] | None = None
) -> list[_Var]:
    out: list[_Var] = []
    for slot, ci in enumerate(fam):
        c = cands[ci]
        out.append(_Var(slot, "x", c.x_range[0], c.x_range[1], False))
        if c.products:
            out.append(_Var(slot, "product", 0, len(c.products) - 1, True))
            nh = max(len(p.heights) for p in c.products)
            out.append(_Var(slot, "height", 0, nh - 1, True))
        for name, (lo, hi) in c.ranges.items():
            step = (hi - lo) / RANGE_STEPS
            if edits and ci in edits:
                # Every new ground edit costs a run: a coarser lattice lets the
                # search come back to designs it has already run.
                step = max(step, EDIT_STEP_M if hi - lo > 4 * EDIT_STEP_M else step)
            out.append(_Var(slot, name, lo, hi, False, step=step))
        for name, opts in c.options.items():
            out.append(_Var(slot, name, 0, len(opts) - 1, True, tuple(opts)))
    return out


def _decode(cands, fam, variables, vec) -> list[tuple[int, dict[str, Any]]]:
    """Search vector -> [(candidate index, measure parameters)] ordered by station."""
    # Only what the search picks; build_candidate_measure adds the fixed values
    # and the product's own parameters.
    params: list[dict[str, Any]] = [{} for _ in fam]
    prods: list[Any] = [None] * len(fam)
    heights: list[int] = [0] * len(fam)
    for v, val in zip(variables, vec, strict=True):
        p = params[v.slot]
        if v.name == "x":
            # Stations on the lattice of the candidate's range (the table's stations).
            lo, hi = v.low, v.high
            k = min(round((float(val) - lo) / STATION_STEP_M),
                    math.floor((hi - lo) / STATION_STEP_M + 1e-9))
            p["x"] = float(lo + max(k, 0) * STATION_STEP_M)
        elif v.name == "product":
            prods[v.slot] = cands[fam[v.slot]].products[int(round(val))]
        elif v.name == "height":
            heights[v.slot] = int(round(val))
        elif v.integer:
            p[v.name] = v.options[int(round(val))]
        else:
            # A lattice of 1/RANGE_STEPS of the range: designs an engineer can
            # build, and repeated ground edits come from the cache.
            step = v.step or (v.high - v.low) / RANGE_STEPS
            if step > 0:
                k = min(round((float(val) - v.low) / step),
                        math.floor((v.high - v.low) / step + 1e-9))
                p[v.name] = float(v.low + k * step)
            else:
                p[v.name] = float(v.low)
    out = []
    for slot, ci in enumerate(fam):
        p = params[slot]
        prod = prods[slot]
        if prod is not None:
            p["product"] = prod.name
            p["height"] = prod.heights[min(heights[slot], len(prod.heights) - 1)]
        out.append((ci, p))
    return out


# ---- screening --------------------------------------------------------------------


@dataclass
class ScreenResult:
    """One design judged on the search rocks.

    ``labels`` are the measures' labels, in the order of ``results``;
    ``reason`` says why a design that could not be judged is infeasible.
    """

    cost: float
    feasible: bool
    violation: float
    checks: list[list[Check]]
    results: list[MeasureResult]
    residual: int
    reason: str = ""
    labels: list[str] = field(default_factory=list)


@dataclass
class _Table:
    """Per rock: first downslope passage at the table stations, and how its path ended.

    A table for an edited section shares the bare table and overlays only what
    changed: the rows of the resumed rocks at the stations downslope of the
    restart station.
    """

    h: np.ndarray  # (N, S) m
    e_kj: np.ndarray  # (N, S) kJ
    v: np.ndarray  # (N, S) m/s
    max_x: np.ndarray
    x_end: np.ndarray
    status: np.ndarray
    rows: np.ndarray | None = None  # resumed rocks
    first_col: int = 0  # first overlaid station
    oh: np.ndarray | None = None  # (len(rows), S - first_col)
    oe: np.ndarray | None = None
    ov: np.ndarray | None = None

    def column(self, j: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Passing height (m), energy (kJ) and speed (m/s) of every rock at station j."""
        if self.rows is None or j < self.first_col:
            return self.h[:, j], self.e_kj[:, j], self.v[:, j]
        k = j - self.first_col
        h, e, v = self.h[:, j].copy(), self.e_kj[:, j].copy(), self.v[:, j].copy()
        h[self.rows] = self.oh[:, k]
        e[self.rows] = self.oe[:, k]
        v[self.rows] = self.ov[:, k]
        return h, e, v


class Screening:
    """Fast, common-random-number evaluation of candidate designs (see module docs)."""

    def __init__(
        self,
        project: Project,
        registry: Registry,
        spec: DesignSpec,
        concept: Any,
        *,
        rocks: int,
        seed: int,
        progress: Callable[[str], None] | None = None,
    ) -> None:
        from .design import build_candidate_measure

        self.project = project
        self.registry = registry
        self.spec = spec
        self.concept = concept
        self.n = int(rocks)
        self.seed = int(seed)
        self._build = build_candidate_measure
        self._measure_cache: dict[tuple, Any] = {}
        self.section = section_from_project(project)
        self.releases = draw_releases(project, self.n, self.seed)
        self.key = engine_key(self.seed)
        self.settings = engine_settings(project)
        self.protect_x = float(project.protect.x)
        allowed = spec.residual_count
        if spec.residual_fraction is not None:
            allowed = int(math.floor(spec.residual_fraction * self.n + 1e-9))
        self.allowed_residual = int(allowed or 0)
        # Stations: every barrier candidate's range at STATION_STEP_M; restart
        # stations upslope of every edit candidate's range.
        x0, x1 = self.section.x[0], self.section.x[-1]
        sts, restarts = [], [np.zeros(0)]
        r_max = float(np.max(self.releases.radius))
        self.margin = 2.0 * r_max + 0.5
        self.edit_candidates = {i for i, c in enumerate(spec.candidates) if self._is_edit(i)}
        for i, c in enumerate(spec.candidates):
            lo, hi = c.x_range
            sts.append(np.arange(lo, hi + 1e-9, STATION_STEP_M))
            if i in self.edit_candidates:
                # Profile edits may start upslope of their x (a berm's cut face).
                lo_r = max(x0, lo - 30.0 - self.margin)
                restarts.append(np.arange(lo_r, hi + 1e-9, RESTART_STEP_M))
        self.grid = np.unique(np.clip(np.concatenate(sts + [np.array([self.protect_x])]), x0, x1))
        self.restart_x = np.unique(np.clip(np.concatenate(restarts), x0, x1))
        t0 = time.perf_counter()
        bare = run_ensemble(
            self.section, self.releases, key=self.key, grid=self.grid,
            restart_stations=self.restart_x, settings=self.settings, record_speed=True,
        )
        self.bare_runtime_s = time.perf_counter() - t0
        cols = np.searchsorted(bare.grid, self.grid)
        self.bare = _Table(
            h=bare.grid_height[:, cols].astype(float),
            e_kj=bare.grid_energy[:, cols].astype(float) / 1e3,
            v=bare.grid_speed[:, cols].astype(float),
            max_x=bare.max_x, x_end=bare.x_end, status=bare.status,
        )
        self.restart_state = bare.restart_state
        self.restart_rng = bare.restart_rng
        self.mass = bare.mass
        self.radius = bare.radius
        # One uniform per rock for the gaps of a boulder row (common to all designs).
        self.u_gap = np.random.default_rng(np.random.SeedSequence([self.seed, 7919])).random(
            self.n)
        self._edit_cache: dict[tuple, _Table] = {}
        # A cost above any design's: infeasible designs cost at least this much.
        self.penalty_floor = 1e3 + 1e5 * spec.max_measures * max(1.0, spec.length_m)
        self.evaluations = 0
        self.edit_runs = 0

    def _is_edit(self, ci: int) -> bool:
        """Does candidate ``ci`` edit the ground? (Judged from a mid-range design.)"""
        c = self.spec.candidates[ci]
        variables = _variables(self.spec.candidates, (ci,))
        mid = [0.5 * (v.low + v.high) if not v.integer else 0 for v in variables]
        try:
            (m,) = self.measures(_decode(self.spec.candidates, (ci,), variables, mid))
            footprint = call_plugin(self.registry, m, "footprint", self.section)
        except ValueError:
            # Cannot tell from the middle of its range: treat it as the costly kind.
            return c.kind in ("ditch", "berm")
        return isinstance(footprint, ProfileEdit)

    # -- measures -----------------------------------------------------------------
    def measures(self, decoded: Sequence[tuple[int, dict[str, Any]]]) -> list[ProtectiveMeasure]:
        """The measures of a decoded design, built once per set of parameters.

        Raises
        ------
        ValueError
            The values are not valid for a measure (see ``build_candidate_measure``).
        PluginError
            A measure's class failed to instantiate or to label itself.
        """
        cands = self.spec.candidates
        out = []
        for ci, p in decoded:
            key = (ci, tuple(sorted(p.items())))
            m = self._measure_cache.get(key)
            if m is None:
                if len(self._measure_cache) > 20000:
                    self._measure_cache.clear()
                m = self._build(cands[ci], self.registry, p)
                # The report labels the designs it lists itself, also those that
                # never got as far as place_measures: a faulty label() shows here.
                call_plugin(self.registry, m, "label")
                self._measure_cache[key] = m
            out.append(m)
        return out

    def cost(self, measures: Sequence[ProtectiveMeasure]) -> float:
        """Cost of a design (currency units).

        Raises
        ------
        KeyError or ValueError
            From the cost model: it has no price for one of the measures.
        """
        model, total = self.spec.cost_model, 0.0
        for m in measures:
            q = call_plugin(self.registry, m, "quantities", self.section)
            total += float(call_plugin(self.registry, model, "cost", m, q, self.spec.length_m))
        return total

    # -- tables -------------------------------------------------------------------
    def _table_for(self, edits: Sequence[ProfileEdit], edited: Section | None) -> _Table:
        if not edits:
            return self.bare
        key = tuple((round(e.x_start, 6), round(e.x_end, 6),
                     tuple(np.round(np.asarray(e.points, float).ravel(), 6)), e.material)
                    for e in edits)
        hit = self._edit_cache.get(key)
        if hit is not None:
            return hit
        first = min(e.x_start for e in edits)
        q = np.searchsorted(self.restart_x, first - self.margin, side="right") - 1
        if q < 0:
            raise ValueError("no restart station upslope of the edit")
        xs = self.restart_x[q]
        state = self.restart_state[:, q]
        go = np.isfinite(state[:, core.RS_X])
        idx = np.flatnonzero(go)
        t = _Table(h=self.bare.h, e_kj=self.bare.e_kj, v=self.bare.v,
                   max_x=self.bare.max_x.copy(), x_end=self.bare.x_end.copy(),
                   status=self.bare.status.copy())
        if idx.size:
            sub = Releases(
                radius=self.releases.radius[idx], density=self.releases.density,
                x=self.releases.x[idx], height=self.releases.height[idx],
                vx=self.releases.vx[idx], vy=self.releases.vy[idx],
                spin=self.releases.spin[idx], spin_rolling=self.releases.spin_rolling[idx],
            )
            first = int(np.searchsorted(self.grid, xs, side="right"))
            res = run_ensemble(
                edited, sub, key=self.key, grid=self.grid[first:], settings=self.settings,
                record_speed=True,
                resume=(np.ones(idx.size, bool), state[idx], self.restart_rng[idx, q]),
            )
            cols = np.searchsorted(res.grid, self.grid[first:])
            t.rows = idx
            t.first_col = first
            t.oh = res.grid_height[:, cols].astype(float)
            t.oe = res.grid_energy[:, cols].astype(float) / 1e3
            t.ov = res.grid_speed[:, cols].astype(float)
            t.max_x[idx] = res.max_x
            t.x_end[idx] = res.x_end
            t.status[idx] = res.status
        self.edit_runs += 1
        if len(self._edit_cache) > 256:
            self._edit_cache.clear()
        self._edit_cache[key] = t
        return t

    # -- one design -----------------------------------------------------------------
    def screen(self, measures: Sequence[ProtectiveMeasure]) -> ScreenResult:
        """Judge a design on the search rocks (see the module docs)."""
        self.evaluations += 1
        try:
            placed = place_measures(self.project, self.registry, measures, self.section)
        except ProjectError as exc:
            # A measure that does not fit, or two in one place: an infeasible
            # design, not an error. A PluginError (a fault) goes on up.
            return ScreenResult(math.inf, False, math.inf, [], [], self.n, reason=exc.message)
        edits = [p.footprint for p in placed if isinstance(p.footprint, ProfileEdit)]
        edited = edited_section(self.project, self.section, placed) if edits else None
        try:
            table = self._table_for(edits, edited)
        except ValueError as exc:
            return ScreenResult(math.inf, False, math.inf, [], [], self.n, reason=str(exc))
        alive = np.ones(self.n, dtype=bool)
        results: list[MeasureResult | None] = [None] * len(placed)
        order = sorted(range(len(placed)), key=lambda i: _start(placed[i].footprint))
        for i in order:
            p = placed[i]
            fp = p.footprint
            res = MeasureResult(measure=p.measure, index=i, n_rocks=self.n)
            if isinstance(fp, Barrier):
                j = int(np.argmin(np.abs(self.grid - fp.x)))
                h, e_kj, v = table.column(j)
                met = alive & np.isfinite(h)
                over = met & (h > fp.height_m)
                gap = np.zeros(self.n, dtype=bool)
                if fp.behaviour == BarrierBehaviour.BLOCKS:
                    pgap = np.clip((fp.gap_m - 2.0 * self.radius) / fp.spacing_m, 0.0, 1.0)
                    gap = met & ~over & (self.u_gap < pgap)
                hit = met & ~over & ~gap
                broken = hit & (e_kj > fp.capacity_kj)
                held = hit & ~broken
                res.met, res.passed_over = int(met.sum()), int(over.sum())
                res.passed_through_gap, res.broken_through = int(gap.sum()), int(broken.sum())
                res.caught = int(held.sum())
                if fp.behaviour == BarrierBehaviour.RIGID:
                    res.rebounded = res.caught
                res.passing_height_m = h[met]
                res.energy_kj = e_kj[met]
                res.velocity_ms = v[met]
                res.mass_kg = self.mass[met]
                res.radius_m = self.radius[met]
                alive &= ~held
            else:
                met = alive & (table.max_x >= fp.catch_from)
                inside = (table.status == core.STOPPED) & (table.x_end >= fp.catch_from) & (
                    table.x_end <= fp.catch_to)
                held = met & inside
                res.met, res.caught = int(met.sum()), int(held.sum())
                res.passed_over = res.met - res.caught
                res.mass_kg = self.mass[met]
                res.radius_m = self.radius[met]
                res.reach_m = table.max_x[met] - fp.catch_from
                alive &= ~held
            results[i] = res
        residual = int((alive & reaches_protected_zone(table.max_x, table.status,
                                                       self.protect_x)).sum())
        checks = [call_plugin(self.registry, self.concept, "checks", res) for res in results]
        violation = 0.0
        for cs in checks:
            for c in cs:
                if not c.ok:
                    if c.value is None or not math.isfinite(c.value):
                        violation += 1.0
                    else:
                        violation += abs(c.value - c.target) / max(abs(c.target), 1e-9)
        if residual > self.allowed_residual:
            violation += 1.0 + (residual - self.allowed_residual) / max(self.n, 1) * 100.0
        labels = [p.label for p in placed]
        try:
            cost = self.cost([p.measure for p in placed])
        except (KeyError, ValueError) as exc:
            # The cost model's contract: no price for a measure skips the design.
            why = exc.args[0] if exc.args else type(exc).__name__
            return ScreenResult(
                math.inf, False, math.inf, checks, results, residual, labels=labels,
                reason=f"cost model {self.spec.cost_model.name!r} has no price for this "
                       f"design: {why}")
        return ScreenResult(cost, violation == 0.0, violation, checks, results, residual,
                            labels=labels)


def _start(fp: Barrier | ProfileEdit) -> float:
    return fp.x if isinstance(fp, Barrier) else fp.x_start


# ---- the search -----------------------------------------------------------------


@dataclass
class Alternative:
    """The best design of one family, screened and then checked exactly."""

    name: str
    family: tuple[int, ...]
    measures: list[ProtectiveMeasure] = field(default_factory=list)
    cost: float = math.inf
    screened_feasible: bool = False
    feasible: bool = False
    holds_on_fresh_rocks: bool | None = None
    checks: list[dict[str, Any]] = field(default_factory=list)
    residual: int | None = None
    fresh_residual: int | None = None
    fresh_failures: list[str] = field(default_factory=list)
    reason: str = ""
    evaluations: int = 0
    wall_s: float = 0.0
    evaluation: Evaluation | None = None

    def as_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "measures": [{"type": m.kind, **m.params.model_dump(mode="json")}
                         for m in self.measures],
            "cost": None if not math.isfinite(self.cost) else round(self.cost, 2),
            "feasible": self.feasible,
            "holds_on_fresh_rocks": self.holds_on_fresh_rocks,
            "checks": self.checks,
            "residual": self.residual,
            "fresh_residual": self.fresh_residual,
            "reason": self.reason,
            "evaluations": self.evaluations,
        }


@dataclass
class OptimisationResult:
    alternatives: list[Alternative]
    best: Alternative | None
    reason: str
    rocks: int
    seed: int
    fresh_rocks: int
    fresh_seed: int
    wall_s: float
    evaluations: int
    edit_runs: int
    currency: str = ""

    def summary(self) -> dict[str, Any]:
        return {
            "rocks": self.rocks,
            "seed": self.seed,
            "fresh_rocks": self.fresh_rocks,
            "fresh_seed": self.fresh_seed,
            "runtime_s": round(self.wall_s, 3),
            "designs_evaluated": self.evaluations,
            "edit_runs": self.edit_runs,
            "currency": self.currency,
            "alternatives": [a.as_dict() for a in self.alternatives],
            "best": None if self.best is None else self.best.name,
            "reason": self.reason,
        }


def _search_family(screen: Screening, fam: tuple[int, ...], seed: int) -> tuple[Any, Any]:
    cands = screen.spec.candidates
    variables = _variables(cands, fam, screen.edit_candidates)
    has_edit = any(i in screen.edit_candidates for i in fam)
    big = screen.penalty_floor

    def objective(vec: np.ndarray) -> float:
        decoded = _decode(cands, fam, variables, vec)
        try:
            measures = screen.measures(decoded)
        except ValueError:
            return 4.0 * big
        r = screen.screen(measures)
        if r.feasible:
            return r.cost
        if not math.isfinite(r.violation):
            return 4.0 * big
        return big + min(r.cost, big) + big * min(r.violation, 2.0) / 2.0

    bounds = [(v.low, v.high) for v in variables]
    integrality = np.array([v.integer for v in variables])
    dims = len(variables)
    # Designs with ground edits cost a run each (of the rocks below the restart
    # station); barriers alone are read from the table.
    popsize = 4 if has_edit else (15 if len(fam) == 1 else 10)
    maxiter = 12 if has_edit else (80 if len(fam) == 1 else 50)
    res = differential_evolution(
        objective, bounds, integrality=integrality, seed=seed, popsize=popsize,
        maxiter=maxiter, tol=1e-3, mutation=(0.5, 1.0), recombination=0.7, polish=False,
        init="sobol" if dims > 1 else "latinhypercube",
    )
    return res, _decode(cands, fam, variables, res.x)


def optimise(
    project: Project,
    registry: Registry,
    *,
    rocks: int | None = None,
    seed: int | None = None,
    progress: Callable[[str, int, int], None] | None = None,
) -> OptimisationResult:
    """Search every family of candidate measures for its cheapest admissible design.

    Parameters
    ----------
    project : Project
        With a ``design:`` section.
    registry : Registry
    rocks, seed : int, optional
        Search rocks and seed (default: the project's).
    progress : callable, optional
        Called as ``progress(stage, done, total)``.
    """
    from .design import resolve_design
    from .evaluate import build_concept

    t0 = time.perf_counter()
    spec = resolve_design(project, registry)
    concept = build_concept(project, registry)
    n = int(project.rocks.count if rocks is None else rocks)
    s = int(project.rocks.seed if seed is None else seed)
    # The design's residual target becomes the protected zone's allowance, so
    # that the exact checks, the fresh rocks and `check` of design.yaml agree.
    allowed = spec.residual_fraction
    if allowed is None:
        allowed = (spec.residual_count or 0) / max(n, 1)
    project = project.model_copy(
        update={"protect": project.protect.model_copy(update={"allowed_fraction": allowed})}
    )
    fresh_n = int(spec.fresh_rocks) if spec.fresh_rocks else n
    fresh_n = max(fresh_n, n)
    fresh_seed = int(spec.fresh_seed) if spec.fresh_seed is not None else s + 1000003
    screen = Screening(project, registry, spec, concept, rocks=n, seed=s)
    fams = families(spec.candidates, spec.max_measures)
    alternatives: list[Alternative] = []
    for fi, fam in enumerate(fams):
        if progress:
            progress("search", fi, len(fams))
        alt = Alternative(name=family_name(spec.candidates, fam), family=fam)
        ev0 = screen.evaluations
        ft = time.perf_counter()
        res, decoded = _search_family(screen, fam, seed=int(
            np.random.SeedSequence([s, fi]).generate_state(1)[0]))
        alt.evaluations = screen.evaluations - ev0
        try:
            alt.measures = sorted(screen.measures(decoded), key=lambda m: m.x)
            sr = screen.screen(alt.measures)
        except ValueError as exc:
            alt.reason = f"no design of this family fits: {exc}"
            alternatives.append(alt)
            continue
        alt.cost = sr.cost
        alt.screened_feasible = sr.feasible
        alt.wall_s = time.perf_counter() - ft
        if not sr.feasible:
            alt.reason = _why(sr)
        alternatives.append(alt)

    # Exact checks of every family's best: the search rocks, then fresh ones.
    for ai, alt in enumerate(alternatives):
        if progress:
            progress("check", ai, len(alternatives))
        if not alt.measures or not alt.screened_feasible:
            # Nothing admissible to confirm; the screening said why.
            continue
        ev = evaluate_design(project, registry, alt.measures, concept, rocks=n, seed=s)
        alt.evaluation = ev
        alt.feasible = ev.ok
        alt.checks = [c.as_dict() for cs in ev.checks for c in cs]
        alt.residual = ev.protect["reaching"] if ev.protect else None
        if alt.screened_feasible and not ev.ok:
            alt.reason = "passes the screening but not the exact check: " + "; ".join(
                ev.failures())
        elif not alt.screened_feasible and not alt.reason:
            alt.reason = "; ".join(ev.failures())
        if alt.feasible:
            fresh = evaluate_design(project, registry, alt.measures, concept, rocks=fresh_n,
                                    seed=fresh_seed)
            alt.holds_on_fresh_rocks = fresh.ok
            alt.fresh_residual = fresh.protect["reaching"] if fresh.protect else None
            alt.fresh_failures = fresh.failures()
    feasible = [a for a in alternatives if a.feasible]
    robust = [a for a in feasible if a.holds_on_fresh_rocks]
    # The cheapest design that also holds on fresh rocks; only if none does, the
    # cheapest on the search rocks (and the report warns).
    pool = robust or feasible
    best = min(pool, key=lambda a: a.cost) if pool else None
    reason = ""
    if best is None:
        reason = "no family of candidate measures meets every target; see each family's reason"
    elif not robust:
        reason = "no admissible design holds on the fresh rocks; the cheapest is shown"
    return OptimisationResult(
        alternatives=alternatives, best=best, reason=reason, rocks=n, seed=s,
        fresh_rocks=fresh_n, fresh_seed=fresh_seed, wall_s=time.perf_counter() - t0,
        evaluations=screen.evaluations, edit_runs=screen.edit_runs,
        currency=getattr(spec.cost_model.params, "currency", ""),
    )


def _why(sr: ScreenResult) -> str:
    if sr.reason:
        return sr.reason
    parts = []
    for label, cs in zip(sr.labels, sr.checks, strict=True):
        for c in cs:
            if not c.ok:
                parts.append(f"{label}: {c.name} {c.detail}")
    if not parts:
        parts.append(f"{sr.residual} rocks reach the protected zone")
    return "best design found still fails: " + "; ".join(parts)

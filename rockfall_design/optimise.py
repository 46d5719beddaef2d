"""Least-cost design: the cheapest admissible design of every family, proven on fresh rocks.

How it works, with common random numbers (every design sees the same rocks):

1. One run of the search rocks on the bare slope keeps, at stations every
   :data:`STATION_STEP_M` along every barrier candidate's range, each rock's
   passing height, energy and speed at its first passage downslope, and at
   restart stations upslope of every ground-edit candidate each rock's full
   state (``engine.run_ensemble``).
2. Screening (:class:`Screening`) judges a design on those rocks through the
   one judgement (:mod:`rockfall_design.judge.outcomes`): barriers from the
   table, ground edits by a run of only the rocks that pass the restart
   station just upslope of the edit, resumed from their saved state.
3. Search. Catalogue choices (products and heights, options) are discrete
   and few: they are enumerated, in increasing order of cost. Barrier
   positions are enumerated on the station grid: for each combination of
   catalogue choices the rocks reaching the protected zone are counted for
   every combination of stations at once (bit sets), and the combinations
   within the residual target are screened in full. Ground edits (ditch,
   berm), whose every geometry costs a run, are searched with
   ``scipy.optimize.differential_evolution`` over their lattice, the
   barriers beside them enumerated exactly for each geometry.
4. Decision (:func:`decide`). Designs that pass the screening, or miss it
   within its margin (``Screening.violation``),
   are evaluated exactly in order of cost, once each, with rocks planned
   from the screening (more where a design is near a limit, up to
   ``design.max_rocks``: :func:`plan_rocks`); a design is admitted only when
   every check and the residual hold with their upper confidence bounds
   (``safety.confidence``).
5. Verification. The first admitted design of a family is checked on fresh
   rocks: an independent seed and at least twice the rocks that decided it.
   If it fails there, the next design in order of cost is decided: a family
   is never dropped because its first candidate failed.

What the screening leaves out (a rock that breaks through a barrier goes on
with its bare-slope path and full energy; a rock returned by a wall stays
upslope of it; the gap passage of a boulder row is drawn from another
stream) is settled by the exact decision, which is why designs that miss the
screening by a small margin are decided exactly too.

A design that does not fit (a measure's ``footprint`` raises ValueError, two
measures stand in one place) or that the cost model has no price for (its
``cost`` raises KeyError or ValueError) is not part of the design space.
Any other failure of plugin code is a
:class:`~rockfall_design.errors.PluginError` that stops the search (exit 3).
"""

from __future__ import annotations

import heapq
import itertools
import math
import time
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy.optimize import differential_evolution

from .engine import Releases, Section, core, run_ensemble
from .errors import ProjectError
from .evaluate import (
    MIN_BARRIER_SPACING_M,
    Evaluation,
    PlacedMeasure,
    edited_section,
    evaluate_design,
    place_measures,
)
from .judge.bounds import fraction_upper_bound, rocks_to_show_fraction
from .judge.outcomes import (
    Judgement,
    RockFates,
    barrier_outcomes,
    judge_measures,
    reaches_protected_zone,
)
from .measures import Barrier, BarrierBehaviour, MeasureResult, Outcome, ProfileEdit
from .plugins import call_plugin
from .safety import DEFAULT_CONFIDENCE, Check
from .simulation import draw_releases, engine_key, engine_settings, section_from_project

if TYPE_CHECKING:  # pragma: no cover
    from .design import CandidateSpec, DesignSpec
    from .measures import ProtectiveMeasure
    from .plugins import Registry
    from .project import Project

__all__ = ["Alternative", "Decision", "OptimisationResult", "Screening", "decide", "families",
           "optimise"]

#: Spacing (m) of the stations where barrier candidates may stand.
STATION_STEP_M = 0.5
#: Continuous design variables take one of RANGE_STEPS + 1 values across their range.
RANGE_STEPS = 100
#: Lattice (m) of the continuous dimensions of ground edits (ditch width, ...).
EDIT_STEP_M = 0.25
#: Spacing (m) of the restart stations upslope of ground-edit candidates.
RESTART_STEP_M = 2.0
#: Continuous parameters of a barrier candidate take BARRIER_RANGE_STEPS + 1 values.
BARRIER_RANGE_STEPS = 10
#: Placements of one combination of catalogue choices screened in full, fewest through first.
MAX_SCREENS_PER_LEVEL = 80
#: Designs decided exactly that only came within the screening's margin, per family.
MAX_NEAR_PER_FAMILY = 6
#: Designs of one combination of catalogue choices decided exactly, at most.
MAX_EXACT_PER_LEVEL = 3
#: The search runs at least this many times the rocks that show the residual target.
SEARCH_FACTOR = 1
#: Designs the screening could not judge (too few rocks at a measure) that may fail
#: exactly before the family's other such designs are no longer decided.
MAX_UNJUDGED_FAILURES = 3
#: Exact decisions (each a run of the rocks) of one family, at most.
MAX_EXACT_PER_FAMILY = 40


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
    near: bool = False
    approximate: bool = False  # some rock's path only approximated (see Screening.judge)


@dataclass
class _Approx:
    """Where a screening rests on rocks whose paths it approximates (see Screening.judge)."""

    reaching: int  # approximated rocks among those counted as reaching the protected zone
    any: bool  # any approximated rock at all
    touched: list[bool]  # per measure: met by approximated rocks from upslope


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
        self.allowed_fraction = (spec.residual_fraction if spec.residual_fraction is not None
                                 else self.allowed_residual / max(self.n, 1))
        self.max_rocks = max(self.n, int(spec.max_rocks))
        self.confidence = float(getattr(concept.params, "confidence", DEFAULT_CONFIDENCE))
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
        self.edit_rocks = 0

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
        self.edit_rocks += int(idx.size)
        if len(self._edit_cache) > 256:
            self._edit_cache.clear()
        self._edit_cache[key] = t
        return t

    # -- one design -----------------------------------------------------------------
    def screen(self, measures: Sequence[ProtectiveMeasure]) -> ScreenResult:
        """Judge a design on the search rocks, through the one judgement (see module docs)."""
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
        judgement, approx = self.judge(placed, table)
        checks = [call_plugin(self.registry, self.concept, "checks", res)
                  for res in judgement.results]
        labels = [p.label for p in placed]
        try:
            cost = self.cost([p.measure for p in placed])
        except (KeyError, ValueError) as exc:
            # The cost model's contract: no price for a measure skips the design.
            why = exc.args[0] if exc.args else type(exc).__name__
            return ScreenResult(
                math.inf, False, math.inf, checks, judgement.results, judgement.reaching,
                labels=labels,
                reason=f"cost model {self.spec.cost_model.name!r} has no price for this "
                       f"design: {why}")
        approximate = approx.any
        violation, near = self.violation(checks, judgement.reaching, approx)
        # The screening admits only what it judged exactly (no rock whose path it
        # approximates); a design that passes with such rocks, or misses within
        # the margin, is left to the exact decision.
        feasible = violation == 0.0 and not approximate
        near = near or (violation == 0.0 and approximate)
        return ScreenResult(cost, feasible, violation, checks, judgement.results,
                            judgement.reaching, labels=labels, near=near,
                            approximate=approximate)

    def judge(self, placed: Sequence[PlacedMeasure], table: _Table) -> tuple[Judgement, _Approx]:
        """The design's outcomes on the search rocks, by the one judgement.

        Barriers are met in the order of their stations; a rock a barrier
        stops (caught, or returned by a rigid one) ends its path there, so the
        measures downslope of it never meet it. A rock that passes a barrier
        goes on along its path of the table (bare or edited ground).

        Returns the judgement and where it rests on rocks whose paths the
        screening only approximates (:class:`_Approx`): rocks that broke
        through a barrier (the exact run lets them go on with the surplus
        energy only), were returned by a rigid one (they may come back over
        it), or met a row of blocks (its gap draws come from another stream).
        """
        fates = RockFates(max_x=table.max_x.copy(), x_end=table.x_end.copy(),
                          status=table.status.copy(), mass=self.mass, radius=self.radius)
        alive = np.ones(self.n, dtype=bool)
        approx = np.zeros(self.n, dtype=bool)
        upstream: list[tuple[float, np.ndarray]] = []  # (station, rocks approximated there)
        outcomes: list[np.ndarray | None] = [None] * len(placed)
        meetings: list[np.ndarray | None] = [None] * len(placed)
        for i in sorted(range(len(placed)), key=lambda k: _start(placed[k].footprint)):
            fp = placed[i].footprint
            if not isinstance(fp, Barrier):
                continue
            j = self.station(fp.x)
            h, e_kj, v = table.column(j)
            out = barrier_outcomes(fp, h, e_kj, self.radius, self.u_gap, alive)
            stopped = (out == Outcome.CAUGHT) | (out == Outcome.REBOUNDED)
            here = (out == Outcome.BROKEN_THROUGH) | (out == Outcome.REBOUNDED)
            if fp.behaviour == BarrierBehaviour.BLOCKS:
                here = out != Outcome.NOT_MET
            approx |= here
            upstream.append((fp.x, here))
            fates.max_x[stopped] = np.minimum(fates.max_x[stopped], fp.x)
            fates.x_end[stopped] = fp.x
            fates.status[stopped] = np.where(out[stopped] == Outcome.CAUGHT, core.CAUGHT,
                                             core.STOPPED)
            alive &= ~stopped
            outcomes[i] = out
            meetings[i] = np.column_stack([h, v, e_kj])
        judgement = judge_measures(placed, outcomes, meetings, fates, self.protect_x)
        # A measure's checks rest on approximated rocks when such rocks, from a
        # barrier upslope of it, met it.
        touched = []
        for p, out in zip(placed, judgement.outcomes, strict=True):
            start = _start(p.footprint)
            before = np.zeros(self.n, dtype=bool)
            for x, m in upstream:
                if x < start:
                    before |= m
            touched.append(bool((before & (out != Outcome.NOT_MET)).any()))
        uncertain = int((approx & reaches_protected_zone(fates.max_x, fates.status,
                                                         self.protect_x)).sum())
        return judgement, _Approx(uncertain, bool(approx.any()), touched)

    def station(self, x: float) -> int:
        """Index of the table station nearest ``x`` (m)."""
        k = int(np.searchsorted(self.grid, x))
        if k > 0 and (k == self.grid.size or x - self.grid[k - 1] <= self.grid[k] - x):
            k -= 1
        return k

    def violation(
        self, checks: Sequence[Sequence[Check]], residual: int, approx: _Approx | None = None
    ) -> tuple[float, bool]:
        """How far a design misses its targets (0: it meets them), and whether within the margin.

        A check that holds on its point value but could not hold with its
        confidence bound even with ``design.max_rocks`` rocks (and likewise
        the residual) counts as a small miss. The second value says whether
        every miss may be the screening's approximation, so that the design
        is decided exactly before it may be rejected (the margin): each
        failed check belongs to a measure that rocks with approximated paths
        met (``approx.touched``), and the residual misses only through such
        rocks. Elsewhere the screening is the exact run's judgement of the
        same rocks.
        """
        touched = approx.touched if approx is not None else [False] * len(checks)
        uncertain = approx.reaching if approx is not None else 0
        violation, near = 0.0, approx is not None and approx.any
        for cs, t in zip(checks, touched, strict=True):
            for c in cs:
                if c.ok and _check_may_hold(c, self.n, self.max_rocks):
                    continue
                near &= t
                if c.ok:
                    violation += 1e-3  # holds on the point value, never with confidence
                elif c.value is None or not math.isfinite(c.value):
                    violation += 1.0
                else:
                    violation += abs(c.value - c.target) / max(abs(c.target), 1e-9)
        if residual > self.allowed_residual:
            violation += 1.0 + (residual - self.allowed_residual) / max(self.n, 1) * 100.0
            near &= residual - uncertain <= self.allowed_residual
        elif not _fraction_may_hold(residual, self.n, self.allowed_fraction, self.max_rocks,
                                    self.confidence):
            violation += 1e-3
            near &= uncertain > 0
        return violation, near and violation > 0.0


def _start(fp: Barrier | ProfileEdit) -> float:
    return fp.x if isinstance(fp, Barrier) else fp.x_start


# ---- the search space: barrier options, enumerated ----------------------------------


@dataclass
class _Option:
    """One barrier of one candidate: its parameters, measure, footprint and cost."""

    ci: int
    params: dict[str, Any]
    measure: ProtectiveMeasure
    footprint: Barrier
    cost: float
    label: str
    j: int  # station of the table


def _lattice(lo: float, hi: float, step: float) -> np.ndarray:
    """lo, lo + step, ... up to hi (inclusive within round-off)."""
    if hi <= lo or step <= 0:
        return np.array([float(lo)])
    return lo + step * np.arange(math.floor((hi - lo) / step + 1e-9) + 1)


def _discrete_choices(c: CandidateSpec) -> list[dict[str, Any]]:
    """Every catalogue choice of a candidate: product and height, options, range lattice."""
    axes: list[list[dict[str, Any]]] = []
    if c.products:
        axes.append([{"product": p.name, "height": h} for p in c.products for h in p.heights])
    for name, opts in c.options.items():
        axes.append([{name: o} for o in opts])
    for name, (lo, hi) in c.ranges.items():
        axes.append([{name: float(v)} for v in _lattice(lo, hi, (hi - lo) / BARRIER_RANGE_STEPS)])
    out = []
    for combo in itertools.product(*axes):
        d: dict[str, Any] = {}
        for part in combo:
            d.update(part)
        out.append(d)
    return out


class _BarrierSlots:
    """The barrier options of every barrier candidate, built and priced once per run.

    Per table (bare, or edited by a ground edit) and option, lazily: which
    rocks it lets on for sure (neither stopped nor broken through, see
    :meth:`passes`) and whether its checks hold as the first barrier the
    rocks meet (:meth:`first_ok`).
    """

    def __init__(self, screen: Screening) -> None:
        self.screen = screen
        self.options: dict[int, list[_Option]] = {}
        self.skipped: dict[int, Counter] = {}
        self._rows: dict[tuple[int, int, int], np.ndarray] = {}
        self._alone: dict[tuple[int, int], np.ndarray] = {}

    def of(self, ci: int) -> list[_Option]:
        """Options of candidate ``ci`` (every catalogue choice at every grid station)."""
        if ci in self.options:
            return self.options[ci]
        sc = self.screen
        c = sc.spec.candidates[ci]
        out: list[_Option] = []
        skipped: Counter = Counter()
        for d in _discrete_choices(c):
            for x in _lattice(*c.x_range, STATION_STEP_M):
                params = {**d, "x": float(x)}
                try:
                    (m,) = sc.measures([(ci, params)])
                    fp = call_plugin(sc.registry, m, "footprint", sc.section)
                    call_plugin(sc.registry, m, "design_properties")
                except ValueError as exc:
                    # Does not fit here: not part of the space.
                    skipped[f"does not fit: {exc}"] += 1
                    continue
                try:
                    cost = sc.cost([m])
                except (KeyError, ValueError) as exc:
                    # The cost model's contract: no price skips the design.
                    why = exc.args[0] if exc.args else type(exc).__name__
                    skipped[f"cost model {sc.spec.cost_model.name!r} has no price for this "
                            f"design: {why}"] += 1
                    continue
                if not isinstance(fp, Barrier):
                    continue
                out.append(_Option(ci, params, m, fp, cost,
                                   call_plugin(sc.registry, m, "label"), sc.station(fp.x)))
        self.options[ci] = out
        self.skipped[ci] = skipped
        return out

    @staticmethod
    def _table_key(j: int, table: _Table, table_id: int) -> int:
        # Stations upslope of an edit's restart see the bare table: share them.
        return 0 if (table.rows is None or j < table.first_col) else table_id

    def _outcome(self, o: _Option, table: _Table) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                           np.ndarray]:
        sc = self.screen
        h, e_kj, v = table.column(o.j)
        out = barrier_outcomes(o.footprint, h, e_kj, sc.radius, sc.u_gap,
                               np.ones(sc.n, dtype=bool))
        return out, h, e_kj, v

    def passes(self, ci: int, ks: np.ndarray, table: _Table, table_id: int) -> np.ndarray:
        """(len(ks), rocks) float32: 1 where option k lets the rock on for sure.

        A rock it stops (catches or returns) is 0, and so is one whose further
        path the screening only approximates (broken through; any rock at a
        row of blocks, whose gap draws come from another stream).
        """
        opts = self.options[ci]
        out = np.empty((len(ks), self.screen.n), dtype=np.float32)
        for i, k in enumerate(ks):
            key = (ci, int(k), self._table_key(opts[k].j, table, table_id))
            row = self._rows.get(key)
            if row is None:
                o = opts[k]
                oc = self._outcome(o, table)[0]
                row = (oc == Outcome.NOT_MET) | (oc == Outcome.PASSED_OVER) | (
                    oc == Outcome.PASSED_THROUGH_GAP)
                if o.footprint.behaviour == BarrierBehaviour.BLOCKS:
                    row = oc == Outcome.NOT_MET
                if len(self._rows) > 100_000:
                    self._rows.clear()
                self._rows[key] = row
            out[i] = row
        return out

    def first_ok(self, ci: int, ks: np.ndarray, table: _Table, table_id: int) -> np.ndarray:
        """Do options ks pass their checks as the first barrier the rocks meet?

        The first barrier of a design meets every rock that crosses its station
        on the table, so these are exactly its checks in any design in which no
        other barrier stands upslope of it (edits upslope are in the table).
        Checks that hold on the point values but could not hold with the
        confidence bounds even with ``design.max_rocks`` rocks count as failed.
        """
        sc = self.screen
        opts = self.options[ci]
        out = np.empty(len(ks), dtype=bool)
        for i, k in enumerate(ks):
            o = opts[k]
            tk = self._table_key(o.j, table, table_id)
            arr = self._alone.get((ci, tk))
            if arr is None:
                arr = self._alone[(ci, tk)] = np.full(len(opts), -1, dtype=np.int8)
            if arr[k] < 0:
                oc, h, e_kj, v = self._outcome(o, table)
                placed = PlacedMeasure(0, o.measure, o.footprint, o.label)
                fates = RockFates(max_x=table.max_x, x_end=table.x_end, status=table.status,
                                  mass=sc.mass, radius=sc.radius)
                (res,) = judge_measures([placed], [oc], [np.column_stack([h, v, e_kj])],
                                        fates, None).results
                checks = call_plugin(sc.registry, sc.concept, "checks", res)
                arr[k] = all(c.ok and _check_may_hold(c, sc.n, sc.max_rocks) for c in checks)
            out[i] = bool(arr[k])
        return out


@dataclass
class _Screened:
    """A design that passed the screening (or missed it within the margin)."""

    cost: float
    measures: list[ProtectiveMeasure]
    result: ScreenResult
    level: tuple


@dataclass
class _Tally:
    """What the designs of a family that were ruled out failed on (for the report)."""

    reasons: Counter = field(default_factory=Counter)
    designs: int = 0
    capped_levels: int = 0
    best_fail: ScreenResult | None = None
    best_fail_measures: list[ProtectiveMeasure] = field(default_factory=list)
    min_residual: int | None = None
    over_limit: float | None = None  # cost of the first design past the cost limit
    why: str = ""  # why the first design that did not fit did not
    searched: bool = False  # ground edits searched by scipy, not enumerated

    def fail(self, sr: ScreenResult, measures: Sequence[ProtectiveMeasure]) -> None:
        names = [c.name for cs in sr.checks for c in cs if not c.ok]
        if sr.reason:
            names = ["does not fit"]
        for nm in names:
            self.reasons[nm] += 1
        if sr.residual > 0 and not names:
            self.reasons["residual"] += 1
        if self.best_fail is None or sr.violation < self.best_fail.violation:
            self.best_fail, self.best_fail_measures = sr, list(measures)


def _through(reach: np.ndarray, passes: Sequence[np.ndarray]) -> np.ndarray:
    """Rocks through every barrier for each combination of options: (n1, n2, ...).

    ``sum_r reach[r] * P1[a, r] * P2[b, r] * ...``: one matrix product for
    one or two barriers (float32 counts are exact below 2**24 rocks).
    """
    first = passes[0] * reach
    if len(passes) == 1:
        return np.rint(first.sum(axis=1)).astype(np.int64)
    if len(passes) == 2:
        return np.rint(first @ passes[1].T).astype(np.int64)
    return np.stack([_through(first[a], list(passes[1:])) for a in range(first.shape[0])])


def _level_combos(levels: list[np.ndarray]) -> Any:
    """Tuples of level indices, one per slot, in increasing order of summed cost."""
    start = tuple(0 for _ in levels)
    heap = [(float(sum(lv[0] for lv in levels)), start)]
    seen = {start}
    while heap:
        cost, idx = heapq.heappop(heap)
        yield cost, idx
        for s in range(len(levels)):
            if idx[s] + 1 < len(levels[s]):
                nxt = idx[:s] + (idx[s] + 1,) + idx[s + 1:]
                if nxt not in seen:
                    seen.add(nxt)
                    c = cost - levels[s][idx[s]] + levels[s][idx[s] + 1]
                    heapq.heappush(heap, (c, nxt))


def _barrier_designs(
    screen: Screening,
    slots: _BarrierSlots,
    barrier_cis: Sequence[int],
    fixed: Sequence[ProtectiveMeasure],
    fixed_cost: float,
    table: _Table,
    table_id: int,
    tally: _Tally,
    cost_limit: float = math.inf,
) -> Any:
    """Designs of ``fixed`` measures plus one barrier per ``barrier_cis``, cheapest first.

    Every combination of the barriers' catalogue choices and grid stations is
    considered. Catalogue choices are taken in increasing order of cost; for
    each, the rocks reaching the protected zone are counted for every
    combination of stations at once (bit sets of the rocks each barrier would
    stop, judged by :func:`~rockfall_design.judge.outcomes.barrier_outcomes`);
    the combinations within the residual target (plus the screening margin)
    are screened in full, fewest reaching first, and those that pass (or
    miss within the margin) are yielded as :class:`_Screened`, in order of
    cost. Yields nothing more once the cost exceeds ``cost_limit``.
    """
    fixed = list(fixed)
    if not barrier_cis:
        if fixed_cost <= cost_limit:
            sr = screen.screen(fixed)
            tally.designs += 1
            if sr.feasible or sr.near:
                # Each geometry its own level: MAX_EXACT_PER_LEVEL counts per geometry.
                yield _Screened(sr.cost, fixed, sr, (table_id,))
            else:
                tally.fail(sr, fixed)
        return
    opts = [slots.of(ci) for ci in barrier_cis]
    if any(not o for o in opts):
        return
    costs = [np.array([o.cost for o in op]) for op in opts]
    levels = [np.unique(c) for c in costs]
    members = [[np.flatnonzero(c == lv) for lv in lvs] for c, lvs in zip(costs, levels,
                                                                          strict=True)]
    reach = reaches_protected_zone(table.max_x, table.status, screen.protect_x).astype(
        np.float32)
    edits = [call_plugin(screen.registry, m, "footprint", screen.section) for m in fixed]
    stretches = [(e.x_start, e.x_end) for e in edits if isinstance(e, ProfileEdit)]
    # Rocks through for sure (the table knows their fate) must be within the
    # target, and within what design.max_rocks rocks could show with confidence;
    # a design that misses only through rocks breaking through is screened in
    # full and, within the margin, decided exactly.
    limit = screen.allowed_residual
    while limit >= 0 and not _fraction_may_hold(limit, screen.n, screen.allowed_fraction,
                                                screen.max_rocks, screen.confidence):
        limit -= 1
    k_slots = len(opts)
    for level_cost, idx in _level_combos(levels):
        total = fixed_cost + level_cost
        if total > cost_limit:
            tally.over_limit = total if tally.over_limit is None else min(tally.over_limit, total)
            return
        ks = [members[s][idx[s]] for s in range(k_slots)]

        def shaped(a: np.ndarray, s: int) -> np.ndarray:
            return a.reshape([a.shape[0] if u == s else 1 for u in range(k_slots)])

        xs = [np.array([opts[s][k].footprint.x for k in ks[s]]) for s in range(k_slots)]
        valid = np.ones([len(k) for k in ks], dtype=bool)
        for s in range(k_slots):
            xv = shaped(xs[s], s)
            for lo, hi in stretches:
                valid &= ~((xv > lo + 1e-6) & (xv < hi - 1e-6))
            for t in range(s):
                xt = shaped(xs[t], t)
                valid &= np.abs(xv - xt) >= MIN_BARRIER_SPACING_M
                if barrier_cis[t] == barrier_cis[s]:
                    valid &= xt < xv  # one order of two barriers of one candidate
        n_comb = int(valid.size)
        tally.designs += n_comb
        # The first barrier a rock meets judges every rock that crosses it: its own
        # checks decide, whatever stands downslope.
        xb = np.stack(np.broadcast_arrays(*[shaped(xs[s], s) for s in range(k_slots)]))
        first = np.argmin(xb, axis=0)
        alone = [slots.first_ok(barrier_cis[s], ks[s], table, table_id)
                 for s in range(k_slots)]
        first_ok = np.zeros(valid.shape, dtype=bool)
        all_ok = np.ones(valid.shape, dtype=bool)
        for s in range(k_slots):
            ok_s = np.broadcast_to(shaped(alone[s], s), valid.shape)
            first_ok |= (first == s) & ok_s
            all_ok &= ok_s
        tally.reasons["first barrier's checks"] += int((valid & ~first_ok).sum())
        valid &= first_ok
        if not valid.any():
            continue
        # Count only over the options that appear in some admissible placement.
        used = [np.flatnonzero(valid.any(axis=tuple(u for u in range(k_slots) if u != s)))
                for s in range(k_slots)]
        sub = _through(reach, [slots.passes(barrier_cis[s], ks[s][used[s]], table, table_id)
                               for s in range(k_slots)])
        big = np.iinfo(np.int64).max
        residual = np.full(valid.shape, big, dtype=np.int64)
        residual[np.ix_(*used)] = sub
        residual = np.where(valid, residual, big)
        rmin = int(residual.min())
        if rmin < big:
            tally.min_residual = rmin if tally.min_residual is None else min(tally.min_residual,
                                                                            rmin)
        ok = residual <= limit
        tally.reasons["residual"] += int((valid & ~ok).sum())
        cand = np.flatnonzero(ok.ravel())
        if cand.size == 0:
            continue
        # Placements whose every barrier holds on its own first, then fewest through.
        order = cand[np.lexsort((residual.ravel()[cand], ~all_ok.ravel()[cand]))]
        if order.size > MAX_SCREENS_PER_LEVEL:
            tally.capped_levels += 1
            order = order[:MAX_SCREENS_PER_LEVEL]
        found: list[_Screened] = []
        passed = 0
        for flat in order:
            pos = np.unravel_index(flat, residual.shape)
            ms = fixed + [opts[s][ks[s][pos[s]]].measure for s in range(k_slots)]
            sr = screen.screen(ms)
            if sr.feasible or sr.near:
                found.append(_Screened(sr.cost, ms, sr, (table_id,) + tuple(idx)))
                passed += sr.feasible
                if passed >= MAX_EXACT_PER_LEVEL:
                    break  # more than the decisions this combination gets
            else:
                tally.fail(sr, ms)
        # Within one level of cost, designs that pass come before those within the margin.
        found.sort(key=lambda d: (d.cost, not d.result.feasible, d.result.violation,
                                  d.result.residual))
        yield from found


# ---- deciding and verifying, with rocks added where they decide something ----------


@dataclass
class Decision:
    """The exact evaluation of one design: admitted with confidence, or why not."""

    admitted: bool
    rocks: int
    evaluation: Evaluation
    reason: str = ""


def decide(
    project: Project,
    registry: Registry,
    measures: Sequence[ProtectiveMeasure],
    concept: Any,
    *,
    rocks: int,
    seed: int,
    max_rocks: int | None = None,
) -> Decision:
    """Evaluate a design exactly with ``rocks`` rocks; admit it only with the bounds.

    One look that can admit: a design is admitted when every check and the
    residual hold with their upper confidence bounds (``safety.confidence``).
    Looking again with more rocks until it passes would admit designs that
    do not hold more often than ``1 - confidence``, so the number of rocks is
    planned beforehand (:func:`plan_rocks`). The one exception: when all
    that keeps a design from being admitted is a check that too few rocks
    met to be bounded at all (no bound, so that look could not admit), it
    is run again with the rocks that bring enough there, up to
    ``max_rocks``.
    """
    cap = int(max_rocks or rocks)
    while True:
        ev = evaluate_design(project, registry, measures, concept, rocks=rocks, seed=seed)
        if ev.holds_with_confidence:
            return Decision(True, rocks, ev)
        if not ev.ok:
            return Decision(False, rocks, ev, "; ".join(ev.failures()))
        more = _rocks_to_bound(ev, rocks, cap)
        if more is None:
            why = "; ".join(ev.failures_with_confidence())
            return Decision(False, rocks, ev, f"holds on the point values of {rocks:,} rocks "
                                              f"but not with {100 * ev.confidence:g} % "
                                              f"confidence: {why}")
        rocks = more


def _rocks_to_bound(ev: Evaluation, rocks: int, cap: int) -> int | None:
    """More rocks for a design held back only by checks too few rocks met to be bounded.

    None when the look could have admitted the design (a bound failed, or
    the residual's did) or no more rocks are allowed.
    """
    prot = ev.protect
    if rocks >= cap or (prot is not None and not prot["ok_with_confidence"]):
        return None
    need = 0.0
    for res, cs in zip(ev.results, ev.checks, strict=True):
        for c in cs:
            if c.holds_with_confidence:
                continue
            if c.bound is not None or c.rocks_needed is None or not res.met:
                return None
            need = max(need, rocks * 1.3 * c.rocks_needed / res.met)
    return int(min(cap, rocks * math.ceil(need / rocks))) if need > rocks else None


#: Planned rocks leave this share of a design's margin to the confidence bound.
PLAN_CUSHION = 0.7


def plan_rocks(sr: ScreenResult, screen: Screening) -> int:
    """Rocks with which a screened design is to be decided: more where it is near a limit.

    From the screening on ``n`` rocks: a check that holds on its point value
    ``v`` but not with its bound ``b`` (target ``t``) needs about
    ``n ((b - v) / (PLAN_CUSHION (v - t)))**2`` rocks (the gap between an
    order-statistic bound and the point value shrinks as 1/sqrt(n)); a
    check with too few rocks at the measure to be bounded needs more rocks
    there; the residual needs the rocks with which the Clopper-Pearson bound
    of the observed fraction (plus a third) stays within the allowed one.
    Rounded up to a multiple of ``n``, at most ``design.max_rocks``.
    """
    n, cap = screen.n, screen.max_rocks
    need = float(n)
    for cs, res in zip(sr.checks, sr.results, strict=True):
        for c in cs:
            if c.holds_with_confidence or not c.ok:
                continue
            if c.bound is None or c.value is None:
                # Too few rocks met the measure: enough of them to bound it.
                at = max(res.met, 1)
                need = max(need, 1.3 * n * (c.rocks_needed or 4 * at) / at)
                continue
            margin = abs(c.value - c.target)
            gap = abs(c.bound - c.value)
            need = max(need, float(cap) if margin <= 0 else n * (gap / (PLAN_CUSHION * margin))**2)
    f = sr.residual / max(n, 1)
    if fraction_upper_bound(sr.residual, n, screen.confidence) > screen.allowed_fraction:
        m = n
        while m < cap and fraction_upper_bound(math.ceil(1.34 * f * m), m,
                                               screen.confidence) > screen.allowed_fraction:
            m *= 2
        need = max(need, float(m))
    return int(min(cap, n * math.ceil(min(need, cap) / n - 1e-9)))


def _fraction_may_hold(reaching: int, n: int, allowed: float, rocks: int,
                       confidence: float) -> bool:
    """The Clopper-Pearson bound of the observed fraction, with ``rocks`` rocks, is allowed."""
    return fraction_upper_bound(round(reaching / max(n, 1) * rocks), rocks,
                                confidence) <= allowed


def _check_may_hold(c: Check, n: int, rocks: int) -> bool:
    """Could a check that holds on its point value hold with its bound with ``rocks`` rocks?

    The gap between an order-statistic bound and the point value shrinks
    about as 1/sqrt(n) (the spread of a sample quantile); a check without a
    bound (too few rocks met the measure) may be bounded with more rocks.
    """
    if c.holds_with_confidence or c.value is None:
        return True
    if c.bound is None:
        return rocks > n  # unbounded with n rocks: more rocks may bound it
    predicted = c.value + (c.bound - c.value) * math.sqrt(n / rocks)
    # It holds when the value stays on the side of the target it is on now.
    return (c.value >= c.target) == (predicted >= c.target)


# ---- families and the result --------------------------------------------------------


@dataclass
class Alternative:
    """The cheapest admissible design of one family, decided exactly and verified."""

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
    exact_evaluations: int = 0
    wall_s: float = 0.0
    evaluation: Evaluation | None = None
    decision_rocks: int | None = None
    fresh_rocks: int | None = None
    fresh_seed: int | None = None
    proof: str = ""
    dominated: str = ""

    @property
    def holds(self) -> bool:
        """Admitted with confidence, verified on fresh rocks, not dominated."""
        return self.feasible and bool(self.holds_on_fresh_rocks) and not self.dominated

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
            "decision_rocks": self.decision_rocks,
            "fresh_residual": self.fresh_residual,
            "fresh_rocks": self.fresh_rocks,
            "fresh_seed": self.fresh_seed,
            "reason": self.reason,
            "proof": self.proof,
            "dominated": self.dominated or None,
            "evaluations": self.evaluations,
            "exact_evaluations": self.exact_evaluations,
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
    search_rocks: int = 0
    confidence: float = 0.95
    exact_evaluations: int = 0
    rocks_simulated: int = 0
    safety: Any = None  # the project's safety concept, as stated (its confidence)

    def summary(self) -> dict[str, Any]:
        return {
            "rocks": self.rocks,
            "seed": self.seed,
            "search_rocks": self.search_rocks,
            "fresh_rocks": self.fresh_rocks,
            "fresh_seed": self.fresh_seed,
            "confidence": self.confidence,
            "runtime_s": round(self.wall_s, 3),
            "designs_evaluated": self.evaluations,
            "exact_evaluations": self.exact_evaluations,
            "rocks_simulated": self.rocks_simulated,
            "edit_runs": self.edit_runs,
            "currency": self.currency,
            "alternatives": [a.as_dict() for a in self.alternatives],
            "best": None if self.best is None else self.best.name,
            "proof": "" if self.best is None else self.best.proof,
            "reason": self.reason,
        }


def _edit_designs(
    screen: Screening,
    slots: _BarrierSlots,
    fam: tuple[int, ...],
    tally: _Tally,
    seed: int,
    cost_limit: float = math.inf,
) -> list[_Screened]:
    """Designs of a family with ground edits: scipy over the edits, barriers enumerated.

    Every ground edit costs a run of the rocks below its restart station, so
    the edits' stations, options and continuous parameters (on a lattice, so
    that the search comes back to geometries it has run) are searched with
    ``scipy.optimize.differential_evolution``; for each edit geometry the
    family's barriers are enumerated exactly on its table
    (:func:`_barrier_designs`). Every design that passed the screening on
    the way is kept, cheapest first, for the exact decision.
    """
    cands = screen.spec.candidates
    tally.searched = True
    edit_slots = tuple(ci for ci in fam if ci in screen.edit_candidates)
    barrier_cis = [ci for ci in fam if ci not in screen.edit_candidates]
    variables = _variables(cands, edit_slots, screen.edit_candidates)
    big = screen.penalty_floor
    seen: dict[tuple, float] = {}
    kept: dict[tuple, _Screened] = {}

    def objective(vec: np.ndarray) -> float:
        decoded = _decode(cands, edit_slots, variables, vec)
        key = tuple((ci, tuple(sorted(p.items()))) for ci, p in decoded)
        if key in seen:
            return seen[key]
        try:
            edits = screen.measures(decoded)
            # Placing first: a geometry that does not fit is out of the space
            # before the cost model is asked to price it.
            placed = place_measures(screen.project, screen.registry, edits, screen.section)
            fixed_cost = screen.cost(edits)
            if fixed_cost > cost_limit:
                # Dearer than a design that already holds: not worth a run.
                tally.over_limit = min(tally.over_limit or math.inf, fixed_cost)
                seen[key] = big + fixed_cost
                return seen[key]
            edited = edited_section(screen.project, screen.section, placed)
            table = screen._table_for([p.footprint for p in placed], edited)
        except (KeyError, ValueError, ProjectError) as exc:
            tally.reasons["does not fit"] += 1
            tally.why = tally.why or getattr(exc, "message", None) or str(exc)
            seen[key] = 4.0 * big
            return seen[key]
        first = next(iter(_barrier_designs(screen, slots, barrier_cis, edits, fixed_cost, table,
                                           id(table), tally, cost_limit)), None)
        if first is None:
            value = big + fixed_cost
        else:
            kept[key + tuple((m.kind, m.x) for m in first.measures)] = first
            value = first.cost if first.result.feasible else big + first.cost
        seen[key] = value
        return value

    bounds = [(v.low, v.high) for v in variables]
    integrality = np.array([v.integer for v in variables])
    differential_evolution(
        objective, bounds, integrality=integrality, seed=seed, popsize=6, maxiter=12,
        tol=1e-3, mutation=(0.5, 1.0), recombination=0.7, polish=False,
        init="sobol" if len(variables) > 1 else "latinhypercube",
    )
    return sorted((d for d in kept.values() if d.cost <= cost_limit),
                  key=lambda d: (d.cost, not d.result.feasible))


def _cause(screen: Screening, slots: _BarrierSlots, fam: tuple[int, ...], tally: _Tally) -> str:
    """Why no design of a family meets the targets, with numbers."""
    cands = screen.spec.candidates
    n, allowed = screen.n, screen.allowed_residual
    reach = reaches_protected_zone(screen.bare.max_x, screen.bare.status, screen.protect_x)
    if not any(ci in screen.edit_candidates for ci in fam):
        # Rocks that never cross any station where the family's barriers may stand.
        crossing = np.zeros(n, dtype=bool)
        for ci in fam:
            lo, hi = cands[ci].x_range
            cols = (screen.grid >= lo - 1e-9) & (screen.grid <= hi + 1e-9)
            crossing |= np.isfinite(screen.bare.h[:, cols]).any(axis=1)
        missed = int((reach & ~crossing).sum())
        if missed > allowed:
            lo = min(cands[ci].x_range[0] for ci in fam)
            hi = max(cands[ci].x_range[1] for ci in fam)
            below = screen.releases.x[reach & ~crossing]
            where = (f"rocks released below x = {hi:g} m never meet a barrier in {lo:g}-{hi:g} m"
                     if below.size and float(below.min()) > hi else
                     f"rocks that never cross {lo:g}-{hi:g} m")
            return (f"{where}: {missed:,} of {n:,} ({100 * missed / n:.2f} %) reach the "
                    f"protected zone at x >= {screen.protect_x:g} m, "
                    f"{100 * screen.allowed_fraction:.2f} % allowed")
    if tally.min_residual is not None and tally.min_residual > allowed:
        return (f"every design of this family lets at least {tally.min_residual:,} of {n:,} "
                f"rocks ({100 * tally.min_residual / n:.2f} %) reach the protected zone at "
                f"x >= {screen.protect_x:g} m, {100 * screen.allowed_fraction:.2f} % allowed")
    if tally.best_fail is not None:
        return "the design that comes closest still fails: " + _why(tally.best_fail)
    if tally.over_limit is not None and tally.designs == 0:
        return f"its cheapest design costs {tally.over_limit:,.0f}"
    skipped: Counter = Counter()
    for ci in fam:
        skipped.update(slots.skipped.get(ci, {}))
    if skipped:
        why, count = skipped.most_common(1)[0]
        return f"no design of this family is in the space: {why} ({count:,} designs)"
    return f"no design of this family fits on the section{': ' + tally.why if tally.why else ''}"


def _proof(alt: Alternative, tally: _Tally, n: int, currency: str) -> str:
    """What was proven about a family's chosen design."""
    top = ", ".join(f"{k} ({v:,})" for k, v in tally.reasons.most_common(4))
    capped = (f"; in {tally.capped_levels} catalogue combinations only the "
              f"{MAX_SCREENS_PER_LEVEL} placements with fewest rocks through were screened"
              if tally.capped_levels else "")
    space = ("designs the search over its ground edits evaluated"
             if tally.searched else "designs in the space")
    return (f"cheapest of {tally.designs:,} {space} ({alt.exact_evaluations} "
            f"evaluated exactly); every cheaper design fails on {n:,} rocks: "
            f"{top or 'none cheaper'}{capped}")


def _settle(
    alt: Alternative,
    designs: Any,
    tally: _Tally,
    project: Project,
    registry: Registry,
    concept: Any,
    screen: Screening,
    spec: DesignSpec,
    *,
    seed: int,
    fresh_seed: int,
) -> int:
    """Decide a family's screened designs in order of cost until one holds; fill ``alt``.

    Returns the rocks simulated. The first design admitted with confidence
    and holding on fresh rocks is the family's; one that fails on fresh rocks
    is not chosen and the next is decided. A design in which a measure holds
    no rock is dominated by the same design without it: the family is
    reported as such (that design belongs to a smaller family).
    """
    per_level: Counter = Counter()
    decisions = near = simulated = unjudged_failures = 0
    for d in designs:
        if decisions >= MAX_EXACT_PER_FAMILY:
            alt.reason = (f"{alt.reason}; stopped after {MAX_EXACT_PER_FAMILY} exact "
                          "decisions of this family")
            break
        if per_level[d.level] >= MAX_EXACT_PER_LEVEL:
            continue
        # Too few rocks met one of its measures in the screening to bound its
        # checks: the screening could not judge it. After a few such designs
        # failed exactly, the rest of them are not decided (and said so).
        unjudged = any(c.bound is None and c.value is not None
                       for cs in d.result.checks for c in cs)
        if unjudged and unjudged_failures >= MAX_UNJUDGED_FAILURES:
            tally.reasons["too few rocks at a measure to judge in the screening, not decided"] += 1
            continue
        if not d.result.feasible:
            if near >= MAX_NEAR_PER_FAMILY:
                tally.reasons["within the screening margin, not decided"] += 1
                continue
            near += 1
        per_level[d.level] += 1
        decisions += 1
        alt.screened_feasible = alt.screened_feasible or d.result.feasible
        planned = plan_rocks(d.result, screen)
        dec = decide(project, registry, d.measures, concept, rocks=planned, seed=seed,
                     max_rocks=screen.max_rocks)
        alt.exact_evaluations += 1
        simulated += dec.rocks
        if not dec.admitted:
            tally.reasons["exact: " + (dec.reason.split(":")[0][:60] or "fails")] += 1
            alt.reason = dec.reason
            unjudged_failures += unjudged
            continue
        idle = [r.measure.label() for r in dec.evaluation.results if r.caught == 0]
        if idle and len(d.measures) > 1:
            alt.measures = sorted(d.measures, key=lambda m: m.x)
            alt.cost = d.cost
            alt.dominated = (f"its cheapest admitted design ({d.cost:,.0f}) has "
                             f"{', '.join(idle)} holding no rock: dominated by the same design "
                             "without it")
            alt.reason = alt.dominated
            return simulated
        fresh_n = max(2 * dec.rocks, int(spec.fresh_rocks or 0))
        fresh = evaluate_design(project, registry, d.measures, concept, rocks=fresh_n,
                                seed=fresh_seed)
        alt.exact_evaluations += 1
        simulated += fresh_n
        alt.measures = sorted(d.measures, key=lambda m: m.x)
        alt.cost = d.cost
        alt.evaluation = dec.evaluation
        alt.decision_rocks = dec.rocks
        alt.checks = [c.as_dict() for cs in dec.evaluation.checks for c in cs]
        alt.residual = dec.evaluation.protect["reaching"] if dec.evaluation.protect else None
        alt.holds_on_fresh_rocks = fresh.ok
        alt.fresh_rocks, alt.fresh_seed = fresh_n, fresh_seed
        alt.fresh_residual = fresh.protect["reaching"] if fresh.protect else None
        alt.fresh_failures = fresh.failures()
        alt.feasible = True  # admitted with confidence on the deciding rocks
        if fresh.ok:
            alt.reason = ""
            return simulated
        # Not chosen: it fits the noise of the search rocks. Decide the next one.
        tally.reasons["fails on fresh rocks"] += 1
        alt.reason = ("the cheapest admitted design fails on fresh rocks: "
                      + "; ".join(fresh.failures()))
    return simulated


def optimise(
    project: Project,
    registry: Registry,
    *,
    rocks: int | None = None,
    seed: int | None = None,
    progress: Callable[[str, int, int], None] | None = None,
) -> OptimisationResult:
    """The cheapest design of every family of candidate measures that holds, proven on fresh rocks.

    Parameters
    ----------
    project : Project
        With a ``design:`` section.
    registry : Registry
    rocks, seed : int, optional
        Search rocks and seed (default: the project's).
    progress : callable, optional
        Called as ``progress(stage, done, total)``.

    Notes
    -----
    Each family's designs are screened cheapest first (see
    :func:`_barrier_designs`, :func:`_edit_designs`); those that pass the
    screening, or miss it within its margin, are decided exactly in order of
    cost (:func:`decide`: admitted only with the confidence bounds, rocks
    doubled while that is undecided) and the first admitted one is verified
    on fresh rocks: an independent seed and at least twice the rocks that
    decided it. A design that fails there is not chosen; the next one in
    order of cost is decided. The best design overall is the cheapest family
    design that holds.
    """
    from .design import resolve_design
    from .evaluate import build_concept

    t0 = time.perf_counter()
    spec = resolve_design(project, registry)
    stated = build_concept(project, registry)
    confidence = float(getattr(stated.params, "confidence", DEFAULT_CONFIDENCE))
    n = int(project.rocks.count if rocks is None else rocks)
    s = int(project.rocks.seed if seed is None else seed)
    concept = stated
    # The design's residual target becomes the protected zone's allowance, so
    # that the exact checks, the fresh rocks and `check` of design.yaml agree.
    allowed = spec.residual_fraction
    if allowed is None:
        allowed = (spec.residual_count or 0) / max(n, 1)
    project = project.model_copy(
        update={"protect": project.protect.model_copy(update={"allowed_fraction": allowed})}
    )
    fresh_seed = int(spec.fresh_seed) if spec.fresh_seed is not None else s + 1000003
    # A search that cannot see the residual target decides nothing: it needs the
    # rocks with which none reaching would show the target with confidence.
    needed = rocks_to_show_fraction(allowed, confidence) if allowed > 0 else None
    if needed is not None:
        n = max(n, min(int(spec.max_rocks), SEARCH_FACTOR * needed))
    screen = Screening(project, registry, spec, concept, rocks=n, seed=s)
    slots = _BarrierSlots(screen)
    fams = families(spec.candidates, spec.max_measures)
    alternatives: list[Alternative] = []
    exact_total, simulated = 0, n
    currency = getattr(spec.cost_model.params, "currency", "")
    # Families with fewer measures first: the cheapest design that holds so far
    # bounds what the later families need to look at (a dearer design cannot be
    # the answer), and the report says so for a family cut short by it.
    order = sorted(range(len(fams)), key=lambda i: (len(fams[i]), i))
    found: dict[int, Alternative] = {}
    limit = math.inf
    for done, fi in enumerate(order):
        fam = fams[fi]
        if progress:
            progress("search", done, len(fams))
        ft = time.perf_counter()
        ev0 = screen.evaluations
        alt = Alternative(name=family_name(spec.candidates, fam), family=fam)
        tally = _Tally()
        fam_seed = int(np.random.SeedSequence([s, fi]).generate_state(1)[0])
        if any(ci in screen.edit_candidates for ci in fam):
            designs: Any = iter(_edit_designs(screen, slots, fam, tally, fam_seed, limit))
        else:
            designs = _barrier_designs(screen, slots, list(fam), [], 0.0, screen.bare, 0, tally,
                                       cost_limit=limit)
        simulated += _settle(alt, designs, tally, project, registry, concept, screen, spec,
                             seed=s, fresh_seed=fresh_seed)
        if progress:
            progress("check", done + 1, len(fams))
        alt.evaluations = screen.evaluations - ev0
        alt.wall_s = time.perf_counter() - ft
        if not alt.holds_on_fresh_rocks and not alt.dominated:
            alt.reason = alt.reason or _cause(screen, slots, fam, tally)
            if math.isfinite(limit):
                alt.reason = (f"no design of this family cheaper than the best so far "
                              f"({limit:,.0f} {currency}) holds: {alt.reason}")
        elif alt.holds:
            alt.proof = _proof(alt, tally, n, currency)
            limit = min(limit, alt.cost)
        exact_total += alt.exact_evaluations
        found[fi] = alt
    alternatives = [found[i] for i in range(len(fams))]
    pool = [a for a in alternatives if a.holds]
    best = min(pool, key=lambda a: a.cost) if pool else None
    reason = "" if best is not None else (
        "no family of candidate measures has a design that holds with "
        f"{100 * confidence:g} % confidence and on fresh rocks; see each family's reason")
    return OptimisationResult(
        alternatives=alternatives, best=best, reason=reason,
        rocks=best.decision_rocks if best is not None else n, seed=s,
        fresh_rocks=best.fresh_rocks if best is not None else 2 * n,
        fresh_seed=fresh_seed, wall_s=time.perf_counter() - t0,
        evaluations=screen.evaluations, edit_runs=screen.edit_runs, currency=currency,
        search_rocks=n, confidence=confidence, exact_evaluations=exact_total, safety=stated,
        rocks_simulated=simulated + screen.edit_rocks,
    )


def _why(sr: ScreenResult) -> str:
    if sr.reason:
        return sr.reason
    parts = []
    for label, cs in zip(sr.labels, sr.checks, strict=True):
        for c in cs:
            if not c.ok:
                value = "-" if c.value is None else f"{c.value:.2f}"
                parts.append(f"{label}: {c.name} {value} < target {c.target:.2f} ({c.detail})")
    if not parts:
        parts.append(f"{sr.residual} rocks reach the protected zone")
    return "; ".join(parts)

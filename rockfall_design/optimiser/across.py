"""Designs that hold across the scenarios of a study.

With a ``study:`` section and ``design.scenarios: all`` (or ``{share: S}``),
a design must hold in every scenario of the study (or in at least
``ceil(S k)`` of its ``k`` scenarios). Each scenario is the project with the
study's values set (:func:`~rockfall_design.studies.with_values`) and its own
rocks: its own seed (:func:`~rockfall_design.studies.scenarios`), never rocks
pooled across scenarios, so that a design is judged in each scenario as
``check`` judges it there.

The search is the single-scenario one, run per scenario and merged:

1. Each scenario has its own screening (its rocks on its bare slope).
2. Per family, every scenario's screened designs (those that pass its
   screening, or miss within the margin), cheapest first, are merged into
   one stream in order of cost. A design that holds in the required
   scenarios passes (or nearly passes) their screenings, so it is in the
   stream of each of them: the merged stream misses none.
3. Each design of the stream is screened in every scenario; with too few
   passing it is ruled out. Otherwise it is decided exactly in each
   scenario that passed (:func:`~.decide.decide`: admitted only on the
   confidence bounds, with the rocks planned from that scenario's
   screening), the scenario nearest to failing first, and, if admitted in
   enough scenarios, checked on fresh rocks in each of them (the scenario's
   seed + 1000003, at least twice the rocks that decided it there).
4. The family's design is the first that holds so; the chosen design is the
   cheapest family design.

The report names the binding scenario: the one where the chosen design has
the least margin (the smallest relative slack of a check, or of the
residual, with the confidence bounds in place), and the scenarios that
failed the next cheaper design decided.

Without ``design.scenarios`` none of this runs: :func:`~rockfall_design.optimiser.optimise`
is the single-scenario optimiser, untouched.
"""

from __future__ import annotations

import functools
import heapq
import math
import time
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ..judge.design_spec import resolve_design, with_residual_target
from ..judge.placing import build_concept
from ..judge.sequential import LookSchedule, Verdict, plan_looks
from ..plugins.concept import DEFAULT_CONFIDENCE
from ..studies.scenarios import ScenarioRun, required_scenarios, scenario_runs
from .alternatives import (
    FRESH_OFFSET,
    MAX_EXACT_PER_FAMILY,
    MAX_MARGINAL_PER_FAMILY,
    MAX_NEAR_PER_FAMILY,
    MAX_UNJUDGED_FAILURES,
    Alternative,
    OptimisationResult,
    listed_entry,
    measure_dicts,
)
from .decide import checker_margin, decide, look_concept, verify_fresh
from .driver import FamilyTask, search_families
from .screening import Screening
from .search import MAX_EXACT_PER_LEVEL, _barrier_designs, _BarrierSlots, _edit_designs, _Tally
from .space import families

if TYPE_CHECKING:  # pragma: no cover
    from ..plugins import Registry
    from ..plugins.measure import ProtectiveMeasure
    from ..project import Project

__all__ = ["AcrossResult", "optimise_across"]

#: Designs of one family screened in every scenario, at most.
MAX_DESIGNS_PER_FAMILY = 400
#: Offset of a scenario's fresh seed from its own seed (as the single optimiser's).


def _design_key(measures: Sequence[ProtectiveMeasure]) -> tuple:
    return tuple(sorted((m.kind, repr(sorted(m.params.model_dump(mode="json").items())))
                        for m in measures))


@dataclass
class _Scenario:
    """A scenario's search state: its run, design spec, concept, screening and slots."""

    run: ScenarioRun
    project: Any
    spec: Any
    concept: Any
    screen: Screening
    slots: _BarrierSlots
    looks: LookSchedule

    @property
    def fresh_seed(self) -> int:
        if self.spec.fresh_seed is not None:
            return int(self.spec.fresh_seed)
        return self.run.seed + FRESH_OFFSET


@dataclass
class AcrossResult(OptimisationResult):
    """:class:`OptimisationResult` of a design across scenarios, with what each scenario said.

    ``summary()`` has the keys of the single-scenario optimiser and
    ``scenarios``: ``share``, ``required``, ``of``, ``per_scenario`` (the
    chosen design in each scenario: ``index``, ``values``, ``seed``,
    ``admitted``, ``decision_rocks``, ``margin``, ``binds_at``,
    ``holds_on_fresh_rocks``, ``fresh_seed``, ``fresh_rocks``, ``reason``),
    ``binding`` (the scenario of least margin) and ``next_cheaper`` (the
    next cheaper design decided and the scenarios it failed in), all null
    without a design.
    """

    share: float = 1.0
    required: int = 1
    runs: list[ScenarioRun] = field(default_factory=list)
    per_family: dict[str, dict[str, Any]] = field(default_factory=dict)

    def scenarios_block(self, name: str | None = None) -> dict[str, Any]:
        """The ``scenarios`` object of the chosen design (or of family ``name``)."""
        if name is None:
            name = self.best.name if self.best is not None else None
        info = self.per_family.get(name or "", {})
        return {"share": self.share, "required": self.required, "of": len(self.runs),
                "scenarios": [r.head() for r in self.runs],
                "per_scenario": info.get("per_scenario"), "binding": info.get("binding"),
                "next_cheaper": info.get("next_cheaper")}

    def summary(self) -> dict[str, Any]:
        out = super().summary()
        for alt in out["alternatives"]:
            info = self.per_family.get(alt["name"], {})
            alt["scenarios"] = info.get("per_scenario")
            alt["binding"] = info.get("binding")
        out["scenarios"] = self.scenarios_block()
        return out


def _build(run: ScenarioRun, registry: Registry, rocks: int | None) -> tuple[_Scenario, int]:
    """A scenario's screening with the rocks that can show its residual target."""
    project = run.project
    spec = resolve_design(project, registry)
    concept = build_concept(project, registry)
    confidence = float(getattr(concept.params, "confidence", DEFAULT_CONFIDENCE))
    n = int(project.rocks.count if rocks is None else rocks)
    project, allowed = with_residual_target(project, spec, n)
    # The single optimiser's looks: the screening is the first, at the look's
    # confidence, and the exact decisions go on from there (decide).
    looks = plan_looks(n, max(n, int(spec.max_rocks)), confidence,
                       allowed if allowed > 0 else None)
    n = looks.sizes[0]
    screen = Screening(project, registry, spec,
                       look_concept(registry, concept, looks.look_confidence), rocks=n,
                       seed=run.seed)
    return _Scenario(run, project, spec, concept, screen, _BarrierSlots(screen), looks), n


def _designs(sc: _Scenario, fam: tuple[int, ...], fam_seed: int, limit: float,
             tally: _Tally) -> Any:
    """One scenario's screened designs of a family, cheapest first (the single search's)."""
    if any(ci in sc.screen.edit_candidates for ci in fam):
        return iter(_edit_designs(sc.screen, sc.slots, fam, tally, fam_seed, limit))
    return _barrier_designs(sc.screen, sc.slots, list(fam), [], 0.0, sc.screen.bare, 0, tally,
                            cost_limit=limit)


@dataclass
class _Verdict:
    """One design across the scenarios: per scenario what was found, and whether it holds."""

    holds: bool
    rows: list[dict[str, Any]]
    failed_in: list[int]
    reason: str
    decisions: list[Any]
    simulated: int = 0
    exact: int = 0
    feasible: bool = False  # passes the screening (not only within its margin) in enough
    unjudged: bool = False  # too few rocks at a measure in a screening to judge it
    undecided: str = ""  # not held, but not rejected with confidence in enough scenarios: why


def _judge_design(scs: Sequence[_Scenario], measures: Sequence[ProtectiveMeasure],
                  required: int, registry: Registry,
                  gate: Callable[[bool, bool], str] | None = None) -> _Verdict:
    """Screen a design in every scenario; decide and verify it in those it may hold in.

    ``gate(feasible, unjudged)`` may hold back the exact decision of a
    design that passes the screening in enough scenarios only within its
    margin (``feasible`` False) or that too few rocks met at a measure to
    judge (``unjudged``), as the single-scenario optimiser does: it returns
    the reason, or "" to decide.
    """
    k = len(scs)
    rows: list[dict[str, Any]] = [{**sc.run.head(), "admitted": False, "decision_rocks": None,
                                   "margin": None, "binds_at": "", "holds_on_fresh_rocks": None,
                                   "fresh_seed": None, "fresh_rocks": None, "reason": ""}
                                  for sc in scs]
    screened = [sc.screen.screen(measures) for sc in scs]
    passing = [j for j, sr in enumerate(screened) if sr.feasible or sr.near]
    failed = [j for j in range(k) if j not in passing]
    for j in failed:
        rows[j]["reason"] = "fails the screening"
    if len(passing) < required:
        return _Verdict(False, rows, failed, f"fails the screening in scenario(s) "
                        f"{', '.join(str(scs[j].run.index) for j in failed)}", [None] * k)
    feasible = sum(screened[j].feasible for j in passing) >= required
    unjudged = any(c.bound is None and c.value is not None
                   for j in passing for cs in screened[j].checks for c in cs)
    held_back = gate(feasible, unjudged) if gate is not None else ""
    if held_back:
        return _Verdict(False, rows, failed, held_back, [None] * k, feasible=feasible,
                        unjudged=unjudged, undecided=f"not decided ({held_back})")
    # The scenario nearest to failing first: its failure ends the design soonest.
    passing.sort(key=lambda j: (-screened[j].violation, screened[j].feasible))
    decisions: list[Any] = [None] * k
    simulated = exact = 0
    admitted: list[int] = []
    for j in passing:
        sc = scs[j]
        dec = decide(sc.project, registry, measures, sc.concept,
                     rocks=sc.screen.n, seed=sc.run.seed, looks=sc.looks,
                     margin=checker_margin(sc.spec, sc.looks.confidence))
        simulated += dec.simulated
        exact += dec.exact
        decisions[j] = dec
        rows[j]["decision_rocks"] = dec.rocks
        slack, rows[j]["binds_at"] = dec.evaluation.margin()
        rows[j]["margin"] = round(slack, 4) if math.isfinite(slack) else None
        if dec.admitted:
            rows[j]["admitted"] = True
            admitted.append(j)
        else:
            rows[j]["reason"] = dec.reason
            failed.append(j)
            if k - len(failed) < required:
                break
    if len(admitted) < required:
        why = "; ".join(f"scenario {scs[j].run.index}: {rows[j]['reason']}" for j in failed)
        # Rejected with confidence only where the screening or the decision said
        # so; a scenario where the design is marginal, or that was not decided
        # after the others failed, may still hold.
        marginal = [j for j in failed
                    if decisions[j] is not None and decisions[j].verdict is Verdict.MARGINAL]
        rejected = len(failed) - len(marginal)
        undecided = ""
        if marginal and k - rejected >= required:
            undecided = ("marginal in scenario(s) "
                         + ", ".join(str(scs[j].run.index) for j in marginal))
        return _Verdict(False, rows, failed, why, decisions, simulated, exact, feasible,
                        unjudged, undecided)
    holding = 0
    fresh_marginal: list[int] = []
    for i, j in enumerate(admitted):
        sc = scs[j]
        fresh_n = max(2 * decisions[j].rocks, int(sc.spec.fresh_rocks or 0))
        check = verify_fresh(sc.project, registry, measures, sc.concept, rocks=fresh_n,
                             seed=sc.fresh_seed, max_rocks=sc.looks.sizes[-1],
                             margin=checker_margin(sc.spec, sc.looks.confidence))
        simulated += check.simulated
        exact += check.exact
        held = check.verdict is Verdict.ADMITTED
        rows[j].update(holds_on_fresh_rocks=held, fresh_seed=sc.fresh_seed,
                       fresh_rocks=check.rocks)
        if held:
            holding += 1
            continue
        if check.verdict is Verdict.MARGINAL:
            fresh_marginal.append(j)
            rows[j]["reason"] = "marginal on fresh rocks: " + check.reason
        else:
            rows[j]["reason"] = "fails on fresh rocks: " + check.reason
        failed.append(j)
        if holding + len(admitted) - i - 1 < required:
            break  # too few scenarios left to verify
    if holding < required:
        why = "; ".join(f"scenario {scs[j].run.index}: {rows[j]['reason']}" for j in failed
                        if rows[j]["reason"])
        # As above: only what failed with confidence (in the search or on
        # fresh rocks) rejects; a scenario marginal on fresh rocks may hold.
        marginal = fresh_marginal + [
            j for j in failed
            if decisions[j] is not None and decisions[j].verdict is Verdict.MARGINAL]
        rejected = len(failed) - len(marginal)
        undecided = ""
        if marginal and k - rejected >= required:
            undecided = ("marginal in scenario(s) "
                         + ", ".join(str(scs[j].run.index) for j in sorted(marginal)))
        return _Verdict(False, rows, failed, why, decisions, simulated, exact, feasible,
                        unjudged, undecided)
    return _Verdict(True, rows, failed, "", decisions, simulated, exact, feasible, unjudged)


def optimise_across(
    project: Project,
    registry: Registry,
    *,
    rocks: int | None = None,
    seed: int | None = None,
    progress: Callable[[str, int, int], None] | None = None,
) -> AcrossResult:
    """The cheapest design of every family that holds in the study's required scenarios.

    Parameters
    ----------
    project : Project
        With ``study:`` and ``design.scenarios``.
    registry : Registry
    rocks : int, optional
        Search rocks of every scenario (default ``rocks.count``; at least the
        rocks that can show the residual target).
    seed : int, optional
        The run seed the scenarios' seeds derive from (default ``rocks.seed``).
    progress : callable, optional
        Called as ``progress(stage, done, total)``.
    """

    t0 = time.perf_counter()
    share = project.design.scenario_share if project.design is not None else None
    share = 1.0 if share is None else share
    s = int(project.rocks.seed if seed is None else seed)
    runs = scenario_runs(project, s)
    required = required_scenarios(share, len(runs))
    built = [_build(run, registry, rocks) for run in runs]
    scs = [b for b, _ in built]
    n = max(m for _, m in built)
    spec = scs[0].spec
    currency = getattr(spec.cost_model.params, "currency", "")
    confidence = scs[0].screen.confidence
    fams = families(spec.candidates, spec.max_measures)
    per_family: dict[str, dict[str, Any]] = {}

    def search_family(alt: Alternative, task: FamilyTask) -> int:
        simulated = 0
        tallies = [_Tally() for _ in scs]
        streams = [((j, d) for d in _designs(sc, task.family, task.seed, task.limit, t))
                   for j, (sc, t) in enumerate(zip(scs, tallies, strict=True))]
        seen: set[tuple] = set()
        reasons: Counter = Counter()
        last_failed: dict[str, Any] | None = None
        decided = designs = 0
        # The single optimiser's limits on exact decisions (see _settle): per level
        # of catalogue choices, of designs within the margin only, of unjudged ones.
        per_level: Counter = Counter()
        undecided: list[tuple[Any, str]] = []  # (design, why): not rejected with confidence
        state = {"near": 0, "unjudged_failures": 0}
        gate = functools.partial(_gate, state)

        for j_src, d in heapq.merge(*streams, key=lambda item: item[1].cost):
            key = _design_key(d.measures)
            if key in seen:
                continue
            seen.add(key)
            designs += 1
            if designs > MAX_DESIGNS_PER_FAMILY or decided >= MAX_EXACT_PER_FAMILY:
                alt.reason = (f"stopped after {designs - 1} designs screened in every scenario "
                              f"and {decided} decided exactly")
                break
            level = (j_src, d.level)
            if per_level[level] >= MAX_EXACT_PER_LEVEL:
                undecided.append((d, "not decided (the catalogue combination's decisions "
                                     "were used up)"))
                continue
            verdict = _judge_design(scs, d.measures, required, registry, gate)
            if not verdict.holds and verdict.undecided:
                undecided.append((d, verdict.undecided))
            simulated += verdict.simulated
            alt.exact_evaluations += verdict.exact
            if verdict.exact:
                decided += 1
                per_level[level] += 1
                state["near"] += not verdict.feasible
                state["unjudged_failures"] += verdict.unjudged and not verdict.holds
            if not verdict.holds:
                reasons[_reason_key(verdict.reason)] += 1
                alt.reason = verdict.reason
                # the next cheaper design than the one chosen, for the report
                last_failed = {
                    "measures": measure_dicts(d.measures),
                    "cost": round(d.cost, 2),
                    "failed_in": [scs[j].run.index for j in verdict.failed_in],
                    "reason": verdict.reason}
                continue
            _list_undecided(alt, undecided, d.cost)
            _fill(alt, d, verdict, scs, per_family, last_failed, reasons, designs, currency)
            break
        if not alt.holds_on_fresh_rocks:
            _list_undecided(alt, undecided, math.inf)
            alt.reason = alt.reason or (
                "no design of this family passes the screening in "
                f"{required} of {len(scs)} scenarios")
        return simulated

    searched = search_families(fams, spec.candidates, currency, search_family,
                               lambda: sum(sc.screen.evaluations for sc in scs), progress)
    alternatives, best = searched.alternatives, searched.best
    return AcrossResult(
        alternatives=alternatives, best=best,
        reason="" if best is not None else _no_design(required, len(scs), confidence),
        rocks=best.decision_rocks if best is not None else n, seed=s,
        fresh_rocks=best.fresh_rocks if best is not None else 2 * n,
        fresh_seed=best.fresh_seed if best is not None else s + FRESH_OFFSET,
        wall_s=time.perf_counter() - t0,
        evaluations=sum(sc.screen.evaluations for sc in scs),
        edit_runs=sum(sc.screen.edit_runs for sc in scs), currency=currency,
        search_rocks=n, confidence=confidence, exact_evaluations=searched.exact_evaluations,
        rocks_simulated=(sum(sc.screen.n for sc in scs) + searched.rocks_simulated
                         + sum(sc.screen.edit_rocks for sc in scs)),
        share=share, required=required, runs=runs, per_family=per_family,
        marginal=searched.marginal,
        decided=sum(a.exact_evaluations for a in alternatives))


def _no_design(required: int, k: int, confidence: float) -> str:
    """Why no design was chosen across the scenarios."""
    return (f"no family of candidate measures has a design that holds in {required} of "
            f"{k} scenarios with {100 * confidence:g} % confidence and on fresh rocks; "
            "see each family's reason")


def _reason_key(reason: str) -> str:
    """What a design failed on, for the proof line's tally: never cut mid-word.

    ``scenario 2: fails with 99 % confidence on 4,603 rocks: fence: height_factor
    ...; scenario 3: ...`` counts as ``fails with 99 % confidence on 4,603 rocks``
    (the first scenario's first clause); a reason without scenarios counts as its
    first clause.
    """
    first = reason.split(";")[0].strip()
    if first.startswith("scenario ") and ": " in first:
        first = first.split(": ", 1)[1]
    return first.split(": ")[0].strip() or "fails"


def _list_undecided(alt: Alternative, undecided: Sequence[tuple[Any, str]], top: float) -> None:
    """Count the designs cheaper than ``top`` not rejected with confidence; list the cheapest.

    One per cost, at most :data:`MAX_MARGINAL_PER_FAMILY`, with why each is
    undecided (marginal in some scenarios, or held back by a budget of
    decisions), as ``alt.marginal`` entries (``values`` None: a design across
    scenarios has one set of values per scenario; ``--json``'s
    ``scenarios`` block has them for the chosen design).
    """
    cheaper = sorted(((d, why) for d, why in undecided if d.cost < top),
                     key=lambda t: t[0].cost)
    alt.undecided = len(cheaper)
    seen: set[float] = set()
    for d, why in cheaper:
        key = round(float(d.cost), 2)
        if key in seen or len(alt.marginal) >= MAX_MARGINAL_PER_FAMILY:
            continue
        seen.add(key)
        alt.marginal.append(listed_entry(alt.name, d.measures,
                                         [m.label() for m in d.measures], key, rocks=None,
                                         values=None, reason=why,
                                         decided=why.startswith("marginal")))


def _gate(state: dict[str, int], feasible: bool, unjudged: bool) -> str:
    """Why a family's design is not decided exactly (see :func:`_judge_design`), or ""."""
    if unjudged and state["unjudged_failures"] >= MAX_UNJUDGED_FAILURES:
        return "too few rocks at a measure to judge in the screening, not decided"
    if not feasible and state["near"] >= MAX_NEAR_PER_FAMILY:
        return "within the screening margin, not decided"
    return ""


def _fill(alt: Alternative, d: Any, verdict: _Verdict, scs: Sequence[_Scenario],
          per_family: dict[str, dict[str, Any]], last_failed: dict[str, Any] | None,
          reasons: Counter, designs: int, currency: str) -> None:
    """A family's design that holds across the scenarios: its alternative and scenario report."""
    rows = verdict.rows
    held = [j for j, r in enumerate(rows) if r["admitted"] and r["holds_on_fresh_rocks"]]
    bind = min(held, key=lambda j: math.inf if rows[j]["margin"] is None else rows[j]["margin"])
    dec = verdict.decisions[bind]
    ev = dec.evaluation
    alt.measures = sorted(d.measures, key=lambda m: m.x)
    alt.cost = d.cost
    alt.evaluation = ev
    alt.decision_rocks = max(rows[j]["decision_rocks"] for j in held)
    alt.checks = [c.as_dict() for cs in ev.checks for c in cs]
    alt.residual = ev.protect["reaching"] if ev.protect else None
    alt.holds_on_fresh_rocks = True
    alt.fresh_rocks = max(rows[j]["fresh_rocks"] for j in held)
    alt.fresh_seed = rows[bind]["fresh_seed"]
    alt.feasible = True
    alt.screened_feasible = True
    alt.reason = ""
    top = ", ".join(f"{k} ({v:,})" for k, v in reasons.most_common(4) if v)
    undecided = (f", or is marginal or was not decided in enough of them ({alt.undecided:,}; "
                 "the cheapest listed)" if alt.undecided else "")
    alt.proof = (f"cheapest of {designs:,} designs screened in all {len(scs)} scenarios "
                 f"({alt.exact_evaluations} exact runs); every cheaper design fails with "
                 f"confidence in too many scenarios{undecided}: {top or 'none cheaper'}")
    run = scs[bind].run
    per_family[alt.name] = {
        "per_scenario": rows,
        "binding": {**run.head(), "margin": rows[bind]["margin"],
                    "binds_at": rows[bind]["binds_at"]},
        "next_cheaper": last_failed,
    }

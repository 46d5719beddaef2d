"""The optimiser on one section: every family searched, decided and verified on fresh rocks.

:func:`optimise` screens each family's designs cheapest first, decides those
the screening cannot reject (sequentially, :mod:`.decide`), verifies the
first admitted one on fresh rocks and reports the marginal and undecided
designs cheaper than it. The loop over the families is
:func:`~rockfall_design.optimiser.driver.search_families`, shared with
the scenarios' driver (:mod:`.across`).
"""

from __future__ import annotations

import math
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..judge.sequential import LookSchedule, Verdict, plan_looks
from ..plugins.concept import DEFAULT_CONFIDENCE
from ..run.reach import reaches_protected_zone

if TYPE_CHECKING:  # pragma: no cover
    from ..judge.design_spec import DesignSpec
    from ..plugins import Registry
    from ..project import Project
from .alternatives import (
    FRESH_OFFSET,
    MAX_DEFERRED_KEPT,
    MAX_DEFERRED_PER_COST,
    MAX_DEFERRED_PER_FAMILY,
    MAX_EXACT_PER_FAMILY,
    MAX_MARGINAL_PER_FAMILY,
    MAX_UNDECIDED_LISTED,
    MAX_UNJUDGED_FAILURES,
    Alternative,
    OptimisationResult,
    fresh_failures,
    listed_entry,
)
from .decide import (
    SHORT,
    Decider,
    Decision,
    checker_margin,
    look_concept,
    look_values,
    verify_fresh,
)
from .driver import FamilyTask, search_families
from .screening import Screening, ScreenResult
from .search import (
    MAX_EXACT_PER_LEVEL,
    MAX_SCREENS_PER_LEVEL,
    _barrier_designs,
    _BarrierSlots,
    _EditSearch,
    _Tally,
)
from .space import families, family_name


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


def _proof(alt: Alternative, tally: _Tally, looks: LookSchedule, currency: str) -> str:
    """What was proven about a family's chosen design (never cut short)."""
    top = ", ".join(f"{k} ({v:,})" for k, v in tally.reasons.most_common() if v)
    capped = (f"; in {tally.capped_levels} catalogue combinations only the "
              f"{MAX_SCREENS_PER_LEVEL} placements with fewest rocks through were screened"
              if tally.capped_levels else "")
    space = ("designs the search over its ground edits evaluated"
             if tally.searched else "designs in the space")
    conf = f"{100 * looks.confidence:g} %"
    k = sum(1 for m in alt.marginal if m.get("decided", True) and not m.get("short_of_margin"))
    marginal = ""
    if k or alt.undecided:
        parts = [f"is marginal ({k})"] if k else []
        if alt.undecided:
            parts.append(f"was not decided ({alt.undecided:,})")
        marginal = ", or " + " or ".join(parts) + " (the cheapest that may hold listed)"
    short = (", or falls short of the checker's margin,"
             if any(k.startswith(SHORT) and v for k, v in tally.reasons.items()) else "")
    return (f"cheapest admitted of {tally.designs:,} {space} ({alt.exact_evaluations} "
            f"evaluated exactly); every cheaper design fails{short} with {conf} confidence "
            f"(looks of {looks.sizes[0]:,} to {looks.sizes[-1]:,} rocks){marginal}: "
            f"{top or 'none cheaper'}{capped}")


def _marginal_entry(alt_name: str, d: Any, dec: Decision) -> dict[str, Any]:
    return listed_entry(alt_name, d.measures, d.result.labels, d.cost, rocks=dec.rocks,
                        values=dec.values, reason=dec.reason, decided=True,
                        margin_undecided=dec.margin_undecided,
                        short_of_margin=dec.short_of_margin)


def _undecided_entry(alt_name: str, d: Any, why: str, screen: Screening) -> dict[str, Any]:
    """A cheaper design that a budget left undecided, as the search rocks saw it.

    Listed beside the marginal designs so that the report names every cheaper
    design it did not reject with confidence: a checker who reruns with
    another seed and gets it chosen finds it here.
    """
    sr = d.result
    residual = None if screen.project.protect is None else int(sr.residual)
    values = look_values(sr.checks, sr.labels, residual, screen.n, screen.allowed_fraction,
                         screen.confidence)
    conf = f"{100 * screen.confidence:.4g} %"
    return listed_entry(alt_name, d.measures, sr.labels, d.cost, rocks=screen.n,
                        values=values, decided=False,
                        reason=(f"not decided ({why}); on the {screen.n:,} search rocks it "
                                f"neither holds nor fails with {conf} confidence"))


def _listed_at(alt: Alternative, cost: float) -> bool:
    """Is a design of this cost already listed beside the family's design?"""
    return any(round(m["cost"], 2) == round(float(cost), 2) for m in alt.marginal)


def _keep_cheapest(alt: Alternative, entry: dict[str, Any]) -> None:
    """Add a marginal or undecided entry; the family keeps the cheapest ones."""
    alt.marginal.append(entry)
    alt.marginal.sort(key=lambda m: m["cost"])
    del alt.marginal[MAX_MARGINAL_PER_FAMILY:]


def _settle(
    alt: Alternative,
    designs: Any,
    tally: _Tally,
    decider: Decider,
    spec: DesignSpec,
    concept: Any,
    *,
    fresh_seed: int,
    skipped: list[tuple[Any, str]] | None = None,
) -> int:
    """Decide a family's screened designs in order of cost until one holds; fill ``alt``.

    Returns the rocks simulated. Each design the screening did not reject is
    decided sequentially (:meth:`Decider.decide`); the first admitted one
    that holds on fresh rocks is the family's (:func:`~.decide.verify_fresh`,
    sequential too); one that fails there with confidence is not chosen and
    the next is decided; one marginal there, like a marginal design of the
    search, is kept for the report. A design in which a measure holds no
    rock is dominated by the same design without it: the family is reported
    as such (that design belongs to a smaller family).

    Contenders first: a design that meets its targets on the point values of
    the search rocks is decided as the stream reaches it; one that misses
    them there, but not with confidence (most often because the screening
    approximates some of its rocks), is set aside and decided only if it is
    cheaper than the family's design once that is found (at most
    :data:`MAX_DEFERRED_PER_FAMILY` of them, cheapest first; the rest are
    counted as not decided).

    ``skipped``: the designs an earlier call left undecided (and this call's
    are added to it), so that the count and list of cheaper undecided designs
    are of all of them when ``alt`` already holds a design and more come.
    """
    state = _SettleState(alt, tally, decider, spec, concept, fresh_seed)
    if skipped is not None:
        state.skipped = skipped
    deferred: list[Any] = []
    for d in designs:
        if state.decisions >= MAX_EXACT_PER_FAMILY:
            tally.reasons["not decided: the family's decisions were used up"] += 1
            break
        if not d.result.feasible and not d.result.point_ok:
            if len(deferred) < MAX_DEFERRED_KEPT:
                deferred.append(d)
            continue
        if state.decide(d):
            break
    top = alt.cost if alt.holds_on_fresh_rocks or alt.dominated else math.inf
    budget = MAX_DEFERRED_PER_FAMILY
    per_cost: Counter = Counter()
    # Cheapest first; among designs of one cost (one catalogue combination at
    # several stations) the one closest to holding first, and at most
    # MAX_DEFERRED_PER_COST of them, so that the budget reaches the family's
    # other combinations.
    why = "misses its targets on the point values of the search rocks, not with confidence"
    for d in sorted(deferred, key=lambda d: (d.cost, d.result.violation)):
        if d.cost >= top:
            break
        if budget <= 0 or per_cost[round(d.cost, 2)] >= MAX_DEFERRED_PER_COST:
            tally.reasons[f"not decided: {why}"] += 1
            state.skipped.append((d, why))
            continue
        budget -= 1
        per_cost[round(d.cost, 2)] += 1
        if state.decide(d):
            top = alt.cost
    _list_undecided(alt, state.skipped, top, decider.screen)
    return state.simulated


def _list_undecided(alt: Alternative, skipped: list[tuple[Any, str]], top: float,
                    screen: Screening) -> None:
    """Count the cheaper designs a budget left undecided; list the cheapest, one per cost.

    They are listed beside the marginal designs (which keep their own places):
    the family's report then names every cost below its design that may hold,
    up to :data:`MAX_UNDECIDED_LISTED` of them. A design that fails with
    confidence on the search rocks as the screening counts them (rocks whose
    paths it approximates included: a rock let through a net with its full
    energy, say) is counted but not listed: the screening alone may not reject
    it, but it is no candidate a checker would look for.
    """
    cheaper = sorted(((d, why) for d, why in skipped if d.cost < top),
                     key=lambda t: (t[0].cost, t[0].result.violation))
    alt.undecided = len(cheaper)
    decided = {round(m["cost"], 2) for m in alt.marginal}
    listed: list[dict[str, Any]] = []
    for d, why in cheaper:
        key = round(float(d.cost), 2)
        if key in decided or len(listed) >= MAX_UNDECIDED_LISTED:
            continue
        if screen.rejects(d.result.checks, int(d.result.residual)):
            continue
        decided.add(key)
        listed.append(_undecided_entry(alt.name, d, why, screen))
    alt.marginal = sorted(alt.marginal + listed, key=lambda m: m["cost"])


@dataclass
class _SettleState:
    """What deciding a family's designs has found so far (see :func:`_settle`)."""

    alt: Alternative
    tally: _Tally
    decider: Decider
    spec: DesignSpec
    concept: Any
    fresh_seed: int
    decisions: int = 0
    simulated: int = 0
    unjudged_failures: int = 0
    per_level: Counter = field(default_factory=Counter)
    marginal_levels: set = field(default_factory=set)  # levels with a design marginal at max
    skipped: list[tuple[Any, str]] = field(default_factory=list)  # (design, why not decided)

    def decide(self, d: Any) -> bool:
        """Decide one design; True when it is the family's (holds, or dominated)."""
        alt, tally = self.alt, self.tally
        if self.per_level[d.level] >= MAX_EXACT_PER_LEVEL:
            why = "the catalogue combination's decisions were used up"
            tally.reasons[f"not decided: {why}"] += 1
            self.skipped.append((d, why))
            return False
        if d.level in self.marginal_levels:
            # Its placements come closest to holding first: once one of them ran
            # to max_rocks undecided, the next (a station or two away, missing
            # by more on the search rocks) would most likely run there too, for
            # the same listing (design_two_zones: three fences at 136.5 to
            # 137.5 m, 50,000 rocks each, all marginal).
            why = "a placement of the same catalogue combination is marginal at max_rocks"
            tally.reasons[f"not decided: {why}"] += 1
            self.skipped.append((d, why))
            return False
        # Too few rocks met one of its measures in the screening to bound its
        # checks: the screening could not judge it. After a few such designs
        # failed, the rest of them are not decided (and said so).
        unjudged = any(c.bound is None and c.value is not None
                       for cs in d.result.checks for c in cs)
        if unjudged and self.unjudged_failures >= MAX_UNJUDGED_FAILURES:
            why = "too few rocks at a measure to judge in the screening"
            tally.reasons[f"not decided: {why}"] += 1
            self.skipped.append((d, why))
            return False
        self.per_level[d.level] += 1
        self.decisions += 1
        alt.screened_feasible = alt.screened_feasible or d.result.feasible
        dec = self.decider.decide(d.measures, d.result)
        alt.exact_evaluations += dec.exact
        self.simulated += dec.simulated
        if dec.verdict is Verdict.MARGINAL:
            tally.reasons["marginal"] += 1
            self.marginal_levels.add(d.level)
            # The cheapest ones are kept: deferred designs are decided after
            # dearer contenders, and a cheaper marginal design is the one the
            # report must name.
            _keep_cheapest(alt, _marginal_entry(alt.name, d, dec))
            if not alt.holds_on_fresh_rocks:
                alt.reason = dec.reason
            self.unjudged_failures += unjudged
            return False
        if not dec.admitted:
            tally.reasons[SHORT if dec.short_of_margin else "fails with confidence"] += 1
            alt.rejected += 1
            if dec.short_of_margin and not _listed_at(alt, d.cost):
                # It holds, but a checker's check would confirm it too seldom: a
                # design the engineer may still want to know of (and another seed
                # may admit), so it is listed, marked as such; once per cost (the
                # other placements of a catalogue combination say no more).
                _keep_cheapest(alt, _marginal_entry(alt.name, d, dec))
            if not alt.holds_on_fresh_rocks:
                alt.reason = dec.reason
            self.unjudged_failures += unjudged
            return False
        return self._admitted(d, dec)

    def _admitted(self, d: Any, dec: Decision) -> bool:
        alt, tally = self.alt, self.tally
        screen = self.decider.screen
        ev = dec.evaluation
        idle = [r.measure.label() for r in ev.results if r.caught == 0]
        if idle and len(d.measures) > 1:
            alt.measures = sorted(d.measures, key=lambda m: m.x)
            alt.cost = d.cost
            alt.dominated = (f"its cheapest admitted design ({d.cost:,.0f}) has "
                             f"{', '.join(idle)} holding no rock: dominated by the same design "
                             "without it")
            alt.reason = alt.dominated
            return True
        fresh_n = max(2 * dec.rocks, int(self.spec.fresh_rocks or 0))
        check = verify_fresh(screen.project, screen.registry, d.measures, self.concept,
                             rocks=fresh_n, seed=self.fresh_seed,
                             max_rocks=self.decider.looks.sizes[-1], margin=self.decider.margin)
        alt.exact_evaluations += check.exact
        self.simulated += check.simulated
        fresh = check.evaluation
        if check.verdict is Verdict.REJECTED:
            # Not chosen: it fitted the noise of the search rocks. Decide the next one.
            tally.reasons[(SHORT if check.short_of_margin else "fails with confidence")
                          + " on fresh rocks"] += 1
            alt.rejected += 1
            if check.short_of_margin and not _listed_at(alt, d.cost):
                _keep_cheapest(alt, listed_entry(
                    alt.name, d.measures, d.result.labels, d.cost, rocks=check.rocks,
                    values=check.values, decided=True, short_of_margin=True,
                    reason=(f"admitted on {dec.rocks:,} search rocks; on fresh rocks (seed "
                            f"{self.fresh_seed}) {check.reason}")))
            if not alt.holds_on_fresh_rocks:
                alt.reason = ("the cheapest admitted design fails on fresh rocks: "
                              + check.reason)
            return False
        if check.verdict is Verdict.MARGINAL:
            # Neither held nor failed on fresh rocks up to the last look: it may
            # hold, so it is listed (a rerun at another seed may choose it).
            tally.reasons["marginal on fresh rocks"] += 1
            _keep_cheapest(alt, listed_entry(
                alt.name, d.measures, d.result.labels, d.cost, rocks=check.rocks,
                values=check.values, decided=True, margin_undecided=check.margin_undecided,
                reason=(f"admitted on {dec.rocks:,} search rocks; on fresh rocks (seed "
                        f"{self.fresh_seed}) {check.reason}")))
            if not alt.holds_on_fresh_rocks:
                alt.reason = ("the cheapest admitted design is marginal on fresh rocks: "
                              + fresh_failures(fresh))
            return False
        fresh_n = check.rocks
        alt.measures = sorted(d.measures, key=lambda m: m.x)
        alt.cost = d.cost
        alt.evaluation = ev
        alt.decision_rocks = dec.rocks
        alt.checks = [c.as_dict() for cs in ev.checks for c in cs]
        alt.residual = ev.protect["reaching"] if ev.protect else None
        alt.holds_on_fresh_rocks = True
        alt.fresh_rocks, alt.fresh_seed = fresh_n, self.fresh_seed
        if check.schedule is not None:
            margin = self.decider.margin
            alt.fresh_looks = {"rocks": list(check.schedule.sizes),
                               "look_confidence": check.schedule.look_confidence,
                               "checker_power": None if margin is None else margin.power}
        alt.fresh_residual = fresh.protect["reaching"] if fresh.protect else None
        alt.fresh_failures = fresh.failures()
        alt.fresh_statements = fresh.statements()
        alt.feasible = True  # admitted with confidence on the deciding rocks
        alt.dominated = ""
        alt.reason = ""
        return True


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
    :func:`_barrier_designs`, :func:`~.search._edit_designs`); those that pass the
    screening, or miss it within its margin, are decided exactly in order of
    cost (:func:`~.decide.decide`: admitted only with the confidence bounds, with the
    rocks :func:`~.decide.rocks_to_decide` plans) and the first admitted one is verified
    on fresh rocks: an independent seed and at least twice the rocks that
    decided it. A design that fails there is not chosen; the next one in
    order of cost is decided. The best design overall is the cheapest family
    design that holds.
    """
    from ..judge.design_spec import resolve_design, with_residual_target
    from ..judge.plan import plan_for

    t0 = time.perf_counter()
    plan = plan_for(project, registry)
    # Without a design section, resolve_design says so at the project's line.
    spec = resolve_design(project, registry)
    concept = plan.concept
    confidence = float(getattr(concept.params, "confidence", DEFAULT_CONFIDENCE))
    n = int(project.rocks.count if rocks is None else rocks)
    s = int(project.rocks.seed if seed is None else seed)
    # The design's residual target becomes the protected zone's allowance, so
    # that the exact checks, the fresh rocks and `check` of design.yaml agree.
    project, allowed = with_residual_target(project, spec, n)
    fresh_seed = int(spec.fresh_seed) if spec.fresh_seed is not None else s + FRESH_OFFSET
    # The looks of every decision, fixed before any rock runs: the search rocks
    # are the first look, with at least the rocks with which none reaching
    # shows the residual target at the look's confidence.
    looks = plan_looks(n, max(n, int(spec.max_rocks)), confidence,
                       allowed if allowed > 0 else None)
    n = looks.sizes[0]
    lc = look_concept(registry, concept, looks.look_confidence)
    screen = Screening(project, registry, spec, lc, rocks=n, seed=s)
    decider = Decider(screen, looks, checker_margin(spec, confidence))
    slots = _BarrierSlots(screen)
    fams = families(spec.candidates, spec.max_measures)
    currency = getattr(spec.cost_model.params, "currency", "")
    if allowed <= 0.0:
        # No number of rocks shows that none reaches the zone: nothing can be
        # admitted with confidence, whatever the search found. Say so, at once.
        why = ("design.residual allows no rock to reach the protected zone: no number of "
               "rocks shows that with confidence, so no design can be admitted; write the "
               "fraction you can accept, e.g. residual: {fraction: 0.001}")
        alternatives = [Alternative(name=family_name(spec.candidates, fam), family=fam,
                                    reason=why) for fam in fams]
        return OptimisationResult(
            alternatives=alternatives, best=None, reason=why, rocks=n, seed=s,
            fresh_rocks=2 * n, fresh_seed=fresh_seed, wall_s=time.perf_counter() - t0,
            evaluations=0, edit_runs=0, currency=currency, search_rocks=n,
            confidence=confidence, rocks_simulated=n, looks=looks,
            bare_slope=_bare_slope(screen, allowed, confidence))

    def search_family(alt: Alternative, task: FamilyTask) -> int:
        tally = _Tally()
        edits = None
        if any(ci in screen.edit_candidates for ci in task.family):
            edits = _EditSearch(screen, slots, task.family, tally, task.limit)
            designs: Any = iter(edits.run(task.seed))
        else:
            designs = _barrier_designs(screen, slots, list(task.family), [], 0.0, screen.bare,
                                       0, tally, cost_limit=task.limit)
        skipped: list[tuple[Any, str]] = []
        rocks = _settle(alt, designs, tally, decider, spec, concept, fresh_seed=fresh_seed,
                        skipped=skipped)
        while edits is not None and alt.holds:
            # The lattice next to the chosen ground edit, which the search's
            # samples may have missed at this seed (_EditSearch.around).
            chosen = alt.cost
            near = edits.around(alt.measures, chosen)
            if not near:
                break
            rocks += _settle(alt, iter(near), tally, decider, spec, concept,
                             fresh_seed=fresh_seed, skipped=skipped)
            if not alt.cost < chosen:
                break
            # What was listed as cheaper than the earlier choice and is not
            # cheaper than this one is no longer an alternative to it.
            alt.marginal = [m for m in alt.marginal if m["cost"] < alt.cost]
        if not alt.holds_on_fresh_rocks and not alt.dominated:
            alt.reason = alt.reason or _cause(screen, slots, task.family, tally)
        elif alt.holds:
            alt.proof = _proof(alt, tally, looks, currency)
        return rocks

    searched = search_families(fams, spec.candidates, currency, search_family,
                               lambda: screen.evaluations, progress)
    alternatives, best = searched.alternatives, searched.best
    reason = "" if best is not None else (
        "no family of candidate measures has a design that holds with "
        f"{100 * confidence:g} % confidence and on fresh rocks; see each family's reason")
    return OptimisationResult(
        alternatives=alternatives, best=best, reason=reason,
        rocks=best.decision_rocks if best is not None else n, seed=s,
        fresh_rocks=best.fresh_rocks if best is not None else 2 * n,
        fresh_seed=fresh_seed, wall_s=time.perf_counter() - t0,
        evaluations=screen.evaluations, edit_runs=screen.edit_runs, currency=currency,
        search_rocks=n, confidence=confidence, exact_evaluations=searched.exact_evaluations,
        rocks_simulated=(n + searched.rocks_simulated + screen.edit_rocks
                         + decider.simulated),
        looks=looks, marginal=searched.marginal,
        decided=sum(a.exact_evaluations for a in alternatives),
        bare_slope=_bare_slope(screen, allowed, confidence),
    )


def _bare_slope(screen: Screening, allowed: float, confidence: float) -> dict[str, Any] | None:
    """The bare slope's residual on the search rocks, and whether it already meets the target.

    A project whose bare slope meets its residual target with confidence
    needs no measure for it; every design then holds by the residual alone,
    and the cheapest is only the cheapest place where a measure meets no rock.
    The report says so at its head. One look at the search rocks with the
    Clopper-Pearson upper bound at ``confidence``.

    Returns ``{x, reaching, rocks, upper, allowed, holds}`` (None without a
    protected zone).
    """
    from ..judge.bounds import fraction_upper_bound

    if screen.project.protect is None:
        return None
    reach = reaches_protected_zone(screen.bare.max_x, screen.bare.status, screen.protect_x)
    k, n = int(np.count_nonzero(reach)), screen.n
    upper = fraction_upper_bound(k, n, confidence)
    return {"x": float(screen.protect_x), "reaching": k, "rocks": n, "upper": upper,
            "allowed": float(allowed), "holds": bool(upper <= allowed)}


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

"""Deciding a family's designs in order of cost, in every scenario, verified on fresh rocks.

:class:`FamilyDecision` decides a family's screened designs until one
holds: each in the scenarios whose screening may admit it
(:func:`decide_in_scenarios`), then on fresh rocks (:func:`verify_in_scenarios`).
On a single section (one scenario) a design's decision is that scenario's.
"""

from __future__ import annotations

import itertools
import math
from collections import Counter
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING, Any

import numpy as np

from ..judge.looks import look_values
from ..judge.sequential import LookSchedule, Verdict
from ..run.reach import reaches_protected_zone
from .alternatives import (
    MAX_DEFERRED_KEPT,
    MAX_DEFERRED_PER_COST,
    MAX_DEFERRED_PER_FAMILY,
    MAX_EXACT_PER_FAMILY,
    MAX_MARGINAL_PER_FAMILY,
    MAX_UNDECIDED_LISTED,
    MAX_UNJUDGED_FAILURES,
    Alternative,
    Listed,
    fresh_failures,
    listed_entry,
    measure_dicts,
)
from .decide import SHORT, Decision, verify_fresh
from .search import MAX_EXACT_PER_LEVEL, MAX_SCREENS_PER_LEVEL, Screened, Tally

if TYPE_CHECKING:  # pragma: no cover
    from .scenario import Scenario
    from .screening import ScreenResult


@dataclass
class ScenarioDecision(Decision):
    """A design's :class:`~.decide.Decision` across the scenarios, with each scenario's.

    With one scenario it is that scenario's decision. With more: ADMITTED
    in at least ``required`` scenarios, REJECTED (with confidence, by the
    screening or a decision) in more than ``k - required``, else MARGINAL;
    ``rocks`` the most any admitted scenario needed, ``values`` empty (one
    set per scenario).

    Attributes
    ----------
    per_scenario : list of Decision or None
        Each scenario's decision (None: not decided there).
    rows : list of ScenarioRow
        Each scenario's row of the report.
    failed_in : list of int
        Indices (into the scenarios) of those where it failed or was marginal.
    """

    per_scenario: list[Decision | None] = field(default_factory=list)
    rows: list[ScenarioRow] = field(default_factory=list)
    failed_in: list[int] = field(default_factory=list)

    def held(self) -> list[int]:
        """The scenarios where it was admitted and held on fresh rocks."""
        return [j for j, r in enumerate(self.rows)
                if r.admitted and r.holds_on_fresh_rocks]


@dataclass
class ScenarioRow:
    """A design's row in one scenario (``per_scenario`` in --json, through :meth:`to_json`).

    ``head`` is the scenario's ``{index, values, seed}``
    (:meth:`~rockfall_design.studies.sampling.ScenarioRun.head`); ``margin``
    and ``binds_at`` are the deciding run's slack and where it binds
    (:meth:`~rockfall_design.judge.evaluation.Evaluation.margin`).
    """

    head: dict[str, Any]
    admitted: bool = False
    decision_rocks: int | None = None
    margin: float | None = None
    binds_at: str = ""
    holds_on_fresh_rocks: bool | None = None
    fresh_seed: int | None = None
    fresh_rocks: int | None = None
    reason: str = ""

    def to_json(self) -> dict[str, Any]:
        return {**self.head, **{f.name: getattr(self, f.name) for f in fields(self)
                                if f.name != "head"}}


def _aggregate(scs: Sequence[Scenario], required: int, per: list[Decision | None],
               rows: list[ScenarioRow], failed: list[int]) -> ScenarioDecision:
    """The decision across the scenarios from each one's (see :class:`ScenarioDecision`)."""
    decided = [d for d in per if d is not None]
    if len(scs) == 1:
        (one,) = decided
        return ScenarioDecision(**{f.name: getattr(one, f.name) for f in fields(Decision)},
                                per_scenario=per, rows=rows, failed_in=failed)
    k = len(scs)
    admitted = [j for j, d in enumerate(per) if d is not None and d.admitted]
    marginal = [j for j in failed if per[j] is not None and per[j].verdict is Verdict.MARGINAL]
    rejected = [j for j in failed if j not in marginal]
    verdict = (Verdict.ADMITTED if len(admitted) >= required else
               Verdict.REJECTED if k - len(rejected) < required else Verdict.MARGINAL)
    reason = "" if verdict is Verdict.ADMITTED else "; ".join(
        f"scenario {scs[j].run.index}: {rows[j].reason}" for j in failed if rows[j].reason)
    ev = None
    if admitted:
        ev = per[min(admitted, key=lambda j: _margin(rows[j]))].evaluation
    return ScenarioDecision(
        verdict, max((d.rocks for d in decided), default=0), ev, reason,
        exact=sum(d.exact for d in decided), simulated=sum(d.simulated for d in decided),
        short_of_margin=(verdict is Verdict.REJECTED
                         and all(per[j] is not None and per[j].short_of_margin
                                 for j in rejected)),
        margin_undecided=(verdict is Verdict.MARGINAL
                          and all(per[j].margin_undecided for j in marginal)),
        per_scenario=per, rows=rows, failed_in=failed)


def _margin(row: ScenarioRow) -> float:
    return math.inf if row.margin is None else row.margin


def decide_in_scenarios(scs: Sequence[Scenario], required: int, d: Screened) -> ScenarioDecision:
    """Screen a design in every scenario; decide it in those whose screening may admit it.

    ``d`` comes from the stream of scenario ``d.scenario``, whose screening
    it passed (or missed within the margin): there it is not screened again.
    The scenario nearest to failing is decided first (its failure ends the
    design soonest), each by its own :class:`~.decide.Decider`, until
    enough are admitted or too few are left.
    """
    k = len(scs)
    rows = [ScenarioRow(sc.run.head()) for sc in scs]
    screened = [d.result if j == d.scenario else sc.screen.screen(d.measures)
                for j, sc in enumerate(scs)]
    passing = [j for j, sr in enumerate(screened) if sr.feasible or sr.near]
    failed = [j for j in range(k) if j not in passing]
    for j in failed:
        rows[j].reason = "fails the screening"
    per: list[Decision | None] = [None] * k
    passing.sort(key=lambda j: (-screened[j].violation, screened[j].feasible))
    for j in passing:
        if k - len(failed) < required:
            break  # too few scenarios left to admit it
        dec = per[j] = scs[j].decider.decide(d.measures, screened[j])
        rows[j].decision_rocks = dec.rocks
        if dec.evaluation is not None:
            slack, rows[j].binds_at = dec.evaluation.margin()
            rows[j].margin = round(slack, 4) if math.isfinite(slack) else None
        if dec.admitted:
            rows[j].admitted = True
        else:
            rows[j].reason = dec.reason
            failed.append(j)
    return _aggregate(scs, required, per, rows, failed)


def verify_in_scenarios(scs: Sequence[Scenario], required: int, measures: Sequence[Any],
                        dec: ScenarioDecision) -> ScenarioDecision:
    """Check an admitted design on fresh rocks in every scenario that admitted it.

    Each with its fresh seed and at least twice the rocks that decided it
    there (or ``design.fresh_rocks``), sequentially
    (:func:`~.decide.verify_fresh`); stops once too few are left to hold.
    Fills ``dec.rows``' fresh columns.
    """
    k, rows = len(scs), dec.rows
    admitted = [j for j, r in enumerate(rows) if r.admitted]
    per: list[Decision | None] = [None] * k
    failed = [j for j in range(k) if j not in admitted]
    holding = 0
    for i, j in enumerate(admitted):
        sc, first = scs[j], dec.per_scenario[j]
        assert first is not None
        check = per[j] = verify_fresh(
            sc.project, sc.screen.registry, measures, sc.concept,
            rocks=max(2 * first.rocks, int(sc.spec.fresh_rocks or 0)), seed=sc.fresh_seed,
            max_rocks=sc.looks.sizes[-1], margin=sc.decider.margin, bare=sc.screen.section)
        held = check.verdict is Verdict.ADMITTED
        rows[j].holds_on_fresh_rocks, rows[j].fresh_seed = held, sc.fresh_seed
        rows[j].fresh_rocks = check.rocks
        if held:
            holding += 1
            continue
        rows[j].reason = (("marginal" if check.verdict is Verdict.MARGINAL else "fails")
                             + " on fresh rocks: " + check.reason)
        failed.append(j)
        if holding + len(admitted) - i - 1 < required:
            break  # too few scenarios left to verify
    checks = [c for c in per if c is not None]
    # A scenario marginal in the decision may still hold: it counts as marginal here too.
    per = [dec.per_scenario[j] if j not in admitted else c for j, c in enumerate(per)]
    fresh = _aggregate(scs, required, per, rows, failed)
    fresh.exact = sum(c.exact for c in checks)
    fresh.simulated = sum(c.simulated for c in checks)
    if k > 1 and fresh.admitted:
        bind = min(dec.held(), key=lambda j: _margin(rows[j]))
        fresh.evaluation, fresh.schedule = per[bind].evaluation, per[bind].schedule
        fresh.rocks = max(rows[j].fresh_rocks for j in dec.held())
    return fresh


@dataclass
class FamilyDecision:
    """Deciding one family's screened designs, cheapest first, until one holds (fills ``alt``).

    Parameters
    ----------
    alt : Alternative
        The family's outcome, filled as its designs are decided.
    scenarios : sequence of Scenario
        The study's scenarios (one: the section as written).
    required : int
        Scenarios a design must hold in.
    tallies : list of Tally
        Each scenario's search tally (a design's decision is counted in its
        stream's).
    """

    alt: Alternative
    scenarios: Sequence[Scenario]
    required: int
    tallies: list[Tally]
    #: Designs a budget left undecided, and why, over every :meth:`settle` call.
    skipped: list[tuple[Screened, str]] = field(default_factory=list)
    #: Designs decided and not chosen: (cost, the report's ``next_cheaper`` entry).
    failed: list[tuple[float, dict[str, Any]]] = field(default_factory=list)
    #: The chosen design's rows, binding scenario and next cheaper design.
    scenarios_report: dict[str, Any] | None = None
    decisions: int = 0
    simulated: int = 0
    unjudged_failures: int = 0
    per_level: Counter = field(default_factory=Counter)
    marginal_levels: set = field(default_factory=set)  # levels with a design marginal at max
    #: Some stream was left unread once the family's decisions were used up (:meth:`_skip_rest`).
    unread: bool = False

    def settle(self, designs: Any) -> int:
        """Decide ``designs`` in order of cost until one holds; returns the rocks simulated.

        Each design the screening did not reject is decided sequentially; the
        first admitted one that holds on fresh rocks is the family's; one that
        fails there with confidence is not chosen and the next is decided; one
        marginal there, like a marginal design of the search, is kept for the
        report. A design in which a measure holds no rock is dominated by the
        same design without it: the family is reported as such.

        Contenders first: a design that meets its targets on the point values
        of the search rocks is decided as the stream reaches it; one that
        misses them there, but not with confidence (most often because the
        screening approximates some of its rocks), is set aside and decided
        only if it is cheaper than the family's design once that is found (at
        most :data:`MAX_DEFERRED_PER_FAMILY`, cheapest first, at most
        :data:`MAX_DEFERRED_PER_COST` per cost; the rest are counted as not
        decided). Each call has its own budgets; the undecided designs are
        counted over all calls. Once the family's decisions are used up, the
        rest of the stream is not decided but read on for the listing
        (:meth:`_skip_rest`).
        """
        self.decisions = self.simulated = self.unjudged_failures = 0
        self.per_level, self.marginal_levels = Counter(), set()
        alt = self.alt
        deferred: list[Screened] = []
        stream = iter(designs)
        for d in stream:
            if self.decisions >= MAX_EXACT_PER_FAMILY:
                self._skip_rest(d, stream)
                break
            if not d.result.feasible and not d.result.point_ok:
                if len(deferred) < MAX_DEFERRED_KEPT:
                    deferred.append(d)
                else:
                    self._skip(d, "more designs set aside than the family keeps")
                continue
            if self.decide(d):
                break
        top = alt.cost if alt.holds_on_fresh_rocks or alt.dominated else math.inf
        self.list_undecided(self._settle_deferred(deferred, top))
        return self.simulated

    def _settle_deferred(self, deferred: list[Screened], top: float) -> float:
        """Decide the set-aside designs cheaper than ``top``; the family's cost (or ``top``)."""
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
                self.tallies[d.scenario].reasons[f"not decided: {why}"] += 1
                self.skipped.append((d, why))
                continue
            budget -= 1
            per_cost[round(d.cost, 2)] += 1
            if self.decide(d):
                top = self.alt.cost
        return top

    def list_undecided(self, top: float) -> None:
        """Count the cheaper designs a budget left undecided; list the cheapest, one per cost.

        They are listed beside the marginal designs (which keep their own
        places): the family's report then names every cost below its design
        that may hold, up to :data:`MAX_UNDECIDED_LISTED` of them. A design that
        fails with confidence on the search rocks as its screening counts them
        (rocks whose paths it approximates included: a rock let through a net
        with its full energy, say) is counted but not listed: the screening
        alone may not reject it, but it is no candidate a checker would look for.
        """
        alt = self.alt
        cheaper = sorted(((d, why) for d, why in self.skipped if d.cost < top),
                         key=lambda t: (t[0].cost, t[0].result.violation))
        alt.undecided = len(cheaper)
        decided = {round(m.cost, 2) for m in alt.marginal}
        listed: list[Listed] = []
        for d, why in cheaper:
            key = round(float(d.cost), 2)
            screen = self.scenarios[d.scenario].screen
            if key in decided or len(listed) >= MAX_UNDECIDED_LISTED:
                continue
            if screen.rejects(d.result.checks, int(d.result.residual)):
                continue
            decided.add(key)
            listed.append(self._undecided_entry(d, why))
        alt.marginal = sorted(alt.marginal + listed, key=lambda m: m.cost)

    def _undecided_entry(self, d: Screened, why: str) -> Listed:
        """A cheaper design a budget left undecided, as its stream's search rocks saw it.

        Listed beside the marginal designs so that the report names every cheaper
        design it did not reject with confidence: a checker who reruns with
        another seed and gets it chosen finds it here. Across scenarios its
        values are those of the scenario whose stream it came from (named).
        """
        sc, sr = self.scenarios[d.scenario], d.result
        screen = sc.screen
        residual = None if screen.project.protect is None else int(sr.residual)
        values = look_values(sr.checks, sr.labels, residual, screen.n, screen.allowed_fraction,
                             screen.confidence)
        where = "" if len(self.scenarios) == 1 else f" of scenario {sc.run.index}"
        conf = f"{100 * screen.confidence:.4g} %"
        return listed_entry(self.alt.name, d.measures, sr.labels, d.cost, rocks=screen.n,
                            values=values, decided=False,
                            reason=(f"not decided ({why}); on the {screen.n:,} search rocks"
                                    f"{where} it neither holds nor fails with {conf} "
                                    "confidence"))

    def _skip_rest(self, first: Screened, stream: Iterator[Screened]) -> None:
        """The designs of a stream left once the family's decisions are used up: not decided.

        They are dearer than every design decided so far, but may be cheaper
        than the family's design (a deferred one) or than another family's:
        each is counted and may be listed (:meth:`list_undecided`), never
        dropped unsaid. Cutting the stream here dropped them, and
        design_ditch_or_fence at seed 11 chose a 67,500 fence without naming
        the 29,551 ditch that seeds 12 to 15 choose or name (40 decisions
        spent on ditches of 23,418 to 28,099, its three placements never
        decided). The stream is read on until :data:`MAX_UNDECIDED_LISTED`
        costs could be listed (a stream of barriers screens as it is read;
        no later design would be listed); :attr:`unread` says whether some
        of it was left.
        """
        why = "the family's decisions were used up"
        costs: set[float] = set()
        for d in itertools.chain([first], stream):
            if len(costs) >= MAX_UNDECIDED_LISTED:
                self.unread = True
                return
            self._skip(d, why)
            if not self.scenarios[d.scenario].screen.rejects(d.result.checks,
                                                              int(d.result.residual)):
                costs.add(round(float(d.cost), 2))

    def _skip(self, d: Screened, why: str) -> bool:
        self.tallies[d.scenario].reasons[f"not decided: {why}"] += 1
        self.skipped.append((d, why))
        return False

    def decide(self, d: Screened) -> bool:
        """Decide one design; True when it is the family's (holds, or dominated)."""
        alt, tally = self.alt, self.tallies[d.scenario]
        level = ((d.scenario, d.level) if len(self.scenarios) == 1  # its search's own ids;
                 else tuple(sorted(m.without_station() for m in d.measures)))  # shared ones
        if self.per_level[level] >= MAX_EXACT_PER_LEVEL * len(self.scenarios):
            return self._skip(d, "the catalogue combination's decisions were used up")
        if level in self.marginal_levels:
            # Its placements come closest to holding first: once one of them ran
            # to max_rocks undecided, the next (a station or two away, missing
            # by more on the search rocks) would most likely run there too, for
            # the same listing (design_two_zones: three fences at 136.5 to
            # 137.5 m, 50,000 rocks each, all marginal).
            return self._skip(d, "a placement of the same catalogue combination is marginal "
                                 "at max_rocks")
        # Too few rocks met one of its measures in the screening to bound its
        # checks: the screening could not judge it. After a few such designs
        # failed, the rest of them are not decided (and said so).
        unjudged = any(c.bound is None and c.value is not None
                       for cs in d.result.checks for c in cs)
        if unjudged and self.unjudged_failures >= MAX_UNJUDGED_FAILURES:
            return self._skip(d, "too few rocks at a measure to judge in the screening")
        self.per_level[level] += 1
        self.decisions += 1
        alt.screened_feasible = alt.screened_feasible or d.result.feasible
        dec = decide_in_scenarios(self.scenarios, self.required, d)
        alt.exact_evaluations += dec.exact
        self.simulated += dec.simulated
        if dec.admitted:
            return self._admitted(d, dec)
        self._failed(d, dec)
        if dec.verdict is Verdict.MARGINAL:
            tally.reasons["marginal"] += 1
            self.marginal_levels.add(level)
            # The cheapest ones are kept: deferred designs are decided after
            # dearer contenders, and a cheaper marginal design is the one the
            # report must name.
            self._keep(self._entry(d, dec, dec.reason))
        else:
            tally.reasons[SHORT if dec.short_of_margin else "fails with confidence"] += 1
            alt.rejected += 1
            if dec.short_of_margin and not self._listed_at(d.cost):
                # It holds, but a checker's check would confirm it too seldom: a
                # design the engineer may still want to know of (and another seed
                # may admit), so it is listed, marked as such; once per cost (the
                # other placements of a catalogue combination say no more).
                self._keep(self._entry(d, dec, dec.reason))
        if not alt.holds_on_fresh_rocks:
            alt.reason = dec.reason
        self.unjudged_failures += unjudged
        return False

    def _entry(self, d: Screened, dec: Decision, reason: str) -> Listed:
        """A design decided and not chosen, as the report lists it."""
        return listed_entry(self.alt.name, d.measures, d.result.labels, d.cost, rocks=dec.rocks,
                            values=dec.values, reason=reason, decided=True,
                            margin_undecided=dec.margin_undecided,
                            short_of_margin=dec.short_of_margin)

    def _listed_at(self, cost: float) -> bool:
        """Is a design of this cost already listed beside the family's design?"""
        return any(round(m.cost, 2) == round(float(cost), 2) for m in self.alt.marginal)

    def _keep(self, entry: Listed) -> None:
        """Add a marginal or undecided entry; the family keeps the cheapest ones."""
        marginal = self.alt.marginal
        marginal.append(entry)
        marginal.sort(key=lambda m: m.cost)
        del marginal[MAX_MARGINAL_PER_FAMILY:]

    def _failed(self, d: Screened, dec: ScenarioDecision) -> None:
        """Remember a design decided and not chosen (the report's next cheaper design)."""
        self.failed.append((d.cost, {
            "measures": measure_dicts(d.measures), "cost": round(d.cost, 2),
            "failed_in": [self.scenarios[j].run.index for j in dec.failed_in],
            "reason": dec.reason}))

    def _idle(self, dec: ScenarioDecision) -> list[str]:
        """Measures that hold no rock in any scenario that admitted the design."""
        evs = [p.evaluation for p in dec.per_scenario if p is not None and p.admitted]
        idle = [r.measure.label() for r in evs[0].results if r.caught == 0]
        return [lb for lb in idle
                if all(r.caught == 0 for ev in evs[1:] for r in ev.results
                       if r.measure.label() == lb)]

    def _admitted(self, d: Screened, dec: ScenarioDecision) -> bool:
        alt = self.alt
        idle = self._idle(dec)
        if idle and len(d.measures) > 1:
            alt.measures = sorted(d.measures, key=lambda m: m.x)
            alt.cost = d.cost
            alt.dominated = (f"its cheapest admitted design ({d.cost:,.0f}) has "
                             f"{', '.join(idle)} holding no rock: dominated by the same design "
                             "without it")
            alt.reason = alt.dominated
            return True
        check = verify_in_scenarios(self.scenarios, self.required, d.measures, dec)
        alt.exact_evaluations += check.exact
        self.simulated += check.simulated
        if check.admitted:
            self._chosen(d, dec, check)
            return True
        self._failed(d, check)
        # Across scenarios each one's reason names it, with its fresh seed in its row.
        seed = f" (seed {self.scenarios[0].fresh_seed})" if len(self.scenarios) == 1 else ""
        reason = f"admitted on {dec.rocks:,} search rocks; on fresh rocks{seed} {check.reason}"
        if check.verdict is Verdict.REJECTED:
            # Not chosen: it fitted the noise of the search rocks. Decide the next one.
            self.tallies[d.scenario].reasons[
                (SHORT if check.short_of_margin else "fails with confidence")
                + " on fresh rocks"] += 1
            alt.rejected += 1
            if check.short_of_margin and not self._listed_at(d.cost):
                self._keep(self._entry(d, check, reason))
            if not alt.holds_on_fresh_rocks:
                alt.reason = "the cheapest admitted design fails on fresh rocks: " + check.reason
            return False
        # Neither held nor failed on fresh rocks up to the last look: it may
        # hold, so it is listed (a rerun at another seed may choose it).
        self.tallies[d.scenario].reasons["marginal on fresh rocks"] += 1
        self._keep(self._entry(d, check, reason))
        if not alt.holds_on_fresh_rocks:
            alt.reason = ("the cheapest admitted design is marginal on fresh rocks: "
                          + (fresh_failures(check.evaluation) if check.evaluation is not None
                             else check.reason))
        return False

    def _chosen(self, d: Screened, dec: ScenarioDecision, check: ScenarioDecision) -> None:
        """The family's design: it holds in the required scenarios and on fresh rocks."""
        alt, rows = self.alt, dec.rows
        held = dec.held()
        bind = min(held, key=lambda j: _margin(rows[j]))
        ev = dec.per_scenario[bind].evaluation
        fresh = check.evaluation
        alt.measures = sorted(d.measures, key=lambda m: m.x)
        alt.cost = d.cost
        alt.evaluation = ev
        alt.decision_rocks = max(rows[j].decision_rocks for j in held)
        alt.checks = [c.as_dict() for cs in ev.checks for c in cs]
        alt.residual = ev.residual.reaching if ev.residual is not None else None
        alt.holds_on_fresh_rocks = True
        alt.fresh_rocks, alt.fresh_seed = check.rocks, rows[bind].fresh_seed
        if check.schedule is not None:
            margin = self.scenarios[bind].decider.margin
            alt.fresh_looks = {"rocks": list(check.schedule.sizes),
                               "look_confidence": check.schedule.look_confidence,
                               "checker_power": None if margin is None else margin.power}
        alt.fresh_residual = fresh.residual.reaching if fresh.residual is not None else None
        alt.fresh_failures = fresh.failures()
        alt.fresh_statements = fresh.statements()
        alt.feasible = True  # admitted with confidence on the deciding rocks
        alt.screened_feasible = alt.screened_feasible or len(self.scenarios) > 1
        alt.dominated = ""
        alt.reason = ""
        cheaper = [(c, e) for c, e in self.failed if c < d.cost]
        self.scenarios_report = {
            "per_scenario": [r.to_json() for r in rows],
            "binding": {**self.scenarios[bind].run.head(), "margin": rows[bind].margin,
                        "binds_at": rows[bind].binds_at},
            "next_cheaper": max(cheaper, key=lambda t: t[0])[1] if cheaper else None,
        }

    def cause(self) -> str:
        """Why no design of the family holds, with numbers (in the first scenario)."""
        sc = self.scenarios[0]
        why = family_cause(sc, self.alt.family, self.tallies[0])
        if len(self.scenarios) == 1:
            return why
        return (f"no design of this family passes the screening in {self.required} of "
                f"{len(self.scenarios)} scenarios; in scenario {sc.run.index}: {why}")

    def proof(self) -> str:
        """What was proven about the family's chosen design (never cut short)."""
        k = len(self.scenarios)
        where = "" if k == 1 else f" in more than {k - self.required} of the {k} scenarios"
        return proof_line(self.alt, Tally.merged(self.tallies), self.scenarios[0].looks, where,
                          unread=self.unread)


def proof_line(alt: Alternative, tally: Tally, looks: LookSchedule, where: str = "",
               unread: bool = False) -> str:
    """What was proven about a family's chosen design (never cut short).

    ``where``: where every cheaper design fails (across scenarios: in more
    of them than may fail), after the confidence. ``unread``: designs were
    left unread once the family's decisions were used up, so the count of
    those not decided is a least count.
    """
    top = ", ".join(f"{k} ({v:,})" for k, v in tally.reasons.most_common() if v)
    capped = (f"; in {tally.capped_levels} catalogue combinations only "
              f"{MAX_SCREENS_PER_LEVEL} placements were screened (those that may hold on the "
              "search rocks first, then fewest rocks through)"
              if tally.capped_levels else "")
    # Of its family: a cheaper design of another family is that family's to prove
    # or list (design_ditch_or_fence at seed 11: a fence chosen, ditches cheaper).
    space = ("designs of its family the search over its ground edits evaluated"
             if tally.searched else "designs of its family in the space")
    conf = f"{100 * looks.confidence:g} %"
    k = sum(1 for m in alt.marginal if m.decided and not m.short_of_margin)
    marginal = ""
    if k or alt.undecided:
        parts = [f"is marginal ({k})"] if k else []
        if alt.undecided:
            parts.append(f"was not decided ({alt.undecided:,}{' or more' if unread else ''})")
        marginal = ", or " + " or ".join(parts) + " (the cheapest that may hold listed)"
    short = (", or falls short of the checker's margin,"
             if any(k.startswith(SHORT) and v for k, v in tally.reasons.items()) else "")
    return (f"cheapest admitted of {tally.designs:,} {space} ({alt.exact_evaluations} "
            f"evaluated exactly); every cheaper one fails{short} with {conf} confidence"
            f"{where} (looks of {looks.sizes[0]:,} to {looks.sizes[-1]:,} rocks){marginal}: "
            f"{top or 'none cheaper'}{capped}")


def family_cause(sc: Scenario, fam: tuple[int, ...], tally: Tally) -> str:
    """Why no design of a family meets the targets in a scenario, with numbers."""
    screen = sc.screen
    n, allowed = screen.n, screen.allowed_residual
    if not any(ci in screen.edit_candidates for ci in fam):
        missed = _never_met(sc, fam)
        if missed:
            return missed
    if tally.min_residual is not None and tally.min_residual > allowed:
        return (f"every design of this family lets at least {tally.min_residual:,} of {n:,} "
                f"rocks ({100 * tally.min_residual / n:.2f} %) reach the protected zone at "
                f"x >= {screen.protect_x:g} m, {100 * screen.allowed_fraction:.2f} % allowed")
    if tally.best_fail is not None:
        return "the design that comes closest still fails: " + screen_failures(tally.best_fail)
    if tally.over_limit is not None and tally.designs == 0:
        return f"its cheapest design costs {tally.over_limit:,.0f}"
    skipped: Counter = Counter()
    for ci in fam:
        skipped.update(sc.slots.skipped.get(ci, {}))
    if skipped:
        why, count = skipped.most_common(1)[0]
        return f"no design of this family is in the space: {why} ({count:,} designs)"
    return f"no design of this family fits on the section{': ' + tally.why if tally.why else ''}"


def _never_met(sc: Scenario, fam: tuple[int, ...]) -> str:
    """Too many rocks reaching the zone never cross a station of the family's barriers: why
    (or "")."""
    screen, cands = sc.screen, sc.screen.spec.candidates
    n = screen.n
    reach = reaches_protected_zone(screen.bare.max_x, screen.bare.status, screen.protect_x)
    crossing = np.zeros(n, dtype=bool)
    for ci in fam:
        lo, hi = cands[ci].x_range
        cols = (screen.grid >= lo - 1e-9) & (screen.grid <= hi + 1e-9)
        crossing |= np.isfinite(screen.bare.h[:, cols]).any(axis=1)
    missed = int((reach & ~crossing).sum())
    if missed <= screen.allowed_residual:
        return ""
    lo = min(cands[ci].x_range[0] for ci in fam)
    hi = max(cands[ci].x_range[1] for ci in fam)
    below = screen.releases.x[reach & ~crossing]
    where = (f"rocks released below x = {hi:g} m never meet a barrier in {lo:g}-{hi:g} m"
             if below.size and float(below.min()) > hi else
             f"rocks that never cross {lo:g}-{hi:g} m")
    return (f"{where}: {missed:,} of {n:,} ({100 * missed / n:.2f} %) reach the "
            f"protected zone at x >= {screen.protect_x:g} m, "
            f"{100 * screen.allowed_fraction:.2f} % allowed")


def screen_failures(sr: ScreenResult) -> str:
    """What a screened design fails on, in words."""
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


"""The optimiser's results and the limits of its search.

:class:`Alternative` is one family's outcome (its cheapest design that holds,
or why none does; the marginal and undecided designs cheaper than it),
:class:`SearchOutcome` a whole search; the constants bound the work of
one family (on one section or across the scenarios of a study).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ..judge.evaluation import Evaluation
from ..judge.sequential import LookSchedule

if TYPE_CHECKING:  # pragma: no cover
    from ..plugins.measure import ProtectiveMeasure
    from ..studies.sampling import ScenarioRun
from ..judge.looks import LookValues, beyond_rocks, rocks_to_decide

#: Designs that miss their targets on the point values of the search rocks, but not
#: with confidence, decided per family when cheaper than its design (cheapest first).
MAX_DEFERRED_PER_FAMILY = 8


#: Such designs kept aside while the family's stream is read.
MAX_DEFERRED_KEPT = 400


#: Designs the screening could not judge (too few rocks at a measure) that may fail
#: exactly before the family's other such designs are no longer decided.
MAX_UNJUDGED_FAILURES = 3


#: Sequential decisions of one family, at most.
MAX_EXACT_PER_FAMILY = 40


#: Seed of the search over ground edits (with the family's index), whatever the run seed.
SEARCH_SEED = 20261124


#: Offset of the fresh rocks' seed from the search seed (``design.fresh_seed`` overrides).
FRESH_OFFSET = 1000003


#: Marginal designs a family keeps for the report (the cheapest).
MAX_MARGINAL_PER_FAMILY = 5


#: Deferred designs decided per cost (one catalogue combination at several stations
#: or geometries; the closest to holding first), so that the family's budget of
#: deferred decisions reaches as many of its cheaper combinations as it can.
MAX_DEFERRED_PER_COST = 1


#: Cheaper designs a budget left undecided that a family lists (one per cost, cheapest).
MAX_UNDECIDED_LISTED = 40


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
    #: The safety concept's own sentences on the fresh rocks that verified the
    #: design (``SafetyConcept.statements``: a working-life probability, say).
    fresh_statements: list[str] = field(default_factory=list)
    reason: str = ""
    evaluations: int = 0
    exact_evaluations: int = 0
    wall_s: float = 0.0
    evaluation: Evaluation | None = None
    decision_rocks: int | None = None
    fresh_rocks: int | None = None
    fresh_seed: int | None = None
    #: The fresh-rock looks (``{"rocks": [...], "look_confidence": c}``) of the verification.
    fresh_looks: dict[str, Any] | None = None
    proof: str = ""
    dominated: str = ""
    marginal: list[Listed] = field(default_factory=list)
    rejected: int = 0
    undecided: int = 0  # cheaper designs left undecided by a budget (cheapest listed)

    @property
    def holds(self) -> bool:
        """Admitted with confidence, verified on fresh rocks, not dominated."""
        return self.feasible and bool(self.holds_on_fresh_rocks) and not self.dominated

    def as_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "measures": measure_dicts(self.measures),
            "cost": None if not math.isfinite(self.cost) else round(self.cost, 2),
            "feasible": self.feasible,
            "holds_on_fresh_rocks": self.holds_on_fresh_rocks,
            "checks": self.checks,
            "residual": self.residual,
            "decision_rocks": self.decision_rocks,
            "fresh_residual": self.fresh_residual,
            "fresh_rocks": self.fresh_rocks,
            "fresh_seed": self.fresh_seed,
            "fresh_looks": self.fresh_looks,
            "fresh_statements": self.fresh_statements,
            "reason": self.reason,
            "proof": self.proof,
            "dominated": self.dominated or None,
            "evaluations": self.evaluations,
            "exact_evaluations": self.exact_evaluations,
            "marginal": [m.to_json() for m in self.marginal],
            "undecided": self.undecided,
        }


@dataclass
class SearchOutcome:
    """What one search of the optimiser found: the families' alternatives, the
    chosen design (``best``, None without one, then ``reason``) and how the
    search went (rocks, seeds, looks, designs evaluated, wall time in s).

    The optimiser's own outcome, not the public result: the API hands it
    out wrapped in :class:`rockfall_design.results.OptimiseResult` (whose
    ``result`` it is).
    """

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
    looks: LookSchedule | None = None
    #: The designs listed cheaper than the chosen one, cheapest first
    #: (``summary()["marginal"]`` is their :meth:`Listed.to_json`).
    marginal: list[Listed] = field(default_factory=list)
    decided: int = 0
    bare_slope: dict[str, Any] | None = None

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
            "alternatives": [self.alternative_json(a) for a in self.alternatives],
            # the chosen design, the same object as the Python API's ``best``;
            # ``best_name`` is the string ``best`` was, kept for older readers
            "best": None if self.best is None else self.best.as_dict(),
            "best_name": None if self.best is None else self.best.name,
            "proof": "" if self.best is None else self.best.proof,
            "reason": self.reason,
            "decided": self.decided,
            "marginal": [m.to_json() for m in self.marginal],
            "bare_slope": self.bare_slope,
            "looks": None if self.looks is None else {
                "rocks": list(self.looks.sizes), "confidence": self.looks.confidence,
                "look_confidence": self.looks.look_confidence},
        }

    def alternative_json(self, alt: Alternative) -> dict[str, Any]:
        """A family's entry of ``alternatives`` in :meth:`summary`."""
        return alt.as_dict()


@dataclass
class AcrossOutcome(SearchOutcome):
    """:class:`SearchOutcome` of a design across scenarios, with what each scenario said.

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

    def alternative_json(self, alt: Alternative) -> dict[str, Any]:
        """A family's entry, with its design's row in each scenario and the binding one."""
        info = self.per_family.get(alt.name, {})
        return {**alt.as_dict(), "scenarios": info.get("per_scenario"),
                "binding": info.get("binding")}

    def summary(self) -> dict[str, Any]:
        return {**super().summary(), "scenarios": self.scenarios_block()}


def fresh_failures(fresh: Evaluation) -> str:
    """What fails on the fresh rocks: the point failures, or that some bound misses."""
    return "; ".join(fresh.failures()) or (
        "its point values hold, but not every check or the residual with its bound")


def measure_dicts(measures: Sequence[ProtectiveMeasure]) -> list[dict[str, Any]]:
    """Measures as the project file writes them: ``{type, **params}`` each."""
    return [{"type": m.kind, **m.params.model_dump(mode="json")} for m in measures]


@dataclass
class Listed:
    """A cheaper design listed as marginal or undecided beside a family's design.

    ``values`` are the look's point values and bounds
    (:func:`~rockfall_design.judge.looks.look_values`), None for a design across
    scenarios; ``rocks_to_decide`` follows from them (None when they hold:
    ``margin_undecided``, the checker's margin is what is open).
    ``short_of_margin``: it holds with its bounds, but falls short of the
    checker's margin with confidence (listed so that the engineer knows of it).
    :meth:`to_json` is its entry of ``marginal`` in --json.
    """

    family: str
    measures: list[dict[str, Any]]
    labels: list[str]
    cost: float
    rocks: int | None
    values: LookValues | None
    reason: str
    decided: bool
    margin_undecided: bool = False
    short_of_margin: bool = False

    @property
    def rocks_to_decide(self) -> int | None:
        """About how many rocks would decide it
        (:func:`~rockfall_design.judge.looks.rocks_to_decide`)."""
        if self.values is None or self.margin_undecided or self.short_of_margin:
            return None
        return rocks_to_decide(self.values, use_limits=self.decided)  # else: search rocks

    @property
    def beyond_rocks(self) -> str | None:
        """:func:`~rockfall_design.judge.looks.beyond_rocks`, as :attr:`rocks_to_decide` reckons."""
        return beyond_rocks(self.values) if self.values is not None and self.decided else None

    def to_json(self) -> dict[str, Any]:
        return {"name": self.family, "family": self.family, "measures": self.measures,
                "labels": self.labels, "cost": self.cost, "rocks": self.rocks,
                "rocks_to_decide": self.rocks_to_decide,
                "values": None if self.values is None else self.values.to_json(),
                "reason": self.reason, "decided": self.decided,
                "margin_undecided": self.margin_undecided,
                "short_of_margin": self.short_of_margin}


def listed_entry(family: str, measures: Sequence[ProtectiveMeasure], labels: Sequence[str],
                 cost: float, *, rocks: int | None, values: LookValues | None,
                 reason: str, decided: bool, margin_undecided: bool = False,
                 short_of_margin: bool = False) -> Listed:
    """A cheaper design listed as marginal or undecided (see :class:`Listed`)."""
    return Listed(family, measure_dicts(measures), list(labels), round(float(cost), 2), rocks,
                  values, reason, decided, bool(margin_undecided), bool(short_of_margin))

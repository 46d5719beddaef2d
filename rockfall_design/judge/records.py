"""What the judge hands on: a check's summary, its measures and the verdict, as objects.

The results after the judge travel as these frozen objects, not as dicts:
the report reads their attributes, and JSON is made only at the edges (the
CLI's ``--json``, summary.json, serve's answers) through each type's one
``to_json()``, which gives today's dict key for key and in the same order
(``benchmarks/golden.py`` hashes it). ``from_json`` reads such a dict back,
for a report of a saved run and for callers that still hold a dict.

The run's own part (stations, stops, the protected zone's count) is
:class:`rockfall_design.run.summary.RunSummary`, which the run room builds;
the judge adds the measures, their checks (the plugin contract's
:class:`~rockfall_design.plugins.concept.Check`), the residual with its
bounds and the verdict.

See Also
--------
rockfall_design.judge.verdict : how the verdict is reached from a :class:`CheckSummary`.
rockfall_design.judge.bounds : the confidence bounds the records carry.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from enum import StrEnum
from typing import Any

from ..plugins.concept import Check, DesignValue
from ..run.summary import ReachSummary, RunSummary

__all__ = [
    "State",
    "Bill",
    "BillLine",
    "DesignVerdict",
    "ProtectRecord",
    "MeasureRecord",
    "CheckSummary",
    "check_from_json",
    "check_of",
    "run_of",
]


class State(StrEnum):
    """The four states of a verdict, a measure or a check, in the words every report uses.

    The values are the words themselves, so that a state is its JSON (and
    compares equal to the string of a saved summary).
    """

    #: Every check and the residual hold with their one-sided confidence bounds.
    HOLDS_WITH_CONFIDENCE = "holds with confidence"
    #: They hold on their point values, not all with their bounds.
    HOLDS_ON_POINT_VALUES = "holds on point values only"
    #: A check or the residual misses its target on its point value.
    FAILS = "fails"
    #: Nothing was tested (no rock met the measure, or nothing to check).
    UNTESTED = "untested"


@dataclass(frozen=True)
class DesignVerdict:
    """The verdict on one design (or a set of scenarios or sections).

    Attributes
    ----------
    state : State
        One of the four states.
    headline : str
        One sentence that begins with the state's words, capitalised
        ("Holds with confidence: ..."): the first line of every report.
    details : tuple of str
        What fails and by how much, or what is not settled and what would
        settle it, or why nothing was tested; one line each.
    untested : tuple of str
        The labels of the measures that no rock met.
    rocks_needed : int or None
        For ``holds on point values only``: about how many rocks (in all,
        at the observed rates) would settle every open item; None when no
        number of rocks can (or for the other states).
    confidence : float
        The one-sided confidence of the bounds (-), as the plan resolved it
        (``safety.confidence``); keyword only and required: a verdict
        carries the confidence it was reached at, never a default.
    parts : tuple of (str, State)
        The scenarios or sections it sums up, each with its state.
    """

    state: State
    headline: str
    details: tuple[str, ...] = ()
    untested: tuple[str, ...] = ()
    rocks_needed: int | None = None
    confidence: float = field(kw_only=True)
    parts: tuple[tuple[str, State], ...] = field(default=(), repr=False, kw_only=True)

    @property
    def holds(self) -> bool:
        """True for both "holds" states (the checks pass on their point values)."""
        return self.state in (State.HOLDS_WITH_CONFIDENCE, State.HOLDS_ON_POINT_VALUES)

    @property
    def with_confidence(self) -> bool:
        """True only for ``holds with confidence``."""
        return self.state == State.HOLDS_WITH_CONFIDENCE

    def lines(self) -> list[str]:
        """The headline and then each detail, as a report prints them."""
        return [self.headline, *self.details]

    def to_json(self) -> dict[str, Any]:
        """JSON-ready: ``state``, ``headline``, ``details``, ``untested_measures``, ..."""
        out: dict[str, Any] = {
            "state": self.state.value,
            "headline": self.headline,
            "details": list(self.details),
            "untested_measures": list(self.untested),
            "rocks_needed": self.rocks_needed,
            "confidence": self.confidence,
        }
        if self.parts:
            out["parts"] = [{"name": n, "state": s.value} for n, s in self.parts]
        return out

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> DesignVerdict:
        """The verdict from its :meth:`to_json` (a section's JSON block, say)."""
        return cls(State(d["state"]), str(d["headline"]), tuple(d.get("details") or ()),
                   tuple(d.get("untested_measures") or ()), d.get("rocks_needed"),
                   confidence=float(d["confidence"]),
                   parts=tuple((p["name"], State(p["state"])) for p in d.get("parts") or ()))

    # The names of before the records (callers in other rooms still use them).
    as_dict = to_json
    from_dict = from_json


@dataclass(frozen=True)
class ProtectRecord(ReachSummary):
    """The rocks reaching the protected zone against what is allowed, with their bounds.

    Attributes
    ----------
    x, reaching, fraction, unresolved
        As :class:`~rockfall_design.run.summary.ReachSummary` (m, rocks, -, rocks).
    upper_fraction, lower_fraction : float
        One-sided Clopper-Pearson bounds of the fraction at the confidence (-).
    allowed_fraction : float
        The fraction allowed to reach the zone (-).
    ok : bool
        The fraction is within the allowance.
    ok_with_confidence : bool
        Its upper bound is.
    fails_with_confidence : bool
        Its lower bound exceeds the allowance.
    """

    upper_fraction: float
    allowed_fraction: float
    ok: bool
    ok_with_confidence: bool
    lower_fraction: float
    fails_with_confidence: bool

    def to_json(self) -> dict[str, Any]:
        return {"x": self.x, "reaching": self.reaching, "fraction": self.fraction,
                "upper_fraction": self.upper_fraction, "unresolved": self.unresolved,
                "allowed_fraction": self.allowed_fraction, "ok": self.ok,
                "ok_with_confidence": self.ok_with_confidence,
                "lower_fraction": self.lower_fraction,
                "fails_with_confidence": self.fails_with_confidence}

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> ProtectRecord:
        """From :meth:`to_json`; a bound or verdict a dict leaves out is the unsure side."""
        fraction = float(d.get("fraction", 0.0))
        return cls(float(d["x"]), int(d["reaching"]), fraction, int(d.get("unresolved") or 0),
                   float(d.get("upper_fraction", 1.0)), float(d.get("allowed_fraction", 0.0)),
                   bool(d.get("ok")), bool(d.get("ok_with_confidence")),
                   float(d.get("lower_fraction", 0.0)), bool(d.get("fails_with_confidence")))


def check_from_json(d: Mapping[str, Any]) -> Check:
    """A :class:`~rockfall_design.plugins.concept.Check` from its ``as_dict()``."""
    return Check(
        name=str(d["name"]), value=d.get("value"), target=d.get("target"),  # type: ignore[arg-type]
        ok=bool(d.get("ok")), unit=str(d.get("unit", "-")), detail=str(d.get("detail") or ""),
        bound=d.get("bound"), ok_with_confidence=d.get("ok_with_confidence"),
        rocks_needed=d.get("rocks_needed"), optimistic=d.get("optimistic"),
        fails_with_confidence=d.get("fails_with_confidence"), symbol=str(d.get("symbol") or ""),
        relation=str(d.get("relation") or ""), target_symbol=str(d.get("target_symbol") or ""),
        design_values=tuple(DesignValue(**v) for v in d.get("design_values") or ()))


def check_state(check: Check, met: int) -> State:
    """The state of one check of a measure that ``met`` rocks met.

    ``untested`` when no rock met the measure and the check has no value (a
    statistic of no rock says nothing; a check of geometry, such as a braking
    distance against the protected zone, has its value without rocks and is
    judged on it); ``fails`` when it misses its target on its point value;
    ``holds with confidence`` when it holds with its bound in place (or the
    concept reports no bound); else ``holds on point values only``.
    """
    if met <= 0 and check.value is None:
        return State.UNTESTED
    if not check.ok:
        return State.FAILS
    return (State.HOLDS_WITH_CONFIDENCE if check.holds_with_confidence
            else State.HOLDS_ON_POINT_VALUES)


@dataclass(frozen=True)
class MeasureRecord:
    """One measure of a check: where it stands, what the rocks did there, its checks.

    Attributes
    ----------
    type, label : str
        The measure's kind and its label in the reports.
    x : float
        Its station (m).
    params : mapping
        Its parameters as resolved (JSON-ready, units in their names).
    met, caught, passed_over, broken_through, rebounded, passed_through_gap : int
        Rocks that met it, and what became of them.
    checks : tuple of Check
        The safety concept's checks of it.
    passing : mapping or None
        The distributions of the rocks that met a barrier
        (:func:`rockfall_design.run.passages.passage_block`); None for a
        ground edit.
    """

    type: str
    label: str
    x: float
    params: Mapping[str, Any]
    met: int
    caught: int
    passed_over: int
    broken_through: int
    rebounded: int
    passed_through_gap: int
    checks: tuple[Check, ...]
    passing: Mapping[str, Any] | None = None

    @property
    def ok(self) -> bool:
        """Every check holds on its point value."""
        return all(c.ok for c in self.checks)

    @property
    def through(self) -> int:
        """Rocks that broke through it or passed a gap."""
        return self.broken_through + self.passed_through_gap

    def check_states(self) -> list[State]:
        """The state of each check (:func:`check_state`)."""
        return [check_state(c, self.met) for c in self.checks]

    @property
    def state(self) -> State | None:
        """The measure's own word: a failing check's, else untested without a rock,
        else its least sure check's; None for a measure with no check."""
        states = set(self.check_states())
        if State.FAILS in states:
            return State.FAILS
        if self.met <= 0:
            return State.UNTESTED
        if State.HOLDS_ON_POINT_VALUES in states:
            return State.HOLDS_ON_POINT_VALUES
        return State.HOLDS_WITH_CONFIDENCE if self.checks else None

    def to_json(self, states: bool = False) -> dict[str, Any]:
        """The measure's block of ``check --json``; with ``states``, each state too."""
        checks = [c.as_dict() for c in self.checks]
        if states:
            checks = [{**c, "state": s.value} for c, s in zip(checks, self.check_states(),
                                                              strict=True)]
        out: dict[str, Any] = {
            "type": self.type, "label": self.label, "x": self.x, "params": self.params,
            "met": self.met, "caught": self.caught, "passed_over": self.passed_over,
            "broken_through": self.broken_through, "rebounded": self.rebounded,
            "passed_through_gap": self.passed_through_gap, "checks": checks, "ok": self.ok,
            "passing": self.passing}
        if states:
            out["state"] = None if self.state is None else self.state.value
        return out

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> MeasureRecord:
        return cls(str(d.get("type", "?")), str(d.get("label") or d.get("type", "?")),
                   d.get("x"), d.get("params") or {},  # type: ignore[arg-type]
                   int(d.get("met") or 0), int(d.get("caught") or 0),
                   int(d.get("passed_over") or 0), int(d.get("broken_through") or 0),
                   int(d.get("rebounded") or 0), int(d.get("passed_through_gap") or 0),
                   tuple(check_from_json(c) for c in d.get("checks") or ()), d.get("passing"))


@dataclass(frozen=True)
class CheckSummary:
    """The summary of a check (``check --json``): the run, the measures, the residual.

    Attributes
    ----------
    run : RunSummary
        The run with the measures in place.
    safety_concept : str
        The concept that judged it.
    measures : tuple of MeasureRecord
        In project order.
    protect : ProtectRecord or None
        The residual against its allowance; None without ``protect:``.
    concept_statements : tuple of str
        The concept's own sentences on the check.
    ok : bool
        Every check and the residual hold on their point values (false when
        nothing was tested, once judged).
    failures : tuple of str
        One line per failed check.
    confidence : float
        One-sided confidence of every bound (-), as the plan resolved it.
    holds_with_confidence : bool
        ``ok`` with the bounds in place of the point values.
    verdict : DesignVerdict or None
        The verdict (:func:`rockfall_design.judge.verdict.judged`); None
        before it is judged.
    """

    run: RunSummary
    safety_concept: str
    measures: tuple[MeasureRecord, ...]
    protect: ProtectRecord | None
    concept_statements: tuple[str, ...]
    ok: bool
    failures: tuple[str, ...]
    confidence: float
    holds_with_confidence: bool
    verdict: DesignVerdict | None = None

    @property
    def rocks(self) -> int:
        """Rocks of the run."""
        return self.run.rocks

    def with_verdict(self, verdict: DesignVerdict) -> CheckSummary:
        """The summary headed by ``verdict``; a check of nothing is not ``ok``."""
        if verdict.state == State.UNTESTED:
            return replace(self, verdict=verdict, ok=False, holds_with_confidence=False)
        return replace(self, verdict=verdict)

    def to_json(self) -> dict[str, Any]:
        """The dict of ``check --json`` (with ``verdict`` and states once judged)."""
        out = self.run.to_json()
        out["safety_concept"] = self.safety_concept
        judged = self.verdict is not None
        out["measures"] = [m.to_json(states=judged) for m in self.measures]
        if self.protect is not None:
            out["protect"] = self.protect.to_json()
        if self.concept_statements:
            out["concept_statements"] = list(self.concept_statements)
        out.update({"ok": self.ok, "failures": list(self.failures),
                    "confidence": self.confidence,
                    "holds_with_confidence": self.holds_with_confidence})
        if self.verdict is not None:
            out = {"verdict": self.verdict.to_json(), **out}
        return out

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> CheckSummary:
        """From :meth:`to_json`, judged or not (a saved ``check --json``)."""
        prot, verdict = d.get("protect"), d.get("verdict")
        return cls(
            run=RunSummary.from_json(d), safety_concept=str(d.get("safety_concept") or ""),
            measures=tuple(MeasureRecord.from_json(m) for m in d.get("measures") or ()),
            protect=None if prot is None else ProtectRecord.from_json(prot),
            concept_statements=tuple(d.get("concept_statements") or ()),
            ok=bool(d.get("ok")), failures=tuple(d.get("failures") or ()),
            confidence=float(d["confidence"]),
            holds_with_confidence=bool(d.get("holds_with_confidence")),
            verdict=None if not verdict else DesignVerdict.from_json(verdict))


def run_of(summary: RunSummary | CheckSummary | Mapping[str, Any]) -> RunSummary:
    """The run's part of a summary: a record's, or a saved summary dict read back.

    A check's run carries the judge's residual (:class:`ProtectRecord`) as
    its ``protect``, as the check's JSON does.
    """
    if isinstance(summary, CheckSummary):
        return replace(summary.run, protect=summary.protect)
    if isinstance(summary, RunSummary):
        return summary
    return RunSummary.from_json(summary)


def check_of(summary: CheckSummary | Mapping[str, Any]) -> CheckSummary:
    """A check's summary as its record: itself, or a saved ``check --json`` read back."""
    return summary if isinstance(summary, CheckSummary) else CheckSummary.from_json(summary)


@dataclass(frozen=True)
class BillLine:
    """One line of a design's bill.

    Attributes
    ----------
    measure : str
        The measure's label.
    quantity : str
        What is billed ("fence RX-100 4 m", "excavation_m3", "fixed cost of
        the measure", "the measure as priced").
    count : float
        How many ``unit`` over the whole site length.
    unit : str
        ``m``, ``m3``, ``each``, ``lump sum`` ...
    unit_price, amount : float
        Currency per unit; currency.
    per_m : float or None
        The quantity per running metre of slope; None for a fixed cost or a
        lump sum.
    source : str
        Where the price comes from (cost model and catalogue).
    """

    measure: str
    quantity: str
    count: float
    unit: str
    unit_price: float
    amount: float
    per_m: float | None
    source: str

    def to_json(self) -> dict[str, Any]:
        return {"measure": self.measure, "quantity": self.quantity, "count": self.count,
                "unit": self.unit, "unit_price": self.unit_price, "amount": self.amount,
                "per_m": self.per_m, "source": self.source}

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> BillLine:
        return cls(str(d["measure"]), str(d["quantity"]), float(d["count"]), str(d["unit"]),
                   float(d["unit_price"]), float(d["amount"]), d.get("per_m"),
                   str(d.get("source") or ""))


@dataclass(frozen=True)
class Bill:
    """The bill of a design: its lines, the total the optimiser compared, the site length.

    Attributes
    ----------
    items : tuple of BillLine
    total : float
        The sum of the measures' prices (currency): the design's cost.
    length_m : float
        The site length the quantities are counted over (m).
    model : str
        The cost model that priced it.
    currency : str or None
        The catalogue's currency; None where the bill does not say.
    """

    items: tuple[BillLine, ...]
    total: float
    length_m: float
    model: str
    currency: str | None = None

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"items": [it.to_json() for it in self.items],
                               "total": self.total, "length_m": self.length_m,
                               "model": self.model}
        if self.currency is not None:
            out["currency"] = self.currency
        return out

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> Bill:
        return cls(tuple(BillLine.from_json(it) for it in d.get("items") or ()),
                   float(d["total"]), float(d["length_m"]), str(d.get("model") or ""),
                   d.get("currency"))

"""A look's verdict with the checker's margin, and its values for the report.

A look judges a design on its rocks at the look's confidence
(:mod:`~rockfall_design.judge.sequential`); with ``design.checker_power`` it
admits only what a checker's check would confirm often enough, and rejects
as short of that margin only what misses it with confidence
(:mod:`~rockfall_design.judge.margin`). The optimiser's decisions
(:mod:`rockfall_design.optimiser.decide`) take every look's verdict from here,
whether the look is an exact run or a screening that judged every rock exactly,
and a look's point values and bounds (:class:`LookValues`) with the rocks
that would decide it (:func:`rocks_to_decide`) and what fails with
confidence (:func:`rejections`).

See Also
--------
rockfall_design.judge.margin : the margin's rates and bounds.
rockfall_design.judge.bounds : the bounds.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any

from ..plugins import guard
from .bounds import fraction_lower_bound, fraction_upper_bound
from .margin import CheckerMargin
from .sequential import Verdict

if TYPE_CHECKING:  # pragma: no cover
    from ..plugins import Registry
    from ..plugins.concept import Check, SafetyConcept
    from .design_spec import DesignSpec
    from .evaluation import Evaluation

__all__ = ["LookCheck", "LookResidual", "LookValues", "beyond_rocks", "checker_margin",
           "checks_at", "judge_look", "look_concept", "look_values", "rejections",
           "rocks_to_decide", "verdict_of", "with_margin"]


def checker_margin(spec: DesignSpec, confidence: float) -> CheckerMargin | None:
    """The project's checker's margin (``design.checker_power``; None: turned off)."""
    power = spec.checker_power
    return None if power is None else CheckerMargin(float(confidence), float(power))


def look_concept(registry: Registry, concept: SafetyConcept, confidence: float) -> SafetyConcept:
    """The project's safety concept with its bounds at a look's ``confidence``."""
    params = concept.params.model_copy(update={"confidence": float(confidence)})
    look = guard(registry).instantiate(type(concept), params)
    # The design block keeps its bounds at the project's confidence: the
    # survey is one fixed sample, looked at once, not the growing rock sample
    # the looks' confidences are spent on.
    look.design_block = concept.design_block
    return look


def verdict_of(ev: Evaluation) -> Verdict:
    """A look's verdict on its own bounds, without the checker's margin."""
    if ev.holds_with_confidence:
        return Verdict.ADMITTED
    if ev.fails_with_confidence:
        return Verdict.REJECTED
    return Verdict.UNDECIDED


def checks_at(registry: Registry, concept: SafetyConcept, results: Sequence[Any],
               confidence: float) -> list[list[Check]]:
    """A look's checks again, its measures' ``results`` judged by ``concept`` with its
    bounds at ``confidence`` (no rock runs)."""
    judge = guard(registry).concept(look_concept(registry, concept, confidence))
    return [judge.checks(res) for res in results]


def judge_look(ev: Evaluation, registry: Registry, margin: CheckerMargin | None,
               checker_rocks: int,
               last_checker_rocks: int | None = None) -> tuple[Verdict, list[str]]:
    """A look's verdict, with the checker's margin (:mod:`rockfall_design.judge.margin`).

    Parameters
    ----------
    ev : Evaluation
        The look's exact run, judged at the look's confidence.
    registry : Registry
    margin : CheckerMargin or None
        None: admitted when it holds with the look's bounds, as such.
    checker_rocks : int
        Rocks of the checker's check the margin is for, if this look decides.
    last_checker_rocks : int, optional
        Rocks of the checker's check if the last look decides (default
        ``checker_rocks``). A design is rejected as short of the margin only
        when it misses the margin for this check too: a larger check needs a
        smaller margin, so a design short of the margin at an early look may
        still show it at a later one; rejecting it early made the choice hang
        on the seed (design_two_zones' 339,000 fence at seeds 14 and 15).

    Returns
    -------
    verdict, notes : Verdict, list of str
        REJECTED with ``notes`` empty: fails with confidence; with ``notes``
        (one line): short of the margin with confidence, what and why.
        UNDECIDED with ``notes`` (one line): it holds with the look's bounds,
        but the margin is neither shown nor missed.
    """
    prot = ev.residual
    return with_margin(
        verdict_of(ev), lambda c: checks_at(registry, ev.concept, ev.judgement.results, c),
        [p.label for p in ev.placed],
        None if prot is None else int(prot.reaching),
        None if prot is None else float(prot.allowed_fraction),
        ev.run.result.n, ev.confidence, margin, checker_rocks, last_checker_rocks)


def with_margin(verdict: Verdict, checks_at: Callable[[float], list[list[Check]]],
                 labels: Sequence[str], reaching: int | None, allowed: float | None, n: int,
                 confidence: float, margin: CheckerMargin | None,
                 checker_rocks: int,
                 last_checker_rocks: int | None = None) -> tuple[Verdict, list[str]]:
    """:func:`judge_look` of any look: its verdict without the margin, its checks at any
    confidence (``checks_at``), the rocks reaching the protected zone of its ``n``."""
    if margin is None or verdict is Verdict.REJECTED:
        return verdict, []
    m = margin.at_look(confidence, n, checker_rocks, None if reaching is None else allowed)
    # The margin's bounds are stricter than the look's: only what holds with the
    # look's can hold with them (no checks again for the rest).
    holds = verdict is Verdict.ADMITTED and all(
        c.holds_with_confidence for cs in checks_at(m.admit) for c in cs)
    if holds and reaching is not None and m.residual_rate is not None:
        holds = fraction_upper_bound(reaching, n, confidence) <= m.residual_rate
    if holds:
        return Verdict.ADMITTED, []
    power = f"{100 * margin.power:g} %"
    # Short of the margin only if short of the smallest margin a later look
    # could still ask for: the checker's check of the last look's rocks.
    last = checker_rocks if last_checker_rocks is None else max(checker_rocks,
                                                                last_checker_rocks)
    if last != checker_rocks:
        m = margin.at_look(confidence, n, last, None if reaching is None else allowed)

    def why(rocks: int, than: str = "less than") -> str:
        return (f"a check of {rocks:,} rocks at another seed would confirm it with "
                f"{100 * margin.confidence:g} % confidence {than} {power} of the time")

    short = []
    for lab, cs in zip(labels, checks_at(m.short), strict=True):
        for c in cs:
            if c.ok_with_confidence is None:
                missed = not c.ok
            elif m.short_pessimistic:
                # its pessimistic bound at `short` misses: not merely too few rocks
                missed = c.bound is not None and not c.ok_with_confidence
            else:
                missed = c.rejects
            if missed:
                value = "-" if c.value is None else f"{c.value:.2f}"
                short.append(f"{lab}: {c.name} {value}, target {c.target:.2f}")
    if (reaching is not None and m.residual_rate is not None
            and fraction_lower_bound(reaching, n, confidence) > m.residual_rate):
        short.append(f"{reaching:,} of {n:,} rocks reach the protected zone")
    if short:
        return Verdict.REJECTED, [f"{'; '.join(short)} ({why(last)})"]
    if verdict is Verdict.ADMITTED:
        return Verdict.UNDECIDED, [
            f"it holds with {100 * confidence:.4g} % confidence on {n:,} rocks, but neither "
            f"shows nor misses the checker's margin ({why(checker_rocks, 'at least')})"]
    return Verdict.UNDECIDED, []


def _finite(x: float | None) -> float | None:
    """``x``, or None where it is not a finite number (JSON has no infinity: a factor
    over a demand whose lower bound is 0 is unbounded)."""
    return None if x is None or not math.isfinite(x) else float(x)


@dataclass(frozen=True)
class LookCheck:
    """One check of a look, its point value and both bounds (None: not finite)."""

    measure: str
    name: str
    value: float | None
    bound: float | None
    optimistic: float | None
    target: float
    unit: str
    #: The bounds with rocks without end (``Check.limits``); None: the value.
    limits: tuple[float, float] | None = None


@dataclass(frozen=True)
class LookResidual:
    """The rocks reaching the protected zone at a look: count, fraction, both bounds (-)."""

    reaching: int
    fraction: float
    lower: float
    upper: float
    allowed: float


@dataclass(frozen=True)
class LookValues:
    """Point values and both bounds of a look, for the report of a marginal design.

    ``residual`` is None without a protected zone. :meth:`to_json` is the
    ``values`` object of a listed design in --json.
    """

    rocks: int
    confidence: float
    checks: list[LookCheck]
    residual: LookResidual | None

    def to_json(self) -> dict[str, Any]:
        """``{rocks, confidence, checks: [{measure, name, value, bound, optimistic, target,
        unit[, limits]}], residual: {reaching, fraction, lower, upper, allowed}}``
        (``limits`` only where a check gives them)."""
        out = asdict(self)
        for c in out["checks"]:
            if c["limits"] is None:
                del c["limits"]
            else:
                c["limits"] = list(c["limits"])
        return out


def look_values(checks: Sequence[Sequence[Check]], labels: Sequence[str], residual: int | None,
                n: int, allowed: float | None, confidence: float) -> LookValues:
    """Point values and both bounds of a look, for the report of a marginal design."""
    rows = [LookCheck(lab, c.name, _finite(c.value), _finite(c.bound), _finite(c.optimistic),
                      c.target, c.unit, _limits(c.limits))
            for lab, cs in zip(labels, checks, strict=True) for c in cs]
    res = None
    if residual is not None and allowed is not None:
        res = LookResidual(int(residual), residual / max(n, 1),
                           fraction_lower_bound(residual, n, confidence),
                           fraction_upper_bound(residual, n, confidence), allowed)
    return LookValues(int(n), confidence, rows, res)


def _limits(limits: tuple[float, float] | None) -> tuple[float, float] | None:
    """``Check.limits`` as finite floats, or None."""
    if limits is None or not all(math.isfinite(x) for x in limits):
        return None
    return float(limits[0]), float(limits[1])


def rocks_to_decide(values: LookValues, use_limits: bool = True) -> int | None:
    """About how many rocks would decide a marginal design (None: it sits on the target,
    or no number would: :func:`beyond_rocks`).

    Each bound's distance from where it tends with rocks without end (the
    point value, or the check's ``limits``) shrinks about as 1/sqrt(n)
    (order statistics and Clopper-Pearson alike): a check or residual whose
    bound across the target is ``w`` from that end, the end ``d`` beyond the
    target, at ``n`` rocks is decided at about ``n (w / d)**2`` rocks. The
    largest such count over the undecided items. ``use_limits`` False reckons
    every check as if its bounds closed on its value: for a design looked at
    on the search's rocks only, whose point value is too rough for its limits.
    """
    need = _need(values, use_limits)
    return int(math.ceil(need)) if values.rocks < need < math.inf else None


def beyond_rocks(values: LookValues) -> str | None:
    """Why no number of rocks decides a look's design, or None: a check whose bounds stay
    across the target with rocks without end (its ``limits``, e.g. a design block's survey)."""
    for c in values.checks:
        if _need_check(c, values.rocks) == math.inf and c.limits is not None:
            return (f"{c.measure}: at this look's point value, {c.name}'s bounds would stay "
                    f"across the target {c.target:g} {c.unit} with any number of rocks "
                    f"({c.limits[0]:.4g} to {c.limits[1]:.4g} {c.unit}: an uncertainty beside "
                    "the rocks')")
    return None


def _need_check(c: LookCheck, n: int, use_limits: bool = True) -> float:
    """Rocks that would decide one check (0: decided; inf: none would)."""
    v, t = c.value, c.target
    ends = [b for b in (c.bound, c.optimistic) if b is not None and math.isfinite(b)]
    if v is None or not ends:
        return 0.0
    # Decided (held or failed, whichever way the check runs) when both bounds
    # lie on one side of the target; else the bound across it must come back.
    lo, hi = min(ends + [v]), max(ends + [v])
    if lo >= t or hi <= t:
        return 0.0
    end_lo, end_hi = (v, v) if c.limits is None or not use_limits else c.limits
    if v > t:
        w, d = end_lo - lo, end_lo - t
    else:
        w, d = hi - end_hi, t - end_hi
    if d <= 0.0:  # across the target even with rocks without end (or on it)
        return math.inf
    return n * (max(w, 0.0) / d) ** 2


def _need(values: LookValues, use_limits: bool = True) -> float:
    """:func:`rocks_to_decide` as a float: 0 when decided, inf when no number would."""
    n = values.rocks
    need = max([_need_check(c, n, use_limits) for c in values.checks], default=0.0)
    r = values.residual
    if r is not None and r.upper > r.allowed and r.lower <= r.allowed:
        d = abs(r.fraction - r.allowed)
        w = max(r.upper - r.fraction, r.fraction - r.lower)
        need = max(need, n * (w / d) ** 2 if d > 0.0 else math.inf)
    return need


def rejections(checks: Sequence[Sequence[Check]], labels: Sequence[str], residual: int | None,
               n: int, allowed: float | None, confidence: float) -> list[str]:
    """One line per check (and the residual) that fails with confidence."""
    out = []
    for lab, cs in zip(labels, checks, strict=True):
        for c in cs:
            if c.rejects:
                unit = "" if c.unit == "-" else f" {c.unit}"
                best = "-" if c.optimistic is None else f"{c.optimistic:.2f}{unit}"
                out.append(f"{lab}: {c.name} at best {best}, target {c.target:.2f}{unit}")
    if residual is not None and allowed is not None:
        low = fraction_lower_bound(residual, n, confidence)
        if residual > 0 and low > allowed:
            out.append(f"{residual:,} of {n:,} rocks reach the protected zone: at least "
                       f"{100 * low:.3f} %, allowed {100 * allowed:.3f} %")
    return out or ["fails"]

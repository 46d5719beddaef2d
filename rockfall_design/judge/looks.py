"""A look's verdict with the checker's margin: admitted, rejected or undecided.

A look judges a design on its rocks at the look's confidence
(:mod:`~rockfall_design.judge.sequential`); with ``design.checker_power`` it
admits only what a checker's check would confirm often enough, and rejects
as short of that margin only what misses it with confidence
(:mod:`~rockfall_design.judge.margin`). The optimiser's decisions
(:mod:`rockfall_design.optimiser.decide`) take every look's verdict from here,
whether the look is an exact run or a screening that judged every rock exactly.

See Also
--------
rockfall_design.judge.margin : the margin's rates and bounds.
rockfall_design.judge.bounds : the bounds.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
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

__all__ = ["checker_margin", "checks_at", "judge_look", "look_concept", "verdict_of",
           "with_margin"]


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
        ev.study.result.n, ev.confidence, margin, checker_rocks, last_checker_rocks)


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

"""Deciding a design exactly, with the rocks it needs, on the confidence bounds."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ..evaluate import (
    Evaluation,
    evaluate_design,
)
from ..judge.bounds import fraction_upper_bound

if TYPE_CHECKING:  # pragma: no cover
    from ..measures import ProtectiveMeasure
    from ..plugins import Registry
    from ..project import Project

from .screening import Screening, ScreenResult

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

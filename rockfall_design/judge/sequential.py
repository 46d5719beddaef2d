"""Sequential decisions: looks at a design with more rocks, the error fixed in advance.

A design is judged on the rocks it has: *admitted* when every check and the
residual hold with their upper confidence bounds, *rejected* when one of
them fails even with its lower (favourable) bound, *undecided* otherwise.
An undecided design gets more rocks and is looked at again. Looking again
until a design passes would admit, across all the looks, designs that do
not hold far more often than ``1 - confidence``; so the looks and the error
each may spend are fixed before the first rock runs (an alpha-spending
schedule, here the simplest one):

* the looks are at ``n_0, 2 n_0, 4 n_0, ...`` rocks, the last one at the cap
  (``design.max_rocks``), ``J`` looks in all;
* each look uses the bounds at the one-sided confidence
  ``c_J = 1 - (1 - c) / J`` on each side.

Why it holds at every look (the union bound, whatever the dependence between
looks, and they are strongly dependent: look ``j + 1`` reuses the rocks of
look ``j``): for a design that does not hold, each look's upper bounds fall
on the wrong side of the truth with probability at most ``(1 - c) / J``, so
it is admitted at any look with probability at most ``J (1 - c) / J = 1 - c``.
The same argument on the lower bounds bounds the chance that a design that
holds is ever rejected by ``1 - c``. Order-statistic bounds of percentiles
and Clopper-Pearson bounds of fractions are exact at any fixed sample size
(:mod:`rockfall_design.judge.bounds`), which is all each look needs.

A design still undecided at the last look is *marginal*: its true value is
within the resolution of that many rocks. It is never admitted.

The price of the schedule is wider bounds per look: with ``J = 5`` looks at
95 %, each look bounds at 99 %, and showing a residual of 0.1 % with no rock
reaching takes 4,603 rocks instead of 2,995. Time-uniform confidence
sequences (Howard et al. 2021; Waudby-Smith & Ramdas 2023) allow looks after
every rock at a similar price; with a handful of geometrically spaced looks
the union bound is as tight and needs nothing beyond the fixed-sample bounds.

References
----------
.. [1] Jennison, C. and Turnbull, B. W. (2000). *Group Sequential Methods
   with Applications to Clinical Trials*. Chapman & Hall/CRC, ch. 7 (error
   spending) and ch. 9 (repeated confidence intervals).
.. [2] Howard, S. R., Ramdas, A., McAuliffe, J. and Sekhon, J. (2021).
   Time-uniform, nonparametric, nonasymptotic confidence sequences. *Annals
   of Statistics* 49(2), 1055-1080.
.. [3] Waudby-Smith, I. and Ramdas, A. (2023). Estimating means of bounded
   random variables by betting. *JRSS B* 86(1), 1-27.

See Also
--------
rockfall_design.judge.bounds : the bounds each look uses.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

from .bounds import rocks_to_show_fraction

__all__ = ["LookSchedule", "Verdict", "plan_looks"]


class Verdict(enum.Enum):
    """What one look (or the last) says of a design."""

    ADMITTED = "admitted"
    REJECTED = "rejected"
    UNDECIDED = "undecided"
    MARGINAL = "marginal"


@dataclass(frozen=True)
class LookSchedule:
    """The looks of a sequential decision and the confidence of each.

    Attributes
    ----------
    sizes : tuple of int
        Rocks at each look, increasing; the last is the cap.
    confidence : float
        The overall one-sided confidence of each side (``safety.confidence``).
    spent_over : int
        The number of looks the error ``1 - confidence`` is divided over; at
        least ``len(sizes)``.
    """

    sizes: tuple[int, ...]
    confidence: float
    spent_over: int

    @property
    def look_confidence(self) -> float:
        """One-sided confidence of every look's bounds, ``1 - (1 - c) / J``."""
        return 1.0 - (1.0 - self.confidence) / self.spent_over

    def __len__(self) -> int:
        return len(self.sizes)


def _sizes(first: int, cap: int, growth: float) -> tuple[int, ...]:
    out = [first]
    while out[-1] < cap:
        out.append(min(cap, int(math.ceil(out[-1] * growth))))
    return tuple(out)


def plan_looks(first: int, cap: int, confidence: float, allowed_fraction: float | None = None,
               growth: float = 2.0) -> LookSchedule:
    """The looks from ``first`` rocks to ``cap``, each ``growth`` times the last.

    Parameters
    ----------
    first : int
        Rocks at the first look (the search rocks), at least.
    cap : int
        Rocks at the last look (``design.max_rocks``).
    confidence : float
        Overall one-sided confidence per side, 0 < c < 1.
    allowed_fraction : float, optional
        The residual target. The first look then has at least the rocks
        with which no rock reaching shows it at the look confidence (else
        no design could be admitted there).
    growth : float
        Ratio of successive looks (> 1).

    Returns
    -------
    LookSchedule
        With the fewest looks ``J`` such that the schedule from the first
        look that ``J`` allows has at most ``J`` looks.
    """
    if growth <= 1.0:
        raise ValueError("growth must exceed 1")
    first = max(1, int(first))
    cap = max(first, int(cap))
    # The error is divided over J looks, and J depends on the first look,
    # which grows with J: take the smallest J that is self-consistent (the
    # sizes are then at most J, so dividing over J is valid).
    top = len(_sizes(first, cap, growth)) + 4
    for spent in range(1, top + 1):
        look_c = 1.0 - (1.0 - confidence) / spent
        n0 = first
        if allowed_fraction is not None and allowed_fraction > 0.0:
            n0 = max(n0, int(rocks_to_show_fraction(allowed_fraction, look_c) or n0))
        n0 = min(n0, cap)
        sizes = _sizes(n0, cap, growth)
        if len(sizes) <= spent:
            return LookSchedule(sizes, float(confidence), spent)
    sizes = _sizes(first, cap, growth)  # pragma: no cover - the loop always returns
    return LookSchedule(sizes, float(confidence), max(len(sizes), top))

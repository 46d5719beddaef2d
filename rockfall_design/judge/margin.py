"""The checker's margin: admit a design only if a checker's own check would confirm it.

A design admitted at its limit holds, with confidence; but an engineer who
checks it again with rocks of another seed confirms it with confidence only
as often as that check's power allows: a design whose true p95 sits just
inside its target passes its checker's check about half the time. The
optimiser therefore admits a design only when, with confidence, a check of
``n_c`` fresh rocks at a seed of the checker's own (twice the rocks that
decided the design, as design.yaml says to repeat it) confirms it with
confidence ``c`` with a chance of at least ``p`` (``design.checker_power``).

Every check the safety concepts make comes down to counting rocks:

* the residual holds with confidence when the Clopper-Pearson upper bound of
  ``R / n`` is within the allowed fraction ``a``: when ``R <= r_c``, with
  ``r_c`` the largest count whose bound is (exactly computable);
* a percentile check holds with confidence when the order-statistic upper
  bound of the percentile ``Q`` of the ``m`` rocks at the measure is within
  its limit ``t``: when the rocks beyond ``t`` number at most ``k_c``, the
  count the bound's index allows (:mod:`~rockfall_design.judge.bounds`).

Either way the checker confirms the design when a binomial count with the
design's true rate ``q`` (of rocks reaching the zone, of rocks beyond ``t``)
stays at or below a threshold, which it does with a chance falling in
``q``. The checker confirms it with chance ``p`` up to a rate ``q_p``; the
optimiser admits the design when its own count shows ``q <= q_p`` with the
look's confidence, and rejects it (short of the checker's margin) when its
count shows ``q > q_p`` with that confidence. A look decides exactly as a
check of the same rocks at other confidences:

* residual: exact. ``r_c`` as above, ``q_p`` the rate at which
  ``P[Binomial(n_c, q_p) <= r_c] = p`` (the inverse of the binomial CDF in
  its rate), and the look's Clopper-Pearson bounds of ``R / n`` compared
  with ``q_p`` instead of ``a``;
* percentile checks: through the normal approximation of the binomial
  counts, in which the threshold and ``q_p`` are ``z_c`` and ``z_c + z_p``
  standard errors of ``n_c`` rocks inside the rate ``1 - Q``. The look
  admits when the check's bound at the confidence ``Phi(z_l + (z_c + z_p)
  sqrt(n / n_c))`` holds (``z_l`` the look's own quantile, ``n`` its rocks)
  and rejects when its bound at ``Phi((z_c + z_p) sqrt(n / n_c) - z_l)``
  fails. The approximation needs some tens of rocks beyond the limit at
  the check's rocks (at 95 % and ``p = 0.9``, a check of 10,000 rocks at a
  measure has about 500 beyond its p95); neither ``Q`` nor ``m`` enters.

The look's own error is spent as every look's is
(:mod:`~rockfall_design.judge.sequential`): a design a checker would confirm
with a chance below ``p`` is admitted at some look with probability at most
``1 - confidence``, and one it would confirm with at least ``p`` is rejected
for the margin with at most that. The maximum as a statistic has no bound
and no margin (a larger check sees a larger maximum): it is judged on its
value, as before.

References
----------
.. [1] Hahn, G. J. and Meeker, W. Q. (1991). *Statistical Intervals*. Wiley,
   ch. 5 (distribution-free bounds of quantiles) and ch. 6 (binomial).
.. [2] Julious, S. A. (2004). Sample sizes for clinical trials with normal
   data. *Statistics in Medicine* 23, 1921-1986 (a study sized on a pilot's
   estimate, the power of the next one).

See Also
--------
rockfall_design.judge.bounds : the bounds.
rockfall_design.judge.sequential : the looks and the error each spends.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

from ..project.schema import DEFAULT_CHECKER_POWER
from .bounds import fraction_upper_bound

__all__ = ["DEFAULT_CHECKER_POWER", "MAX_CONFIDENCE", "CheckerMargin", "Margin", "residual_rate"]

#: The highest confidence a margin's bound is taken at (z = 7.94).
MAX_CONFIDENCE = 1.0 - 1e-15


@dataclass(frozen=True)
class Margin:
    """The confidences at which one look judges the checker's margin.

    Attributes
    ----------
    admit : float
        Confidence of the bounds with which every percentile check must hold.
    short : float
        Confidence of the bounds with which a percentile check that misses
        shows the design short of the margin.
    short_pessimistic : bool
        True: "misses" is the check's upper (pessimistic) bound at ``short``
        missing its target; False: its lower (optimistic) bound at ``short``
        missing it (the margin is then smaller than the look's own spread).
    residual_rate : float or None
        ``q_p``: the largest rate of rocks reaching the protected zone a
        checker confirms with the chance asked for (None: no residual target).
    """

    admit: float
    short: float
    short_pessimistic: bool
    residual_rate: float | None


@dataclass(frozen=True)
class CheckerMargin:
    """What a checker's check needs of a design (see the module docs).

    Parameters
    ----------
    confidence : float
        The checker's one-sided confidence (``safety.confidence``), 0 < c < 1.
    power : float
        The chance with which the checker's check confirms the design, 0 < p < 1.
    """

    confidence: float
    power: float

    def __post_init__(self) -> None:
        for name in ("confidence", "power"):
            v = getattr(self, name)
            if not 0.0 < v < 1.0:
                raise ValueError(f"{name} must lie in (0, 1), got {v!r}")

    def at_look(self, look_confidence: float, rocks: int, checker_rocks: int,
                allowed: float | None) -> Margin:
        """The margin's confidences at one look.

        Parameters
        ----------
        look_confidence : float
            The look's one-sided confidence (its share of the error).
        rocks : int
            Rocks of the look, ``n``.
        checker_rocks : int
            Rocks of the checker's check, ``n_c``.
        allowed : float or None
            The allowed fraction reaching the protected zone (None: none).
        """
        from scipy.special import ndtr, ndtri

        z_l = float(ndtri(look_confidence))
        k = (float(ndtri(self.confidence)) + float(ndtri(self.power))) * math.sqrt(
            max(rocks, 1) / max(checker_rocks, 1))
        z_short = k - z_l
        rate = None if allowed is None else residual_rate(
            float(allowed), int(checker_rocks), self.confidence, self.power)
        # Past z = 7.9 a confidence is 1 - 1e-15 and no longer a double apart
        # from 1: there the bound's confidence stops growing (see the docs).
        return Margin(admit=min(float(ndtr(z_l + k)), MAX_CONFIDENCE),
                      short=min(float(ndtr(abs(z_short))), MAX_CONFIDENCE),
                      short_pessimistic=z_short >= 0.0, residual_rate=rate)


@lru_cache(maxsize=1024)
def residual_rate(allowed: float, checker_rocks: int, confidence: float, power: float) -> float:
    """``q_p``: the largest rate at which a check of ``checker_rocks`` confirms the residual.

    The check confirms it when ``R <= r_c`` (the largest count whose
    Clopper-Pearson upper bound at ``confidence`` is within ``allowed``);
    ``P[Binomial(n_c, q) <= r_c]`` falls in ``q``, and ``q_p`` is where it
    equals ``power``. 0 when no count of that many rocks shows ``allowed``
    (then nothing can be admitted: the check itself could never confirm).
    """
    from scipy.special import bdtri


    n = int(checker_rocks)
    if n <= 0 or allowed <= 0.0:
        return 0.0
    if fraction_upper_bound(0, n, confidence) > allowed:
        return 0.0
    # The bound rises with the count: bisect for the largest r_c that shows it.
    lo, hi = 0, n
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if fraction_upper_bound(mid, n, confidence) <= allowed:
            lo = mid
        else:
            hi = mid - 1
    if lo >= n:
        return 1.0
    return float(bdtri(lo, n, power))

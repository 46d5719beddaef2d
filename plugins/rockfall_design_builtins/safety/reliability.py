"""The built-in safety concept ``reliability``: a target probability over the working life.

An ordinary plugin with an entry point of its own (``reliability``): the
public ``rockfall_design`` API and the shared helpers of this package only.

Practice designs a fence with partial factors on percentiles (``uni11211``,
``onr24810``); Marchelli, De Biagi & Peila (2020) design it for a target
probability that it fails within its working life, from the frequency of
falls and the simulated per-block probability of failure. With falls
arriving as a Poisson process of rate :math:`\\lambda` (per year) and each
block failing independently with probability :math:`p`, the failures over a
working life of :math:`T` years are Poisson with mean :math:`\\lambda T p`, so

.. math::

    P_f(T) = 1 - \\exp(-\\lambda \\, T \\, p),

and the target :math:`P_f(T) \\le P_t` is :math:`p \\le p_{max} = -\\ln(1 - P_t)
/ (\\lambda T)`. The simulation estimates :math:`p` as a count of :math:`k`
failing rocks of :math:`n`, with its Clopper-Pearson bounds at the project's
confidence; :math:`P_f` is monotone in :math:`p`, so the bounds carry over.

What fails, per block:

* at each barrier or ground edit, the block passes over, breaks through
  or slips through a gap (``failure_probability``, one check per measure:
  each measure on its own must meet the target);
* at the protected zone, the block reaches it: the judge's residual, held
  to :math:`p_{max}` (:meth:`ReliabilityConcept.allowed_residual_fraction`;
  the stricter of it and the project's own allowance, where one is given).

Each holds to :math:`P_t` on its own; the probability that at least one of
them happens to a block is at most their sum. A fence's braking distance is
checked as by the other concepts (``braking_distance``, Peila & Ronco 2009).

Rock budgets: a zero count bounds :math:`p` below :math:`p_{max}` only from
:math:`n \\ge \\ln(1 - c) / \\ln(1 - p_{max})` rocks (about :math:`3 / p_{max}`
at 95 %). :math:`P_t = 10^{-4}` over :math:`\\lambda T` = 125 falls is
:math:`p_{max} = 8.0 \\times 10^{-7}`, about 3.7 million rocks: far beyond
``design.max_rocks``. Such a check says how many rocks it needs
(``rocks_needed``), stays undecided, and the optimiser reports it marginal.

References
----------
.. [1] Marchelli, M., De Biagi, V. and Peila, D. (2020). Reliability-based
   design of protection net fences: influence of rockfall uncertainties
   through a statistical analysis. Geosciences 10(8), 280.
.. [2] Clopper, C. J. and Pearson, E. S. (1934). The use of confidence or
   fiducial limits illustrated in the case of the binomial. Biometrika 26,
   404-413.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, ClassVar

from pydantic import Field

from rockfall_design import (
    Check,
    MeasureResult,
    SafetyConcept,
    fraction_lower_bound,
    fraction_upper_bound,
    hookimpl,
    rocks_to_show_fraction,
)

from .checks import braking_check, gamma_d_field
from .shared import StrictParams

__all__ = ["ReliabilityConcept", "rockfall_design_safety_concepts", "life_probability"]


def life_probability(p_block: float, falls: float) -> float:
    """P(at least one failing block among Poisson(``falls``) falls), each failing w.p. ``p_block``.

    ``1 - exp(-falls * p_block)``, computed with ``expm1`` so that it keeps
    its digits for the small probabilities design targets are (-).
    """
    return -math.expm1(-falls * p_block)


class ReliabilityConcept(SafetyConcept):
    """Design to a target probability of failure over the working life (Marchelli et al. 2020).

    See the module docstring for the model and its assumptions: Poisson
    arrivals of falls at ``annual_falls`` per year, the simulated rocks a
    fair sample of the falls, independent blocks.
    """

    name: ClassVar[str] = "reliability"
    summary: ClassVar[str] = (
        "target probability that a block passes a measure or reaches the protected zone "
        "within the working life (Poisson falls, Clopper-Pearson bounds)"
    )

    class Params(StrictParams):
        """Fall frequency, working life and target probability."""

        annual_falls: float = Field(
            gt=0.0, le=1e6,
            description="Mean number of blocks falling per year at the release zones "
            "(1/year): from the site's inventory or a magnitude-frequency relation.",
            json_schema_extra={"unit": "1/year"})
        working_life_years: float = Field(
            50.0, gt=0.0, le=1000.0,
            description="Working life of the protection (years); 50 is common for "
            "permanent works (EN 1990's category 4), ILLUSTRATIVE default.",
            json_schema_extra={"unit": "year"})
        target_failure_probability: float = Field(
            1e-4, gt=0.0, lt=1.0,
            description="Largest accepted probability (-) that at least one block passes a "
            "measure or reaches the protected zone within the working life; ILLUSTRATIVE "
            "default, set by the owner or the code.", json_schema_extra={"unit": "-"})
        gamma_d: float = gamma_d_field()

    example: ClassVar[dict[str, Any]] = {
        "annual_falls": 2.5, "working_life_years": 50.0,
        "target_failure_probability": 1e-4, "gamma_d": 1.3, "confidence": 0.95,
    }
    params: Params

    @property
    def falls(self) -> float:
        """Expected falls over the working life, :math:`\\lambda T` (-)."""
        return self.params.annual_falls * self.params.working_life_years

    def allowed_residual_fraction(self) -> float:
        """:math:`p_{max} = -\\ln(1 - P_t) / (\\lambda T)`, the per-block probability allowed (-).

        Held by the judge and the optimiser as the residual's allowance.
        """
        return -math.log1p(-self.params.target_failure_probability) / self.falls

    def life(self, k: int, n: int) -> tuple[float, float, float]:
        """:math:`P_f(T)` of ``k`` failing blocks of ``n`` and its Clopper-Pearson bounds (-)."""
        c = self.params.confidence
        n = max(int(n), 1)
        return (life_probability(k / n, self.falls),
                life_probability(fraction_lower_bound(k, n, c), self.falls),
                life_probability(fraction_upper_bound(k, n, c), self.falls))

    def statements(self, reaching: int | None, rocks: int,
                   results: Sequence[MeasureResult], labels: Sequence[str]) -> list[str]:
        """The working-life probability at the protected zone and at each measure, with bounds.

        Then the assumptions they rest on, in words (see the module).
        """
        p = self.params
        c = 100 * p.confidence
        n = max(int(rocks), 1)
        out = []
        events = [("reaching the protected zone", reaching)] if reaching is not None else []
        events += [(f"passing {label} (over, through or through a gap)",
                    r.passed_over + r.broken_through + r.passed_through_gap)
                   for r, label in zip(results, labels, strict=True)]
        for what, k in events:
            value, _, upper = self.life(int(k), n)
            verdict = "within" if upper <= p.target_failure_probability else (
                "above" if value > p.target_failure_probability else "not shown within")
            out.append(
                f"Probability of at least one block {what} within the working life: P_f = "
                f"1 - exp(-lambda T k/n) = 1 - exp(-{p.annual_falls:g}/year x "
                f"{p.working_life_years:g} years x {int(k):,}/{n:,}) = {value:.3g}; at most "
                f"{upper:.3g} with {c:g} % confidence (the Clopper-Pearson upper bound of k/n "
                f"through the same formula); {verdict} the target "
                f"{p.target_failure_probability:g}.")
        if out:
            out.append(
                f"Assumptions of these probabilities: falls arrive as a Poisson process of "
                f"{p.annual_falls:g} a year over a working life of {p.working_life_years:g} "
                f"years ({self.falls:g} falls expected); the simulated rocks are a fair sample "
                "of those falls (release zones, sizes and ground as the project gives them); "
                "blocks fail independently of each other; each block meets the measures "
                "intact (damage left by earlier blocks is not modelled: they are taken to be "
                "repaired after an event). Each probability holds on its own; that any "
                "one of them happens is at most their sum (Marchelli, De Biagi & Peila 2020).")
        return out

    def checks(self, result: MeasureResult) -> list[Check]:
        """``failure_probability`` of the measure, then its ``braking_distance`` (a fence's)."""
        checks = [self._failure_check(result)]
        props = result.measure.design_properties()
        elongation = props.get("max_elongation_m")
        if elongation is not None and math.isfinite(float(elongation)):
            checks += braking_check(result, float(elongation), self.params.gamma_d)
        return checks

    def _failure_check(self, result: MeasureResult) -> Check:
        """P_f(T) of the rocks that passed this measure (over, through, gap), with its bounds."""
        p = self.params
        n = max(int(result.n_rocks), 1)
        k = int(result.passed_over + result.broken_through + result.passed_through_gap)
        c = p.confidence
        value = life_probability(k / n, self.falls)
        upper = life_probability(fraction_upper_bound(k, n, c), self.falls)
        lower = life_probability(fraction_lower_bound(k, n, c), self.falls)
        p_max = self.allowed_residual_fraction()
        detail = (f"P_f = 1 - exp(-{p.annual_falls:g}/year x {p.working_life_years:g} years x "
                  f"{k}/{n:,} rocks passing) = {value:.3g}, Clopper-Pearson {100 * c:g} % "
                  f"bounds {lower:.3g} to {upper:.3g}; target {p.target_failure_probability:g} "
                  f"(a per-block probability of at most {p_max:.3g})")
        needed = None
        if not upper <= p.target_failure_probability and not lower > p.target_failure_probability:
            total = rocks_to_show_fraction(p_max, c, k)
            if total is not None:
                detail = (f"{detail}; {k} passing of {n:,} cannot show it: it needs at least "
                          f"{total:,} rocks with no more passing")
                # rocks_needed counts rocks at the measure: the share that met it.
                needed = int(math.ceil(total * max(result.met, 1) / n))
        return Check("failure_probability", value, p.target_failure_probability,
                     bool(value <= p.target_failure_probability), "-", detail, upper,
                     bool(upper <= p.target_failure_probability), needed, lower,
                     bool(lower > p.target_failure_probability), "P_f", "<=", "P_t")


@hookimpl
def rockfall_design_safety_concepts() -> list[type[SafetyConcept]]:
    """The built-in ``reliability`` concept, registered by its own entry point."""
    return [ReliabilityConcept]

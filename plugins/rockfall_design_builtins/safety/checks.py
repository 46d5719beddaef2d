"""The checks the built-in safety concepts share: public builders for any concept.

Each returns a :class:`~rockfall_design.Check` with its order-statistic
bounds (see :mod:`.shared` for the statistics); a third party's concept may
use them (docs/plugins.md):

* :func:`factor_check` -- provided figure over a statistic of the rocks
  against a target factor (``spang``);
* :func:`reach_check` and :func:`reach_factor_field` -- a berm's or ditch's
  width over the rocks' reach;
* :func:`limit_check` -- a design value that must not exceed its limit,
  with the detail of its bounds (``uni11211``);
* :func:`braking_check` and :func:`gamma_d_field` -- a fence's braking
  distance against the protected zone (every built-in concept).

Units: m, kJ.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from pydantic import Field

from rockfall_design import Check, DesignValue, MeasureResult, quantile_with_bounds

from .shared import (
    MAX_FACTOR,
    MAX_PARTIAL,
    NO_ROCK,
    number_text,
    rocks_needed,
    rocks_text,
    too_few,
)

__all__ = [
    "braking_check",
    "factor_check",
    "gamma_d_field",
    "limit_check",
    "product_name",
    "reach_check",
    "reach_factor_field",
]


def factor_check(
    name: str,
    provided: float,
    unit: str,
    values: np.ndarray,
    statistic: str,
    quantity: str,
    target: float,
    confidence: float,
    symbols: tuple[str, str, str, str] = ("F", "S", "P", "provided"),
) -> Check:
    """``provided / statistic(values)`` compared with ``target`` (ok if >= target).

    ``symbols``: the factor's symbol, the demand's (its statistic is added as
    a subscript), the provided figure's and what that figure is, for the
    report's table of design values.

    The detail reads e.g. "4.00 m / p95 passing height 1.62 m (upper bound
    1.70 m at 95 %) over 812 rocks". ``bound`` is ``provided`` over the upper
    confidence bound of the statistic: the factor that holds with confidence.
    """
    values = np.asarray(values, dtype=float)
    factor_symbol, demand_symbol, provided_symbol, provided_meaning = symbols
    named = {"symbol": factor_symbol, "relation": ">=", "target_symbol": name}
    figure = DesignValue(provided_symbol, provided_meaning, provided, unit, source="product")
    if values.size == 0:
        return Check(name, None, target, True, "-", NO_ROCK, None, True, **named,
                     design_values=(DesignValue(f"{demand_symbol}_{statistic}",
                                                f"{statistic} {quantity}", None, unit), figure))
    if statistic == "max" or float(statistic[1:]) >= 100.0:
        demand = upper = lower = float(np.max(values))
    else:
        # One partial sort for the percentile and both its bounds.
        demand, lower, upper = quantile_with_bounds(values, float(statistic[1:]) / 100.0,
                                                    confidence)
    named["design_values"] = (
        DesignValue(f"{demand_symbol}_{statistic}", f"{statistic} {quantity} of the rocks",
                    demand, unit, upper), figure)
    bound_text = ("" if statistic == "max" or upper is None else
                  f" (upper bound {number_text(upper, unit)} at {100 * confidence:g} %)")
    detail = (
        f"{number_text(provided, unit)} / {statistic} {quantity} "
        f"{number_text(demand, unit)}{bound_text} over {rocks_text(values.size)}"
    )
    if upper is None:
        detail = f"{detail}; {too_few(statistic, values.size, confidence)}"
    if not demand > 0.0:
        # No demand at the point value; with confidence only if the bound has none too.
        no_demand = upper is not None and not upper > 0.0
        return Check(name, None, target, True, "-", f"{detail}: factor undefined, no demand",
                     None, no_demand or (None if upper is None else provided / upper >= target),
                     **named)
    factor = provided / demand
    # The most favourable factor at this confidence: over the lower bound of
    # the statistic. It fails with confidence only when even that misses.
    f_best = None if lower is None else (math.inf if not lower > 0.0 else provided / lower)
    fails = f_best is not None and bool(f_best < target)
    if upper is None:
        return Check(name, factor, target, bool(factor >= target), "-", detail, None, False,
                     rocks_needed(statistic, confidence), f_best, fails, **named)
    f_bound = provided / upper
    return Check(name, factor, target, bool(factor >= target), "-", detail, f_bound,
                 bool(f_bound >= target), None, f_best, fails, **named)


def reach_check(
    result: MeasureResult, width_m: float, target: float, statistic: str, confidence: float
) -> Check:
    """Berm (or ditch) factor: width / ``statistic`` of the reach of the rocks on it.

    The statistic is the concept's (not the maximum, which grows with the
    number of rocks until every ditch fails).
    """
    return factor_check("reach_factor", width_m, "m", result.reach_m, statistic, "reach",
                         target, confidence, ("F_b", "r", "b", "width of the catch area"))



def reach_factor_field() -> Any:
    """The ``reach_factor`` parameter of a concept that checks berms and ditches (-)."""
    return Field(
        1.0, gt=0.0, le=MAX_FACTOR,
        description="Target of berm or ditch width / reach of the rocks (the statistic "
        "of the concept) (-).", json_schema_extra={"unit": "-"},
    )

def limit_check(name: str, value: float, target: float, unit: str, detail: str,
                bound: float | None, optimistic: float | None, statistic: str, n: int,
                confidence: float, **named: Any) -> Check:
    """A design value that must not exceed ``target``, with its confidence bounds.

    ``value`` at the statistic, ``bound`` at its unfavourable bound (None:
    the ``n`` rocks are too few, the detail says how many it needs) and
    ``optimistic`` at its favourable one (it fails with confidence when even
    that exceeds ``target``). ``named``: the check's symbols and design values.
    """
    fails = optimistic is not None and bool(optimistic > target)
    if bound is None:
        detail = f"{detail}; {too_few(statistic, n, confidence)}"
        return Check(name, value, target, bool(value <= target), unit, detail, None, False,
                     rocks_needed(statistic, confidence), optimistic, fails, **named)
    detail = f"{detail}; with the {100 * confidence:g} % bounds {number_text(bound, unit)}"
    return Check(name, value, target, bool(value <= target), unit, detail, bound,
                 bool(bound <= target), None, optimistic, fails, **named)


def product_name(result: MeasureResult) -> str:
    """``"product NAME"`` of the measure, or its kind where it names no product."""
    name = getattr(getattr(result.measure, "params", None), "product", None)
    return f"product {name}" if name else f"this {result.measure.kind}"


def braking_check(result: MeasureResult, elongation_m: float | None,
                  gamma_d: float = 1.3) -> list[Check]:
    """The braking distance against the protected zone: ``[]`` or one check.

    A fence stops a rock by stretching downslope by up to its maximum
    elongation (EAD 340059 / ETAG 027, measured in the MEL test); what stands
    within that distance is hit by the net even when the rock is caught.
    Peila & Ronco (2009) ask that the distance from the fence to what it
    protects, :math:`d_A`, be at least the elongation times a partial factor,
    :math:`d_A \\ge \\gamma_d \\, d_{MEL}`, :math:`\\gamma_d` = 1.3 for an
    elongation from the MEL test (1.5 from the SEL test). The only thing a
    project declares downslope is its protected zone (``protect.x``): value
    :math:`\\gamma_d d_{MEL}`, target the clearance ``protect.x - x`` (m),
    holds if value <= target. It is geometry, not a statistic of the rocks:
    it holds or fails with confidence alike, rocks or none. (The run itself
    carries each caught rock on by its own braking distance, without the
    factor: ``engine.barriers.braking_distance``.)

    No check without an elongation or without a protected zone
    (``result.clearance_m`` None).

    References
    ----------
    .. [1] Peila, D. and Ronco, C. (2009). Technical note: Design of rockfall
       net fences and the new ETAG 027 European guideline. Natural Hazards
       and Earth System Sciences 9, 1291-1298.
    """
    clearance = result.clearance_m
    if elongation_m is None or clearance is None:
        return []
    required = gamma_d * elongation_m
    ok = bool(required <= clearance)
    detail = (f"gamma_d {gamma_d:g} x maximum elongation {number_text(elongation_m, 'm')} of "
              f"{product_name(result)} (catalogue, MEL test) = {number_text(required, 'm')} "
              f"against "
              f"{number_text(clearance, 'm')} from the fence to the protected zone (protect.x)")
    if not ok:
        detail = f"{detail}: the net would reach into the protected zone while braking a rock"
    return [Check("braking_distance", required, clearance, ok, "m", detail, required,
                  ok, None, required, not ok, "gamma_d d_max", "<=", "d_A",
                  (DesignValue("d_max", f"maximum elongation of {product_name(result)}",
                               elongation_m, "m", source="product"),
                   DesignValue("gamma_d d_max", f"the elongation with its partial factor "
                               f"{gamma_d:g}", required, "m", source="product"),
                   DesignValue("d_A", "clearance from the fence to the protected zone",
                               clearance, "m", source="product")))]


def gamma_d_field() -> Any:
    """The ``gamma_d`` parameter of a concept that checks a fence's braking distance."""
    return Field(
        1.3, ge=1.0, le=MAX_PARTIAL,
        description="Partial factor on the fence's maximum elongation in the braking-distance "
        "check (-): 1.3 for an elongation from the MEL test (Peila & Ronco 2009).",
        json_schema_extra={"unit": "-"},
    )



"""What the built-in safety concepts share: public helpers for any concept.

Statistics of the rocks that met a measure with their distribution-free
order-statistic bounds, the design block's mass and the words of a check's
detail (the checks built from them: :mod:`.checks`). They use only the public
``rockfall_design`` API; a third party's concept may import them (they are
part of the plugin guide, docs/plugins.md) instead of rewriting them:

* :func:`percentile`, :func:`statistic_upper_bound`,
  :func:`statistic_lower_bound`, :func:`statistic_with_bounds` -- a
  statistic (``"p95"``, ``"p99"``, ``"max"``) and its bounds;
* :func:`rocks_needed`, :func:`too_few` -- the rocks that bound a percentile;
* :func:`number_text`, :func:`rocks_text`, :func:`percentile_label` -- words;
* :func:`design_mass` -- the design block's mass, or the rocks' statistic;
* :func:`finite_property`, :class:`StrictParams`, :data:`NO_ROCK`.

Units: m, m/s, kg, kJ.

See Also
--------
rockfall_design.quantile_with_bounds : the order-statistic bounds used here.
"""

from __future__ import annotations

import numpy as np
from pydantic import ConfigDict

from rockfall_design import (
    DesignBlock,
    SafetyParams,
    quantile_lower_bound,
    quantile_upper_bound,
    quantile_with_bounds,
    rocks_to_bound_quantile,
)

__all__ = [
    "MAX_FACTOR",
    "MAX_FREEBOARD_M",
    "MAX_PARTIAL",
    "NO_ROCK",
    "StrictParams",
    "design_mass",
    "finite_property",
    "number_text",
    "percentile",
    "percentile_label",
    "rocks_needed",
    "rocks_text",
    "statistic_lower_bound",
    "statistic_upper_bound",
    "statistic_with_bounds",
    "too_few",
]

#: The detail of a check no rock met.
NO_ROCK = "no rock reached the measure"

# Upper bounds of the factors: far above any code's values (partial factors
# of 1.0 to 1.5, safety factors of 1 to 3), low enough that no product of
# them with an energy or a height can overflow into inf.
#: Largest partial factor (-).
MAX_PARTIAL = 10.0
#: Largest target of a safety factor (-).
MAX_FACTOR = 100.0
#: Largest minimum freeboard (m).
MAX_FREEBOARD_M = 100.0


class StrictParams(SafetyParams):
    """Strict parameters that also reject NaN and infinity."""

    model_config = ConfigDict(allow_inf_nan=False)




def finite_property(properties: dict[str, float], key: str) -> float | None:
    """``properties[key]`` as a float if present and finite, else None."""
    value = properties.get(key)
    if value is None:
        return None
    value = float(value)
    return value if np.isfinite(value) else None


def percentile(values: np.ndarray, q: float) -> float:
    """``numpy.percentile(values, q)`` (linear, type 7) of a non-empty array, by partition.

    The optimiser asks for thousands of percentiles; a partial sort around the
    two order statistics it needs is several times faster than a full one.
    """
    v = np.asarray(values, dtype=float).ravel()
    h = (v.size - 1) * q / 100.0
    lo = int(np.floor(h))
    hi = min(lo + 1, v.size - 1)
    part = np.partition(v, (lo, hi)) if hi != lo else np.partition(v, lo)
    return float(part[lo] + (h - lo) * (part[hi] - part[lo]))


def statistic_upper_bound(values: np.ndarray, statistic: str, confidence: float) -> float | None:
    """Upper confidence bound of ``statistic`` (the maximum bounds itself); None: too few."""
    if statistic == "max" or float(statistic[1:]) >= 100.0:
        return float(np.max(values))
    return quantile_upper_bound(values, float(statistic[1:]) / 100.0, confidence)


def statistic_lower_bound(values: np.ndarray, statistic: str, confidence: float) -> float | None:
    """Lower confidence bound of ``statistic``; None: too few rocks to bound it.

    The maximum of nested samples only grows with more rocks, so the
    sample's maximum is its own lower bound: a maximum that fails now fails
    with every larger sample of the same rocks.
    """
    if statistic == "max" or float(statistic[1:]) >= 100.0:
        return float(np.max(values))
    return quantile_lower_bound(values, float(statistic[1:]) / 100.0, confidence)


def rocks_needed(statistic: str, confidence: float) -> int:
    """Rocks at a measure that bound its ``statistic`` at ``confidence``."""
    return rocks_to_bound_quantile(float(statistic[1:]) / 100.0, confidence)


def too_few(statistic: str, n: int, confidence: float) -> str:
    """Why a percentile cannot be bounded: how many rocks it needs."""
    need = rocks_needed(statistic, confidence)
    return (f"{rocks_text(n)} cannot bound the {statistic} at {100 * confidence:g} % confidence: "
            f"it needs at least {need} rocks at the measure")


def percentile_label(percentile: float) -> str:
    """``95.0`` -> ``"p95"``, ``97.5`` -> ``"p97.5"``."""
    return f"p{percentile:g}"


def rocks_text(n: int) -> str:
    return f"{n} rock" if n == 1 else f"{n} rocks"


def number_text(value: float, unit: str) -> str:
    """A value with its unit, to a precision that suits the unit."""
    digits = 1 if unit == "kJ" else 2
    return f"{value:.{digits}f} {unit}"


def statistic_with_bounds(values: np.ndarray, statistic: str, confidence: float,
                          percent: float | None = None
                          ) -> tuple[float, float | None, float | None]:
    """A percentile statistic of non-empty ``values`` with its lower and upper bound.

    :func:`percentile` (of ``percent``, by default the statistic's own),
    :func:`statistic_lower_bound` and :func:`statistic_upper_bound` of
    ``statistic`` (``"p95"`` ...), in that order; a bound is None where the
    rocks are too few to give it. The same numbers, bit for bit, from one
    partial sort where it can (:func:`rockfall_design.quantile_with_bounds`:
    its point value is this one where its rank ``(n - 1) q`` is the one
    :func:`percentile` takes), else two: a check asks for all three of each
    of its arrays, and the optimiser for tens of thousands of checks.
    """
    if statistic == "max" or float(statistic[1:]) >= 100.0:
        top = float(np.max(values))
        return percentile(values, 100.0 if percent is None else percent), top, top
    v = np.asarray(values, dtype=float).ravel()
    pct = float(statistic[1:]) if percent is None else float(percent)
    q = float(statistic[1:]) / 100.0
    point, lower, upper = quantile_with_bounds(v, q, confidence)
    if (v.size - 1) * pct / 100.0 != (v.size - 1) * q:  # another rank: percentile's own
        point = percentile(v, pct)
    return point, lower, upper


def design_mass(block: DesignBlock | None, masses: np.ndarray, statistic: str,
                confidence: float) -> tuple[float, float | None, float | None, str]:
    """The mass of the design block (kg): point, lower and upper bound, and its words.

    The project's design block (``rocks.design_block``, a block survey's
    percentile or a return period's block) where it gives one, else the
    ``statistic`` of the simulated rocks' ``masses`` with its order-statistic
    bounds at ``confidence`` (None: too few rocks to bound it).
    """
    if block is not None:
        return (block.mass_kg, block.lower_kg, block.upper_kg,
                f"design block {block.mass_kg:.1f} kg (rocks.design_block: {block.source})")
    point, lower, upper = statistic_with_bounds(masses, statistic, confidence)
    return (point, lower, upper, f"{statistic} mass {point:.1f} kg of the simulated rocks")

"""Numbers rounded to what is meaningful for their unit, for every table of the reports.

A module of its own, without pandas, so that the terminal's tables round as
the documents' do without loading pandas (:mod:`.tables` re-exports it).
"""

from __future__ import annotations

import math
from typing import Any

__all__ = ["round_value"]

#: Decimals kept for a value of a unit (unknown units keep 3 significant decimals).
_DECIMALS = {"-": 2, "m": 2, "kJ": 0, "kj": 0, "m/s": 1, "rad/s": 1, "%": 2, "kg": 0}


def round_value(value: Any, unit: str = "-") -> Any:
    """A number rounded for its unit; None, NaN and non-numbers as they are.

    Parameters
    ----------
    value : float or None
    unit : str
        ``"-"`` (a factor: 0.01), ``"m"`` (0.01 m), ``"kJ"`` (1 kJ),
        ``"m/s"`` (0.1), ``"cost"`` (whole currency units), ``"count"`` (whole
        numbers); other units 0.001.

    Returns
    -------
    float, int or the value unchanged
    """
    if value is None or isinstance(value, bool) or not isinstance(value, int | float):
        return value
    if not math.isfinite(value):
        return value
    if unit in ("cost", "count"):
        return int(round(value))
    digits = _DECIMALS.get(unit, 3)
    return int(round(value)) if digits == 0 else round(float(value), digits)



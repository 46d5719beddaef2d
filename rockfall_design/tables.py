"""Moved: the tables are now :mod:`rockfall_design.report.tables`.

This module stays so that ``from rockfall_design.tables import ...`` in users'
scripts and notebooks keeps working: it hands on the public names of
:mod:`rockfall_design.report.tables`, which new code imports instead.
"""

from .report.tables import (
    alternatives_frame,
    check_columns,
    checks_frame,
    measure_text,
    measures_frame,
    round_value,
)

__all__ = [
    "round_value",
    "check_columns",
    "measure_text",
    "alternatives_frame",
    "measures_frame",
    "checks_frame",
]

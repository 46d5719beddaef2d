"""Tables a job's page shows: a study's and a calibration's, as plain JSON rows."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from ..calibration.calibration_result import CalibrationResult


def study_tables(res: Any) -> list[dict[str, Any]]:
    """A study's scenarios (the varied values and the statistics at every station,
    without their bounds) and its sensitivity, as tables for the page."""
    sc = res.scenarios
    cols = [c for c in sc.columns if c != "seed" and not str(c).endswith((" upper", " lower"))]
    sens = res.sensitivity
    scols = [c for c in ("parameter", "target", "effect", "unit", "low", "high", "resolved")
             if c in sens.columns]
    return [_table("Scenarios", sc[cols]), _table("Sensitivity", sens[scols])]


def calibration_tables(result: CalibrationResult) -> list[dict[str, Any]]:
    """A calibration's fitted values with their bootstrap intervals, and its fit."""
    rows = [[p.path, p.value, p.low, p.high, p.range, p.identified, p.at_bound or ""]
            for p in result.parameters]
    fit = result.fit
    fit_rows = [["distance_kind", fit.distance_kind], ["distance", fit.distance],
                ["ks_statistic", fit.ks_statistic], ["ks_pvalue", fit.ks_pvalue]]
    return [{"title": "Fitted inputs", "rows": plain_json(rows),
             "columns": ["input", "value", "low", "high", "range", "identified", "at bound"]},
            {"title": "Fit", "columns": ["item", "value"], "rows": plain_json(fit_rows)}]


def _table(title: str, frame: Any) -> dict[str, Any]:
    rows = [[_cell(v) for v in row] for row in frame.itertuples(index=False)]
    return {"title": title, "columns": [str(c) for c in frame.columns], "rows": rows}


def _cell(v: Any) -> Any:
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return plain_json(v)


def plain_json(v: Any) -> Any:
    """``v`` as plain JSON data: string keys, lists, scalars; anything else as its text."""
    if isinstance(v, dict):
        return {str(k): plain_json(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [plain_json(x) for x in v]
    if isinstance(v, float | int | str | bool) or v is None:
        return v
    return str(v)

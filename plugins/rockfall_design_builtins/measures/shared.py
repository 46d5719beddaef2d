"""What the built-in measures share: the section they need, strict parameters and
the geometry and bill helpers (lengths in m, areas in m^2, volumes in m^3 per
running metre).

Part of the built-in measures (:mod:`rockfall_design_builtins.measures`);
it registers nothing itself.
"""

from __future__ import annotations

import math
from typing import Any, Protocol

import numpy as np
from pydantic import ConfigDict

from rockfall_design import (
    MeasureParams,
    ProfileEdit,
    Quantity,
)

__all__ = [
    "SectionLike",
    "StrictParams",
    "STATION_RANGE",
    "ground_at",
    "range_text",
    "check_station",
    "check_stretch",
    "check_vertices",
    "cut_and_fill",
    "running_metre",
    "earthworks",
    "edit_volumes",
    "MATERIAL_DESCRIPTION",
]

#: Bounds of a station design variable: the optimiser substitutes the
#: candidate's station range for these NaNs.
STATION_RANGE = (math.nan, math.nan)


class SectionLike(Protocol):
    """What a measure needs of a slope section (``rockfall_design.engine.Section``)."""

    @property
    def x(self) -> np.ndarray:
        """Ground vertices' x (m), strictly increasing."""
        ...

    @property
    def y(self) -> np.ndarray:
        """Ground vertices' y (m)."""
        ...

    def ground_height(self, x: Any) -> Any:
        """Ground height (m) at ``x``, linear between vertices."""
        ...


class StrictParams(MeasureParams):
    """Strict parameters that also reject NaN and infinity."""

    model_config = ConfigDict(allow_inf_nan=False)




def ground_at(section: SectionLike, x: float) -> float:
    """Ground height (m) of ``section`` at station ``x`` (m), linear between vertices."""
    return float(np.interp(x, np.asarray(section.x, float), np.asarray(section.y, float)))


def range_text(section: SectionLike) -> str:
    """``"x0 to x1 m"``: the stations the section runs between, for messages."""
    return f"{float(section.x[0]):g} to {float(section.x[-1]):g} m"


def check_station(section: SectionLike, x: float, what: str) -> None:
    """A barrier must stand strictly inside the section."""
    x0, x1 = float(section.x[0]), float(section.x[-1])
    if not x0 < x < x1:
        raise ValueError(
            f"{what} at x = {x:g} m is outside the section, which runs from {range_text(section)}"
        )


def check_stretch(section: SectionLike, x_start: float, x_end: float, what: str) -> None:
    """An edited stretch must lie within the section."""
    x0, x1 = float(section.x[0]), float(section.x[-1])
    if not x0 <= x_start:
        raise ValueError(
            f"{what} starts at x = {x_start:g} m, upslope of the section's start "
            f"(the section runs from {range_text(section)})"
        )
    if not x_end <= x1:
        raise ValueError(
            f"{what} runs to x = {x_end:g} m, past the section's end "
            f"(the section runs from {range_text(section)})"
        )


def check_vertices(points: np.ndarray, what: str) -> None:
    """New ground vertices must advance in x: a measure too small for float64 has none."""
    if not (np.diff(points[:, 0]) > 0).all():
        raise ValueError(
            f"{what} is too small to shape the ground: its vertices at x = "
            f"{points[0, 0]:g} to {points[-1, 0]:g} m coincide (make it wider or deeper)"
        )


def cut_and_fill(
    x_old: np.ndarray, y_old: np.ndarray, x_new: np.ndarray, y_new: np.ndarray
) -> tuple[float, float]:
    """Cut and fill areas between two ground polylines over the new one's range.

    Parameters
    ----------
    x_old, y_old : ndarray
        Original ground vertices (m), x strictly increasing, covering
        ``[x_new[0], x_new[-1]]``.
    x_new, y_new : ndarray
        New ground vertices (m), x strictly increasing.

    Returns
    -------
    cut, fill : float
        Area (m^2, i.e. m^3 per running metre) where the original ground lies
        above the new ground (excavated) and below it (filled).

    Notes
    -----
    Both grounds are linear between the merged breakpoints, so is their
    difference d = y_old - y_new; on an interval where d keeps its sign the
    trapezoid rule is exact, and where it changes sign the interval is split
    at the root. The result is exact up to rounding.
    """
    a, b = float(x_new[0]), float(x_new[-1])
    inner = x_old[(x_old > a) & (x_old < b)]
    xs = np.union1d(np.asarray(x_new, float), inner)
    d = np.interp(xs, x_old, y_old) - np.interp(xs, x_new, y_new)
    cut = fill = 0.0
    for i in range(xs.size - 1):
        h = float(xs[i + 1] - xs[i])
        d0, d1 = float(d[i]), float(d[i + 1])
        if d0 >= 0.0 and d1 >= 0.0:
            cut += 0.5 * h * (d0 + d1)
        elif d0 <= 0.0 and d1 <= 0.0:
            fill -= 0.5 * h * (d0 + d1)
        else:  # sign change: split at the root
            t = d0 / (d0 - d1)
            pos, neg = (d0, d1) if d0 > 0.0 else (d1, d0)
            h_pos = h * (t if d0 > 0.0 else 1.0 - t)
            cut += 0.5 * h_pos * pos
            fill -= 0.5 * (h - h_pos) * neg
    return cut, fill


def running_metre(measure: Any, quantities: dict[str, float]) -> list[Quantity]:
    """A barrier's bill: one running metre named after its kind, of its product at its height."""
    height = quantities.get("height_m", measure.params.height)
    return [Quantity(measure.kind, 1.0, "m", product=measure.params.product, size=height)]


def earthworks(quantities: dict[str, float]) -> list[Quantity]:
    """A ground edit's bill: excavated and filled m^3 per running metre."""
    return [Quantity("excavation_m3", quantities["excavation_m3_per_m"], "m3"),
            Quantity("fill_m3", quantities.get("fill_m3_per_m", 0.0), "m3")]


def edit_volumes(section: SectionLike, edit: ProfileEdit) -> tuple[float, float]:
    """Cut and fill (m^3 per running metre) of ``edit`` on ``section`` (:func:`cut_and_fill`)."""
    pts = np.asarray(edit.points, float)
    return cut_and_fill(
        np.asarray(section.x, float), np.asarray(section.y, float), pts[:, 0], pts[:, 1]
    )


# ---------------------------------------------------------------------------
# barriers
# ---------------------------------------------------------------------------




MATERIAL_DESCRIPTION = (
    "Material of the excavated surfaces (a name from the project's materials); "
    "None keeps the original ground's material."
)

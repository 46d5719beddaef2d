"""A rockfall protection embankment: an earth mound with a steep uphill face.

An example third-party measure for rockfall-design, and the plugin author's
walk-through of the plugin guide (docs/plugins.md). Unlike the built-in
barriers it changes the ground, and unlike a ditch or a berm it adds ground
rather than taking it away: rocks that reach it strike a steep, reinforced
uphill face and come to rest in front of it, or climb over its crest.

Geometry (all lengths in m, angles in degrees), on the ground y(x) of the
section:

* the uphill toe at ``x`` on the ground, y_t = y(x);
* the uphill face rises at ``uphill_face_deg`` to the crest, ``height``
  above the toe: y_c = y_t + height, reached at x_1 = x + height / tan(alpha);
* the crest is horizontal, ``crest_width`` long, to x_2 = x_1 + crest_width;
* the downhill face falls at ``downhill_face_deg`` from (x_2, y_c) until it
  meets the ground at x_e (solved exactly, segment by segment).

Rocks that come to rest with their centre between ``catch_zone`` upslope
of the toe and the downhill edge of the crest, [x - catch_zone, x_2], are
caught (a rock that the face throws back further upslope than that is
reported as passed over: the catch rule of a ground edit knows only where a
rock stops). Its design property is that width, ``width_m`` = catch_zone + x_2 - x,
which a safety concept compares with how far the rocks that meet it run
(their reach): a rock that crosses the crest has run further.

It is priced by its own quantity, ``embankment_fill_m3`` (m^3 of fill per
running metre: the area between the new and the old ground), with a default
price that a project's cost catalogue overrides
(``prices: {embankment_fill_m3: PRICE}`` for ``unit_prices``).

The optimiser searches its ``height`` (1.5 to 6 m) and its uphill face
(55 to 75 degrees) unless a project's candidate fixes them, as their
fields declare (``json_schema_extra={"design": ...}``).
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np
from pydantic import ConfigDict, Field

from rockfall_design import MeasureParams, ProfileEdit, ProtectiveMeasure, Quantity, hookimpl

__all__ = ["Embankment", "EmbankmentParams", "fill_area", "rockfall_design_measures"]


class EmbankmentParams(MeasureParams):
    """Parameters of a rockfall protection embankment."""

    model_config = ConfigDict(allow_inf_nan=False)

    x: float = Field(description="Station of the uphill toe (m).",
                     json_schema_extra={"unit": "m"})
    height: float = Field(
        gt=0, le=15, description="Height of the crest above the uphill toe (m).",
        json_schema_extra={"unit": "m", "design": {"bounds": [1.5, 6.0]}},
    )
    crest_width: float = Field(
        2.0, gt=0, le=20, description="Width of the horizontal crest (m).",
        json_schema_extra={"unit": "m"},
    )
    uphill_face_deg: float = Field(
        60.0, ge=30, le=85, description="Slope of the reinforced uphill face (degrees).",
        json_schema_extra={"unit": "deg", "design": {"bounds": [55.0, 75.0]}},
    )
    downhill_face_deg: float = Field(
        35.0, ge=10, le=45, description="Slope of the downhill face (degrees).",
        json_schema_extra={"unit": "deg"},
    )
    catch_zone: float = Field(
        6.0, gt=0, le=30,
        description="Length upslope of the toe where rocks at rest count as caught (m).",
        json_schema_extra={"unit": "m"},
    )
    material: str | None = Field(
        None, description="Material of the embankment's surfaces (a name from the "
        "project's materials); None keeps the original ground's.",
        json_schema_extra={"unit": None},
    )


def _ground(xs: np.ndarray, ys: np.ndarray, x: float) -> float:
    return float(np.interp(x, xs, ys))


def fill_area(xs: np.ndarray, ys: np.ndarray, points: np.ndarray) -> float:
    """Area (m^2, i.e. m^3 per running metre) between new ground ``points`` and the old ground.

    Parameters
    ----------
    xs, ys : ndarray
        Old ground vertices (m), x increasing, covering the new ground's range.
    points : ndarray, shape (k, 2)
        New ground vertices (m), x increasing, on or above the old ground.

    Notes
    -----
    Both grounds are linear between the merged breakpoints, so the trapezoid
    rule over them is exact; a new ground below the old one would count
    negative (it is not, for an embankment).
    """
    a, b = float(points[0, 0]), float(points[-1, 0])
    inner = xs[(xs > a) & (xs < b)]
    grid = np.union1d(points[:, 0], inner)
    d = np.interp(grid, points[:, 0], points[:, 1]) - np.interp(grid, xs, ys)
    return float(np.sum(0.5 * np.diff(grid) * (d[1:] + d[:-1])))


class Embankment(ProtectiveMeasure):
    """Rockfall protection embankment with a steep uphill face (see the module)."""

    kind: ClassVar[str] = "embankment"
    summary: ClassVar[str] = "earth embankment with a steep uphill face that stops rocks in front"
    Params: ClassVar[type[MeasureParams]] = EmbankmentParams
    example: ClassVar[dict[str, Any]] = {"x": 40.0, "height": 3.0}
    #: Fill, placed and compacted, with its reinforced face (currency per m^3):
    #: ILLUSTRATIVE, overridden by the project's cost catalogue.
    default_prices: ClassVar[dict[str, Any]] = {"embankment_fill_m3": 45.0}

    params: EmbankmentParams

    def _points(self, section: Any) -> np.ndarray:
        """New ground vertices from the toe to where the downhill face meets the ground."""
        p = self.params
        xs = np.asarray(section.x, float)
        ys = np.asarray(section.y, float)
        if not xs[0] <= p.x < xs[-1]:
            raise ValueError(f"the embankment at x = {p.x:g} m is outside the section, which "
                             f"runs from {xs[0]:g} to {xs[-1]:g} m")
        y_t = _ground(xs, ys, p.x)
        y_c = y_t + p.height
        x_1 = p.x + p.height / math.tan(math.radians(p.uphill_face_deg))
        x_2 = x_1 + p.crest_width
        tan_b = math.tan(math.radians(p.downhill_face_deg))

        def gap(s: float) -> float:  # downhill face minus ground, > 0 while above it
            return y_c - (s - x_2) * tan_b - _ground(xs, ys, s)

        if x_2 >= xs[-1] or gap(x_2) <= 0:
            raise ValueError(f"the embankment at x = {p.x:g} m does not fit: its crest runs "
                             "past the section's end or into the ground")
        s_lo, g_lo = x_2, gap(x_2)
        for s_hi in xs[xs > x_2]:
            g_hi = gap(float(s_hi))
            if g_hi <= 0.0:  # the face meets the ground in [s_lo, s_hi]: both linear there
                x_e = s_lo + g_lo * (float(s_hi) - s_lo) / (g_lo - g_hi)
                break
            s_lo, g_lo = float(s_hi), g_hi
        else:
            raise ValueError(
                f"the embankment at x = {p.x:g} m does not fit: its {p.downhill_face_deg:g} deg "
                "downhill face never meets the ground before the section's end (the ground "
                "below is steeper than the face; move it onto gentler ground)")
        if x_e - x_2 < 1e-6:
            x_e = x_2 + 1e-6
        return np.array([[p.x, y_t], [x_1, y_c], [x_2, y_c], [x_e, _ground(xs, ys, x_e)]])

    def footprint(self, section: Any) -> ProfileEdit:
        """The new ground from the toe to the downhill foot; ValueError if it does not fit."""
        p = self.params
        points = self._points(section)
        x_2 = float(points[2, 0])
        catch_from = max(p.x - p.catch_zone, float(section.x[0]))
        return ProfileEdit(x_start=float(points[0, 0]), x_end=float(points[-1, 0]),
                           points=points, catch_from=catch_from, catch_to=x_2,
                           material=p.material)

    def design_properties(self) -> dict[str, float]:
        """``width_m``: the catch zone plus the embankment up to its crest's downhill edge (m)."""
        p = self.params
        to_crest = p.height / math.tan(math.radians(p.uphill_face_deg)) + p.crest_width
        return {"width_m": p.catch_zone + to_crest}

    def quantities(self, section: Any) -> dict[str, float]:
        """``fill_m3_per_m`` (m^3/m), ``height_m``, ``footprint_m`` (m, toe to foot)."""
        points = self._points(section)
        area = fill_area(np.asarray(section.x, float), np.asarray(section.y, float), points)
        return {"fill_m3_per_m": area, "height_m": self.params.height,
                "footprint_m": float(points[-1, 0] - points[0, 0])}

    def bill_from(self, quantities: dict[str, float]) -> list[Quantity]:
        """``embankment_fill_m3``: fill per running metre (m^3/m)."""
        return [Quantity("embankment_fill_m3", quantities["fill_m3_per_m"], "m3")]

    def label(self) -> str:
        p = self.params
        return f"embankment ({p.height:g} m high, face {p.uphill_face_deg:g} deg) at x = {p.x:g} m"


@hookimpl
def rockfall_design_measures() -> list[type[ProtectiveMeasure]]:
    """The embankment."""
    return [Embankment]

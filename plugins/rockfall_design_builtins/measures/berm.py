"""The built-in bench cut into the slope, with a cut face above it, ``type: berm``.

An ordinary plugin with an entry point of its own (``berm``). Lengths in m,
angles in degrees.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np
from pydantic import Field

from rockfall_design import (
    MeasureParams,
    ProfileEdit,
    ProtectiveMeasure,
    Quantity,
    hookimpl,
)

from .shared import (
    MATERIAL_DESCRIPTION,
    STATION_RANGE,
    SectionLike,
    StrictParams,
    check_stretch,
    check_vertices,
    earthworks,
    edit_volumes,
    ground_at,
    range_text,
)

__all__ = ["Berm", "BermParams", "rockfall_design_measures"]


class BermParams(StrictParams):
    """Parameters of a bench cut into the slope."""

    x: float = Field(
        description="Station of the bench's upslope edge, the foot of the cut face (m).",
        json_schema_extra={"unit": "m"},
    )
    width: float = Field(
        gt=0, description="Width of the bench along x (m).",
        json_schema_extra={"unit": "m", "design": {"bounds": [2.0, 20.0]}},
    )
    cut_face_deg: float = Field(
        default=60.0,
        ge=30,
        le=85,
        description="Slope of the cut face above the bench (degrees), 30..85.",
        json_schema_extra={"unit": "deg"},
    )
    material: str | None = Field(
        default=None, description=MATERIAL_DESCRIPTION,
        json_schema_extra={"unit": None},
    )


class Berm(ProtectiveMeasure):
    """Horizontal bench (berm) cut into the slope, with a cut face above it.

    Parameters (``Params``)
    -----------------------
    x : float
        Upslope edge of the bench, the foot of the cut face (m).
    width : float
        Width B of the bench (m), > 0.
    cut_face_deg : float, default 60
        Slope phi of the cut face (degrees), 30..85.
    material : str, optional
        Material of the new surfaces; None keeps the original ground's.

    Notes
    -----
    Geometry: the bench is horizontal at y_b = y(x + B), so its outer edge
    lies on the original ground, and runs from x to x + B. The cut face rises
    from (x, y_b) upslope at phi, y = y_b + (x - s) tan(phi) for s <= x, until
    it first meets the original ground at x_c < x (solved exactly, segment by
    segment). The cut height is H = y(x_c) - y_b. On a straight slope of
    angle beta < phi, H = B tan(beta) / (1 - tan(beta) / tan(phi)) and the
    excavated area is B H / 2.

    Footprint: a :class:`ProfileEdit` over [x_c, x + B]; rocks that come to
    rest with their centre on the bench, [x, x + B], are caught. Safety
    concepts compare ``width_m`` with the rocks' reach on the bench.

    Quantities per running metre: ``excavation_m3_per_m`` (exact area),
    ``fill_m3_per_m`` (normally 0), ``width_m``, ``cut_height_m``.
    """

    kind: ClassVar[str] = "berm"
    summary: ClassVar[str] = "horizontal bench cut into the slope that stops rocks on it"
    Params: ClassVar[type[MeasureParams]] = BermParams
    example: ClassVar[dict[str, Any]] = {"x": 85.0, "width": 8.0, "cut_face_deg": 60.0}
    design_variables: ClassVar[dict[str, tuple[float, float]]] = {
        "x": STATION_RANGE,
        "width": (2.0, 20.0),
    }

    params: BermParams

    def _geometry(self, section: SectionLike) -> tuple[float, float, float]:
        """(x_c, y(x_c), y_b) of the berm on ``section``; ValueError if it does not fit."""
        p = self.params
        x_b = p.x + p.width
        x0 = float(section.x[0])
        if not x0 < p.x:
            raise ValueError(
                f"the berm at x = {p.x:g} m is outside the section, which runs from "
                f"{range_text(section)}"
            )
        check_stretch(section, p.x, x_b, "the berm")
        y_b = ground_at(section, x_b)
        y_x = ground_at(section, p.x)
        if not y_x > y_b:
            raise ValueError(
                f"the berm does not fit: the ground at x = {p.x:g} m ({y_x:g} m) is not above "
                f"the bench level y({x_b:g} m) = {y_b:g} m, so there is nothing to cut"
            )
        tan_phi = math.tan(math.radians(p.cut_face_deg))
        xs = np.asarray(section.x, float)
        ys = np.asarray(section.y, float)

        def gap(s: float, ground: float) -> float:  # ground minus cut face, > 0 above it
            return ground - (y_b + (p.x - s) * tan_phi)

        s_hi, g_hi = p.x, gap(p.x, y_x)
        for k in range(int(np.searchsorted(xs, p.x, side="left")) - 1, -1, -1):
            s_lo = float(xs[k])
            g_lo = gap(s_lo, float(ys[k]))
            if g_lo <= 0.0:
                x_c = s_hi - g_hi * (s_hi - s_lo) / (g_hi - g_lo)
                return x_c, ground_at(section, x_c), y_b
            s_hi, g_hi = s_lo, g_lo
        raise ValueError(
            f"the berm does not fit: its {p.cut_face_deg:g} deg cut face from x = {p.x:g} m "
            f"never meets the ground before the section's start at x = {x0:g} m "
            "(the slope above is too steep or the section too short; "
            "steepen the cut face or narrow the bench)"
        )

    def footprint(self, section: SectionLike) -> ProfileEdit:
        """The edited stretch [x_c, x + width]; ValueError if the berm does not fit.

        Raises
        ------
        ValueError
            If the bench runs past the section's end, the ground at ``x`` is not
            above the bench level, or the cut face never meets the ground
            within the section.
        """
        p = self.params
        x_c, y_c, y_b = self._geometry(section)
        x_b = p.x + p.width
        points = np.array([[x_c, y_c], [p.x, y_b], [x_b, y_b]])
        check_vertices(points, "the berm")
        return ProfileEdit(
            x_start=x_c,
            x_end=x_b,
            points=points,
            catch_from=p.x,
            catch_to=x_b,
            material=p.material,
        )

    def design_properties(self) -> dict[str, float]:
        """``width_m`` (m), the bench width."""
        return {"width_m": self.params.width}

    def quantities(self, section: SectionLike) -> dict[str, float]:
        """``excavation_m3_per_m``, ``fill_m3_per_m`` (m^3/m), ``width_m``, ``cut_height_m``."""
        edit = self.footprint(section)
        cut, fill = edit_volumes(section, edit)
        pts = np.asarray(edit.points, float)
        return {
            "excavation_m3_per_m": cut,
            "fill_m3_per_m": fill,
            "width_m": self.params.width,
            "cut_height_m": float(pts[0, 1] - pts[1, 1]),
        }

    def bill_from(self, quantities: dict[str, float]) -> list[Quantity]:
        """``excavation_m3`` and ``fill_m3`` per running metre."""
        return earthworks(quantities)

    def label(self) -> str:
        p = self.params
        return f"berm ({p.width:g} m wide) at x = {p.x:g} m"


@hookimpl
def rockfall_design_measures() -> list[type[ProtectiveMeasure]]:
    """The built-in berm, registered by its own entry point."""
    return [Berm]

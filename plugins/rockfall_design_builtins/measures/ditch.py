"""The built-in trapezoidal catch ditch dug into the slope, ``type: ditch``.

An ordinary plugin with an entry point of its own (``ditch``). Lengths in m,
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
)

__all__ = ["Ditch", "DitchParams", "rockfall_design_measures"]


class DitchParams(StrictParams):
    """Parameters of a trapezoidal catch ditch."""

    x: float = Field(
        description="Station of the ditch's upslope edge (m).",
        json_schema_extra={"unit": "m"},
    )
    width: float = Field(
        gt=0, description="Top width of the ditch along x (m).",
        json_schema_extra={"unit": "m", "design": {"bounds": [2.0, 20.0]}},
    )
    depth: float = Field(
        gt=0, description="Depth of the bottom below the lower of the two edges (m).",
        json_schema_extra={"unit": "m", "design": {"bounds": [0.5, 5.0]}},
    )
    upslope_side_deg: float = Field(
        default=45.0, ge=10, le=80, description="Slope of the upslope side (degrees), 10..80.",
        json_schema_extra={"unit": "deg"},
    )
    downslope_side_deg: float = Field(
        default=45.0, ge=10, le=80, description="Slope of the downslope side (degrees), 10..80.",
        json_schema_extra={"unit": "deg"},
    )
    material: str | None = Field(
        default=None, description=MATERIAL_DESCRIPTION,
        json_schema_extra={"unit": None},
    )


class Ditch(ProtectiveMeasure):
    """Trapezoidal catch ditch dug into the slope.

    Parameters (``Params``)
    -----------------------
    x : float
        Upslope edge x_a (m).
    width : float
        Top width W (m), > 0: the downslope edge is x_b = x_a + W.
    depth : float
        Depth d (m), > 0, of the horizontal bottom below the lower edge.
    upslope_side_deg, downslope_side_deg : float, default 45
        Slopes of the two sides (degrees), 10..80.
    material : str, optional
        Material of the new surfaces; None keeps the original ground's.

    Notes
    -----
    Geometry: both edges lie on the original ground, y_a = y(x_a) and
    y_b = y(x_b). The bottom is horizontal at y_0 = min(y_a, y_b) - d. The
    upslope side falls from (x_a, y_a) at ``upslope_side_deg`` to the bottom,
    reaching it at x_a + (y_a - y_0) / tan(alpha_u); the downslope side rises
    from x_b - (y_b - y_0) / tan(alpha_d) at ``downslope_side_deg`` to
    (x_b, y_b). The new ground replaces all of the original one between x_a
    and x_b. The bottom must keep a positive width.

    Footprint: a :class:`ProfileEdit` over [x_a, x_b]; rocks that come to rest
    with their centre in [x_a, x_b] are caught (the engine decides this after
    running the rocks over the edited section, so a rock that rolls back into
    the ditch from its far side is caught too).

    Quantities per running metre: ``excavation_m3_per_m`` (exact area between
    the original and the new ground where the original lies above),
    ``fill_m3_per_m`` (where it lies below, normally 0), ``width_m``,
    ``depth_m``.
    """

    kind: ClassVar[str] = "ditch"
    summary: ClassVar[str] = "trapezoidal catch ditch dug into the slope"
    Params: ClassVar[type[MeasureParams]] = DitchParams
    example: ClassVar[dict[str, Any]] = {
        "x": 90.0,
        "width": 10.0,
        "depth": 2.0,
        "upslope_side_deg": 45.0,
        "downslope_side_deg": 45.0,
    }
    design_variables: ClassVar[dict[str, tuple[float, float]]] = {
        "x": STATION_RANGE,
        "width": (2.0, 20.0),
        "depth": (0.5, 5.0),
    }

    params: DitchParams

    def footprint(self, section: SectionLike) -> ProfileEdit:
        """The edited stretch [x, x + width]; ValueError if it does not fit.

        Raises
        ------
        ValueError
            If either edge lies outside the section, or the side slopes leave
            no bottom (bottom width <= 0).
        """
        p = self.params
        x_a, x_b = p.x, p.x + p.width
        check_stretch(section, x_a, x_b, "the ditch")
        y_a, y_b = ground_at(section, x_a), ground_at(section, x_b)
        y_0 = min(y_a, y_b) - p.depth
        run_u = (y_a - y_0) / math.tan(math.radians(p.upslope_side_deg))
        run_d = (y_b - y_0) / math.tan(math.radians(p.downslope_side_deg))
        if run_u + run_d >= p.width:
            raise ValueError(
                f"ditch too narrow: the side slopes need {run_u + run_d:.3g} m of the "
                f"{p.width:g} m width (make it wider or shallower, or the sides steeper)"
            )
        points = np.array([[x_a, y_a], [x_a + run_u, y_0], [x_b - run_d, y_0], [x_b, y_b]])
        check_vertices(points, "the ditch")
        return ProfileEdit(
            x_start=x_a,
            x_end=x_b,
            points=points,
            catch_from=x_a,
            catch_to=x_b,
            material=p.material,
        )

    def design_properties(self) -> dict[str, float]:
        """``width_m`` (m, the top width) and ``depth_m`` (m)."""
        return {"width_m": self.params.width, "depth_m": self.params.depth}

    def quantities(self, section: SectionLike) -> dict[str, float]:
        """``excavation_m3_per_m``, ``fill_m3_per_m`` (m^3/m), ``width_m``, ``depth_m`` (m)."""
        cut, fill = edit_volumes(section, self.footprint(section))
        return {
            "excavation_m3_per_m": cut,
            "fill_m3_per_m": fill,
            "width_m": self.params.width,
            "depth_m": self.params.depth,
        }

    def bill_from(self, quantities: dict[str, float]) -> list[Quantity]:
        """``excavation_m3`` and ``fill_m3`` per running metre."""
        return earthworks(quantities)

    def label(self) -> str:
        p = self.params
        return f"ditch ({p.width:g} m wide, {p.depth:g} m deep) at x = {p.x:g} m"


@hookimpl
def rockfall_design_measures() -> list[type[ProtectiveMeasure]]:
    """The built-in ditch, registered by its own entry point."""
    return [Ditch]

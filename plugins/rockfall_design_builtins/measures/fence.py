"""The built-in flexible rockfall fence (a net barrier), ``type: fence``.

An ordinary plugin with an entry point of its own (``fence``). Lengths in m,
energies in kJ.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np
from pydantic import (
    Field,
    SerializerFunctionWrapHandler,
    model_serializer,
    model_validator,
)

from rockfall_design import (
    Barrier,
    BarrierBehaviour,
    MeasureParams,
    ProtectiveMeasure,
    Quantity,
    hookimpl,
)

from .shared import (
    STATION_RANGE,
    SectionLike,
    StrictParams,
    check_station,
    running_metre,
)

__all__ = ["Fence", "FenceParams", "residual_height_category", "rockfall_design_measures"]


#: The fence's optional figures of its EAD 340059 tests (left out of its summary when absent).
_MEL_FIELDS = ("sel_kj", "max_elongation_m", "elongation_sel_m", "residual_height_fraction")


def _slope_cos(section: SectionLike, x: float) -> float:
    """Cosine of the inclination of the ground segment under ``x`` (the upslope one at a vertex)."""
    xs, ys = np.asarray(section.x, float), np.asarray(section.y, float)
    i = int(np.clip(np.searchsorted(xs, x, side="left") - 1, 0, xs.size - 2))
    dx, dy = xs[i + 1] - xs[i], ys[i + 1] - ys[i]
    return float(dx / math.hypot(dx, dy))


def residual_height_category(fraction: float) -> str:
    """EAD 340059's residual height category of a residual height fraction (-).

    A: at least 50 % of the nominal height after the MEL test; B: more than
    30 % and less than 50 %; C: 30 % or less.
    """
    if fraction >= 0.5:
        return "A"
    return "B" if fraction > 0.3 else "C"



class FenceParams(StrictParams):
    """Parameters of a flexible rockfall fence."""

    x: float = Field(description="Station of the fence (m).", json_schema_extra={"unit": "m"})
    height: float = Field(
        gt=0, description="Nominal height of the fence (m).",
        json_schema_extra={"unit": "m", "design": "catalogue_height"},
    )
    capacity_kj: float = Field(
        gt=0, description="Energy capacity of the product (kJ): its MEL energy class.",
        json_schema_extra={"unit": "kJ", "design": "catalogue_capacity"},
    )
    product: str | None = Field(
        default=None, description="Catalogue name of the product (for reports), optional.",
        json_schema_extra={"unit": None, "design": "catalogue"},
    )
    max_elongation_m: float | None = Field(
        default=None, gt=0,
        description="Maximum elongation of the kit in its MEL test (m): the braking distance "
        "downslope of the fence; optional, set from the catalogue product where it has one.",
        json_schema_extra={"unit": "m"},
    )
    sel_kj: float | None = Field(
        default=None, gt=0,
        description="Service energy level of the kit (kJ), EAD 340059; optional, a third of "
        "capacity_kj (the MEL) where not given.",
        json_schema_extra={"unit": "kJ"},
    )
    elongation_sel_m: float | None = Field(
        default=None, gt=0,
        description="Elongation of the kit in its SEL test (m); optional: without it every "
        "caught rock is braked over the MEL elongation.",
        json_schema_extra={"unit": "m"},
    )
    residual_height_fraction: float | None = Field(
        default=None, gt=0, le=1,
        description="Residual height after the MEL test over the nominal height (-), EAD "
        "340059 (category A >= 0.5, B 0.3 to 0.5, C <= 0.3); optional, set from the catalogue "
        "product where it has one.",
        json_schema_extra={"unit": "-"},
    )

    @model_serializer(mode="wrap")
    def _without_absent_mel_figures(self, handler: SerializerFunctionWrapHandler) -> Any:
        """The parameters, without MEL-test figures the product does not give.

        So that a fence without them is written (summaries, design.yaml) as
        before they existed.
        """
        data = handler(self)
        if isinstance(data, dict):
            for key in _MEL_FIELDS:
                if data.get(key, 0) is None:
                    del data[key]
        return data

    @model_validator(mode="after")
    def _sel_below_mel(self) -> FenceParams:
        """The SEL is a fraction of the MEL (EAD 340059): a given SEL must be below it."""
        if self.sel_kj is not None and not self.sel_kj < self.capacity_kj:
            raise ValueError(f"sel_kj = {self.sel_kj:g} kJ must be below capacity_kj = "
                             f"{self.capacity_kj:g} kJ (the MEL)")
        return self


class Fence(ProtectiveMeasure):
    """Flexible rockfall barrier (net fence), e.g. an ETAG 027 / EAD 340059 kit.

    Parameters (``Params``)
    -----------------------
    x : float
        Station (m).
    height : float
        Nominal height (m), > 0.
    capacity_kj : float
        Energy capacity (kJ), > 0: the MEL energy class of the product.
    product : str, optional
        Catalogue name.
    max_elongation_m : float, optional
        Maximum elongation in the kit's MEL test (m), > 0: how far downslope
        of ``x`` the net may reach while braking a rock.
    residual_height_fraction : float, optional
        Residual height after the MEL test over the nominal height (-), in
        (0, 1].

    sel_kj : float, optional
        Service energy level (kJ), below ``capacity_kj``; a third of it
        where not given (EAD 340059).
    elongation_sel_m : float, optional
        Elongation in the SEL test (m), > 0.

    Notes
    -----
    Footprint: a :class:`Barrier` with behaviour ``NET`` at ``x``, its height
    the nominal height measured perpendicular to the slope, as EAD 340059
    defines it (``height_normal``; ``slope_cos`` from the ground segment
    under ``x``). The engine applies the catch condition where a rock's
    centre crosses ``x``: a rock whose centre passes more than ``height``
    from the slope (``height / cos(slope)`` vertically) goes over; otherwise
    it is caught if its total kinetic energy E <= ``capacity_kj``, and
    breaks through with the surplus E - capacity (velocity and spin scaled
    by sqrt((E - capacity) / E)) if not. A caught rock comes to rest its
    braking distance downslope of ``x``: the SEL elongation up to the SEL,
    the maximum elongation at the MEL, linear in E between
    (:func:`rockfall_design.engine.barriers.braking_distance`); without a
    ``max_elongation_m`` it stops at ``x``.

    Quantities per running metre: ``height_m``, ``capacity_kj`` and the net
    area ``area_m2_per_m`` = height.

    The test figures, where given, also reach the safety concepts as design
    properties (``max_elongation_m``, ``elongation_sel_m``, ``sel_kj``;
    ``residual_height_m`` = fraction x height), which check the braking
    distance and the residual height.
    """

    kind: ClassVar[str] = "fence"
    summary: ClassVar[str] = "flexible rockfall fence (net) of a given height and energy class"
    Params: ClassVar[type[MeasureParams]] = FenceParams
    example: ClassVar[dict[str, Any]] = {"x": 70.0, "height": 4.0, "capacity_kj": 1000.0}
    design_variables: ClassVar[dict[str, tuple[float, float]]] = {
        "x": STATION_RANGE,
        "height": (1.0, 10.0),
    }

    params: FenceParams

    def footprint(self, section: SectionLike) -> Barrier:
        """A ``NET`` barrier at ``x``; ValueError if ``x`` is outside the section."""
        p = self.params
        check_station(section, p.x, "the fence")
        def given(v: float | None) -> float:
            return math.nan if v is None else v

        return Barrier(
            x=p.x, height_m=p.height, capacity_kj=p.capacity_kj, behaviour=BarrierBehaviour.NET,
            slope_cos=_slope_cos(section, p.x), height_normal=True, sel_kj=given(p.sel_kj),
            elongation_sel_m=given(p.elongation_sel_m),
            elongation_mel_m=given(p.max_elongation_m),
        )

    def design_properties(self) -> dict[str, float]:
        """``height_m`` (m), ``capacity_kj`` (kJ) and the test figures the product gives.

        ``sel_kj`` (kJ; a concept takes a third of the capacity where it is
        absent, as EAD 340059 defines the SEL), ``max_elongation_m``,
        ``elongation_sel_m`` (m) and ``residual_height_m`` (m, the residual
        height fraction times the nominal height) only when given, so that
        a fence without them is checked as before.
        """
        p = self.params
        props = {"height_m": p.height, "capacity_kj": p.capacity_kj}
        if p.sel_kj is not None:
            props["sel_kj"] = p.sel_kj
        if p.max_elongation_m is not None:
            props["max_elongation_m"] = p.max_elongation_m
        if p.elongation_sel_m is not None:
            props["elongation_sel_m"] = p.elongation_sel_m
        if p.residual_height_fraction is not None:
            props["residual_height_m"] = p.residual_height_fraction * p.height
        return props

    def quantities(self, section: SectionLike) -> dict[str, float]:
        """``height_m`` (m), ``capacity_kj`` (kJ), ``area_m2_per_m`` (m^2/m)."""
        p = self.params
        return {"height_m": p.height, "capacity_kj": p.capacity_kj, "area_m2_per_m": p.height}

    def bill_from(self, quantities: dict[str, float]) -> list[Quantity]:
        """One running metre of the fence's product at its height (priced by kind)."""
        return running_metre(self, quantities)

    def label(self) -> str:
        p = self.params
        name = f"fence {p.product}" if p.product else "fence"
        return f"{name} ({p.height:g} m, {p.capacity_kj:g} kJ) at x = {p.x:g} m"


@hookimpl
def rockfall_design_measures() -> list[type[ProtectiveMeasure]]:
    """The built-in fence, registered by its own entry point."""
    return [Fence]

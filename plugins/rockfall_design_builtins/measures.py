"""The built-in protective measures: fence, wall, boulder row, ditch and berm.

An ordinary plugin: it uses only the public ``rockfall_design`` API and is
registered through the ``rockfall_design`` entry-point group, exactly as a
third party's measures would be.

Three measures are barriers (:class:`~rockfall_design.Barrier`), which stand
at a station and leave the ground as it is:

* ``fence`` -- flexible net (:attr:`BarrierBehaviour.NET`);
* ``wall`` -- rigid wall of gabions or concrete (:attr:`BarrierBehaviour.RIGID`);
* ``boulder_row`` -- a row of cubic blocks with gaps (:attr:`BarrierBehaviour.BLOCKS`).

Two are edits of the ground (:class:`~rockfall_design.ProfileEdit`), which the
engine splices into the section before the rocks run:

* ``ditch`` -- a trapezoidal catch ditch dug into the slope;
* ``berm`` -- a horizontal bench cut into the slope, with a cut face above it.

The engine, not the measure, applies the catch conditions; each class
documents the condition that its footprint asks for. All lengths are in m,
angles in degrees, energies in kJ, densities in kg/m^3.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar, Protocol

import numpy as np
from pydantic import (
    ConfigDict,
    Field,
    SerializerFunctionWrapHandler,
    model_serializer,
    model_validator,
)

from rockfall_design import (
    Barrier,
    BarrierBehaviour,
    MeasureParams,
    ProfileEdit,
    ProtectiveMeasure,
    Quantity,
    hookimpl,
)

__all__ = [
    "Fence",
    "Wall",
    "BoulderRow",
    "Ditch",
    "Berm",
    "rockfall_design_measures",
]

#: Bounds of a station design variable: the optimiser substitutes the
#: candidate's station range for these NaNs.
_STATION_RANGE = (math.nan, math.nan)


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


class _Params(MeasureParams):
    """Strict parameters that also reject NaN and infinity."""

    model_config = ConfigDict(allow_inf_nan=False)


# ---------------------------------------------------------------------------
# geometry helpers
# ---------------------------------------------------------------------------


def _ground(section: SectionLike, x: float) -> float:
    return float(np.interp(x, np.asarray(section.x, float), np.asarray(section.y, float)))


def _range_text(section: SectionLike) -> str:
    return f"{float(section.x[0]):g} to {float(section.x[-1]):g} m"


def _check_station(section: SectionLike, x: float, what: str) -> None:
    """A barrier must stand strictly inside the section."""
    x0, x1 = float(section.x[0]), float(section.x[-1])
    if not x0 < x < x1:
        raise ValueError(
            f"{what} at x = {x:g} m is outside the section, which runs from {_range_text(section)}"
        )


def _check_stretch(section: SectionLike, x_start: float, x_end: float, what: str) -> None:
    """An edited stretch must lie within the section."""
    x0, x1 = float(section.x[0]), float(section.x[-1])
    if not x0 <= x_start:
        raise ValueError(
            f"{what} starts at x = {x_start:g} m, upslope of the section's start "
            f"(the section runs from {_range_text(section)})"
        )
    if not x_end <= x1:
        raise ValueError(
            f"{what} runs to x = {x_end:g} m, past the section's end "
            f"(the section runs from {_range_text(section)})"
        )


def _check_vertices(points: np.ndarray, what: str) -> None:
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


def _running_metre(measure: Any, quantities: dict[str, float]) -> list[Quantity]:
    """A barrier's bill: one running metre named after its kind, of its product at its height."""
    height = quantities.get("height_m", measure.params.height)
    return [Quantity(measure.kind, 1.0, "m", product=measure.params.product, size=height)]


def _earthworks(quantities: dict[str, float]) -> list[Quantity]:
    """A ground edit's bill: excavated and filled m^3 per running metre."""
    return [Quantity("excavation_m3", quantities["excavation_m3_per_m"], "m3"),
            Quantity("fill_m3", quantities.get("fill_m3_per_m", 0.0), "m3")]


def _edit_volumes(section: SectionLike, edit: ProfileEdit) -> tuple[float, float]:
    pts = np.asarray(edit.points, float)
    return cut_and_fill(
        np.asarray(section.x, float), np.asarray(section.y, float), pts[:, 0], pts[:, 1]
    )


# ---------------------------------------------------------------------------
# barriers
# ---------------------------------------------------------------------------


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


class FenceParams(_Params):
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
        "x": _STATION_RANGE,
        "height": (1.0, 10.0),
    }

    params: FenceParams

    def footprint(self, section: SectionLike) -> Barrier:
        """A ``NET`` barrier at ``x``; ValueError if ``x`` is outside the section."""
        p = self.params
        _check_station(section, p.x, "the fence")
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
        return _running_metre(self, quantities)

    def label(self) -> str:
        p = self.params
        name = f"fence {p.product}" if p.product else "fence"
        return f"{name} ({p.height:g} m, {p.capacity_kj:g} kJ) at x = {p.x:g} m"


class WallParams(_Params):
    """Parameters of a rigid protection wall."""

    x: float = Field(description="Station of the wall (m).", json_schema_extra={"unit": "m"})
    height: float = Field(
        gt=0, description="Height of the wall above the ground (m).",
        json_schema_extra={"unit": "m", "design": "catalogue_height"},
    )
    capacity_kj: float = Field(
        gt=0, description="Energy the wall can take before it fails (kJ).",
        json_schema_extra={"unit": "kJ", "design": "catalogue_capacity"},
    )
    restitution: float = Field(
        default=0.2,
        ge=0,
        le=1,
        description="Coefficient of restitution of the rebound, horizontal (-), 0..1.",
        json_schema_extra={"unit": "-"},
    )
    thickness: float = Field(
        default=1.0, gt=0, description="Mean thickness of the wall (m), for costing.",
        json_schema_extra={"unit": "m"},
    )
    product: str | None = Field(
        default=None, description="Catalogue name of the wall type (for costing), if any.",
        json_schema_extra={"unit": None, "design": "catalogue"},
    )


class Wall(ProtectiveMeasure):
    """Rigid protection wall (gabions, reinforced earth, concrete).

    Parameters (``Params``)
    -----------------------
    x : float
        Station (m).
    height : float
        Height above the ground (m), > 0.
    capacity_kj : float
        Energy the wall can take (kJ), > 0.
    restitution : float, default 0.2
        Coefficient of restitution of the rebound (-), 0..1.
    thickness : float, default 1.0
        Mean thickness (m), for costing.

    Notes
    -----
    Footprint: a :class:`Barrier` with behaviour ``RIGID`` at ``x``. A rock
    whose centre passes more than ``height`` above the ground goes over;
    otherwise, if its total kinetic energy E <= ``capacity_kj``, it rebounds
    with its horizontal velocity reversed and scaled by ``restitution``
    (vertical velocity and spin kept), and if E > capacity the wall fails and
    the rock goes on with the surplus energy.

    Quantities per running metre: ``height_m``, ``capacity_kj``, ``thickness_m``
    and ``volume_m3_per_m`` = height * thickness.
    """

    kind: ClassVar[str] = "wall"
    summary: ClassVar[str] = "rigid wall (gabions, concrete) that stops rocks or bounces them back"
    Params: ClassVar[type[MeasureParams]] = WallParams
    example: ClassVar[dict[str, Any]] = {
        "x": 100.0,
        "height": 3.0,
        "capacity_kj": 2000.0,
        "restitution": 0.2,
        "thickness": 1.5,
    }
    design_variables: ClassVar[dict[str, tuple[float, float]]] = {
        "x": _STATION_RANGE,
        "height": (1.0, 6.0),
    }

    params: WallParams

    def footprint(self, section: SectionLike) -> Barrier:
        """A ``RIGID`` barrier at ``x``; ValueError if ``x`` is outside the section."""
        p = self.params
        _check_station(section, p.x, "the wall")
        return Barrier(
            x=p.x,
            height_m=p.height,
            capacity_kj=p.capacity_kj,
            behaviour=BarrierBehaviour.RIGID,
            restitution=p.restitution,
        )

    def design_properties(self) -> dict[str, float]:
        """``height_m`` (m) and ``capacity_kj`` (kJ)."""
        return {"height_m": self.params.height, "capacity_kj": self.params.capacity_kj}

    def quantities(self, section: SectionLike) -> dict[str, float]:
        """``height_m`` (m), ``capacity_kj`` (kJ), ``thickness_m`` (m), ``volume_m3_per_m``."""
        p = self.params
        return {
            "height_m": p.height,
            "capacity_kj": p.capacity_kj,
            "thickness_m": p.thickness,
            "volume_m3_per_m": p.height * p.thickness,
        }

    def bill_from(self, quantities: dict[str, float]) -> list[Quantity]:
        """One running metre of the wall's product at its height (priced by kind)."""
        return _running_metre(self, quantities)

    def label(self) -> str:
        p = self.params
        return f"wall ({p.height:g} m, {p.capacity_kj:g} kJ) at x = {p.x:g} m"


class BoulderRowParams(_Params):
    """Parameters of a row of cubic blocks with gaps."""

    x: float = Field(description="Station of the row (m).", json_schema_extra={"unit": "m"})
    block_size: float = Field(
        gt=0, description="Edge of the cubic blocks (m); also the row's height.",
        json_schema_extra={"unit": "m", "design": {"bounds": [0.5, 3.0]}},
    )
    gap_ratio: float = Field(
        ge=0,
        lt=1,
        description="Open fraction of the row's length (-), 0 <= g < 1: gap = g * spacing.",
        json_schema_extra={"unit": "-"},
    )
    capacity_kj: float = Field(
        gt=0, description="Energy a block can take before it is displaced (kJ).",
        json_schema_extra={"unit": "kJ"},
    )
    density: float = Field(
        default=2650.0, gt=0, description="Density of the blocks (kg/m^3), for costing.",
        json_schema_extra={"unit": "kg/m^3"},
    )


class BoulderRow(ProtectiveMeasure):
    """Row of large cubic blocks set side by side across the slope, with gaps.

    Parameters (``Params``)
    -----------------------
    x : float
        Station (m).
    block_size : float
        Edge a of the cubic blocks (m), > 0; the row is ``a`` high.
    gap_ratio : float
        Open fraction g of the row's length (-), 0 <= g < 1.
    capacity_kj : float
        Energy a block can take before it is displaced (kJ), > 0.
    density : float, default 2650
        Density of the blocks (kg/m^3).

    Notes
    -----
    Spacing (centre to centre) s = a / (1 - g), clear gap w = g s = s - a.

    Footprint: a :class:`Barrier` with behaviour ``BLOCKS`` at ``x``, of height
    ``a``, with ``gap_m`` = w and ``spacing_m`` = s. A rock whose centre passes
    more than ``a`` above the ground goes over. Otherwise a rock of diameter D
    passes through a gap with probability max(0, w - D) / s (the fraction of
    the row where its centre can pass without touching a block); if it does
    not, it strikes a block and is stopped when its total kinetic energy
    E <= ``capacity_kj``, or displaces the block and goes on with the surplus
    E - capacity.

    Quantities per running metre: ``blocks_per_m`` = 1/s, ``block_volume_m3``
    = a^3, ``block_mass_kg``, ``volume_m3_per_m`` = a^3 / s, ``height_m`` = a,
    ``capacity_kj``.
    """

    kind: ClassVar[str] = "boulder_row"
    summary: ClassVar[str] = "row of large cubic blocks with gaps between them"
    Params: ClassVar[type[MeasureParams]] = BoulderRowParams
    example: ClassVar[dict[str, Any]] = {
        "x": 130.0,
        "block_size": 1.5,
        "gap_ratio": 0.2,
        "capacity_kj": 300.0,
    }
    design_variables: ClassVar[dict[str, tuple[float, float]]] = {
        "x": _STATION_RANGE,
        "block_size": (0.5, 3.0),
    }

    params: BoulderRowParams

    @property
    def spacing_m(self) -> float:
        """Centre-to-centre spacing of the blocks (m): block_size / (1 - gap_ratio)."""
        return self.params.block_size / (1.0 - self.params.gap_ratio)

    @property
    def gap_m(self) -> float:
        """Clear width of a gap (m): gap_ratio * spacing = spacing - block_size."""
        return self.params.gap_ratio * self.spacing_m

    def footprint(self, section: SectionLike) -> Barrier:
        """A ``BLOCKS`` barrier at ``x``; ValueError if ``x`` is outside the section."""
        p = self.params
        _check_station(section, p.x, "the boulder row")
        return Barrier(
            x=p.x,
            height_m=p.block_size,
            capacity_kj=p.capacity_kj,
            behaviour=BarrierBehaviour.BLOCKS,
            gap_m=self.gap_m,
            spacing_m=self.spacing_m,
        )

    def design_properties(self) -> dict[str, float]:
        """``height_m`` (m) = block size and ``capacity_kj`` (kJ)."""
        return {"height_m": self.params.block_size, "capacity_kj": self.params.capacity_kj}

    def quantities(self, section: SectionLike) -> dict[str, float]:
        """Blocks per metre, block volume (m^3) and mass (kg), volume per metre, height."""
        p = self.params
        volume = p.block_size**3
        per_m = 1.0 / self.spacing_m
        return {
            "blocks_per_m": per_m,
            "block_volume_m3": volume,
            "block_mass_kg": volume * p.density,
            "volume_m3_per_m": volume * per_m,
            "height_m": p.block_size,
            "capacity_kj": p.capacity_kj,
        }

    def bill_from(self, quantities: dict[str, float]) -> list[Quantity]:
        """``block_m3``: m^3 of block per running metre."""
        return [Quantity("block_m3", quantities["block_volume_m3"] * quantities["blocks_per_m"],
                         "m3")]

    def label(self) -> str:
        p = self.params
        return f"boulder row ({p.block_size:g} m blocks, gaps {self.gap_m:.2g} m) at x = {p.x:g} m"


# ---------------------------------------------------------------------------
# profile edits
# ---------------------------------------------------------------------------


_MATERIAL_DESCRIPTION = (
    "Material of the excavated surfaces (a name from the project's materials); "
    "None keeps the original ground's material."
)


class DitchParams(_Params):
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
        default=None, description=_MATERIAL_DESCRIPTION,
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
        "x": _STATION_RANGE,
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
        _check_stretch(section, x_a, x_b, "the ditch")
        y_a, y_b = _ground(section, x_a), _ground(section, x_b)
        y_0 = min(y_a, y_b) - p.depth
        run_u = (y_a - y_0) / math.tan(math.radians(p.upslope_side_deg))
        run_d = (y_b - y_0) / math.tan(math.radians(p.downslope_side_deg))
        if run_u + run_d >= p.width:
            raise ValueError(
                f"ditch too narrow: the side slopes need {run_u + run_d:.3g} m of the "
                f"{p.width:g} m width (make it wider or shallower, or the sides steeper)"
            )
        points = np.array([[x_a, y_a], [x_a + run_u, y_0], [x_b - run_d, y_0], [x_b, y_b]])
        _check_vertices(points, "the ditch")
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
        cut, fill = _edit_volumes(section, self.footprint(section))
        return {
            "excavation_m3_per_m": cut,
            "fill_m3_per_m": fill,
            "width_m": self.params.width,
            "depth_m": self.params.depth,
        }

    def bill_from(self, quantities: dict[str, float]) -> list[Quantity]:
        """``excavation_m3`` and ``fill_m3`` per running metre."""
        return _earthworks(quantities)

    def label(self) -> str:
        p = self.params
        return f"ditch ({p.width:g} m wide, {p.depth:g} m deep) at x = {p.x:g} m"


class BermParams(_Params):
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
        default=None, description=_MATERIAL_DESCRIPTION,
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
        "x": _STATION_RANGE,
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
                f"{_range_text(section)}"
            )
        _check_stretch(section, p.x, x_b, "the berm")
        y_b = _ground(section, x_b)
        y_x = _ground(section, p.x)
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
                return x_c, _ground(section, x_c), y_b
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
        _check_vertices(points, "the berm")
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
        cut, fill = _edit_volumes(section, edit)
        pts = np.asarray(edit.points, float)
        return {
            "excavation_m3_per_m": cut,
            "fill_m3_per_m": fill,
            "width_m": self.params.width,
            "cut_height_m": float(pts[0, 1] - pts[1, 1]),
        }

    def bill_from(self, quantities: dict[str, float]) -> list[Quantity]:
        """``excavation_m3`` and ``fill_m3`` per running metre."""
        return _earthworks(quantities)

    def label(self) -> str:
        p = self.params
        return f"berm ({p.width:g} m wide) at x = {p.x:g} m"


@hookimpl
def rockfall_design_measures() -> list[type[ProtectiveMeasure]]:
    """The built-in measures."""
    return [Fence, Wall, Ditch, Berm, BoulderRow]

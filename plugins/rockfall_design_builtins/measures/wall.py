"""The built-in rigid protection wall (gabions or concrete), ``type: wall``.

An ordinary plugin with an entry point of its own (``wall``). Lengths in m,
energies in kJ.
"""

from __future__ import annotations

from typing import Any, ClassVar

from pydantic import Field

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

__all__ = ["Wall", "WallParams", "rockfall_design_measures"]


class WallParams(StrictParams):
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
        "x": STATION_RANGE,
        "height": (1.0, 6.0),
    }

    params: WallParams

    def footprint(self, section: SectionLike) -> Barrier:
        """A ``RIGID`` barrier at ``x``; ValueError if ``x`` is outside the section."""
        p = self.params
        check_station(section, p.x, "the wall")
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
        return running_metre(self, quantities)

    def label(self) -> str:
        p = self.params
        return f"wall ({p.height:g} m, {p.capacity_kj:g} kJ) at x = {p.x:g} m"


@hookimpl
def rockfall_design_measures() -> list[type[ProtectiveMeasure]]:
    """The built-in wall, registered by its own entry point."""
    return [Wall]

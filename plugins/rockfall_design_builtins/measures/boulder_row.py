"""The built-in row of cubic blocks with gaps, ``type: boulder_row``.

An ordinary plugin with an entry point of its own (``boulder_row``).
Lengths in m, energies in kJ, densities in kg/m^3.
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

from .shared import STATION_RANGE, SectionLike, StrictParams, check_station

__all__ = ["BoulderRow", "BoulderRowParams", "rockfall_design_measures"]


class BoulderRowParams(StrictParams):
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
        "x": STATION_RANGE,
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
        check_station(section, p.x, "the boulder row")
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


@hookimpl
def rockfall_design_measures() -> list[type[ProtectiveMeasure]]:
    """The built-in boulder row, registered by its own entry point."""
    return [BoulderRow]

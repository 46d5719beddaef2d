"""The built-in cost model: unit prices per running metre and per cubic metre.

An ordinary plugin: it uses only the public ``rockfall_design`` API and is
registered through the ``rockfall_design`` entry-point group, exactly as a
third party's cost model would be.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, ClassVar

from pydantic import ConfigDict, Field

from rockfall_design import CostModel, CostParams, ProtectiveMeasure, hookimpl

__all__ = ["UnitPrices", "UnitPricesParams", "rockfall_design_cost_models"]

#: At most a billion per unit: a price of 1e308 made a cost of inf, which the
#: cost contract (rightly) calls a bug of this plugin, not of the price file.
_Price = Annotated[float, Field(ge=0, le=1e9)]
_Height = Annotated[float, Field(gt=0)]


class UnitPricesParams(CostParams):
    """Unit prices (in ``currency``) of the built-in measures."""

    model_config = ConfigDict(allow_inf_nan=False)

    currency: str = Field(
        default="EUR", description="Currency of every price (e.g. EUR).",
        json_schema_extra={"unit": None},
    )
    fixed_per_measure: _Price = Field(
        description="Fixed cost of each measure (currency): mobilisation, design, access.",
        json_schema_extra={"unit": "currency"},
    )
    barrier_per_m: dict[str, dict[str, dict[_Height, _Price]]] = Field(
        default_factory=dict,
        description="Barriers (fence, wall): measure type -> product name -> height (m) -> "
        "price per running metre (currency/m).", json_schema_extra={"unit": "currency/m"},
    )
    excavation_per_m3: _Price = Field(
        description="Excavation of ditches and berms (currency/m^3).",
        json_schema_extra={"unit": "currency/m^3"},
    )
    fill_per_m3: _Price = Field(
        default=0.0, description="Fill placed by ditches and berms (currency/m^3).",
        json_schema_extra={"unit": "currency/m^3"},
    )
    boulder_per_m3: _Price = Field(
        description="Blocks of a boulder row, supplied and placed (currency/m^3 of block).",
        json_schema_extra={"unit": "currency/m^3"},
    )
    other_per_m: dict[str, _Price] = Field(
        default_factory=dict,
        description="Other measure types (e.g. a third party's): measure type -> price per "
        "running metre (currency/m).", json_schema_extra={"unit": "currency/m"},
    )


_BARRIERS = ("fence", "wall")
_EARTHWORKS = ("ditch", "berm")


class UnitPrices(CostModel):
    """Cost from unit prices: per running metre for barriers, per m^3 for earthworks and blocks.

    The cost of a measure over a length L (m) of slope is
    ``fixed_per_measure`` plus, by measure type:

    * ``fence``, ``wall`` (and any type listed in ``barrier_per_m``):
      ``barrier_per_m[type][product][height] * L``, the price per running
      metre of the measure's catalogue ``product`` at its ``height`` (m);
      a KeyError if the catalogue has no such price.
    * ``ditch``, ``berm``: ``(excavation_m3_per_m * excavation_per_m3 +
      fill_m3_per_m * fill_per_m3) * L`` with the measure's quantities
      (m^3 per running metre).
    * ``boulder_row``: ``block_volume_m3 * blocks_per_m * L * boulder_per_m3``.
    * any other type: ``other_per_m[type] * L``; a KeyError if not listed.

    Prices are in ``currency`` (default EUR).
    """

    name: ClassVar[str] = "unit_prices"
    summary: ClassVar[str] = (
        "unit prices: barriers per metre by product and height, earthworks and blocks per m3"
    )
    Params: ClassVar[type[CostParams]] = UnitPricesParams
    example: ClassVar[dict[str, Any]] = {
        "currency": "EUR",
        "fixed_per_measure": 15000.0,
        "barrier_per_m": {
            "fence": {"RX-100": {3.0: 520.0, 4.0: 600.0, 5.0: 690.0}},
            "wall": {"gabion-2000": {2.0: 900.0, 3.0: 1300.0}},
        },
        "excavation_per_m3": 25.0,
        "fill_per_m3": 18.0,
        "boulder_per_m3": 110.0,
        "other_per_m": {},
    }

    params: UnitPricesParams

    def cost(
        self, measure: ProtectiveMeasure, quantities: dict[str, float], length_m: float
    ) -> float:
        """Cost of ``measure`` over ``length_m`` metres of slope (currency); see the class.

        Raises
        ------
        KeyError
            If there is no price for the measure's type, or for a barrier's
            product and height.
        """
        p = self.params
        kind = measure.kind
        if kind in _BARRIERS or kind in p.barrier_per_m:
            part = self._barrier_price(measure, quantities) * length_m
        elif kind in _EARTHWORKS:
            part = (
                quantities["excavation_m3_per_m"] * p.excavation_per_m3
                + quantities.get("fill_m3_per_m", 0.0) * p.fill_per_m3
            ) * length_m
        elif kind == "boulder_row":
            part = (
                quantities["block_volume_m3"]
                * quantities["blocks_per_m"]
                * length_m
                * p.boulder_per_m3
            )
        elif kind in p.other_per_m:
            part = p.other_per_m[kind] * length_m
        else:
            listed = ", ".join(sorted(p.other_per_m)) or "none"
            raise KeyError(
                f"unit_prices has no price for measure type {kind!r}: add it to other_per_m "
                f"(price per running metre; listed: {listed})"
            )
        return p.fixed_per_measure + part

    def _barrier_price(self, measure: ProtectiveMeasure, quantities: dict[str, float]) -> float:
        """Price per running metre of a barrier's product at its height."""
        kind = measure.kind
        product = getattr(measure.params, "product", None)
        height = quantities.get("height_m", getattr(measure.params, "height", None))
        if height is None:
            raise KeyError(f"unit_prices prices a {kind} by its height, but this {kind} has none")
        if product is None:
            raise KeyError(
                f"unit_prices prices a {kind} by its catalogue product, but this {kind} has "
                "no product"
            )
        table = self.params.barrier_per_m.get(kind)
        if table is None:
            raise KeyError(f"unit_prices has no barrier_per_m prices for {kind}")
        prices = table.get(product)
        if prices is None:
            listed = ", ".join(table) or "none"
            raise KeyError(
                f"unit_prices has no price for {kind} product {product!r} "
                f"(barrier_per_m.{kind} lists: {listed})"
            )
        for h, price in prices.items():
            if math.isclose(h, height, rel_tol=1e-9, abs_tol=1e-9):
                return price
        listed = ", ".join(f"{h:g}" for h in prices) or "none"
        raise KeyError(
            f"unit_prices has no price for {kind} product {product!r} at height "
            f"{height:g} m (priced heights: {listed} m)"
        )


@hookimpl
def rockfall_design_cost_models() -> list[type[CostModel]]:
    """The built-in cost models."""
    return [UnitPrices]

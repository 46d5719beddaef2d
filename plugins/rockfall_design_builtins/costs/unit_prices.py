"""The built-in cost model: unit prices of named quantities.

An ordinary plugin: it uses only the public ``rockfall_design`` API and is
registered through the ``rockfall_design`` entry-point group, exactly as a
third party's cost model would be. It knows no measure by name: it prices
the quantities each measure bills (:class:`~rockfall_design.Quantity`) by
their names.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, ClassVar

from pydantic import ConfigDict, Field

from rockfall_design import CostModel, CostParams, ProtectiveMeasure, Quantity, hookimpl

__all__ = ["UnitPrices", "UnitPricesParams", "rockfall_design_cost_models"]

#: At most a billion per unit: a price of 1e308 made a cost of inf, which the
#: cost contract (rightly) calls a bug of this plugin, not of the price file.
_Price = Annotated[float, Field(ge=0, le=1e9)]
_Height = Annotated[float, Field(gt=0)]
#: A price of a quantity: per unit, or by product, or by product and size.
_PriceEntry = _Price | dict[str, _Price | dict[_Height, _Price]]


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
    prices: dict[str, _PriceEntry] = Field(
        default_factory=dict,
        description="Prices of quantities by name (currency per unit of the quantity): a "
        "number, or product -> price, or product -> size -> price. Overrides the keys above "
        "and a measure's default prices.", json_schema_extra={"unit": "currency/unit"},
    )


#: The named quantities the catalogue's fixed keys price (currency per unit).
_PER_UNIT_KEYS = {
    "excavation_m3": "excavation_per_m3",
    "fill_m3": "fill_per_m3",
    "block_m3": "boulder_per_m3",
}


def _fmt(value: float) -> str:
    return f"{value:g}"


class UnitPrices(CostModel):
    """Cost from unit prices of the named quantities each measure bills.

    The cost of a measure over a length L (m) of slope is
    ``fixed_per_measure + L * sum(amount * unit price)`` over the quantities
    of its bill (:meth:`ProtectiveMeasure.bill`, amounts per running metre).
    A quantity's unit price is looked up by its name, first found:

    1. ``prices[name]``: a number (per unit of the quantity), or a table by
       the quantity's product, or by product and size;
    2. ``barrier_per_m[name]`` (product -> size -> price per running metre:
       the built-in fence and wall bill one running metre named ``fence`` or
       ``wall`` of their product at their height), ``other_per_m[name]`` (per
       running metre: a measure written before bills existed bills one
       running metre named after its type), and ``excavation_per_m3``,
       ``fill_per_m3``, ``boulder_per_m3`` for the quantities
       ``excavation_m3``, ``fill_m3`` and ``block_m3``;
    3. the measure's own ``default_prices[name]``.

    A KeyError when there is none, or none for the quantity's product or
    size. Prices are in ``currency`` (default EUR).
    """

    name: ClassVar[str] = "unit_prices"
    summary: ClassVar[str] = (
        "unit prices of named quantities: barriers per metre by product and height, "
        "earthworks and blocks per m3, any plugin's own quantities"
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
        "prices": {},
    }

    params: UnitPricesParams

    def _entry(self, name: str, measure: ProtectiveMeasure) -> tuple[Any, str] | None:
        """(price entry, where it comes from) for quantity ``name``, or None."""
        p = self.params
        if name in p.prices:
            return p.prices[name], f"prices.{name}"
        if name in p.barrier_per_m:
            return p.barrier_per_m[name], f"barrier_per_m.{name}"
        if name in p.other_per_m:
            return p.other_per_m[name], f"other_per_m.{name}"
        if name in _PER_UNIT_KEYS:
            return getattr(p, _PER_UNIT_KEYS[name]), _PER_UNIT_KEYS[name]
        defaults = getattr(type(measure), "default_prices", None) or {}
        if name in defaults:
            return defaults[name], f"the default prices of {measure.kind}"
        return None

    def _no_price(self, q: Quantity, measure: ProtectiveMeasure) -> str:
        listed = ", ".join(sorted({*self.params.prices, *self.params.barrier_per_m,
                                   *self.params.other_per_m, *_PER_UNIT_KEYS})) or "none"
        where = "prices (currency per " + q.unit + ")"
        if q.product is not None:
            where += " or barrier_per_m (product -> height -> price per running metre)"
        elif q.unit == "m":
            where += " or other_per_m (price per running metre)"
        return (f"unit_prices has no price for measure type {measure.kind!r} (quantity "
                f"{q.name!r}, {q.unit} per running metre): add it to {where}; priced "
                f"quantities: {listed}")

    def unit_price(self, q: Quantity, measure: ProtectiveMeasure) -> float:
        """Price of one unit of quantity ``q`` of ``measure`` (currency per unit).

        Raises
        ------
        KeyError
            No price for the quantity's name, or for its product or size.
        """
        found = self._entry(q.name, measure)
        if found is None:
            raise KeyError(self._no_price(q, measure))
        entry, source = found
        if not isinstance(entry, dict):
            return float(entry)
        if q.product is None:
            raise KeyError(f"unit_prices prices {q.name!r} by product ({source}), but this "
                           f"{measure.kind} has no product")
        prices = entry.get(q.product)
        if prices is None:
            listed = ", ".join(entry) or "none"
            raise KeyError(f"unit_prices has no price for {measure.kind} product "
                           f"{q.product!r} ({source} lists: {listed})")
        if not isinstance(prices, dict):
            return float(prices)
        if q.size is None:
            raise KeyError(f"unit_prices prices {q.name!r} {q.product!r} by size ({source}), "
                           f"but this {measure.kind} gives none")
        for size, price in prices.items():
            if math.isclose(size, q.size, rel_tol=1e-9, abs_tol=1e-9):
                return float(price)
        listed = ", ".join(_fmt(h) for h in prices) or "none"
        raise KeyError(f"unit_prices has no price for {measure.kind} product {q.product!r} "
                       f"at height {_fmt(q.size)} m (priced heights: {listed} m)")

    def price(
        self,
        measure: ProtectiveMeasure,
        bill: list[Quantity],
        quantities: dict[str, float],
        length_m: float,
    ) -> float:
        """Cost of ``measure`` over ``length_m`` metres of slope (currency); see the class.

        Raises
        ------
        KeyError
            If a quantity of the bill has no price (see :meth:`unit_price`).
        """
        per_m = 0.0
        for q in bill:
            per_m += q.amount * self.unit_price(q, measure)
        return self.params.fixed_per_measure + per_m * length_m

    def cost(
        self, measure: ProtectiveMeasure, quantities: dict[str, float], length_m: float
    ) -> float:
        """Cost from the measure's quantities dict: the bill it names from them (``bill_from``).

        Raises
        ------
        KeyError
            As :meth:`price`.
        """
        return self.price(measure, measure.bill_from(quantities), quantities, length_m)

    def missing_price(self, measure: ProtectiveMeasure, bill: list[Quantity]) -> str | None:
        """The first quantity of ``bill`` without any price by its name, or None."""
        for q in bill:
            if self._entry(q.name, measure) is None:
                return (f"no price for quantity {q.name!r} ({q.unit} per running metre): add "
                        f"prices: {{{q.name}: PRICE}} (currency per {q.unit})")
        return None


@hookimpl
def rockfall_design_cost_models() -> list[type[CostModel]]:
    """The built-in cost models."""
    return [UnitPrices]

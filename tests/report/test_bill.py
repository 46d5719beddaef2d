"""The bill of a design: the cost model's own numbers, itemised, adding up to the cost."""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
import pytest
from rockfall_design_builtins.costs import UnitPrices, UnitPricesParams
from rockfall_design_builtins.measures import Ditch, Fence

from rockfall_design import CostModel, CostParams
from rockfall_design.judge.costing import design_bill, design_cost
from rockfall_design.judge.design_spec import DesignSpec
from rockfall_design.plugins import load_registry


class Straight:
    """A straight slope y = -x tan(30 deg), from x = 0 to 200 m."""

    x = np.array([0.0, 200.0])
    y = np.array([0.0, -200.0 * np.tan(np.radians(30.0))])

    def ground_height(self, x):
        return np.interp(x, self.x, self.y)


SECTION = Straight()
PRICES = {"currency": "CHF", "fixed_per_measure": 10000.0,
          "barrier_per_m": {"fence": {"RX-100": {3.0: 520.0, 4.0: 600.0}}},
          "excavation_per_m3": 25.0, "fill_per_m3": 18.0, "boulder_per_m3": 110.0}
MEASURES = [Fence(Fence.Params(x=70, height=4, capacity_kj=1000, product="RX-100")),
            Ditch(Ditch.Params(x=100, width=10, depth=2))]


def spec(model: CostModel, length: float = 120.0) -> DesignSpec:
    return DesignSpec(max_measures=2, residual_count=None, residual_fraction=0.001,
                      fresh_rocks=None, fresh_seed=None, length_m=length, candidates=(),
                      cost_model=model, products={})


@pytest.fixture(scope="module")
def registry():
    return load_registry()


def test_unit_prices_itemised_add_up_to_the_design_cost(registry):
    s = spec(UnitPrices(UnitPricesParams.model_validate(PRICES)))
    bill = design_bill(registry, s, MEASURES, SECTION, "catalogue prices.yaml")
    assert bill.total == pytest.approx(design_cost(registry, s, MEASURES, SECTION))
    assert sum(it.amount for it in bill.items) == pytest.approx(bill.total)
    fence = [it for it in bill.items if it.measure.startswith("fence")]
    assert [(it.quantity, it.count, it.unit, it.unit_price) for it in fence] == [
        ("fixed cost of the measure", 1.0, "each", 10000.0),
        ("fence RX-100 4 m", pytest.approx(120.0), "m", pytest.approx(600.0))]
    ditch = {it.quantity: it for it in bill.items if it.measure.startswith("ditch")}
    q = MEASURES[1].quantities(SECTION)
    assert ditch["excavation_m3"].count == pytest.approx(q["excavation_m3_per_m"] * 120)
    assert ditch["excavation_m3"].unit_price == pytest.approx(25.0)
    for it in bill.items:
        assert it.amount == pytest.approx(it.count * it.unit_price)
        assert it.source == "cost model unit_prices, catalogue prices.yaml"


class _Flat(CostModel):
    """A cost model written before bills: cost() only, a flat price per measure."""

    name: ClassVar[str] = "flat"
    Params: ClassVar[type[CostParams]] = CostParams

    def cost(self, measure: Any, quantities: dict[str, float], length_m: float) -> float:
        return 1234.5


class _Discount(UnitPrices):
    """Prices by bill, but 10 % off a measure of more than one quantity: not additive."""

    name: ClassVar[str] = "unit_prices"

    def price(self, measure, bill, quantities, length_m):
        whole = super().price(measure, bill, quantities, length_m)
        return whole * 0.9 if len(bill) > 1 else whole


@pytest.mark.parametrize("model", [_Flat(CostParams()),
                                   _Discount(UnitPricesParams.model_validate(PRICES))],
                         ids=["cost-only", "not-additive"])
def test_a_model_that_cannot_be_itemised_is_one_lump_sum_per_measure(registry, model):
    s = spec(model)
    bill = design_bill(registry, s, MEASURES, SECTION)
    assert bill.total == pytest.approx(design_cost(registry, s, MEASURES, SECTION))
    ditch = [it for it in bill.items if it.measure.startswith("ditch")]
    assert len(ditch) == 1 and ditch[0].unit == "lump sum"
    assert sum(it.amount for it in bill.items) == pytest.approx(bill.total)

"""Tests of the built-in cost model unit_prices: every formula by hand."""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import ValidationError
from rockfall_design_builtins.costs import UnitPrices, UnitPricesParams
from rockfall_design_builtins.measures import Berm, BoulderRow, Ditch, Fence, Wall

from rockfall_design import CostModel, ProtectiveMeasure
from rockfall_design.plugins import load_registry


class Straight:
    """A straight slope y = -x tan(30 deg), from x = 0 to 200 m."""

    x = np.array([0.0, 200.0])
    y = np.array([0.0, -200.0 * np.tan(np.radians(30.0))])

    def ground_height(self, x):
        return np.interp(x, self.x, self.y)


SECTION = Straight()

PRICES = {
    "currency": "CHF",
    "fixed_per_measure": 10000.0,
    "barrier_per_m": {
        "fence": {"RX-100": {3.0: 520.0, 4.0: 600.0}},
        "wall": {"gabion": {2: 900, 3: 1300}},
    },
    "excavation_per_m3": 25.0,
    "fill_per_m3": 18.0,
    "boulder_per_m3": 110.0,
    "other_per_m": {"catch_net": 75.0},
}


def model(**changes) -> UnitPrices:
    return UnitPrices(UnitPricesParams.model_validate({**PRICES, **changes}))


def cost(m: ProtectiveMeasure, length_m: float = 50.0, prices: UnitPrices | None = None) -> float:
    return (prices or model()).cost(m, m.quantities(SECTION), length_m)


def test_registered_through_the_entry_point():
    reg = load_registry()
    assert reg.cost_models["unit_prices"] is UnitPrices
    assert issubclass(UnitPrices, CostModel)
    assert reg.provider[("cost", "unit_prices")] == "rockfall-design"
    UnitPrices(UnitPrices.Params(**UnitPrices.example))


def test_fence_and_wall_by_product_and_height():
    fence = Fence(Fence.Params(x=70, height=4, capacity_kj=1000, product="RX-100"))
    assert cost(fence) == pytest.approx(10000 + 600 * 50)
    wall_params = dict(x=100, height=3, capacity_kj=2000)
    wall = Wall(Wall.Params(**wall_params))
    if "product" in Wall.Params.model_fields:
        wall = Wall(Wall.Params(**wall_params, product="gabion"))
        assert cost(wall, 20.0) == pytest.approx(10000 + 1300 * 20)
    else:  # the wall has no product: it cannot be priced by product
        with pytest.raises(KeyError, match="no product"):
            cost(wall)


def test_ditch_and_berm_by_volume():
    ditch = Ditch(Ditch.Params(x=100, width=10, depth=2))
    q = ditch.quantities(SECTION)
    assert q["excavation_m3_per_m"] > 0
    expected = 10000 + (q["excavation_m3_per_m"] * 25 + q["fill_m3_per_m"] * 18) * 40
    assert cost(ditch, 40.0) == pytest.approx(expected)
    berm = Berm(Berm.Params(x=100, width=8, cut_face_deg=60))
    q = berm.quantities(SECTION)
    # straight slope: area B H / 2 with H = B tan(b) / (1 - tan(b) / tan(phi))
    t = np.tan(np.radians(30.0))
    height = 8 * t / (1 - t / np.tan(np.radians(60.0)))
    assert q["excavation_m3_per_m"] == pytest.approx(8 * height / 2)
    assert cost(berm, 40.0) == pytest.approx(10000 + 8 * height / 2 * 25 * 40)


def test_boulder_row_by_block_volume():
    row = BoulderRow(BoulderRow.Params(x=130, block_size=1.5, gap_ratio=0.2, capacity_kj=300))
    # spacing 1.5 / 0.8 = 1.875 m: 1 / 1.875 blocks per m of 3.375 m3 each
    expected = 10000 + 1.5**3 * (1 / 1.875) * 30 * 110
    assert cost(row, 30.0) == pytest.approx(expected)


class CatchNet(ProtectiveMeasure):
    kind = "catch_net"
    Params = Fence.Params
    example = Fence.example

    def footprint(self, section):  # pragma: no cover - not needed here
        raise NotImplementedError

    def design_properties(self):
        return {}

    def quantities(self, section):
        return {}


def test_other_kinds_per_metre():
    net = CatchNet(CatchNet.Params(x=1, height=2, capacity_kj=100))
    assert cost(net, 12.0) == pytest.approx(10000 + 75 * 12)
    with pytest.raises(KeyError, match="no price for measure type 'catch_net'.*other_per_m"):
        cost(net, prices=model(other_per_m={}))


@pytest.mark.parametrize(
    ("fence", "prices", "fragment"),
    [
        ({"product": None}, {}, "has no product"),
        ({"product": "RX-999"}, {}, "no price for fence product 'RX-999'"),
        ({"height": 5.0}, {}, "at height 5 m (priced heights: 3, 4 m)"),
        ({}, {"barrier_per_m": {}}, "no price for measure type 'fence' (quantity 'fence'"),
    ],
)
def test_missing_barrier_price_is_a_key_error(fence, prices, fragment):
    params = {"x": 70, "height": 4, "capacity_kj": 1000, "product": "RX-100", **fence}
    m = Fence(Fence.Params(**params))
    with pytest.raises(KeyError) as info:
        cost(m, prices=model(**prices))
    assert fragment in info.value.args[0]


@pytest.mark.parametrize(
    "changes",
    [
        {"fixed_per_measure": -1},
        {"excavation_per_m3": float("nan")},
        {"barrier_per_m": {"fence": {"RX-100": {-3: 10}}}},
        {"barrier_per_m": {"fence": {"RX-100": {3: -10}}}},
        {"other_per_m": {"x": -1}},
        {"unknown": 1},
    ],
)
def test_params_are_strict(changes):
    with pytest.raises(ValidationError):
        UnitPricesParams.model_validate({**PRICES, **changes})


def test_defaults():
    p = UnitPricesParams(fixed_per_measure=0, excavation_per_m3=1, boulder_per_m3=2)
    assert (p.currency, p.fill_per_m3, p.barrier_per_m, p.other_per_m) == ("EUR", 0.0, {}, {})

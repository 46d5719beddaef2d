"""The plugin contract's design additions: design roles in Field metadata, bills, prices."""

from __future__ import annotations

import math
import types
from typing import Literal

import pytest
from pydantic import Field
from rockfall_design_builtins.costs import UnitPrices, UnitPricesParams
from rockfall_design_builtins.measures import Ditch, Fence

from rockfall_design import (
    Barrier,
    BarrierBehaviour,
    MeasureParams,
    ProtectiveMeasure,
    Quantity,
    hookimpl,
)
from rockfall_design.errors import PluginError
from rockfall_design.judge.candidates import build_candidate_measure
from rockfall_design.judge.design_spec import declared_design, resolve_design
from rockfall_design.optimiser.space import decode, discrete_choices, variables_of
from rockfall_design.plugins import call_plugin, load_registry
from rockfall_design.plugins.measure import DesignRole, design_role
from rockfall_design.project import load_project_text

from ..project.test_project import EXAMPLE


class _Params(MeasureParams):
    span: float = Field(2.0, json_schema_extra={"design": {"bounds": [1, 4]}})
    mesh: Literal["ring", "cable"] = Field("ring", json_schema_extra={"design": "options"})
    posts: int = Field(3, json_schema_extra={"design": {"options": [2, 3, 4]}})
    plain: float = 1.0


def test_design_role_vocabulary():
    assert design_role(_Params, "span") == DesignRole("range", bounds=(1.0, 4.0))
    assert design_role(_Params, "mesh") == DesignRole("options", options=("ring", "cable"))
    assert design_role(_Params, "posts") == DesignRole("options", options=(2, 3, 4))
    assert design_role(_Params, "plain") is None
    assert design_role(Fence.Params, "product") == DesignRole("catalogue")
    assert design_role(Fence.Params, "height") == DesignRole("catalogue_height")
    assert design_role(Ditch.Params, "width") == DesignRole("range", bounds=(2.0, 20.0))


@pytest.mark.parametrize(("extra", "fragment"), [
    ({"design": "catalog"}, "expected {'bounds'"),
    ({"design": {"bounds": [3, 1]}}, "low < high"),
    ({"design": {"bounds": "wide"}}, "bounds must be [low, high]"),
    ({"design": {"options": []}}, "non-empty list"),
    ({"design": "options"}, "not a Literal"),
])
def test_a_malformed_declaration_leaves_the_class_out_naming_it(extra, fragment):
    class BadParams(MeasureParams):
        height: float = Field(1.0, json_schema_extra=extra)

    class Bad(ProtectiveMeasure):
        kind = "bad_net"
        Params = BadParams
        example = {"x": 1.0}

        def footprint(self, section):
            raise AssertionError

        def design_properties(self):
            return {}

    with pytest.raises(ValueError, match=fragment.replace("[", r"\[").replace("{", r"\{")):
        design_role(BadParams, "height")
    module = types.SimpleNamespace(rockfall_design_measures=hookimpl(lambda: [Bad]))
    registry = load_registry(extra_plugins=[("bad", module)], entry_points=[])
    assert "bad_net" not in registry.measures
    (failure,) = registry.failures
    assert "height" in failure.reason and fragment in failure.reason


# A barrier whose catalogue roles are declared on fields of its own names.
class NamedParams(MeasureParams):
    net_product: str = Field("A", json_schema_extra={"design": "catalogue"})
    net_height: float = Field(2.0, gt=0, json_schema_extra={"design": "catalogue_height"})
    energy: float = Field(100.0, gt=0, json_schema_extra={"design": "catalogue_capacity"})
    height: float = Field(1.0, gt=0, json_schema_extra={"design": {"bounds": [0.5, 1.5]}})


class Named(ProtectiveMeasure):
    kind = "named_net"
    Params = NamedParams
    example = {"x": 60.0}

    def footprint(self, section):
        p = self.params
        return Barrier(x=p.x, height_m=p.net_height, capacity_kj=p.energy,
                       behaviour=BarrierBehaviour.NET)

    def design_properties(self):
        return {"height_m": self.params.net_height, "capacity_kj": self.params.energy}


def test_catalogue_roles_on_fields_of_any_name():
    d = declared_design(Named)
    assert (d.product, d.height, d.capacity) == ("net_product", "net_height", "energy")
    assert d.ranges == {"height": (0.5, 1.5)}  # a field named height, free here
    module = types.SimpleNamespace(rockfall_design_measures=hookimpl(lambda: [Named]))
    registry = load_registry(extra_plugins=[("named", module)])
    text = EXAMPLE + (
        "design:\n  site: {length_m: 10}\n"
        "  products: {named_net: {A: {capacity_kj: 500, heights: [2, 3]},"
        " B: {capacity_kj: 900, heights: [4]}}}\n"
        "  costs: {params: {fixed_per_measure: 0, excavation_per_m3: 1, boulder_per_m3: 1,"
        " barrier_per_m: {named_net: {A: {2: 10, 3: 12}, B: {4: 20}}}}}\n"
        "  candidates: [{type: named_net, x: [60, 70], net_product: {options: [A, B]}}]\n"
    )
    spec = resolve_design(load_project_text(text), registry)
    (c,) = spec.candidates
    assert [p.name for p in c.products] == ["A", "B"] and c.ranges == {"height": (0.5, 1.5)}
    choices = discrete_choices(c)
    assert {(ch["net_product"], ch["net_height"]) for ch in choices} == {
        ("A", 2.0), ("A", 3.0), ("B", 4.0)}
    variables = variables_of(spec.candidates, (0,))
    assert [(v.name, v.role) for v in variables] == [
        ("x", "x"), ("net_product", "product"), ("net_height", "height"), ("height", "range")]
    ((_, params),) = decode(spec.candidates, (0,), variables, [61.0, 1, 0, 1.0])
    assert params == {"x": 61.0, "net_product": "B", "net_height": 4.0, "height": 1.0}
    m = build_candidate_measure(c, registry, params)
    assert (m.params.energy, m.params.net_height, m.params.height) == (900.0, 4.0, 1.0)
    with pytest.raises(Exception, match="do not give net_height"):
        resolve_design(load_project_text(text.replace("net_product: {options: [A, B]}",
                                                      "net_height: 2")), registry)


class Priced(ProtectiveMeasure):
    kind = "priced"
    Params = NamedParams
    example = {"x": 60.0}
    default_prices = {"mesh_m2": 30.0, "anchor": {"A": {2.0: 100.0}}}

    def footprint(self, section):
        raise AssertionError

    def design_properties(self):
        return {}

    def bill(self, section):
        return [Quantity("mesh_m2", 2.0, "m2"),
                Quantity("anchor", 0.5, "piece", product="A", size=2.0)]


def _prices(**changes) -> UnitPrices:
    base = {"fixed_per_measure": 1000.0, "excavation_per_m3": 10.0, "boulder_per_m3": 5.0}
    return UnitPrices(UnitPricesParams.model_validate({**base, **changes}))


def test_unit_prices_by_name_catalogue_before_the_plugins_defaults():
    m = Priced(NamedParams(x=1.0))
    bill = m.bill(None)
    assert _prices().price(m, bill, {}, 10.0) == pytest.approx(1000 + 10 * (2 * 30 + 0.5 * 100))
    over = _prices(prices={"mesh_m2": 20.0, "anchor": {"A": {2: 80.0}}})
    assert over.price(m, bill, {}, 10.0) == pytest.approx(1000 + 10 * (2 * 20 + 0.5 * 80))
    assert _prices().missing_price(m, bill) is None
    bare = Quantity("paint_m2", 1.0, "m2")
    assert "no price for quantity 'paint_m2' (m2" in _prices().missing_price(m, [bare])
    with pytest.raises(KeyError, match="quantity 'paint_m2'"):
        _prices().price(m, [bare], {}, 10.0)
    with pytest.raises(KeyError, match="at height 3 m"):
        _prices().price(m, [Quantity("anchor", 1.0, "piece", product="A", size=3.0)], {}, 1.0)


def test_the_built_ins_bill_named_quantities():
    fence = Fence(Fence.Params(x=70, height=4, capacity_kj=1000, product="RX-100"))
    assert fence.bill(None) == [Quantity("fence", 1.0, "m", product="RX-100", size=4.0)]
    section = types.SimpleNamespace(x=[0.0, 100.0], y=[50.0, 0.0])
    ditch = Ditch(Ditch.Params(x=40, width=10, depth=2))
    q = ditch.quantities(section)
    assert ditch.bill(section) == [Quantity("excavation_m3", q["excavation_m3_per_m"], "m3"),
                                   Quantity("fill_m3", q["fill_m3_per_m"], "m3")]


@pytest.mark.parametrize("bill", [
    {"a": 1.0},
    [Quantity("a", math.nan, "m")],
    [Quantity("a", -1.0, "m")],
    [Quantity("", 1.0, "m")],
    [("a", 1.0, "m")],
])
def test_a_bad_bill_is_a_plugin_fault(bill):
    class Bad(Priced):
        kind = "bad_bill"

        def bill(self, section):
            return bill

    module = types.SimpleNamespace(rockfall_design_measures=hookimpl(lambda: [Bad]))
    registry = load_registry(extra_plugins=[("badbill", module)], entry_points=[])
    with pytest.raises(PluginError, match="bill\\(\\) returned .* expected a list of Quantity"):
        call_plugin(registry, Bad(NamedParams(x=1.0)), "bill", None)

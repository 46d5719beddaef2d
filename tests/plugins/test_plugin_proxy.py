"""The typed proxy (rockfall_design.plugins.proxy) keeps every guarantee of call_plugin.

A measure, a safety concept and a cost model defined inline, each of whose
methods misbehaves as the test asks: the proxy contains what the plugin
raises (BaseException included) as one PluginError naming the class's name,
its provider and the method; lets the contract's own exceptions through;
and rejects results the contract does not allow.
"""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import BaseModel

from rockfall_design import (
    Barrier,
    BarrierBehaviour,
    Check,
    CostModel,
    CostParams,
    MeasureParams,
    ProtectiveMeasure,
    SafetyConcept,
    SafetyParams,
    hookimpl,
)
from rockfall_design.engine import Material, Section
from rockfall_design.errors import PluginError
from rockfall_design.plugins import (
    GuardedMeasure,
    call_plugin,
    guard,
    load_registry,
)

# What the next call of each method does: return normally unless told otherwise.
BEHAVIOUR: dict[str, object] = {}


def _act(method: str, normal: object) -> object:
    what = BEHAVIOUR.get(method)
    if isinstance(what, BaseException):
        raise what
    return normal if what is None else what


class ProxyNetParams(MeasureParams):
    height_m: float = 3.0


class ProxyNet(ProtectiveMeasure):
    kind = "proxy_net"
    summary = "A net whose methods misbehave on request"
    Params = ProxyNetParams
    example = {"x": 50.0}

    def footprint(self, section):
        return _act("footprint", Barrier(x=self.params.x, height_m=self.params.height_m,
                                         capacity_kj=500.0, behaviour=BarrierBehaviour.NET))

    def design_properties(self):
        return _act("design_properties", {"height_m": self.params.height_m})

    def quantities(self, section):
        return _act("quantities", {"length_m": 1.0})

    def label(self):
        return _act("label", "proxy net")


class ProxyConcept(SafetyConcept):
    name = "proxy_concept"
    summary = "A concept whose checks misbehave on request"
    Params = SafetyParams
    example = {}

    def checks(self, result):
        return _act("checks", [Check(name="x", value=1.0, target=1.0, ok=True)])


class ProxyCost(CostModel):
    name = "proxy_cost"
    summary = "A cost model whose cost misbehaves on request"
    Params = CostParams
    example = {}

    def cost(self, measure, quantities, length_m):
        return _act("cost", 10.0)


class _Plugin:
    @hookimpl
    def rockfall_design_measures(self):
        return [ProxyNet]

    @hookimpl
    def rockfall_design_safety_concepts(self):
        return [ProxyConcept]

    @hookimpl
    def rockfall_design_cost_models(self):
        return [ProxyCost]


@pytest.fixture()
def reg():
    BEHAVIOUR.clear()
    yield load_registry(entry_points=[], extra_plugins=[("proxytest", _Plugin())])
    BEHAVIOUR.clear()


SECTION = Section(np.array([0.0, 100.0]), np.array([50.0, 0.0]), np.array([0]), (Material(),))


def _objects(reg):
    g = guard(reg)
    net = g.instantiate(reg.measure("proxy_net"), ProxyNetParams(x=50.0))
    concept = g.instantiate(reg.safety_concept("proxy_concept"), SafetyParams())
    model = g.instantiate(reg.cost_model("proxy_cost"), CostParams())
    return g, net, concept, model


def test_the_proxy_returns_what_the_plugin_returns(reg):
    g, net, concept, model = _objects(reg)
    m = g.measure(net)
    assert isinstance(m, GuardedMeasure)
    assert m.footprint(SECTION).height_m == 3.0
    assert m.design_properties() == {"height_m": 3.0}
    assert m.quantities(SECTION) == {"length_m": 1.0}
    assert m.label() == "proxy net"
    assert g.concept(concept).checks(None)[0].ok
    assert g.cost_model(model).cost(net, {"length_m": 1.0}, 1.0) == 10.0
    # The same as call_plugin with method names, which stays for older code.
    assert call_plugin(reg, net, "label") == m.label()


@pytest.mark.parametrize("exc", [RuntimeError("boom"), SystemExit(2), KeyboardInterrupt(),
                                 ZeroDivisionError()])
@pytest.mark.parametrize("method", ["footprint", "design_properties", "quantities", "label"])
def test_a_measure_fault_is_one_plugin_error_naming_kind_provider_and_method(reg, method, exc):
    g, net, _, _ = _objects(reg)
    BEHAVIOUR[method] = exc
    call = getattr(g.measure(net), method)
    with pytest.raises(PluginError) as info:
        call(SECTION) if method in ("footprint", "quantities") else call()
    msg = str(info.value)
    assert "measure 'proxy_net' (from proxytest)" in msg
    assert f"failed in {method}()" in msg
    assert type(exc).__name__ in msg
    assert "\n" not in msg


def test_the_contract_exceptions_pass_through(reg):
    g, net, _, model = _objects(reg)
    BEHAVIOUR["footprint"] = ValueError("does not fit")
    with pytest.raises(ValueError, match="does not fit"):
        g.measure(net).footprint(SECTION)
    for exc in (KeyError("no price"), ValueError("no price")):
        BEHAVIOUR["cost"] = exc
        with pytest.raises(type(exc)):
            g.cost_model(model).cost(net, {}, 1.0)


@pytest.mark.parametrize(("method", "bad", "expected"), [
    ("footprint", "a fence", "expected a Barrier or a ProfileEdit"),
    ("footprint", Barrier(x=50.0, height_m=float("nan"), capacity_kj=1.0,
                          behaviour=BarrierBehaviour.NET), "height_m = nan"),
    ("design_properties", {"h": float("nan")}, "expected a dict of str to number"),
    ("label", 3, "expected a str"),
    ("checks", ["ok"], "expected a list of Check"),
    ("cost", -1.0, "expected a finite number >= 0"),
])
def test_results_outside_the_contract_are_plugin_errors(reg, method, bad, expected):
    g, net, concept, model = _objects(reg)
    BEHAVIOUR[method] = bad
    calls = {
        "footprint": lambda: g.measure(net).footprint(SECTION),
        "design_properties": lambda: g.measure(net).design_properties(),
        "label": lambda: g.measure(net).label(),
        "checks": lambda: g.concept(concept).checks(None),
        "cost": lambda: g.cost_model(model).cost(net, {}, 1.0),
    }
    with pytest.raises(PluginError, match=expected) as info:
        calls[method]()
    assert f"{method}() returned" in str(info.value)


def test_instantiating_a_class_is_guarded_too(reg):
    class Broken(BaseModel):
        pass

    g = guard(reg)
    with pytest.raises(PluginError, match=r"measure 'proxy_net' .*failed in __init__\(\)"):
        g.instantiate(reg.measure("proxy_net"), Broken(), "one argument too many")

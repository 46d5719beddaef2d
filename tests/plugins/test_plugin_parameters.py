"""``plugins --json`` describes every parameter: type, unit, default, bounds, options.

Test plugins are written inline as real distributions (see
``plugin_helpers.write_distribution``), the way a third party ships one.
"""

from __future__ import annotations

import json
import sys

import pytest
from pydantic import BaseModel

from rockfall_design.cli.program import main
from rockfall_design.plugins import load_registry, plugins_json
from rockfall_design.plugins.parameters import describe_parameters, unit_from_description

from ..plugin_helpers import write_distribution

# Written as a plugin author following the README (units in the trailing
# parentheses of descriptions) and the newer way (units in Field metadata).
UNITS_PLUGIN = '''
    from typing import Literal

    from pydantic import Field

    from rockfall_design import (
        Barrier,
        BarrierBehaviour,
        MeasureParams,
        ProtectiveMeasure,
        hookimpl,
    )


    class CatchNetParams(MeasureParams):
        height: float = Field(gt=0, le=3, description="height of the net above ground (m)")
        capacity_kj: float = Field(250.0, gt=0, json_schema_extra={"unit": "kJ"},
                                   description="energy the net absorbs")
        price_per_m: float = Field(350.0, ge=0, description="price per running metre")
        damping: float = Field(0.3, ge=0, lt=1, description="damping ratio (-).")
        mesh: Literal["ring", "cable"] = Field("ring", json_schema_extra={"unit": None})
        reserve_kj: float = float("inf")
        "Reserve of the brake rings (kJ)."


    class CatchNet(ProtectiveMeasure):
        kind = "catch_net"
        summary = "low flexible catch net"
        Params = CatchNetParams
        example = {"x": 100.0, "height": 2.0}
        design_variables = {"x": (float("nan"), float("nan")), "height": (0.5, 3.0)}

        def footprint(self, section):
            return Barrier(x=self.params.x, height_m=self.params.height,
                           capacity_kj=self.params.capacity_kj, behaviour=BarrierBehaviour.NET)

        def design_properties(self):
            return {"height_m": self.params.height, "capacity_kj": self.params.capacity_kj}


    @hookimpl
    def rockfall_design_measures():
        return [CatchNet]
'''


@pytest.fixture
def units_plugin(tmp_path, monkeypatch):
    write_distribution(tmp_path, "units_rockfall", UNITS_PLUGIN, "units", version="2.5")
    monkeypatch.syspath_prepend(str(tmp_path))
    yield
    sys.modules.pop("units_rockfall", None)


def test_third_party_parameters_listed_with_units_and_defaults(units_plugin, capsys):
    assert main(["plugins", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)  # one JSON document
    net = next(m for m in data["measures"] if m["kind"] == "catch_net")
    assert (net["distribution"], net["version"], net["plugin"]) == ("units-rockfall", "2.5",
                                                                   "units")
    params = {p["name"]: p for p in net["parameters"]}
    assert list(params) == ["x", "height", "capacity_kj", "price_per_m", "damping", "mesh",
                            "reserve_kj"]
    assert params["x"]["unit"] == "m" and params["x"]["required"] is True
    height = params["height"]
    assert (height["unit"], height["required"], height["default"]) == ("m", True, None)
    assert (height["exclusive_minimum"], height["maximum"]) == (0, 3)
    assert height["description"] == "height of the net above ground (m)"
    assert (params["capacity_kj"]["unit"], params["capacity_kj"]["default"]) == ("kJ", 250.0)
    assert params["price_per_m"]["unit"] is None  # no trailing parentheses
    assert params["damping"]["unit"] == "-"
    assert (params["damping"]["minimum"], params["damping"]["exclusive_maximum"]) == (0, 1)
    mesh = params["mesh"]
    assert (mesh["type"], mesh["options"], mesh["default"], mesh["unit"]) == (
        "string", ["ring", "cable"], "ring", None)
    reserve = params["reserve_kj"]  # unit from the attribute docstring, inf as a string
    assert (reserve["unit"], reserve["default"]) == ("kJ", "inf")
    assert net["design_variables"] == [{"name": "x", "low": None, "high": None},
                                       {"name": "height", "low": 0.5, "high": 3.0}]


def test_human_table_shows_units(units_plugin, capsys):
    assert main(["plugins"]) == 0
    out = capsys.readouterr().out
    assert "catch_net" in out and "height (m)" in out


def test_every_builtin_parameter_documents_its_unit():
    """Each field of a built-in Params says its unit, or says explicitly that it has none."""
    registry = load_registry()
    data = plugins_json(registry)
    seen = 0
    for section in ("measures", "safety_concepts", "cost_models"):
        for name, cls in getattr(registry, section).items():
            if registry.provider[({"measures": "measure", "safety_concepts": "safety",
                                   "cost_models": "cost"}[section], name)] != "rockfall-design":
                continue
            for field_name, info in cls.Params.model_fields.items():
                extra = info.json_schema_extra
                assert isinstance(extra, dict) and "unit" in extra, (name, field_name)
                assert extra["unit"] is None or isinstance(extra["unit"], str)
                seen += 1
        for entry in data[section]:
            for p in entry["parameters"]:
                assert set(p) >= {"name", "type", "unit", "default", "required", "minimum",
                                  "maximum", "options", "description"}
    assert seen > 30
    fence = next(m for m in data["measures"] if m["kind"] == "fence")
    assert {p["name"]: p["unit"] for p in fence["parameters"]} == {
        "x": "m", "height": "m", "capacity_kj": "kJ", "product": None,
        "max_elongation_m": "m", "residual_height_fraction": "-", "sel_kj": "kJ",
        "elongation_sel_m": "m"}
    assert {v["name"] for v in fence["design_variables"]} >= {"x", "height"}


@pytest.mark.parametrize(("text", "unit"), [
    ("height of the net above ground (m)", "m"),
    ("Partial factor (-).", "-"),
    ("Price per kJ of capacity per running metre (currency/(kJ m)).", "currency/(kJ m)"),
    ("price per running metre", None),
    ("Energy capacity (kJ): its class.", None),
    ("Currency of every price (e.g. EUR).", None),
    ("", None),
    (None, None),
])
def test_unit_from_description(text, unit):
    assert unit_from_description(text) == unit


def test_describe_parameters_of_a_model_without_descriptions():
    class P(BaseModel):
        n: int = 3
        names: list[str] = []
        maybe: float | None = None

    described = {p["name"]: p for p in describe_parameters(P)}
    assert described["n"]["type"] == "integer" and described["n"]["default"] == 3
    assert described["names"]["type"] == "array" and described["names"]["default"] == []
    assert described["maybe"]["type"] == "number | null"
    assert all(p["unit"] is None and p["description"] is None for p in described.values())
    json.dumps(list(described.values()), allow_nan=False)

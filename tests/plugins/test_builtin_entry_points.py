"""Each built-in has an entry point of its own: it can be listed, blocked or replaced alone."""

from __future__ import annotations

import importlib
import json
from importlib.metadata import entry_points
from pathlib import Path

import pytest

from rockfall_design import ProtectiveMeasure, hookimpl
from rockfall_design.cli.program import main
from rockfall_design.plugins import load_registry

ROOT = Path(__file__).resolve().parents[2]

MEASURES = ("berm", "boulder_row", "ditch", "fence", "protection_forest", "wall")
CONCEPTS = ("onr24810", "reliability", "spang", "uni11211")
COST_MODELS = ("unit_prices",)


def test_every_builtin_comes_from_its_own_entry_point():
    reg = load_registry()
    for key, names in (("measure", MEASURES), ("safety", CONCEPTS), ("cost", COST_MODELS)):
        for name in names:
            origin = reg.origins[(key, name)]
            assert origin.plugin == name
            assert origin.distribution == "rockfall-design"
    assert not [f for f in reg.failures if f.distribution == "rockfall-design"]


#: Each built-in's module: its entry point names it, and it registers that class alone.
MODULES = {
    **{m: f"rockfall_design_builtins.measures.{m}" for m in MEASURES},
    **{c: f"rockfall_design_builtins.safety.{c}" for c in CONCEPTS},
    "unit_prices": "rockfall_design_builtins.costs.unit_prices",
}
HOOKS = {"measure": ("rockfall_design_measures", "kind"),
         "safety": ("rockfall_design_safety_concepts", "name"),
         "cost": ("rockfall_design_cost_models", "name")}


def test_each_entry_point_is_a_module_that_registers_one_class():
    ours = {ep.name: ep for ep in entry_points(group="rockfall_design")
            if ep.dist is not None and ep.dist.name == "rockfall-design"}
    assert {name: ep.value for name, ep in ours.items()} == MODULES
    for key, names in (("measure", MEASURES), ("safety", CONCEPTS), ("cost", COST_MODELS)):
        hook, attr = HOOKS[key]
        for name in names:
            module = importlib.import_module(MODULES[name])
            classes = getattr(module, hook)()
            assert [getattr(c, attr) for c in classes] == [name]
            # No other registration hook in the module: one built-in per module.
            others = {h for h, _ in HOOKS.values()} - {hook}
            assert not [h for h in others if hasattr(module, h)]


def test_no_metaprogram_registers_the_builtins():
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module("rockfall_design_builtins.entry_points")


@pytest.mark.parametrize("blocked", ["fence", "ditch", "uni11211", "onr24810", "reliability",
                                     "unit_prices"])
def test_blocking_one_builtin_leaves_the_others(blocked):
    reg = load_registry(blocked=[blocked])
    every = {**reg.measures, **reg.safety_concepts, **reg.cost_models}
    assert blocked not in every
    assert set(MEASURES + CONCEPTS + COST_MODELS) - {blocked} <= set(every)
    assert reg.blocked == [blocked]


def test_blocking_the_distribution_still_blocks_every_builtin():
    reg = load_registry(blocked=["rockfall-design"])
    assert not set(MEASURES) & set(reg.measures)
    assert not set(CONCEPTS) & set(reg.safety_concepts)


def test_a_third_party_replaces_one_builtin_alone():
    builtin = load_registry().measures["fence"]

    class OtherFence(builtin):  # same parameters, another provider
        summary = "a third party's fence"

    class Plugin:
        @hookimpl
        def rockfall_design_measures(self) -> list[type[ProtectiveMeasure]]:
            return [OtherFence]

    # Without blocking the built-in, two fences are an error naming both...
    from rockfall_design.errors import PluginError

    with pytest.raises(PluginError, match="'fence' is provided by both"):
        load_registry(extra_plugins=[("otherfence", Plugin())])
    # ...blocking it lets the third party's take its place; the wall stays built-in.
    reg = load_registry(blocked=["fence"], extra_plugins=[("otherfence", Plugin())])
    assert reg.measures["fence"] is OtherFence
    assert reg.origins[("measure", "wall")].plugin == "wall"


def test_plugins_lists_each_builtin_and_block_by_name(capsys):
    assert main(["plugins", "--json", "--block", "fence"]) == 0
    out = json.loads(capsys.readouterr().out)
    kinds = {m["kind"]: m for m in out["measures"]}
    assert "fence" not in kinds
    assert kinds["wall"]["plugin"] == "wall"
    assert out["blocked"] == ["fence"]
    assert {c["name"]: c["plugin"] for c in out["safety_concepts"]}["spang"] == "spang"


def test_a_project_whose_measure_is_blocked_says_so_in_one_line(capsys):
    project = ROOT / "projects" / "quarry_fence_ditch.yaml"
    code = main(["check", str(project), "--rocks", "20", "--block", "fence"])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1
    assert "'fence'" in err and "quarry_fence_ditch.yaml" in err

"""The plugin manager: real entry points, guarded loading, duplicates, blocking, CLI.

Every test builds a fresh registry; test plugins are defined inline, either
as objects passed through ``extra_plugins`` or as real distributions written
into a temporary directory (see ``plugin_helpers.write_distribution``).
"""

from __future__ import annotations

import inspect
import json
import re
import sys
import textwrap
import types
from importlib.metadata import EntryPoint

import pytest

import rockfall_design.plugins.hookspecs as hookspecs
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
from rockfall_design.cli.program import main
from rockfall_design.errors import ExitCode, PluginError
from rockfall_design.plugins import (
    PluginFailure,
    Registry,
    default_registry,
    load_registry,
    plugins_json,
)
from rockfall_design.report.terminal import plugins_table

from ..plugin_helpers import write_distribution

THIRD_PARTY = '''
    """A third-party plugin that uses only the public rockfall_design API."""

    from rockfall_design import (
        Barrier,
        BarrierBehaviour,
        MeasureParams,
        ProtectiveMeasure,
        hookimpl,
    )


    class NetParams(MeasureParams):
        height_m: float = 3.0
        capacity_kj: float = 500.0


    class TestNet(ProtectiveMeasure):
        kind = "test_net"
        summary = "A test net barrier"
        Params = NetParams
        example = {"x": 50.0, "height_m": 3.0, "capacity_kj": 500.0}
        design_variables = {"x": (10.0, 100.0), "height_m": (1.0, 6.0)}

        def footprint(self, section):
            p = self.params
            return Barrier(x=p.x, height_m=p.height_m, capacity_kj=p.capacity_kj,
                           behaviour=BarrierBehaviour.NET)

        def design_properties(self):
            return {"height_m": self.params.height_m, "capacity_kj": self.params.capacity_kj}


    @hookimpl
    def rockfall_design_measures():
        return [TestNet]
'''

BROKEN = '''
    raise ImportError("boom")
'''

# Modules the tests write; removed from sys.modules after each test so that
# the next test imports its own copy from its own tmp_path.
_TEST_MODULES = ("thirdparty_rockfall", "broken_rockfall", "rival_rockfall")


@pytest.fixture(autouse=True)
def _forget_test_modules():
    yield
    for name in _TEST_MODULES:
        sys.modules.pop(name, None)


@pytest.fixture
def baseline() -> Registry:
    """The registry of whatever is installed, before the test's distributions."""
    return load_registry()


@pytest.fixture
def third_party(tmp_path, monkeypatch, baseline):
    """A working and a broken third-party distribution, found via real entry points."""
    write_distribution(tmp_path, "thirdparty_rockfall", THIRD_PARTY, "third")
    write_distribution(tmp_path, "broken_rockfall", BROKEN, "broken")
    monkeypatch.syspath_prepend(str(tmp_path))
    return tmp_path


def make_measure(kind: str, **attrs) -> type[ProtectiveMeasure]:
    """A valid barrier class of ``kind``; ``attrs`` override class attributes."""

    class Params(MeasureParams):
        height_m: float = 2.0

    def footprint(self, section):
        return Barrier(x=self.params.x, height_m=self.params.height_m,
                       capacity_kj=float("inf"), behaviour=BarrierBehaviour.RIGID)

    def design_properties(self):
        return {"height_m": self.params.height_m}

    namespace = {
        "kind": kind,
        "summary": f"{kind} for tests",
        "Params": Params,
        "example": {"x": 10.0, "height_m": 2.0},
        "footprint": footprint,
        "design_properties": design_properties,
        **attrs,
    }
    return type(f"M_{kind}", (ProtectiveMeasure,), namespace)


def plugin_returning(*classes) -> object:
    """A plugin object whose ``rockfall_design_measures`` returns ``classes``."""

    class Plugin:
        @hookimpl
        def rockfall_design_measures(self):
            return list(classes)

    return Plugin()


def failure_of(registry: Registry, plugin: str) -> PluginFailure:
    matches = [f for f in registry.failures if f.plugin == plugin]
    assert matches, f"no failure for {plugin!r} in {registry.failures}"
    return matches[0]


# ---------------------------------------------------------------------------
# real entry points


def test_real_entry_point_is_found_and_a_broken_one_is_reported(third_party, baseline):
    reg = load_registry()

    cls = reg.measure("test_net")
    assert reg.provider[("measure", "test_net")] == "thirdparty-rockfall"
    net = cls(cls.Params(**cls.example))
    fp = net.footprint(None)
    assert fp == Barrier(x=50.0, height_m=3.0, capacity_kj=500.0,
                         behaviour=BarrierBehaviour.NET)
    assert net.design_properties() == {"height_m": 3.0, "capacity_kj": 500.0}

    broken = failure_of(reg, "broken")
    assert broken.distribution == "broken-rockfall"
    assert "boom" in broken.reason and "ImportError" in broken.reason
    assert "\n" not in broken.reason

    # whatever was registered before (the built-ins, once installed) is unaffected
    for section in ("measures", "safety_concepts", "cost_models"):
        before, after = getattr(baseline, section), getattr(reg, section)
        assert before.items() <= after.items()
    assert baseline.provider.items() <= reg.provider.items()
    assert set(baseline.failures) <= set(reg.failures)
    assert set(reg.measures) == set(baseline.measures) | {"test_net"}


def test_entry_points_can_be_given_explicitly(third_party):
    ep = EntryPoint(name="third", value="thirdparty_rockfall", group="rockfall_design")
    reg = load_registry(entry_points=[ep])
    assert list(reg.measures) == ["test_net"]
    # no distribution known: the plugin name stands in as provider
    assert reg.provider[("measure", "test_net")] == "third"
    assert reg.failures == []


def test_entry_point_to_a_missing_module_is_a_failure():
    ep = EntryPoint(name="ghost", value="no_such_module_xyz", group="rockfall_design")
    reg = load_registry(entry_points=[ep])
    assert "no_such_module_xyz" in failure_of(reg, "ghost").reason
    assert reg.measures == {}


# ---------------------------------------------------------------------------
# duplicates and blocking


def test_duplicate_kind_from_two_plugins_names_both(third_party):
    rival = THIRD_PARTY.replace("A test net barrier", "A rival net")
    write_distribution(third_party, "rival_rockfall", rival, "rival")
    with pytest.raises(PluginError) as info:
        load_registry()
    msg = str(info.value)
    assert "'test_net'" in msg
    assert "thirdparty-rockfall" in msg and "rival-rockfall" in msg
    assert "third" in msg and "rival" in msg and "\n" not in msg
    assert info.value.exit_code == ExitCode.PLUGIN_FAULT


def test_duplicates_do_not_depend_on_registration_order():
    a, b = make_measure("wall"), make_measure("wall")
    for order in ([("a", plugin_returning(a)), ("b", plugin_returning(b))],
                  [("b", plugin_returning(b)), ("a", plugin_returning(a))]):
        with pytest.raises(PluginError) as info:
            load_registry(entry_points=[], extra_plugins=order)
        assert str(info.value).startswith(
            "measure kind 'wall' is provided by both a (class M_wall) and b (class M_wall)")


def test_duplicate_safety_concept_and_cost_model_are_errors_too():
    class Concept(SafetyConcept):
        name = "simple"
        Params = SafetyParams

        def checks(self, result):
            return []

    class Cost(CostModel):
        name = "flat"
        Params = CostParams

        def cost(self, measure, quantities, length_m):
            return 0.0

    class One:
        @hookimpl
        def rockfall_design_safety_concepts(self):
            return [Concept]

        @hookimpl
        def rockfall_design_cost_models(self):
            return [Cost]

    class Two:
        @hookimpl
        def rockfall_design_safety_concepts(self):
            return [Concept]

        @hookimpl
        def rockfall_design_cost_models(self):
            return [Cost]

    with pytest.raises(PluginError) as info:
        load_registry(entry_points=[], extra_plugins=[("one", One()), ("two", Two())])
    msg = str(info.value)
    assert "safety concept 'simple'" in msg and "cost model 'flat'" in msg
    reg = load_registry(entry_points=[], extra_plugins=[("one", One())])
    assert reg.safety_concept("simple") is Concept and reg.cost_model("flat") is Cost
    assert reg.provider[("safety", "simple")] == reg.provider[("cost", "flat")] == "one"


def test_nan_design_variable_bounds_mean_the_project_gives_them():
    m = make_measure("fence", design_variables={"x": (float("nan"), float("nan"))})
    reg = load_registry(entry_points=[], extra_plugins=[("p", plugin_returning(m))])
    assert reg.failures == [] and reg.measures == {"fence": m}


def test_the_same_class_twice_from_one_plugin_is_not_a_duplicate():
    m = make_measure("fence")
    reg = load_registry(entry_points=[], extra_plugins=[("p", plugin_returning(m, m))])
    assert reg.measures == {"fence": m}


def test_blocking_by_entry_point_name_removes_it_and_lists_it(third_party):
    write_distribution(third_party, "rival_rockfall", THIRD_PARTY, "rival")
    reg = load_registry(blocked=["rival"])
    assert reg.provider[("measure", "test_net")] == "thirdparty-rockfall"
    assert reg.blocked == ["rival"]
    assert "rival_rockfall" not in sys.modules  # blocked plugins are not imported
    assert all(f.plugin != "rival" for f in reg.failures)


def test_blocking_by_distribution_name_and_a_broken_plugin(third_party):
    reg = load_registry(blocked=["thirdparty-rockfall", "broken"])
    assert "test_net" not in reg.measures
    assert reg.blocked == ["broken", "thirdparty-rockfall"]
    assert all(f.plugin != "broken" for f in reg.failures)


def test_blocking_an_extra_plugin():
    reg = load_registry(entry_points=[], blocked=["p"],
                        extra_plugins=[("p", plugin_returning(make_measure("fence")))])
    assert reg.measures == {} and reg.blocked == ["p"]


# ---------------------------------------------------------------------------
# broken plugins are reported, the others still load


def test_misspelt_hook_name_is_a_failure():
    class Misspelt:
        @hookimpl
        def rockfall_design_measure(self):  # missing "s"
            return [make_measure("typo")]

    good = plugin_returning(make_measure("fence"))
    reg = load_registry(entry_points=[],
                        extra_plugins=[("misspelt", Misspelt()), ("good", good)])
    f = failure_of(reg, "misspelt")
    assert "rockfall_design_measure" in f.reason and "did you mean" in f.reason
    assert list(reg.measures) == ["fence"]


def test_hook_that_raises_is_a_failure_naming_the_plugin():
    class Raising:
        @hookimpl
        def rockfall_design_measures(self):
            raise RuntimeError("kaput")

        @hookimpl
        def rockfall_design_cost_models(self):
            return []

    good = plugin_returning(make_measure("fence"))
    reg = load_registry(entry_points=[],
                        extra_plugins=[("raising", Raising()), ("good", good)])
    f = failure_of(reg, "raising")
    assert "rockfall_design_measures" in f.reason and "kaput" in f.reason
    assert f.distribution is None
    assert list(reg.measures) == ["fence"]


def test_class_with_a_bad_example_is_a_failure_naming_the_class():
    bad = make_measure("bad", example={"x": "not a number"})
    good = make_measure("good")
    reg = load_registry(entry_points=[], extra_plugins=[("p", plugin_returning(bad, good))])
    f = failure_of(reg, "p")
    assert "M_bad" in f.reason and "'bad'" in f.reason and "x" in f.reason
    assert list(reg.measures) == ["good"]  # the plugin's valid classes still load


@pytest.mark.parametrize(
    ("cls", "expected"),
    [
        (make_measure("with_type", example={"type": "with_type", "x": 1.0}), "'type'"),
        (make_measure("Bad Kind"), "lower-case"),
        (make_measure(""), "no kind"),
        (make_measure("noparams", Params=dict), "Params"),
        (make_measure("dv", design_variables={"depth_m": (1.0, 2.0)}), "depth_m"),
        (make_measure("dv2", design_variables={"x": (5.0, 1.0)}), "low must be below"),
        (make_measure("dv3", design_variables={"x": (1.0,)}), "needs bounds"),
        (type("Abstract", (ProtectiveMeasure,),
              {"kind": "abstract", "Params": MeasureParams, "example": {"x": 1.0}}),
         "does not implement"),
        (make_measure("fence")(MeasureParams(x=1.0)), "not a class"),
        (type("NotAMeasure", (), {"kind": "nope"}), "not a subclass of ProtectiveMeasure"),
    ],
)
def test_invalid_classes_are_failures(cls, expected):
    reg = load_registry(entry_points=[], extra_plugins=[("p", plugin_returning(cls))])
    assert reg.measures == {}
    assert expected in failure_of(reg, "p").reason


def test_unmarked_hook_and_non_list_results_are_failures():
    unmarked = types.SimpleNamespace(rockfall_design_measures=lambda: [])

    class NotAList:
        @hookimpl
        def rockfall_design_measures(self):
            return make_measure("fence")

    reg = load_registry(entry_points=[],
                        extra_plugins=[("unmarked", unmarked), ("notalist", NotAList())])
    assert "@hookimpl" in failure_of(reg, "unmarked").reason
    assert "list of classes" in failure_of(reg, "notalist").reason


def test_hook_with_wrong_arguments_and_taken_names_are_failures():
    class WrongArgs:
        @hookimpl
        def rockfall_design_measures(self, project):
            return []

    good = plugin_returning(make_measure("fence"))
    reg = load_registry(entry_points=[], extra_plugins=[
        ("wrong", WrongArgs()), ("good", good), ("good", plugin_returning()), ("again", good),
    ])
    assert "project" in failure_of(reg, "wrong").reason
    assert "already taken" in failure_of(reg, "good").reason
    assert "already registered" in failure_of(reg, "again").reason
    assert list(reg.measures) == ["fence"]


# ---------------------------------------------------------------------------
# the registry


def test_registry_is_sorted_and_lookups_say_did_you_mean():
    plugin = plugin_returning(*(make_measure(k) for k in ("wall", "fence", "ditch")))
    reg = load_registry(entry_points=[], extra_plugins=[("p", plugin)])
    assert list(reg.measures) == ["ditch", "fence", "wall"]
    with pytest.raises(KeyError) as info:
        reg.measure("fense")
    msg = str(info.value)
    assert "did you mean 'fence'?" in msg and "ditch, fence, wall" in msg
    with pytest.raises(KeyError, match="no safety concept is registered"):
        reg.safety_concept("sia")
    with pytest.raises(KeyError, match="unknown cost model 'x'"):
        reg.cost_model("x")


def test_lookup_mentions_failed_plugins():
    class Raising:
        @hookimpl
        def rockfall_design_measures(self):
            raise RuntimeError("kaput")

    reg = load_registry(entry_points=[], extra_plugins=[("raising", Raising())])
    with pytest.raises(KeyError, match="1 plugin failed to load"):
        reg.measure("fence")


def test_default_registry_is_cached_only_without_blocking():
    default_registry.cache_clear()
    try:
        assert default_registry() is default_registry()
        assert default_registry(["x"]) is not default_registry(["x"])
        assert default_registry(["x"]).blocked == ["x"]
    finally:
        default_registry.cache_clear()


# ---------------------------------------------------------------------------
# rendering and the command line


def test_plugins_json_and_table():
    reg = load_registry(entry_points=[], blocked=["gone"], extra_plugins=[
        ("p", plugin_returning(make_measure("fence"))),
        ("raising", types.SimpleNamespace()),
    ])
    data = plugins_json(reg)
    json.dumps(data)
    [fence] = data["measures"]
    assert {k: fence[k] for k in ("kind", "summary", "provider", "parameter_names")} == {
        "kind": "fence", "summary": "fence for tests", "provider": "p",
        "parameter_names": ["x", "height_m"]}
    assert [p["name"] for p in fence["parameters"]] == ["x", "height_m"]
    assert fence["distribution"] is None and fence["version"] is None
    assert data["safety_concepts"] == [] and data["cost_models"] == []
    assert data["blocked"] == ["gone"]
    assert data["failures"][0]["plugin"] == "raising"

    from rich.console import Console

    console = Console(width=200, record=True)
    console.print(plugins_table(reg))
    text = console.export_text()
    for word in ("Measures", "fence for tests", "Blocked", "gone", "Failures", "raising"):
        assert word in text


def test_cli_plugins_json_shows_third_party_and_failure(third_party, capsys):
    assert main(["plugins", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    net = next(m for m in data["measures"] if m["kind"] == "test_net")
    assert net["provider"] == "thirdparty-rockfall"
    assert net["parameter_names"] == ["x", "height_m", "capacity_kj"]
    assert [p["name"] for p in net["parameters"]] == ["x", "height_m", "capacity_kj"]
    assert net["distribution"] == "thirdparty-rockfall" and net["version"] == "1.0"
    broken = next(f for f in data["failures"] if f["plugin"] == "broken")
    assert broken["distribution"] == "broken-rockfall" and "boom" in broken["reason"]


def test_cli_plugins_table_and_block(third_party, capsys):
    assert main(["plugins", "--block", "broken", "--block", "third"]) == 0
    out = capsys.readouterr().out
    assert "Blocked" in out and "broken" in out and "test_net" not in out


def test_cli_plugins_duplicate_is_exit_3_with_one_line(third_party, capsys):
    write_distribution(third_party, "rival_rockfall", THIRD_PARTY, "rival")
    assert main(["plugins", "--json"]) == ExitCode.PLUGIN_FAULT
    captured = capsys.readouterr()
    assert captured.out == ""
    err = captured.err.strip()
    assert err.count("\n") == 0 and "rival-rockfall" in err and "thirdparty-rockfall" in err
    assert main(["plugins", "--json", "--block", "rival"]) == 0


# ---------------------------------------------------------------------------
# meta-tests: every hook is documented, has a working example and is tested


def _hookspecs() -> list[str]:
    return sorted(
        name for name, obj in vars(hookspecs).items()
        if name.startswith("rockfall_design_") and callable(obj)
        and hasattr(obj, "rockfall_design_spec")
    )


def _example_code(doc: str) -> str:
    _, _, rest = doc.partition("Examples\n--------\n")
    _, _, code = rest.partition(".. code-block:: python\n")
    return textwrap.dedent(code)


def test_there_are_hookspecs():
    assert _hookspecs() == ["rockfall_design_cost_models", "rockfall_design_measures",
                            "rockfall_design_safety_concepts"]


@pytest.mark.parametrize("hook", _hookspecs())
def test_every_hookspec_is_documented_with_an_example_that_works(hook):
    doc = inspect.getdoc(getattr(hookspecs, hook))
    assert doc and "Example" in doc
    for section in ("Returns", "Notes", "Called once"):
        assert section in doc, f"{hook}: no {section!r} in its docstring"
    code = _example_code(doc)
    assert code.strip(), f"{hook}: no code block in its Examples"
    assert re.findall(r"^\s*(?:from|import) (\S+)", code, re.M) == ["rockfall_design"]
    module = types.ModuleType(f"example_{hook}")
    exec(compile(code, f"<{hook} example>", "exec"), module.__dict__)
    reg = load_registry(entry_points=[], extra_plugins=[("example", module)])
    assert reg.failures == []
    registered = reg.measures | reg.safety_concepts | reg.cost_models
    assert len(registered) == 1
    (cls,) = registered.values()
    cls(cls.Params(**cls.example))  # the example parameters make a working instance


@pytest.mark.parametrize("hook", _hookspecs())
def test_every_hookspec_is_exercised_by_a_test_here(hook):
    module = sys.modules[__name__]
    tests = [name for name, fn in vars(module).items()
             if name.startswith("test_") and inspect.isfunction(fn)
             and f"def {hook}(" in inspect.getsource(fn)]
    assert tests, f"no test in {__name__} defines a plugin implementing {hook}"


def test_example_concept_and_cost_model_compute():
    """The documented examples do what their docs say."""
    ns: dict = {}
    exec(_example_code(inspect.getdoc(hookspecs.rockfall_design_safety_concepts)), ns)
    exec(_example_code(inspect.getdoc(hookspecs.rockfall_design_cost_models)), ns)
    exec(_example_code(inspect.getdoc(hookspecs.rockfall_design_measures)), ns)
    import numpy as np

    from rockfall_design import MeasureResult

    fence = ns["PostFence"](ns["PostFenceParams"](x=70.0))
    result = MeasureResult(measure=fence, index=0, n_rocks=2, met=2,
                           energy_kj=np.array([20.0, 50.0]))
    (check,) = ns["MaxEnergy"](ns["MaxEnergyParams"]()).checks(result)
    assert isinstance(check, Check)
    assert check.value == pytest.approx(100.0 / 75.0) and check.ok
    cost = ns["UnitRate"](ns["UnitRateParams"]()).cost(fence, fence.quantities(None), 10.0)
    assert cost == pytest.approx((400.0 + 0.5 * 100.0) * 10.0)

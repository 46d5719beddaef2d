"""A plugin can never take the program down: its faults stop the run with exit code 3.

Each test installs a real third-party distribution (``plugin_helpers``) with a
measure, a safety concept and a cost model, all of which work except for the
one method the test makes fail, and runs ``check`` or ``optimise`` through
``rockfall_design.cli.main``. A fault is one line on stderr naming the
plugin's class, the method and the exception, with exit code 3
(``ExitCode.PLUGIN_FAULT``), never a traceback and never "an infeasible
design"; what the contracts allow (a footprint's ValueError: the measure does
not fit; a cost model's KeyError: no price) keeps its documented meaning.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from rockfall_design.cli import main
from rockfall_design.errors import ExitCode

from .plugin_helpers import write_distribution

# Every method calls _step(NAME) first; FAULT chooses which one misbehaves.
PLUGIN = '''
import math

from pydantic import field_validator

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

FAULT = {fault!r}


def _step(method):
    if FAULT == method:
        raise RuntimeError(f"boom in {{method}}")


class BoomNetParams(MeasureParams):
    height_m: float = 3.0
    capacity_kj: float = 500.0

    @field_validator("height_m")
    @classmethod
    def _height(cls, value):
        # The example has 3.0: only "validator_example" breaks registration.
        if (FAULT == "validator" and value == 4.0) or FAULT == "validator_example":
            _step(FAULT)
        return value


class BoomNet(ProtectiveMeasure):
    kind = "boom_net"
    summary = "a net fence that fails where it is told to"
    Params = BoomNetParams
    example = {{"x": 100.0, "height_m": 3.0, "capacity_kj": 500.0}}
    design_variables = {{"height_m": (1.0, 6.0)}}

    def __init__(self, params):
        _step("measure.__init__")
        super().__init__(params)

    def footprint(self, section):
        _step("footprint")
        if FAULT == "misfit":
            raise ValueError("boom_net does not fit here")
        return Barrier(x=self.params.x, height_m=self.params.height_m,
                       capacity_kj=self.params.capacity_kj, behaviour=BarrierBehaviour.NET)

    def design_properties(self):
        _step("design_properties")
        return {{"height_m": self.params.height_m, "capacity_kj": self.params.capacity_kj}}

    def quantities(self, section):
        _step("quantities")
        return {{"height_m": self.params.height_m}}

    def label(self):
        _step("label")
        return super().label()


class BoomConcept(SafetyConcept):
    name = "boom_concept"
    summary = "checks the height of a boom_net"
    Params = SafetyParams
    example = {{}}

    def __init__(self, params):
        _step("safety.__init__")
        super().__init__(params)

    def checks(self, result):
        _step("checks")
        height = result.measure.design_properties()["height_m"]
        if FAULT == "checks_type":
            return {{"height_m": height}}
        return [Check("height_m", height, 1.0, height >= 1.0, unit="m")]


class BoomCostParams(CostParams):
    per_m_per_m: float = 100.0


class BoomCost(CostModel):
    name = "boom_cost"
    summary = "a price per metre of height and of slope"
    Params = BoomCostParams
    example = {{"per_m_per_m": 100.0}}

    def __init__(self, params):
        _step("cost.__init__")
        super().__init__(params)

    def cost(self, measure, quantities, length_m):
        _step("cost")
        if FAULT == "cost_nan":
            return math.nan
        if FAULT == "cost_no_price":
            raise KeyError("the boom catalogue has no price for nets")
        return self.params.per_m_per_m * quantities["height_m"] * length_m


@hookimpl
def rockfall_design_measures():
    return [BoomNet]


@hookimpl
def rockfall_design_safety_concepts():
    return [BoomConcept]


@hookimpl
def rockfall_design_cost_models():
    return [BoomCost]
'''

PROJECT = """\
name: Boom slope
slope:
  points: [[0, 60], [40, 30], [120, 10], [200, 8]]
  materials: talus
materials:
  talus: {restitution: 0.35, friction: 0.55, rolling_resistance: 0.3, roughness_deg: 5}
rocks:
  count: 30
  seed: 7
  mass: 500
  release: {x: 2}
analysis:
  stations: [100]
protect:
  x: 150
safety: {concept: boom_concept}
"""

CHECK = PROJECT + """\
measures:
  - {type: boom_net, x: 100, height_m: 3, capacity_kj: 500}
"""

OPTIMISE = PROJECT + """\
design:
  max_measures: 1
  residual: {fraction: 1.0}
  fresh_rocks: 30
  site: {length_m: 50}
  costs: {model: boom_cost, params: {per_m_per_m: 100}}
  candidates:
    - {type: boom_net, x: [90, 140], height_m: [1, 6], capacity_kj: 500}
"""

COMMANDS = {"check": CHECK, "optimise": OPTIMISE}

# (fault, class name in the message, method in the message, commands that reach it)
FAULTS = [
    ("measure.__init__", "boom_net", "__init__()", ("check", "optimise")),
    ("footprint", "boom_net", "footprint()", ("check", "optimise")),
    ("design_properties", "boom_net", "design_properties()", ("check", "optimise")),
    ("quantities", "boom_net", "quantities()", ("optimise",)),
    ("label", "boom_net", "label()", ("check", "optimise")),
    ("safety.__init__", "boom_concept", "__init__()", ("check", "optimise")),
    ("checks", "boom_concept", "checks()", ("check", "optimise")),
    ("cost.__init__", "boom_cost", "__init__()", ("optimise",)),
    ("cost", "boom_cost", "cost()", ("optimise",)),
]
CASES = [
    pytest.param(command, fault, name, method, id=f"{command}-{fault}")
    for fault, name, method, commands in FAULTS
    for command in commands
]


@pytest.fixture
def install(tmp_path, monkeypatch):
    """Install the plugin with a given fault; returns (distribution name, project path)."""
    # Modules are cached by name: a new name per install, all forgotten afterwards.
    names: list[str] = []

    def install(fault: str, command: str) -> tuple[str, str]:
        module = f"boom_plugin_{len(names)}"
        names.append(module)
        write_distribution(tmp_path, module, PLUGIN.format(fault=fault), "boom",
                           dist_name="boom-plugins")
        monkeypatch.syspath_prepend(str(tmp_path))
        path = tmp_path / f"{command}.yaml"
        path.write_text(COMMANDS[command])
        return "boom-plugins", str(path)

    yield install
    for module in names:
        sys.modules.pop(module, None)


def run(command: str, path: str, *extra: str) -> int:
    return main([command, path, "--rocks", "30", *extra])


def assert_one_line_fault(code: int, err: str, *needles: str) -> None:
    assert code == ExitCode.PLUGIN_FAULT, err
    assert err.count("\n") == 1 and err.startswith("rockfall-design: error: "), err
    assert "Traceback" not in err
    for needle in needles:
        assert needle in err, (needle, err)


@pytest.mark.parametrize("command", ["check", "optimise"])
def test_the_plugin_works_when_nothing_fails(install, capsys, command):
    # The control: every fault below is the one method's, not a broken plugin.
    _, path = install("", command)
    code = run(command, path, "--json")
    out = capsys.readouterr()
    assert code == ExitCode.OK, out.err
    summary = json.loads(out.out)
    if command == "check":
        assert summary["measures"][0]["type"] == "boom_net"
    else:
        assert summary["best"] == "boom_net"


@pytest.mark.parametrize(("command", "fault", "name", "method"), CASES)
def test_a_plugin_that_raises_is_named_with_exit_3(install, capsys, command, fault, name,
                                                   method):
    dist, path = install(fault, command)
    code = run(command, path)
    err = capsys.readouterr().err
    assert_one_line_fault(code, err, repr(name), dist, method, "RuntimeError",
                          f"boom in {fault}")


@pytest.mark.parametrize("command", ["check", "optimise"])
def test_a_measure_failing_inside_the_concept_is_named_not_the_concept(install, capsys,
                                                                       command):
    # The concept calls result.measure.design_properties(): the fault is the measure's.
    _, path = install("design_properties", command)
    code = run(command, path)
    err = capsys.readouterr().err
    assert_one_line_fault(code, err, "measure 'boom_net'")
    assert "boom_concept" not in err


@pytest.mark.parametrize("command", ["check", "optimise"])
def test_checks_of_the_wrong_type_are_a_fault(install, capsys, command):
    dist, path = install("checks_type", command)
    code = run(command, path)
    err = capsys.readouterr().err
    assert_one_line_fault(code, err, "safety concept 'boom_concept'", dist, "checks()",
                          "returned dict", "expected a list of Check")


def test_a_cost_of_nan_is_a_fault(install, capsys):
    dist, path = install("cost_nan", "optimise")
    code = run("optimise", path)
    err = capsys.readouterr().err
    assert_one_line_fault(code, err, "cost model 'boom_cost'", dist, "cost()", "nan",
                          "expected a finite number >= 0")


def test_a_cost_model_without_a_price_skips_the_design_and_says_why(install, capsys):
    # The cost-model contract: KeyError means "no price", not a fault.
    _, path = install("cost_no_price", "optimise")
    code = run("optimise", path, "--json")
    out = capsys.readouterr()
    assert code == ExitCode.CHECK_FAILED, out.err
    assert "Traceback" not in out.err
    summary = json.loads(out.out)
    (alt,) = summary["alternatives"]
    assert summary["best"] is None and not alt["feasible"]
    assert "boom_cost" in alt["reason"] and "no price for nets" in alt["reason"]


def test_a_measure_that_does_not_fit_is_bad_input_or_infeasible(install, capsys):
    # footprint's ValueError is the user's to fix (check: exit 2) and, in the
    # optimiser, an infeasible design: neither is a plugin fault.
    _, path = install("misfit", "check")
    assert run("check", path) == ExitCode.BAD_INPUT
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "does not fit here" in err and "measures[0]" in err
    _, path = install("misfit", "optimise")
    code = run("optimise", path, "--json")
    out = capsys.readouterr()
    assert code == ExitCode.CHECK_FAILED, out.err
    (alt,) = json.loads(out.out)["alternatives"]
    assert "does not fit here" in alt["reason"]


@pytest.mark.parametrize("command", ["simulate", "check"])
def test_a_parameter_validator_that_raises_is_a_fault(install, capsys, command):
    # pydantic passes on what a validator raises unless it is a ValueError or
    # an AssertionError: that is a bug in the plugin's model, not bad input.
    _, path = install("validator", "check")
    Path(path).write_text(CHECK.replace("height_m: 3,", "height_m: 4,"))
    code = run(command, path)
    err = capsys.readouterr().err
    assert_one_line_fault(code, err, "BoomNetParams", "RuntimeError", "boom in validator")


def test_a_validator_that_rejects_the_example_leaves_the_plugin_out(install, capsys):
    """Found at registration: the plugin is reported as not loaded, the rest load."""
    dist, _ = install("validator_example", "check")
    assert main(["plugins", "--json"]) == 0
    listing = json.loads(capsys.readouterr().out)
    assert "boom_net" not in json.dumps(listing["measures"])
    (failure,) = [f for f in listing["failures"] if "boom_net" in json.dumps(f)]
    assert "boom in validator_example" in json.dumps(failure)
    assert "fence" in json.dumps(listing["measures"])

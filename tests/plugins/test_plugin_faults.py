"""A plugin can never take the program down: its faults stop the run with exit code 3.

Each test installs a real third-party distribution (``plugin_helpers``) with a
measure, a safety concept and a cost model, all of which work except for the
one method the test makes fail, and runs ``check`` or ``optimise`` through
``rockfall_design.cli.program.main``. A fault is one line on stderr naming the
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

from rockfall_design.cli.program import main
from rockfall_design.errors import ExitCode

from ..plugin_helpers import write_distribution

# Every method calls _step(NAME) first; FAULT chooses which one misbehaves.
PLUGIN = '''
import math

from pydantic import field_validator

import numpy as np

from rockfall_design import (
    Barrier,
    BarrierBehaviour,
    Check,
    CostModel,
    CostParams,
    MeasureParams,
    ProfileEdit,
    ProtectiveMeasure,
    SafetyConcept,
    SafetyParams,
    hookimpl,
)

FAULT = {fault!r}
EXC = {exc}

if FAULT == "print":
    print("chatty plugin: imported")


def _step(method):
    if FAULT == "print":
        print(f"chatty plugin: in {{method}}")
    if FAULT == method:
        raise EXC(f"boom in {{method}}")


def _fields(kind, fields):
    """The footprint's fields, one replaced as FAULT says: 'barrier:height_m=math.nan'."""
    if FAULT.startswith(kind + ":"):
        name, value = FAULT[len(kind) + 1:].split("=", 1)
        fields[name] = eval(value, {{"math": math, "np": np, "BarrierBehaviour": BarrierBehaviour}})
    return fields


_step("import")


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
        if FAULT == "sigint":  # a real Ctrl-C while plugin code runs
            import os
            import signal
            import time
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(10)  # the handler interrupts the sleep
        if FAULT == "write_ground":  # flattens the ground the engine runs on
            section.y[:] = section.y.min()
        if FAULT == "reopen_ground":
            section.y.flags.writeable = True
        x = self.params.x
        if FAULT.startswith("edit:"):
            g = section.ground_height
            return ProfileEdit(**_fields("edit", dict(
                x_start=x, x_end=x + 4.0, catch_from=x, catch_to=x + 4.0, material=None,
                points=np.array([[x, g(x)], [x + 2.0, g(x + 2.0) - 1.0], [x + 4.0, g(x + 4.0)]]),
            )))
        return Barrier(**_fields("barrier", dict(
            x=x, height_m=self.params.height_m, capacity_kj=self.params.capacity_kj,
            behaviour=BarrierBehaviour.NET)))

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
        if FAULT == "write_result":
            result.energy_kj[:] = 0.0
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
    _step("hook")
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

    def install(fault: str, command: str, exc: str = "RuntimeError") -> tuple[str, str]:
        module = f"boom_plugin_{len(names)}"
        names.append(module)
        write_distribution(tmp_path, module, PLUGIN.format(fault=fault, exc=exc), "boom",
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
        assert summary["best"]["name"] == "boom_net"


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


# ---------------------------------------------------------------------------
# hardening, round 2: what a plugin raises beyond Exception, what it returns,
# what it prints


@pytest.mark.parametrize("exc", ["SystemExit", "KeyboardInterrupt", "BaseException",
                                 "GeneratorExit"])
@pytest.mark.parametrize(("command", "fault", "name", "method"), [
    pytest.param("check", "footprint", "boom_net", "footprint()", id="check-footprint"),
    pytest.param("check", "checks", "boom_concept", "checks()", id="check-checks"),
    pytest.param("optimise", "cost", "boom_cost", "cost()", id="optimise-cost"),
    pytest.param("check", "validator", "BoomNetParams", "validating", id="check-validator"),
])
def test_a_plugin_raising_a_base_exception_is_a_fault_not_an_exit(install, capsys, exc,
                                                                  command, fault, name, method):
    """SystemExit from a plugin used to end the program with its code; KeyboardInterrupt
    passed for a Ctrl-C (exit 130). Both are the plugin's fault: exit 3, one line."""
    dist, path = install(fault, command, exc)
    if fault == "validator":
        Path(path).write_text(CHECK.replace("height_m: 3,", "height_m: 4,"))
    code = run(command, path)
    err = capsys.readouterr().err
    assert_one_line_fault(code, err, name, exc, f"boom in {fault}")
    if fault != "validator":
        assert dist in err and method in err


@pytest.mark.parametrize("exc", ["SystemExit", "KeyboardInterrupt"])
@pytest.mark.parametrize("fault", ["import", "hook"])
def test_a_plugin_raising_a_base_exception_at_load_is_left_out(install, capsys, exc, fault):
    dist, _ = install(fault, "check", exc)
    assert main(["plugins", "--json"]) == 0
    out = capsys.readouterr()
    listing = json.loads(out.out)
    (failure,) = [f for f in listing["failures"] if f["distribution"] == dist]
    assert exc in failure["reason"] and "boom in" in failure["reason"]
    assert "fence" in json.dumps(listing["measures"])


@pytest.mark.parametrize(("fault", "needles"), [
    ("barrier:height_m=math.nan", ("height_m = nan", "expected a finite number")),
    ("barrier:height_m=-1.0", ("height_m = -1", "> 0")),
    ("barrier:height_m=True", ("height_m = True", "expected a number")),
    ("barrier:x=math.nan", ("x = nan",)),
    ("barrier:x=1e300", ("x = 1e+300 m: outside the section", "measure's x = 100 m")),
    ("barrier:capacity_kj=math.nan", ("capacity_kj = nan",)),
    ("barrier:capacity_kj=-5.0", ("capacity_kj = -5", ">= 0")),
    ("barrier:behaviour=7", ("behaviour = 7", "expected a BarrierBehaviour")),
    ("barrier:behaviour='net'", ("behaviour = 'net'",)),
    ("barrier:restitution=1.5", ("restitution = 1.5", "<= 1")),
    ("barrier:gap_m=math.inf", ("gap_m = inf",)),
    ("barrier:spacing_m=0.0", ("spacing_m = 0", "> 0")),
    ("barrier:gap_m=2.0", ("gap_m = 2 wider than spacing_m = 1",)),
    ("edit:points=np.array([[1.0, 2.0, 3.0]])", ("points of shape (1, 3)",)),
    ("edit:points='ground'", ("points = 'ground'",)),
    ("edit:points=np.array([[100.0, math.nan], [104.0, 0.0]])", ("not all finite",)),
    ("edit:points=np.array([[100.0, 20.0], [99.0, 0.0], [104.0, 0.0]])",
     ("x does not increase strictly",)),
    ("edit:points=np.array([[100.0, 500.0], [104.0, 500.0]])", ("do not meet the ground",)),
    ("edit:x_end=math.inf", ("x_end = inf",)),
    ("edit:x_end=90.0", ("x_start = 100 not below x_end = 90",)),
    ("edit:catch_to=math.nan", ("catch_to = nan",)),
    ("edit:catch_from=110.0", ("catch_from = 110 above catch_to = 104",)),
    ("edit:material=3", ("material = 3",)),
])
def test_a_footprint_with_a_bad_field_is_the_plugins_fault(install, capsys, fault, needles):
    """Every field the engine uses is checked; a NaN height must never catch every rock."""
    dist, path = install(fault, "check")
    code = run("check", path)
    err = capsys.readouterr().err
    assert_one_line_fault(code, err, "measure 'boom_net'", dist, "footprint() returned",
                          "bug in the plugin", *needles)


def test_a_bad_footprint_is_a_fault_in_the_optimiser_too(install, capsys):
    dist, path = install("barrier:height_m=math.nan", "optimise")
    code = run("optimise", path)
    err = capsys.readouterr().err
    assert_one_line_fault(code, err, "measure 'boom_net'", dist, "height_m = nan")


def test_a_measure_whose_own_x_is_off_the_section_is_the_projects_fault(install, capsys):
    _, path = install("", "check")
    Path(path).write_text(CHECK.replace("x: 100,", "x: 900,"))
    assert run("check", path) == ExitCode.BAD_INPUT
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "measures[0].x" in err and "outside the section" in err


@pytest.mark.parametrize("command", ["check", "optimise"])
def test_a_plugin_that_prints_cannot_break_json(install, capsys, command):
    _, path = install("print", command)
    code = run(command, path, "--json")
    out = capsys.readouterr()
    assert code == ExitCode.OK, out.err
    json.loads(out.out)  # one JSON document, nothing else
    assert out.out.count("\n") == 1
    assert "chatty plugin: imported" in out.err and "chatty plugin: in footprint" in out.err


@pytest.fixture
def default_sigint():
    """Python's own SIGINT handler, even where the test run inherited SIGINT ignored."""
    import signal

    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def test_a_real_ctrl_c_in_plugin_code_stops_the_run(install, capsys, default_sigint):
    _, path = install("sigint", "check")
    assert run("check", path) == ExitCode.INTERRUPTED
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "interrupted" in err and "Traceback" not in err


def test_a_real_ctrl_c_in_plugin_code_reaches_a_library_caller(install, default_sigint):
    """Used as a library, with Python's default handler, too: not a plugin fault."""
    import signal

    from rockfall_design.errors import Interrupted
    from rockfall_design.judge.evaluation import evaluate
    from rockfall_design.plugins import load_registry
    from rockfall_design.project import load_project

    _, path = install("sigint", "check")
    project = load_project(path)
    with pytest.raises(Interrupted):
        evaluate(project, load_registry(), rocks=5)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


@pytest.mark.parametrize("command", ["check", "optimise"])
@pytest.mark.parametrize("fault, needles", [
    ("write_ground", ("footprint()", "wrote into an array it was handed", "section.y")),
    ("reopen_ground", ("footprint()", "made section.y writeable again")),
    ("write_result", ("checks()", "wrote into an array it was handed", "energy_kj")),
])
def test_a_plugin_that_writes_what_it_was_handed_is_reported(install, capsys, command, fault,
                                                             needles):
    """Issue 27, item 5: a footprint that wrote section.y flattened the ground; now exit 3."""
    dist, path = install(fault, command)
    code = run(command, path)
    err = capsys.readouterr().err
    name = "boom_concept" if fault == "write_result" else "boom_net"
    assert_one_line_fault(code, err, name, dist, "bug in the plugin", *needles)

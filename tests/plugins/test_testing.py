"""rockfall_design.testing: a plugin author's helpers, tried on an inline third-party net.

The net below is what a plugin author would write; the tests use only
``rockfall_design.testing`` and its fixtures (loaded through the pytest11
entry point), as the author's own tests would.
"""

from __future__ import annotations

import types

import pytest
from pydantic import Field

from rockfall_design import (
    Barrier,
    BarrierBehaviour,
    MeasureParams,
    ProtectiveMeasure,
    hookimpl,
)
from rockfall_design.errors import ProjectError
from rockfall_design.testing import (
    assert_breaks_through,
    assert_catches,
    assert_outcome,
    assert_passes_over,
    make_registry,
    run_one_rock,
)


class SoftNetParams(MeasureParams):
    height: float = Field(2.0, gt=0, description="height of the net above ground (m)")
    capacity_kj: float = Field(10.0, gt=0, json_schema_extra={"unit": "kJ"})


class SoftNet(ProtectiveMeasure):
    kind = "soft_net"
    summary = "a light net that holds small, slow rocks"
    Params = SoftNetParams
    example = {"x": 40.0, "height": 2.0, "capacity_kj": 10.0}
    design_variables = {"height": (0.5, 4.0)}

    def footprint(self, section):
        p = self.params
        return Barrier(x=p.x, height_m=p.height, capacity_kj=p.capacity_kj,
                       behaviour=BarrierBehaviour.NET)

    def design_properties(self):
        return {"height_m": self.params.height, "capacity_kj": self.params.capacity_kj}


@hookimpl
def rockfall_design_measures():
    return [SoftNet]


#: The plugin as a module, as an entry point would load it.
soft_net_plugin = types.ModuleType("soft_net_plugin")
soft_net_plugin.rockfall_design_measures = rockfall_design_measures

NET = {"type": "soft_net", "x": 40.0, "height": 2.0, "capacity_kj": 10.0}


@pytest.fixture(scope="module")
def registry():
    return make_registry(soft_net_plugin)


def test_fixtures_come_from_the_pytest11_entry_point(rockfall_registry, tiny_slope):
    reg = rockfall_registry(soft_net_plugin)
    assert "soft_net" in reg.measures and "fence" in reg.measures
    project = tiny_slope(NET, registry=reg)
    assert project.measures[0]["type"] == "soft_net"
    assert project.slope.points[0] == (0.0, 10.0)


def test_slow_rock_is_caught_fast_rock_breaks_through(registry):
    # mass 173 kg (r = 0.25 m): 5 m/s is 2.2 kJ, 20 m/s is 35 kJ; the net holds 10 kJ
    run = assert_catches(NET, speed=5.0, height=1.0, registry=registry)
    met = run.measures[0]
    assert met.held and met.passing_height_m == pytest.approx(1.0, abs=1e-6)
    assert met.velocity_ms == pytest.approx(5.0, rel=1e-6)
    assert met.energy_kj == pytest.approx(0.5 * 2650 * 4 / 3 * 3.141592653589793
                                          * 0.25**3 * 25 / 1e3, rel=1e-6)
    run = assert_breaks_through(NET, speed=20.0, height=1.0, registry=registry)
    assert not run.measures[0].held


def test_high_rock_passes_over(registry):
    assert_passes_over(NET, speed=8.0, height=2.5, registry=registry)


def test_measure_object_needs_no_registry():
    """A measure object brings its class: the helper registers it inline."""
    net = SoftNet(SoftNet.Params(x=30.0, height=1.5, capacity_kj=50.0))
    assert run_one_rock(net, speed=6.0, height=0.8).outcome == "caught"


def test_rolling_rock_and_a_built_in_beside_the_plugin(registry):
    fence = {"type": "fence", "x": 50.0, "height": 3.0, "capacity_kj": 500.0}
    run = run_one_rock([NET, fence], speed=4.0, height=0.25, registry=registry)
    assert run.release["spin"] == "rolling"
    assert run.outcomes[0] in ("caught", "broken_through")
    assert run.measures[0].passing_height_m == pytest.approx(0.25, abs=0.05)


def test_failed_assertion_says_what_happened(registry):
    with pytest.raises(AssertionError, match=r"expected caught .* got broken_through: "
                                             r"measures\[0\] \(soft_net\): broken_through at"):
        assert_catches(NET, speed=20.0, height=1.0, registry=registry)
    with pytest.raises(ValueError, match="unknown outcome"):
        assert_outcome(NET, "held", speed=1.0, height=1.0, registry=registry)


def test_bad_parameters_are_a_project_error(tiny_slope, registry):
    with pytest.raises(ProjectError, match=r"measures\[0\]\.height"):
        tiny_slope({**NET, "height": -1.0}, registry=registry)


def test_broken_plugin_is_an_assertion_with_its_reason():
    broken = types.SimpleNamespace(rockfall_design_measure=hookimpl(lambda: []))
    with pytest.raises(AssertionError, match="unknown hook rockfall_design_measure"):
        make_registry(broken)


def test_import_is_light():
    """pytest imports the module in every run (pytest11): no engine, numba, pandas, scipy."""
    import subprocess
    import sys

    code = ("import sys, rockfall_design.testing\n"
            "heavy = ('numba', 'pandas', 'scipy', 'rockfall_design.engine', "
            "'rockfall_design.judge.evaluation', 'rockfall_design.api')\n"
            "print([m for m in heavy if m in sys.modules])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == "[]"

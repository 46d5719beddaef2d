"""Tests of the built-in safety concepts ``spang`` and ``uni11211``.

The MeasureResults are built by hand: 21 rocks whose values are k times a
step (k = 1..21, in shuffled order), so that with numpy's linear percentile
(position (n - 1) q / 100 in the sorted values) the 95th percentile is the
20th value exactly, the 99th lies 0.8 of the way from the 20th to the 21st,
and the 50th is the 11th.
"""

import math

import numpy as np
import pluggy
import pytest
from numpy.testing import assert_allclose
from pydantic import ValidationError
from rockfall_design_builtins.safety import SpangConcept, Uni11211Concept
from rockfall_design_builtins.safety import spang as spang_module
from rockfall_design_builtins.safety import uni11211 as uni11211_module

from rockfall_design import (
    Barrier,
    BarrierBehaviour,
    Check,
    MeasureParams,
    MeasureResult,
    ProtectiveMeasure,
    SafetyConcept,
)
from rockfall_design.plugins import hookspecs as hookspecs_module

RTOL = 1e-12
K = np.arange(1, 22, dtype=float)  # 1..21
ORDER = np.random.default_rng(7).permutation(21)  # the concepts must not rely on rock order


class StubParams(MeasureParams):
    height_m: float | None = None
    capacity_kj: float | None = None
    width_m: float | None = None


class StubMeasure(ProtectiveMeasure):
    """A measure that only declares the design properties it is given."""

    kind = "stub"
    Params = StubParams

    def footprint(self, section):
        return Barrier(
            x=self.x,
            height_m=self.params.height_m or 0.0,
            capacity_kj=self.params.capacity_kj or math.inf,
            behaviour=BarrierBehaviour.NET,
        )

    def design_properties(self) -> dict[str, float]:
        names = ("height_m", "capacity_kj", "width_m")
        return {n: getattr(self.params, n) for n in names if getattr(self.params, n) is not None}


def result(
    height_m=None,
    capacity_kj=None,
    width_m=None,
    *,
    heights=0.1 * K,
    speeds=1.0 * K,
    energies=10.0 * K,
    masses=100.0 * K,
    radii=0.05 * K,
    reaches=(),
) -> MeasureResult:
    measure = StubMeasure(
        StubParams(x=70.0, height_m=height_m, capacity_kj=capacity_kj, width_m=width_m)
    )
    arrays = [np.asarray(a, dtype=float) for a in (heights, speeds, energies, masses, radii)]
    arrays = [a[ORDER] if a.size == 21 else a for a in arrays]
    met = max(a.size for a in arrays)
    return MeasureResult(
        measure=measure,
        index=0,
        n_rocks=100,
        met=met,
        caught=met,
        passing_height_m=arrays[0],
        velocity_ms=arrays[1],
        energy_kj=arrays[2],
        mass_kg=arrays[3],
        radius_m=arrays[4],
        reach_m=np.asarray(reaches, dtype=float),
    )


def no_rock(height_m=4.0, capacity_kj=500.0, width_m=4.0) -> MeasureResult:
    empty = np.zeros(0)
    return result(
        height_m,
        capacity_kj,
        width_m,
        heights=empty,
        speeds=empty,
        energies=empty,
        masses=empty,
        radii=empty,
        reaches=empty,
    )


def spang(**params) -> SpangConcept:
    return SpangConcept(SpangConcept.Params(**params))


def uni(**params) -> Uni11211Concept:
    return Uni11211Concept(Uni11211Concept.Params(**params))


def by_name(checks: list[Check]) -> dict[str, Check]:
    assert all(isinstance(c, Check) for c in checks)
    return {c.name: c for c in checks}


# --------------------------------------------------------------------------------------
# Registration, parameters, examples
# --------------------------------------------------------------------------------------


def test_hook_registers_both_concepts():
    pm = pluggy.PluginManager(hookspecs_module.PROJECT_NAME)
    pm.add_hookspecs(hookspecs_module)
    pm.register(spang_module)
    pm.register(uni11211_module)
    pm.check_pending()
    # pluggy calls the later registered first; each module gives its one class.
    returned = pm.hook.rockfall_design_safety_concepts()
    assert returned == [[Uni11211Concept], [SpangConcept]]
    concepts = [SpangConcept, Uni11211Concept]
    assert [c.name for c in concepts] == ["spang", "uni11211"]
    for concept in concepts:
        assert issubclass(concept, SafetyConcept) and concept.summary
        params = concept.Params(**concept.example)
        assert params == concept.Params()  # the example spells out the defaults
        assert set(concept.example) == set(concept.Params.model_fields)
        for name, field in concept.Params.model_fields.items():
            assert field.description, f"{concept.name}.{name} has no description"


def test_default_parameters():
    assert SpangConcept.Params().model_dump() == {
        "height_factor": 2.0,
        "energy_factor": 1.0,
        "reach_factor": 1.0,
        "statistic": "p95",  # as the README advises (issue 25); the maximum has no bound
        "gamma_d": 1.3,  # Peila & Ronco (2009), on a fence's maximum elongation
        "confidence": 0.95,
    }
    assert Uni11211Concept.Params().model_dump() == {
        "gamma_tr": 1.02,
        "gamma_dp": 1.02,
        "gamma_volf": 1.02,
        "gamma_gamma": 1.0,
        "gamma_e": 1.2,
        "f_min_m": 0.5,
        "percentile": 95.0,
        "reach_factor": 1.0,
        "gamma_d": 1.3,
        "confidence": 0.95,
    }


@pytest.mark.parametrize(
    ("concept", "params"),
    [
        (SpangConcept, {"height_facter": 2.0}),
        (SpangConcept, {"statistic": "p90"}),
        (SpangConcept, {"height_factor": 0.0}),
        (SpangConcept, {"energy_factor": math.nan}),
        (Uni11211Concept, {"gamma_trajectory": 1.02}),
        (Uni11211Concept, {"gamma_e": 0.9}),
        (Uni11211Concept, {"percentile": 0.0}),
        (Uni11211Concept, {"percentile": 101.0}),
        (Uni11211Concept, {"f_min_m": -0.1}),
        (Uni11211Concept, {"gamma_tr": math.inf}),
    ],
)
def test_params_are_strict(concept, params):
    with pytest.raises(ValidationError):
        concept.Params(**params)


# --------------------------------------------------------------------------------------
# spang
# --------------------------------------------------------------------------------------


def test_spang_factors_with_max():
    checks = spang(statistic="max").checks(result(height_m=4.0, capacity_kj=500.0))
    assert [c.name for c in checks] == ["height_factor", "energy_factor"]
    height, energy = checks
    assert_allclose(height.value, 4.0 / 2.1, rtol=RTOL)
    assert_allclose(energy.value, 500.0 / 210.0, rtol=RTOL)
    assert (height.target, height.ok, height.unit) == (2.0, False, "-")
    assert (energy.target, energy.ok, energy.unit) == (1.0, True, "-")
    assert height.detail == "4.00 m / max passing height 2.10 m over 21 rocks"
    assert energy.detail == "500.0 kJ / max energy 210.0 kJ over 21 rocks"


@pytest.mark.parametrize(
    ("statistic", "critical_height", "design_energy"),
    [
        ("max", 2.1, 210.0),
        ("p95", 2.0, 200.0),  # position 19 of 0..20: the 20th value
        ("p99", 2.0 + 0.8 * 0.1, 200.0 + 0.8 * 10.0),  # position 19.8
    ],
)
def test_spang_statistics(statistic, critical_height, design_energy):
    checks = by_name(spang(statistic=statistic).checks(result(height_m=5.0, capacity_kj=300.0)))
    assert_allclose(checks["height_factor"].value, 5.0 / critical_height, rtol=RTOL)
    assert_allclose(checks["energy_factor"].value, 300.0 / design_energy, rtol=RTOL)
    assert checks["height_factor"].detail.startswith(f"5.00 m / {statistic} passing height ")


@pytest.mark.parametrize(
    ("height_m", "capacity_kj", "height_ok", "energy_ok"),
    [
        (4.3, 211.0, True, True),  # 4.3 / 2.1 = 2.05 >= 2; 211 / 210 >= 1
        (4.1, 209.0, False, False),  # 1.95 < 2; 0.995 < 1
    ],
)
def test_spang_verdicts_on_both_sides_of_the_targets(height_m, capacity_kj, height_ok, energy_ok):
    checks = by_name(spang(statistic="max").checks(result(height_m=height_m,
                                                          capacity_kj=capacity_kj)))
    assert checks["height_factor"].ok is height_ok
    assert checks["energy_factor"].ok is energy_ok


def test_spang_target_reached_exactly_holds():
    # p95 height 2.0, energy 200.0: factors exactly 2 and 1
    checks = by_name(spang(statistic="p95").checks(result(height_m=4.0, capacity_kj=200.0)))
    assert checks["height_factor"].value == 2.0 and checks["height_factor"].ok
    assert checks["energy_factor"].value == 1.0 and checks["energy_factor"].ok


def test_spang_custom_targets():
    checks = by_name(
        spang(height_factor=3.0, energy_factor=1.5, statistic="max").checks(
            result(height_m=6.0, capacity_kj=400.0))
    )
    assert checks["height_factor"].target == 3.0 and not checks["height_factor"].ok  # 2.86
    assert checks["energy_factor"].target == 1.5 and checks["energy_factor"].ok  # 1.90


def test_spang_reach_factor():
    reaches = [0.5, 1.0, 3.2, 2.0]
    (check,) = spang(statistic="max").checks(result(width_m=4.0, reaches=reaches))
    assert check.name == "reach_factor"
    assert_allclose(check.value, 4.0 / 3.2, rtol=RTOL)
    assert check.ok and check.target == 1.0
    assert check.detail == "4.00 m / max reach 3.20 m over 4 rocks"
    (check,) = spang(statistic="max").checks(result(width_m=3.0, reaches=reaches))
    assert_allclose(check.value, 3.0 / 3.2, rtol=RTOL)
    assert not check.ok
    (check,) = spang(reach_factor=1.5, statistic="max").checks(result(width_m=4.0,
                                                                    reaches=reaches))
    assert check.target == 1.5 and not check.ok
    # The reach takes the concept's statistic too (the maximum grows with the sample):
    # p95 of [0.5, 1.0, 2.0, 3.2] by linear interpolation is 2.0 + 0.85 * 1.2 = 3.02 m.
    (check,) = spang(statistic="p95").checks(result(width_m=4.0, reaches=reaches))
    assert_allclose(check.value, 4.0 / 3.02, rtol=RTOL)
    # Four rocks cannot bound a p95 (59 are needed at 95 %): no bound, not admitted.
    assert check.bound is None and check.ok_with_confidence is False
    assert "needs at least 59 rocks" in check.detail


# --------------------------------------------------------------------------------------
# uni11211
# --------------------------------------------------------------------------------------


def test_uni11211_default_design_values():
    checks = uni().checks(result(height_m=4.0, capacity_kj=600.0))
    assert [c.name for c in checks] == ["design_energy", "design_height"]
    energy, height = checks
    gamma_f = 1.02 * 1.02
    v_d = 20.0 * gamma_f  # p95 of 1..21 m/s
    m_d = 2000.0 * 1.02 * 1.0  # p95 of 100..2100 kg
    assert_allclose(energy.value, 0.5 * m_d * v_d**2 / 1000.0, rtol=RTOL)
    assert_allclose(energy.value, 441.63232128, rtol=RTOL)
    assert_allclose(energy.target, 600.0 / 1.2, rtol=RTOL)
    assert energy.ok and energy.unit == "kJ"
    # h_d = p95 height 2.0 m x gamma_F; design block d_d = 2 x p95 radius 1.0 m = 2.0 m,
    # so the freeboard is d_d / 2 = 1.0 m (more than f_min 0.5 m)
    assert_allclose(height.value, 2.0 * gamma_f + 1.0, rtol=RTOL)
    assert height.target == 4.0 and height.ok and height.unit == "m"
    assert height.detail == (
        "h_d + f = 3.08 m with h_d = p95 passing height 2.00 m x gamma_F 1.04, "
        "f = max(0.5 m, d_d/2 = 1.00 m), over 21 rocks; nominal height 4.00 m; "
        "21 rocks cannot bound the p95 at 95 % confidence: it needs at least 59 rocks "
        "at the measure"
    )
    assert energy.detail.startswith("E_d = 1/2 m_d v_d^2 = 441.6 kJ with m_d = p95 mass 2000.0 kg")
    assert "limit 600.0 kJ / gamma_E 1.2 = 500.0 kJ" in energy.detail
    assert energy.bound is None and energy.ok_with_confidence is False


def test_uni11211_minimum_freeboard():
    # p95 radius 0.2 m: half the design block (0.2 m) < f_min, so f = f_min
    (height,) = uni().checks(result(height_m=4.0, radii=0.01 * K))
    assert_allclose(height.value, 2.0 * 1.02 * 1.02 + 0.5, rtol=RTOL)
    (height,) = uni(f_min_m=0.8).checks(result(height_m=4.0, radii=0.01 * K))
    assert_allclose(height.value, 2.0 * 1.02 * 1.02 + 0.8, rtol=RTOL)


def test_uni11211_custom_factors_and_percentile():
    concept = uni(
        gamma_tr=1.1,
        gamma_dp=1.05,
        gamma_volf=1.1,
        gamma_gamma=1.03,
        gamma_e=1.0,
        f_min_m=0.0,
        percentile=50.0,
    )
    energy, height = concept.checks(result(height_m=4.0, capacity_kj=200.0))
    gamma_f = 1.1 * 1.05
    v_d = 11.0 * gamma_f  # median of 1..21
    m_d = 1100.0 * 1.1 * 1.03
    assert_allclose(energy.value, 0.5 * m_d * v_d**2 / 1000.0, rtol=RTOL)
    assert_allclose(energy.target, 200.0, rtol=RTOL)
    assert energy.ok is bool(0.5 * m_d * v_d**2 / 1000.0 <= 200.0)
    assert_allclose(height.value, 1.1 * gamma_f + 0.55, rtol=RTOL)  # f = p50 radius 0.55
    assert "p50 passing height" in height.detail


def test_uni11211_interpolated_percentile():
    # p99: 0.8 of the way from the 20th to the 21st value
    (energy,) = uni(percentile=99.0).checks(result(capacity_kj=1000.0))
    v_d = 20.8 * 1.02 * 1.02
    m_d = 2080.0 * 1.02
    assert_allclose(energy.value, 0.5 * m_d * v_d**2 / 1000.0, rtol=RTOL)


@pytest.mark.parametrize(
    ("capacity_kj", "ok"),
    [
        (1.2 * 442.0, True),  # limit 442 kJ >= E_d 441.63 kJ
        (1.2 * 441.0, False),  # limit 441 kJ < E_d
    ],
)
def test_uni11211_energy_verdict(capacity_kj, ok):
    (energy,) = uni().checks(result(capacity_kj=capacity_kj))
    assert energy.ok is ok


@pytest.mark.parametrize(("height_m", "ok"), [(3.09, True), (3.08, False)])  # needs 3.0808
def test_uni11211_height_verdict(height_m, ok):
    (height,) = uni().checks(result(height_m=height_m))
    assert height.ok is ok
    assert height.target == height_m


def test_uni11211_reach_factor():
    (check,) = uni().checks(result(width_m=4.0, reaches=[0.5, 3.2, 2.0]))
    assert check.name == "reach_factor"
    # the concept's percentile (p95 of [0.5, 2.0, 3.2] = 2.0 + 0.9 * 1.2 = 3.08 m)
    assert_allclose(check.value, 4.0 / 3.08, rtol=RTOL)
    assert check.ok
    (check,) = uni(reach_factor=1.3).checks(result(width_m=4.0, reaches=[0.5, 3.2, 2.0]))
    assert not check.ok


# --------------------------------------------------------------------------------------
# Edge cases, both concepts
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("concept", [spang(), uni()])
def test_no_rock_met_the_measure(concept):
    checks = concept.checks(no_rock())
    assert len(checks) == 3
    for check in checks:
        assert check.value is None and check.ok is True
        assert check.detail == "no rock reached the measure"


@pytest.mark.parametrize("concept", [spang(), uni()])
def test_only_declared_and_finite_properties_are_checked(concept):
    assert concept.checks(result()) == []
    assert concept.checks(result(capacity_kj=math.inf)) == []
    assert [c.name for c in concept.checks(result(width_m=2.0, reaches=[1.0]))] == ["reach_factor"]


def test_zero_demand_gives_no_factor():
    checks = spang().checks(result(capacity_kj=100.0, energies=np.zeros(5)))
    (energy,) = checks
    assert energy.value is None and energy.ok
    assert "no demand" in energy.detail
    (reach,) = spang().checks(result(width_m=3.0, reaches=[0.0, 0.0]))
    assert reach.value is None and reach.ok


def test_checks_are_json_friendly():
    for concept in (spang(), uni()):
        for check in concept.checks(result(4.0, 500.0, 3.0, reaches=[1.0, 2.0])):
            data = check.as_dict()
            assert isinstance(data["value"], float) and isinstance(data["ok"], bool)
            assert isinstance(data["target"], float)
            assert "\n" not in data["detail"]

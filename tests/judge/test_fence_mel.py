"""A fence product's MEL-test figures: maximum elongation and residual height.

Where the catalogue (or the measure) gives ``max_elongation_m`` and
``residual_height_fraction``, both concepts check that the protected zone does
not start within the braking distance, and ``uni11211`` checks the design
height against the residual height; without them nothing changes.
"""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import ValidationError
from rockfall_design_builtins.measures import Fence, FenceParams
from rockfall_design_builtins.safety import SpangConcept, Uni11211Concept

from rockfall_design import MeasureResult
from rockfall_design.errors import ProjectError
from rockfall_design.judge.candidates import build_candidate_measure
from rockfall_design.judge.design_spec import resolve_design
from rockfall_design.judge.evaluation import evaluate
from rockfall_design.plugins import load_registry
from rockfall_design.project import load_project, load_project_text

from ..project.test_project import EXAMPLE, line_of

K = np.arange(1, 22, dtype=float)  # 21 rocks: the p95 is the 20th value


@pytest.fixture(scope="module")
def registry():
    return load_registry()


def fence(**extra) -> Fence:
    params = {"x": 100.0, "height": 4.0, "capacity_kj": 1000.0, "product": "RX-T", **extra}
    return Fence(FenceParams(**params))


def result(measure: Fence, clearance_m: float | None = None) -> MeasureResult:
    """21 rocks at the fence: p95 passing height 2.0 m, radius 1.0 m, speed 20 m/s."""
    return MeasureResult(
        measure=measure, index=0, n_rocks=100, met=21, caught=21,
        passing_height_m=0.1 * K, velocity_ms=1.0 * K, energy_kj=10.0 * K,
        mass_kg=10.0 * K, radius_m=0.05 * K, clearance_m=clearance_m,
    )


def by_name(checks):
    return {c.name: c for c in checks}


# --------------------------------------------------------------------------------------
# The measure
# --------------------------------------------------------------------------------------

def test_without_figures_the_fence_declares_what_it_did():
    assert fence().design_properties() == {"height_m": 4.0, "capacity_kj": 1000.0}


def test_without_figures_the_fence_is_written_as_before():
    # summaries and design.yaml list the parameters: no null figures in them
    assert fence().params.model_dump(mode="json") == {
        "x": 100.0, "height": 4.0, "capacity_kj": 1000.0, "product": "RX-T"}
    dumped = fence(max_elongation_m=6.5).params.model_dump(mode="json")
    assert dumped["max_elongation_m"] == 6.5 and "residual_height_fraction" not in dumped


def test_figures_become_design_properties():
    props = fence(max_elongation_m=6.5, residual_height_fraction=0.6).design_properties()
    assert props == {"height_m": 4.0, "capacity_kj": 1000.0, "max_elongation_m": 6.5,
                     "residual_height_m": pytest.approx(2.4)}


@pytest.mark.parametrize("extra", [{"max_elongation_m": 0}, {"max_elongation_m": -1},
                                   {"residual_height_fraction": 0},
                                   {"residual_height_fraction": 1.2}])
def test_bad_figures_are_rejected(extra):
    with pytest.raises(ValidationError):
        fence(**extra)


# --------------------------------------------------------------------------------------
# The checks
# --------------------------------------------------------------------------------------

@pytest.mark.parametrize("concept", [SpangConcept(SpangConcept.Params()),
                                     Uni11211Concept(Uni11211Concept.Params())])
def test_braking_distance_reaching_the_protected_zone_fails(concept):
    m = fence(max_elongation_m=6.0)
    check = by_name(concept.checks(result(m, clearance_m=5.0)))["braking_distance"]
    # Peila & Ronco's gamma_d = 1.3 on the elongation: 7.8 m against 5 m.
    assert (check.value, check.target, check.unit) == (pytest.approx(7.8), 5.0, "m")
    assert not check.ok and check.ok_with_confidence is False
    assert check.fails_with_confidence and check.rejects
    assert "product RX-T" in check.detail and "maximum elongation 6.00 m" in check.detail
    assert "protected zone" in check.detail


@pytest.mark.parametrize("concept", [SpangConcept(SpangConcept.Params()),
                                     Uni11211Concept(Uni11211Concept.Params())])
def test_braking_distance_short_of_the_protected_zone_holds(concept):
    check = by_name(concept.checks(result(fence(max_elongation_m=6.0), 8.0)))["braking_distance"]
    assert check.ok and check.ok_with_confidence and not check.fails_with_confidence


@pytest.mark.parametrize("concept", [SpangConcept(SpangConcept.Params()),
                                     Uni11211Concept(Uni11211Concept.Params())])
@pytest.mark.parametrize(("extra", "clearance"), [({}, 5.0), ({"max_elongation_m": 6.0}, None)])
def test_no_braking_check_without_elongation_or_protected_zone(concept, extra, clearance):
    names = [c.name for c in concept.checks(result(fence(**extra), clearance))]
    assert "braking_distance" not in names


def test_uni11211_height_uses_the_residual_height():
    concept = Uni11211Concept(Uni11211Concept.Params())
    nominal = by_name(concept.checks(result(fence())))["design_height"]
    # h_d + f = 2.0 x 1.0404 + 1.0 = 3.08 m: holds on the nominal 4 m ...
    assert nominal.ok and nominal.target == 4.0 and "nominal height 4.00 m" in nominal.detail
    residual = by_name(concept.checks(result(fence(residual_height_fraction=0.6))))
    height = residual["design_height"]
    # ... but not on the residual 0.6 x 4 = 2.4 m
    assert height.value == pytest.approx(nominal.value)
    assert height.target == pytest.approx(2.4) and not height.ok
    assert "residual height after the MEL test 2.40 m of product RX-T" in height.detail
    assert "in place of the nominal height" in height.detail
    tall = by_name(concept.checks(result(fence(height=6.0, residual_height_fraction=0.6))))
    assert tall["design_height"].ok and tall["design_height"].target == pytest.approx(3.6)


def test_spang_height_factor_stays_on_the_nominal_height():
    concept = SpangConcept(SpangConcept.Params())
    plain = by_name(concept.checks(result(fence())))["height_factor"]
    residual = by_name(concept.checks(result(fence(residual_height_fraction=0.3))))
    assert residual["height_factor"].value == plain.value


# --------------------------------------------------------------------------------------
# The catalogue
# --------------------------------------------------------------------------------------

DESIGN = """\
design:
  residual: {fraction: 0.01}
  site: {length_m: 100}
  products:
    fence:
      RX-T: {capacity_kj: 1000, heights: [3, 4], max_elongation_m: 6.5,
             residual_height_fraction: 0.6}
      RX-P: {capacity_kj: 1000, heights: [3, 4]}
  costs:
    params: {currency: EUR, fixed_per_measure: 1000, excavation_per_m3: 25, boulder_per_m3: 110,
             barrier_per_m: {fence: {RX-T: {3: 500, 4: 600},
                                                    RX-P: {3: 500, 4: 600}}}}
  candidates:
    - type: fence
      x: [90, 140]
"""


def test_catalogue_figures_reach_the_measure(registry):
    spec = resolve_design(load_project_text(EXAMPLE + DESIGN), registry)
    (candidate,) = spec.candidates
    product = candidate.product("RX-T")
    assert product.extra == {"max_elongation_m": 6.5, "residual_height_fraction": 0.6}
    m = build_candidate_measure(candidate, registry, {"x": 100, "product": "RX-T", "height": 4})
    assert (m.params.max_elongation_m, m.params.residual_height_fraction) == (6.5, 0.6)
    assert m.design_properties()["residual_height_m"] == pytest.approx(2.4)
    plain = build_candidate_measure(candidate, registry, {"x": 100, "product": "RX-P",
                                                          "height": 4})
    assert plain.design_properties() == {"height_m": 4.0, "capacity_kj": 1000.0}


@pytest.mark.parametrize(
    ("old", "new", "key", "fragment"),
    [
        ("residual_height_fraction: 0.6", "residual_height_fraction: 60",
         "design.products.fence.RX-T.residual_height_fraction",
         "expected a number > 0 and <= 1 (the product's residual height after the MEL test"),
        ("max_elongation_m: 6.5", "max_elongation_m: 0",
         "design.products.fence.RX-T.max_elongation_m",
         "(the product's maximum elongation (braking distance) in the MEL test, m)"),
        ("max_elongation_m: 6.5", "max_elongation_m: long",
         "design.products.fence.RX-T.max_elongation_m", "expected a number"),
    ],
)
def test_bad_catalogue_figures_are_errors_at_their_line(old, new, key, fragment):
    text = EXAMPLE + DESIGN.replace(old, new)
    with pytest.raises(ProjectError) as info:
        load_project_text(text)
    err = info.value
    assert (err.line, err.key) == (line_of(text, new.split(":")[0] + ":"), key), str(err)
    assert fragment in err.message


# --------------------------------------------------------------------------------------
# End to end: the judge hands the clearance to the concepts
# --------------------------------------------------------------------------------------

@pytest.mark.parametrize(("x", "ok"), [(138.0, True), (140.5, True), (141.5, False)])
def test_check_names_the_product_whose_net_reaches_the_protected_zone(tmp_path, registry, x,
                                                                       ok):
    # protect.x = 150: 1.3 x an elongation of 7 m = 9.1 m fits at 140.9 m, not beyond
    text = EXAMPLE + (
        "measures:\n"
        f"  - {{type: fence, x: {x}, height: 4, capacity_kj: 5000, product: RX-T,\n"
        "     max_elongation_m: 7}\n"
        "safety:\n  concept: uni11211\n"
    )
    path = tmp_path / "p.yaml"
    path.write_text(text)
    ev = evaluate(load_project(path), registry, rocks=50, seed=1)
    (checks,) = ev.checks
    check = by_name(checks)["braking_distance"]
    assert check.target == pytest.approx(150.0 - x)
    assert check.ok is ok
    assert "product RX-T" in check.detail


# --------------------------------------------------------------------------------------
# The optimiser rejects a product whose net would reach the protected zone
# --------------------------------------------------------------------------------------

def _small(tmp_path, rx050: str):
    from ..optimiser.test_optimise import PROJECTS, SMALL

    products = (PROJECTS / "catalogue_products.yaml").read_text()
    old = ("RX-050: {capacity_kj: 500, heights: [2, 3, 4], max_elongation_m: 4.5,\n"
           "           elongation_sel_m: 3.0, residual_height_fraction: 0.6}")
    assert old in products
    (tmp_path / "products.yaml").write_text(products.replace(old, rx050))
    text = (SMALL.replace("SEED", "3")
            .replace("PRODUCTS", str(tmp_path / "products.yaml"))
            .replace("COSTS", str(PROJECTS / "catalogue_costs.yaml")))
    return load_project_text(text, "small.yaml")


def test_optimiser_passes_over_a_product_whose_net_reaches_the_protected_zone(tmp_path,
                                                                              registry):
    from rockfall_design.optimiser import optimise

    # The fence stands at 58..64 m and the protected zone starts at 150 m.
    plain = optimise(_small(tmp_path, "RX-050: {capacity_kj: 500, heights: [2, 3, 4]}"),
                     registry)
    assert plain.best.measures[0].params.product == "RX-050"  # the cheapest, without figures
    short = optimise(_small(tmp_path, "RX-050: {capacity_kj: 500, heights: [2, 3, 4], "
                                      "max_elongation_m: 65}"), registry)
    assert short.best.cost == plain.best.cost  # 1.3 x 65 m of braking fits in 86..92 m
    names = [c["name"] for c in short.best.checks]
    assert "braking_distance" in names
    long = optimise(_small(tmp_path, "RX-050: {capacity_kj: 500, heights: [2, 3, 4], "
                                     "max_elongation_m: 75}"), registry)
    assert long.best.measures[0].params.product != "RX-050"
    assert long.best.cost > plain.best.cost

"""The fence as EAD 340059 tests it: braking distance in the run and in the checks; the concepts.

The braking-distance design check fails where the protected zone starts within
gamma_d x the maximum elongation and holds with the zone 10 m further; a caught
rock rests its braking distance downslope; ``reliability`` and ``onr24810``
judge as their formulas say; an EAD concept rejects a catalogue fence without
its test figures at the product's line.
"""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import pytest
from numpy.testing import assert_allclose

from rockfall_design.errors import ProjectError
from rockfall_design.judge.design_spec import resolve_design
from rockfall_design.judge.evaluation import evaluate
from rockfall_design.project import load_project, load_project_text

DATA = Path(__file__).resolve().parents[1] / "data"

# Level ground; rocks launched horizontally 10 m above it at x = 0 meet a
# fence at x = 6 m at 3.24 m, far below its 1667 kJ SEL (MEL 5000 kJ / 3).
FLIGHT = """
name: flight
slope:
  points: [[-20, 0], [300, 0]]
  materials: ground
materials:
  ground: {{restitution: 0.3, friction: 0.5, rolling_resistance: 0.4}}
rocks:
  count: {count}
  seed: 3
  radius: 0.3
  release: {{x: 0, height: 10, velocity: [5, 0], spin: 2}}
measures:
  - {{type: fence, x: 6, height: 5.0, capacity_kj: 5000, max_elongation_m: 5.5,
     elongation_sel_m: 3.6, residual_height_fraction: 0.6}}
{extra}
"""


def project(extra: str = "", count: int = 20):
    return load_project_text(FLIGHT.format(count=count, extra=textwrap.dedent(extra)),
                             "test.yaml")


def _check(ev, name):
    (c,) = [c for c in ev.checks[0] if c.name == name]
    return c


@pytest.mark.parametrize("concept", ["spang", "uni11211", "onr24810"])
def test_a_zone_within_the_elongation_fails_and_ten_metres_further_holds(registry, concept):
    near = evaluate(project(f"protect: {{x: 11}}\nsafety: {{concept: {concept}}}"), registry)
    far = evaluate(project(f"protect: {{x: 21}}\nsafety: {{concept: {concept}}}"), registry)
    b_near, b_far = _check(near, "braking_distance"), _check(far, "braking_distance")
    # gamma_d 1.3 x 5.5 m = 7.15 m: more than the 5 m to the zone, less than 15 m.
    assert_allclose(b_near.value, 1.3 * 5.5)
    assert not b_near.ok and b_near.rejects and "protected zone" in b_near.detail
    assert b_far.ok and b_far.holds_with_confidence
    assert "braking_distance" in " ".join(near.failures())
    assert "braking_distance" not in " ".join(far.failures())


def test_a_caught_rock_rests_its_braking_distance_beyond_the_fence(registry):
    ev = evaluate(project("protect: {x: 9}"), registry)
    r = ev.run.result
    res = ev.results[0]
    assert res.caught == res.met == r.n
    # Below the SEL: the SEL elongation, 3.6 m, horizontally.
    assert_allclose(r.x_end, 6.0 + 3.6)
    assert_allclose(r.max_x, 6.0 + 3.6)
    # The zone at x = 9 m is within the braking distance: every rock reaches it.
    assert ev.protect["reaching"] == r.n


def test_reliability_states_the_working_life_probability_with_its_bounds(registry):
    extra = """
    protect: {x: 40}
    safety: {concept: reliability, annual_falls: 2.5, working_life_years: 50,
             target_failure_probability: 0.5}
    """
    ev = evaluate(project(extra, count=40), registry)
    c = _check(ev, "failure_probability")
    assert c.value == 0.0 and c.ok  # every rock caught
    # Clopper-Pearson upper bound of 0 of 40 at 95 %: 1 - 0.05^(1/40).
    p_up = 1.0 - 0.05 ** (1 / 40)
    assert_allclose(c.bound, -math.expm1(-125 * p_up), rtol=1e-9)
    assert not c.ok_with_confidence and c.rocks_needed is not None
    # The residual is held to p_max = -ln(1 - P_t) / (lambda T).
    assert_allclose(ev.protect["allowed_fraction"], -math.log1p(-0.5) / 125)


def test_reliability_needs_millions_of_rocks_for_a_target_of_1e_4(registry):
    extra = """
    protect: {x: 40}
    safety: {concept: reliability, annual_falls: 2.5, target_failure_probability: 1.0e-4}
    """
    ev = evaluate(project(extra, count=10), registry)
    c = _check(ev, "failure_probability")
    p_max = -math.log1p(-1e-4) / 125
    assert_allclose(p_max, 8.0e-7, rtol=1e-3)
    # Zero of n bounds p below p_max from n >= ln(0.05) / ln(1 - p_max): 3.7 million.
    assert "3,744,477 rocks" in c.detail and c.rocks_needed == 3_744_477  # all met it


def test_onr24810_takes_the_sel_for_frequent_and_the_mel_for_rare_events(registry):
    rare = evaluate(project("safety: {concept: onr24810, event: rare}"), registry)
    frequent = evaluate(project("safety: {concept: onr24810, event: frequent, "
                                "consequence_class: CC3}"), registry)
    assert _check(rare, "design_energy").target == 5000.0
    assert_allclose(_check(frequent, "design_energy").target, 5000.0 / 3.0)
    # Frequent events: the residual height (0.6 x 5 m); rare: the nominal height.
    assert_allclose(_check(frequent, "design_height").target, 3.0)
    assert _check(rare, "design_height").target == 5.0
    e = rare.results[0].energy_kj
    assert "99 % fractile" in _check(rare, "design_energy").detail
    assert_allclose(_check(frequent, "design_energy").value, 1.21 * float(
        __import__("numpy").percentile(e, 99)), rtol=1e-9)


def test_an_ead_concept_rejects_a_catalogue_fence_without_its_test_figures(registry, tmp_path):
    text = (DATA / "design_small.yaml").read_text()
    text = text.replace("concept: spang, height_factor: 2.0, energy_factor: 1.0, statistic: p95",
                        "concept: uni11211")
    (tmp_path / "catalogue_costs.yaml").write_text((DATA / "catalogue_costs.yaml").read_text())
    (tmp_path / "catalogue_products.yaml").write_text(
        "fence:\n  RX-050: {capacity_kj: 500, heights: [2, 3]}\n")
    path = tmp_path / "design.yaml"
    path.write_text(text)
    project = load_project(path)
    with pytest.raises(ProjectError, match=r"catalogue_products.yaml:2: .*RX-050.*uni11211.*"
                                           r"max_elongation_m, residual_height_fraction"):
        resolve_design(project, registry)
    # spang does not require them.
    path.write_text((DATA / "design_small.yaml").read_text())
    resolve_design(load_project(path), registry)

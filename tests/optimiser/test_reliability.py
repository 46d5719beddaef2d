"""Design to a target reliability: ``optimise`` with the ``reliability`` concept.

The chosen design's probability that a block reaches the protected zone within
the working life is verified on fresh rocks with its Clopper-Pearson bound
carried through P_f = 1 - exp(-lambda T p) (Marchelli, De Biagi & Peila 2020),
and the report states it with its bound and its assumptions. At two seeds.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from rockfall_design_builtins.safety_reliability import life_probability

from rockfall_design.judge.bounds import fraction_upper_bound
from rockfall_design.judge.evaluation import evaluate, evaluate_design
from rockfall_design.judge.placing import build_concept
from rockfall_design.optimiser import optimise
from rockfall_design.project import load_project_text
from rockfall_design.report.design_values import how_sure

PROJECTS = Path(__file__).resolve().parents[2] / "projects"

# The talus of tests/optimiser/test_optimise.py with heavier blocks, one fence
# family, at most 800 rocks: lambda T = 0.2/year x 50 years = 10 falls, P_t =
# 0.2, so p_max = -ln(0.8)/10 = 2.2 % per block, which a few hundred rocks can
# show. The target binds: about 4 % of the blocks break through the 500 kJ
# RX-050 at x = 60 m (p95 energy 468 kJ, max 1,170 kJ on 800 rocks), a few
# per mille through the 1,000 kJ RX-100.
RELIABLE = """
name: Small talus slope, designed to a target reliability
slope:
  points: [[0, 60], [12, 55], [85, 4], [92, 0], [175, -2]]
  materials: [talus, talus, talus, meadow]
materials:
  talus: {restitution: 0.25, friction: 0.6, rolling_resistance: 0.6, roughness_deg: 4,
          scatter: {restitution: 0.03, friction: 0.05, rolling_resistance: 0.05}}
  meadow: {restitution: 0.15, friction: 0.7, rolling_resistance: 0.7, roughness_deg: 3}
rocks:
  count: 400
  seed: SEED
  density: 2650
  volume: {lognormal: [1.5, 0.4]}
  release: {x: [14, 22], height: 0.5, velocity: [1.0, 0], spin: 0}
protect:
  x: 150
safety: {concept: reliability, annual_falls: 0.2, working_life_years: 50,
         target_failure_probability: 0.2}
design:
  max_measures: 1
  max_rocks: 800
  residual: {fraction: 0.05}
  site: {length_m: 100}
  products: PRODUCTS
  costs: {model: unit_prices, file: COSTS}
  candidates:
    - type: fence
      x: [58, 64]
      product: [RX-050, RX-100, RX-150]
"""

TARGET, FALLS = 0.2, 0.2 * 50


def _project(seed: int):
    text = (RELIABLE.replace("SEED", str(seed))
            .replace("PRODUCTS", str(PROJECTS / "catalogue_products.yaml"))
            .replace("COSTS", str(PROJECTS / "catalogue_costs.yaml")))
    return load_project_text(text, "reliable.yaml")


@pytest.mark.parametrize("seed", [5, 23])
def test_optimise_meets_a_target_reliability_verified_on_fresh_rocks(registry, seed):
    project = _project(seed)
    res = optimise(project, registry)
    best = res.best
    assert best is not None and best.holds, res.reason
    # The cheaper RX-050 lets too many blocks through: the target chose RX-100.
    assert [m.params.product for m in best.measures] == ["RX-100"]
    # The concept sets the allowance: p_max = -ln(1 - P_t) / (lambda T) < 5 %.
    concept = build_concept(project, registry)
    p_max = concept.allowed_residual_fraction()
    assert 0.0223 < p_max < 0.0224
    # On the fresh rocks that verified it, the life probability's upper bound
    # (Clopper-Pearson on k/n, through 1 - exp(-lambda T p)) is within the target.
    k, n = best.fresh_residual, best.fresh_rocks
    assert n >= 2 * best.decision_rocks
    upper = life_probability(fraction_upper_bound(k, n, 0.95), FALLS)
    assert upper <= TARGET
    zone, *_, assumptions = best.fresh_statements
    assert f"x {k:,}/{n:,})" in zone and f"at most {upper:.3g} with 95 % confidence" in zone
    assert "within the target 0.2" in zone
    for words in ("Poisson process of 0.2 a year", "working life of 50 years",
                  "10 falls expected", "fair sample", "independently"):
        assert words in assumptions
    # Each measure's own probability (a block passing it) holds on the fresh rocks too.
    assert best.fresh_failures == []
    # The report says it, under "How sure".
    summary = res.summary()
    assert summary["best"]["fresh_statements"] == best.fresh_statements


def test_the_chosen_design_holds_again_on_rocks_of_a_third_seed(registry):
    """Neither the search's nor the verification's rocks: the point value is within target."""
    project = _project(5)
    best = optimise(project, registry).best
    concept = build_concept(project, registry)
    ev = evaluate_design(project, registry, best.measures, concept, rocks=800, seed=777)
    k, n = ev.protect["reaching"], 800
    assert life_probability(k / n, FALLS) <= TARGET
    (zone, fence, assumptions) = ev.statements()
    assert "reaching the protected zone" in zone and "passing fence" in fence


def test_check_states_the_life_probability_with_its_bound_and_assumptions(registry):
    """``check`` of the RX-050 alone: the report's "How sure" says it misses the target."""
    project = load_project_text(
        RELIABLE.replace("SEED", "5").split("design:")[0]
        + "measures:\n  - {type: fence, x: 60, height: 2, capacity_kj: 500, "
        "max_elongation_m: 4.5, residual_height_fraction: 0.6}\n", "check.yaml")
    ev = evaluate(project, registry, rocks=800)
    summary = ev.summary()
    zone, fence, assumptions = summary["concept_statements"]
    (res,) = ev.results
    k = res.passed_over + res.broken_through + res.passed_through_gap
    assert k > 0.0223 * 800  # more than p_max of the blocks pass the fence
    assert f"x {k:,}/800)" in fence and "above the target 0.2" in fence
    assert "Poisson process" in assumptions
    lines = how_sure(summary)
    assert lines[-3:] == [zone, fence, assumptions]


def test_the_optimise_report_states_the_fresh_probability_and_its_assumptions(tmp_path,
                                                                               capsys):
    from rockfall_design.cli.program import main

    text = (RELIABLE.replace("SEED", "5")
            .replace("PRODUCTS", str(PROJECTS / "catalogue_products.yaml"))
            .replace("COSTS", str(PROJECTS / "catalogue_costs.yaml")))
    path = tmp_path / "reliable.yaml"
    path.write_text(text, encoding="utf-8")
    assert main(["optimise", str(path), "--report", str(tmp_path / "report")]) == 0
    panel = capsys.readouterr().out
    for name in ("report.md", "report.html"):
        page = " ".join((tmp_path / "report" / name).read_text(encoding="utf-8").split())
        assert "fresh rocks (seed" in page and "that verified the chosen design" in page
        assert "Probability of at least one block reaching the protected zone" in page
        assert "with 95 % confidence (the Clopper-Pearson upper bound" in page
        assert "Poisson process of 0.2 a year over a working life of 50 years" in page
    assert "Poisson process of 0.2 a year" in " ".join(panel.split())

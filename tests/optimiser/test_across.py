"""Designs across the scenarios of a study: check --scenarios, optimise with design.scenarios."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rockfall_design.cli.program import main
from rockfall_design.errors import ProjectError
from rockfall_design.project import load_project_text
from rockfall_design.studies.sampling import required_scenarios

ROOT = Path(__file__).resolve().parents[2]
PROJECTS = ROOT / "projects"

# The small slope of test_optimise.py, with a study of four scenarios: the
# restitution of the talus and the median rock volume, two values each.
SMALL = """\
name: Small talus slope
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
  volume: {lognormal: [0.8, 0.4]}
  release: {x: [14, 22], height: 0.5, velocity: [1.0, 0], spin: 0}
protect:
  x: 150
measures:
  - {type: fence, x: 60, height: 3, capacity_kj: 1000}
safety: {concept: spang, height_factor: 2.0, energy_factor: 1.0, statistic: p95}
study:
  vary:
    materials.talus.restitution: [0.2, 0.3]
    rocks.volume.lognormal.0: [0.5, 1.2]
  scenarios: grid
design:
  scenarios: SCENARIOS
  max_measures: 1
  max_rocks: 400
  residual: {fraction: 0.02}
  site: {length_m: 100}
  products: PRODUCTS
  costs: {model: unit_prices, file: COSTS}
  candidates:
    - type: fence
      x: [58, 64]
      product: [RX-050, RX-100, RX-150]
"""


def study_text(seed: int = 3, scenarios: str = "all") -> str:
    """The small study project (four scenarios) at ``seed`` with ``design.scenarios``."""
    return (SMALL.replace("SEED", str(seed)).replace("SCENARIOS", scenarios)
            .replace("PRODUCTS", str(PROJECTS / "catalogue_products.yaml"))
            .replace("COSTS", str(PROJECTS / "catalogue_costs.yaml")))


def _write(tmp_path: Path, text: str, name: str = "p.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _json(capsys) -> dict:
    return json.loads(capsys.readouterr().out)


def test_workers_without_scenarios_is_refused(tmp_path, capsys):
    assert main(["check", str(_write(tmp_path, study_text())), "--workers", "2"]) == 2
    assert "give --scenarios too" in capsys.readouterr().err


def test_required_scenarios():
    assert required_scenarios(1.0, 9) == 9
    assert required_scenarios(0.9, 9) == 9    # ceil(8.1)
    assert required_scenarios(0.5, 4) == 2
    assert required_scenarios(0.01, 4) == 1
    assert required_scenarios(0.25, 4) == 1   # exactly a quarter: no rounding up


def test_design_scenarios_is_checked_where_written():
    with pytest.raises(ProjectError, match=r"p.yaml:26: design.scenarios.share: expected a "
                                           r"number > 0 and <= 1, got 1.5"):
        load_project_text(study_text(scenarios="{share: 1.5}"), "p.yaml")
    with pytest.raises(ProjectError, match=r"p.yaml:26: design.scenarios: expected all or"):
        load_project_text(study_text(scenarios="most"), "p.yaml")
    no_study = study_text().replace("study:\n  vary:\n    materials.talus.restitution: [0.2, 0.3]\n"
                               "    rocks.volume.lognormal.0: [0.5, 1.2]\n  scenarios: grid\n",
                               "")
    with pytest.raises(ProjectError, match=r"design.scenarios: the design's scenarios are "
                                           "those of a study"):
        load_project_text(no_study, "p.yaml")
    share = load_project_text(study_text(scenarios="{share: 0.5}"), "p.yaml")
    assert share.design.scenario_share == 0.5
    assert share.resolved_dict()["design"]["scenarios"] == {"share": 0.5}


def test_a_design_without_scenarios_keeps_its_record():
    text = study_text().replace("  scenarios: all\n", "")
    project = load_project_text(text, "p.yaml")
    assert project.design.scenarios is None
    assert "scenarios" not in project.resolved_dict()["design"]  # the hash is as before


def test_check_scenarios_reports_every_scenario_and_the_binding_one(tmp_path, capsys):
    path = _write(tmp_path, study_text())
    assert main(["check", str(path), "--scenarios", "--json", "--workers", "1"]) == 0
    out = _json(capsys)
    # the same numbers on a pool of processes (each scenario carries its seed)
    assert main(["check", str(path), "--scenarios", "--json", "--workers", "2"]) == 0
    pooled = _json(capsys)
    for a, b in zip(out["scenarios"], pooled["scenarios"], strict=True):
        a.pop("runtime_s"), b.pop("runtime_s")
        assert a == b
    assert out["of"] == 4 and out["required"] == 4 and out["holds_in"] == 4 and out["ok"]
    assert [s["index"] for s in out["scenarios"]] == [0, 1, 2, 3]
    assert len({s["seed"] for s in out["scenarios"]}) == 4
    assert out["scenarios"][3]["values"] == {"materials.talus.restitution": 0.3,
                                             "rocks.volume.lognormal.0": 1.2}
    margins = [s["margin"] for s in out["scenarios"]]
    assert out["binding"]["margin"] == min(margins)
    # bigger rocks carry more energy and fly higher: they bind
    assert out["binding"]["values"]["rocks.volume.lognormal.0"] == 1.2
    for s in out["scenarios"]:  # each scenario's block is check's own JSON
        assert s["measures"][0]["type"] == "fence" and "protect" in s


def test_check_scenarios_fails_and_names_the_scenarios(tmp_path, capsys):
    # 300 kJ holds the small rocks (scenarios 0 and 2), not the big ones (1 and 3):
    # margins of +55 % and -25 % or more on seeds 3, 4 and 5
    weak = study_text().replace("capacity_kj: 1000", "capacity_kj: 300")
    path = _write(tmp_path, weak)
    assert main(["check", str(path), "--scenarios", "--json", "--workers", "1"]) == 1
    out = _json(capsys)
    assert out["holds_in"] == 2 and out["required"] == 4 and not out["ok"]
    assert [s["ok"] for s in out["scenarios"]] == [True, False, True, False]
    assert out["binding"]["index"] in (1, 3) and out["binding"]["margin"] < 0
    assert {f.split(" (")[0] for f in out["failures"]} == {"scenario 1", "scenario 3"}
    # half of the scenarios is what it holds in
    half = _write(tmp_path, weak.replace("scenarios: all", "scenarios: {share: 0.5}"), "q.yaml")
    assert main(["check", str(half), "--scenarios", "--workers", "1"]) == 0
    text = capsys.readouterr().out
    assert "Binding scenario" in text and "Design holds in 2 of 4 scenarios; required: 2" in text


@pytest.mark.parametrize("seed", [3, 4])
def test_optimise_across_all_scenarios_passes_check_in_every_scenario(tmp_path, capsys, seed):
    path = _write(tmp_path, study_text(seed))
    out_dir = tmp_path / "out"
    assert main(["optimise", str(path), "--json", "--out", str(out_dir)]) == 0
    out = _json(capsys)
    block = out["scenarios"]
    assert block["of"] == 4 and block["required"] == 4
    assert all(r["admitted"] and r["holds_on_fresh_rocks"] for r in block["per_scenario"])
    assert block["binding"]["index"] in range(4)
    assert block["binding"]["margin"] == min(r["margin"] for r in block["per_scenario"])
    head = (out_dir / "design.yaml").read_text()
    assert "binding scenario" in head and "check design.yaml --scenarios" in head
    # the done-when: the design passes check in every scenario
    design = str(out_dir / "design.yaml")
    assert main(["check", design, "--scenarios", "--json", "--workers", "1"]) == 0
    checked = _json(capsys)
    assert checked["holds_in"] == 4 and checked["holds_with_confidence_in"] == 4
    assert [s["seed"] for s in checked["scenarios"]] == [s["seed"] for s in block["scenarios"]]


def test_a_share_of_the_scenarios_never_costs_more_than_all(tmp_path, capsys):
    costs = {}
    for share in ("all", "{share: 0.5}"):
        path = _write(tmp_path, study_text(3, share))
        assert main(["optimise", str(path), "--json"]) == 0
        out = _json(capsys)
        best = next(a for a in out["alternatives"] if a["name"] == out["best"]["name"])
        costs[share] = best["cost"]
        assert sum(r["holds_on_fresh_rocks"] is True
                   for r in out["scenarios"]["per_scenario"]) >= out["scenarios"]["required"]
    assert costs["{share: 0.5}"] <= costs["all"]


def test_optimise_across_terminal_report_names_the_binding_scenario(tmp_path, capsys):
    path = _write(tmp_path, study_text())
    assert main(["optimise", str(path)]) == 0
    text = capsys.readouterr().out
    assert "a design must hold in 4 of 4" in text and "Binding scenario" in text

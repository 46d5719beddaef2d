"""Every bundled example project runs as it is."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rockfall_design.cli import main
from rockfall_design.project import Project, load_corridor

from .plugin_helpers import install_embankment_example

# Catalogue files (products, prices) and the materials library live beside the
# projects but are not projects.
PROJECTS = sorted(
    p
    for p in (Path(__file__).resolve().parents[1] / "projects").glob("*.yaml")
    if not p.name.startswith("catalogue_") and p.name != "materials.yaml"
)


@pytest.mark.parametrize("path", PROJECTS, ids=[p.stem for p in PROJECTS])
def test_example_project_runs(path, capsys, tmp_path, monkeypatch):
    if path.name == "design_embankment.yaml":  # its candidate is the example plugin's
        install_embankment_example(tmp_path, monkeypatch)
    loaded = load_corridor(path)
    if isinstance(loaded, Project):
        projects = [loaded]
    else:  # a corridor: every section runs, the totals add them up
        projects = [s.project for s in loaded.sections]
    if any(p.measures for p in projects):
        code = main(["check", str(path), "--rocks", "30", "--json"])
        assert code in (0, 1)
    else:
        assert main(["simulate", str(path), "--rocks", "30", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    if isinstance(loaded, Project):
        assert out["rocks"] == 30
    else:
        assert out["totals"]["rocks"] == 30 * len(projects)
        assert [s["rocks"] for s in out["sections"]] == [30] * len(projects)


#: Examples whose file says they hold: each must hold with confidence at its own seed and
#: rocks, and at two fresh seeds with twice its rocks (issue 25: no example that holds
#: only at its own seed). The seeds were chosen before the design was checked with them.
HOLDING = ("quarry_fence_ditch.yaml",)
FRESH_SEEDS = (1001, 1002)


def test_the_examples_that_say_they_hold_are_the_ones_checked_here():
    said = {p.name for p in PROJECTS
            if "holds with confidence" in " ".join(
                line.lstrip("# ") for line in p.read_text().splitlines()
                if line.startswith("#"))}
    assert said == set(HOLDING)
    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    assert "passes" not in readme.split("Other bundled projects", 1)[1]


@pytest.mark.parametrize("name", HOLDING)
def test_an_example_that_says_it_holds_holds_with_confidence_at_fresh_seeds(name, capsys):
    import rockfall_design as rd

    path = Path(__file__).resolve().parents[1] / "projects" / name
    project = rd.load_project(path)
    n = project.rocks.count
    runs = [(project.rocks.seed, n)] + [(s, 2 * n) for s in FRESH_SEEDS]
    for seed, rocks in runs:
        code = main(["check", str(path), "--seed", str(seed), "--rocks", str(rocks), "--json"])
        out = json.loads(capsys.readouterr().out)
        assert out["verdict"]["state"] == "holds with confidence", (seed, rocks, out["verdict"])
        assert code == 0 and out["ok"] and out["holds_with_confidence"]


def test_the_spang_default_statistic_is_the_percentile_the_readme_advises():
    from rockfall_design_builtins.safety import SpangConcept

    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    assert "statistic: p95" in readme
    assert SpangConcept.Params().statistic == "p95"

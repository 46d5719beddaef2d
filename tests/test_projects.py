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

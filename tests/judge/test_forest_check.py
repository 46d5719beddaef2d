"""A protection forest checked as a measure: the stand reaches the engine, the run counts it."""

from __future__ import annotations

from pathlib import Path

import rockfall_design as rd
from rockfall_design.judge.placing import build_measures, edited_section, place_measures
from rockfall_design.plugins import load_registry
from rockfall_design.project import load_project
from rockfall_design.run.releases import section_from_project

PROJECTS = Path(__file__).resolve().parents[2] / "projects"

MEASURES = """
measures:
  - type: protection_forest
    x: 30
    length: 50
    stems_per_ha: 800
    dbh_mean_cm: 35
  - type: fence           # a fence may stand inside a forest: the ground is kept
    x: 70
    height: 4.0
    capacity_kj: 1000
"""


def _project(tmp_path: Path) -> Path:
    text = (PROJECTS / "design_forest_or_fence.yaml").read_text(encoding="utf-8")
    text = text.split("design:")[0] + MEASURES
    path = tmp_path / "forest.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def test_the_forest_gives_its_stretch_forested_copies_of_the_ground(tmp_path):
    project = load_project(_project(tmp_path))
    registry = load_registry()
    bare = section_from_project(project)
    placed = place_measures(project, registry, build_measures(project, registry), bare)
    section = edited_section(project, bare, placed)
    assert section.forested and not bare.forested
    mids = 0.5 * (section.x[1:] + section.x[:-1])
    stems = [section.materials[m].stems_per_ha for m in section.segment_material]
    for xm, n in zip(mids, stems, strict=True):
        assert n == (800.0 if 30.0 < xm < 80.0 else 0.0)
    # The ground itself is the bare section's.
    assert (abs(section.ground_height(bare.x) - bare.y) < 1e-9).all()


def test_a_check_reports_what_the_forest_did(tmp_path):
    c = rd.check(_project(tmp_path), rocks=400, seed=3, trajectories=3)
    f = c.summary["forest"]
    assert 0 < f["met_stems"] <= 400 and 0 <= f["stopped"] <= f["met_stems"]
    s = f["stopped_share"]
    assert s["lower"] <= f["stopped"] / 400 <= s["upper"]

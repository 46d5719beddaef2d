"""A material's forest: accepted with its defaults, one clear line for a bad key, in SI."""

from __future__ import annotations

import pytest

from rockfall_design.engine import columns
from rockfall_design.errors import ProjectError
from rockfall_design.project import load_project
from rockfall_design.project.schema import DEFAULT_TREE_HEIGHT_M
from rockfall_design.run.releases import section_from_project

PROJECT = """\
name: t
description: t
slope:
  points: [[0, 30], [40, 10], [80, 10]]
  materials: [g, w]
materials:
  g: {{restitution: 0.3, friction: 0.6}}
  w: {{restitution: 0.3, friction: 0.6, forest: {{{forest}}}}}
rocks: {{count: 10, seed: 1, radius: 0.4, release: {{x: 1, height: 1, velocity: [0.5, 0]}}}}
protect: {{x: 70}}
"""


def _load(tmp_path, forest):
    path = tmp_path / "p.yaml"
    path.write_text(PROJECT.format(forest=forest))
    return load_project(path)


def test_a_forest_reaches_the_engine_in_its_units(tmp_path):
    p = _load(tmp_path, "stems_per_ha: 600, dbh_mean_cm: 30, dbh_sd_cm: 8")
    f = p.materials["w"].forest
    assert (f.stems_per_ha, f.dbh_mean_cm, f.dbh_sd_cm) == (600.0, 30.0, 8.0)
    assert f.tree_height_m == DEFAULT_TREE_HEIGHT_M
    section = section_from_project(p)
    assert section.forested
    row = section.material_table()[1]
    assert row[columns.M_STEMS] == pytest.approx(0.06)  # stems per m^2
    assert row[columns.M_DBH] == pytest.approx(0.30)
    assert row[columns.M_SD_DBH] == pytest.approx(0.08)
    assert section.material_table()[0][columns.M_STEMS] == 0.0


@pytest.mark.parametrize(("forest", "message"), [
    ("stems_per_ha: 0, dbh_mean_cm: 30", "stems_per_ha"),
    ("stems_per_ha: 600", "dbh_mean_cm"),
    ("stems_per_ha: 600, dbh_mean_cm: 30, dbh_sd_cm: 40", "dbh_sd_cm: must be at most"),
    ("stems_per_ha: 600, dbh_mean_cm: 30, tree_height: 5", "tree_height"),
    ("stems_per_ha: 50000, dbh_mean_cm: 30", "stems_per_ha"),
])
def test_a_bad_forest_key_is_one_clear_error(tmp_path, forest, message):
    with pytest.raises(ProjectError, match=message) as err:
        _load(tmp_path, forest)
    text = str(err.value)
    assert "p.yaml" in text and "forest" in text and "\n" not in text.strip()


def test_a_material_without_trees_records_and_hashes_as_before(tmp_path):
    """The resolved record leaves out forest: where there is none (golden hashes unchanged)."""
    p = _load(tmp_path, "stems_per_ha: 600, dbh_mean_cm: 30")
    materials = p.resolved_dict()["materials"]
    assert "forest" not in materials["g"]
    assert materials["w"]["forest"]["stems_per_ha"] == 600.0

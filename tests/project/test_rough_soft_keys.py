"""The rough_soft keys and a material's ranges: accepted where they belong, one clear line else."""

from __future__ import annotations

from pathlib import Path

import pytest

from rockfall_design.errors import ProjectError
from rockfall_design.project import load_project

LIBRARY = Path(__file__).resolve().parents[2] / "projects" / "materials.yaml"

PROJECT = """\
name: t
description: t
slope:
  points: [[0, 30], [40, 10], [80, 10]]
  materials: g
materials:
  g: {{{material}}}
rocks: {{count: 10, seed: 1, radius: 0.4, release: {{x: 1, height: 1, velocity: [0.5, 0]}}}}
protect: {{x: 70}}
"""


def _load(tmp_path, material):
    path = tmp_path / "p.yaml"
    path.write_text(PROJECT.format(material=material))
    return load_project(path)


def test_rough_soft_takes_its_keys_and_ranges(tmp_path):
    p = _load(tmp_path, "impact_model: rough_soft, restitution: 0.3, friction: 0.6, "
                        "rolling_resistance: 0.2, obstacle_height_m: 0.1, drag_speed_ms: 6, "
                        "ranges: {restitution: [0.2, 0.4], drag_speed_ms: [2, 15]}")
    m = p.materials["g"]
    assert (m.obstacle_height_m, m.drag_speed_ms) == (0.1, 6.0)
    assert m.ranges == {"restitution": (0.2, 0.4), "drag_speed_ms": (2.0, 15.0)}


@pytest.mark.parametrize(("material", "message"), [
    ("restitution: 0.3, friction: 0.6, obstacle_height_m: 0.1",
     "obstacle_height_m: only for impact_model rough_soft"),
    ("restitution: 0.3, friction: 0.6, drag_speed_ms: 5", "drag_speed_ms: only for"),
    ("restitution: 0.3, friction: 0.6, ranges: {restitution: [0.4, 0.5]}",
     r"the range \[0.4, 0.5\] must hold the value 0.3"),
    ("restitution: 0.3, friction: 0.6, ranges: {colour: [0, 1]}",
     "'colour' is not a numeric parameter"),
])
def test_misplaced_keys_are_one_clear_error(tmp_path, material, message):
    with pytest.raises(ProjectError, match=message) as err:
        _load(tmp_path, material)
    assert "p.yaml" in str(err.value)


CALIBRATE = """\
calibrate:
  observed: stops.csv
  fit: auto
"""


def test_fit_auto_takes_each_section_materials_calibrated_parameters_and_ranges(tmp_path):
    path = tmp_path / "p.yaml"
    text = PROJECT.replace("materials: g", "materials: [ground_vegetated_slope, ground_hard_floor]")
    text = text.replace("  g: {{{material}}}", f"  library: {LIBRARY}")
    path.write_text(text.format() + CALIBRATE)
    (tmp_path / "stops.csv").write_text("x\n60\n")
    p = load_project(path)
    # rough_soft: the soil's resistance alone; restitution and obstacle height stay at
    # the class's values (stops do not identify them, docs/calibration.md).
    assert p.calibrate.fit == {
        "materials.ground_vegetated_slope.rolling_resistance": (0.05, 0.6),
        "materials.ground_hard_floor.rolling_resistance": (0.02, 0.4),
    }


def test_fit_auto_without_ranges_says_which_range_is_missing(tmp_path):
    path = tmp_path / "p.yaml"
    path.write_text(PROJECT.format(material="restitution: 0.3, friction: 0.6") + CALIBRATE)
    (tmp_path / "stops.csv").write_text("x\n60\n")
    with pytest.raises(ProjectError, match="fit: auto needs the range of "
                                           "materials.g.restitution"):
        load_project(path)


def test_fit_auto_takes_three_rough_soft_grounds(tmp_path):
    """Three inputs (three ground classes, one calibrated parameter each), as on Authume P1."""
    path = tmp_path / "p.yaml"
    text = PROJECT.replace("[80, 10]]", "[80, 10], [120, 9]]").replace(
        "materials: g", "materials: [ground_vegetated_slope, ground_hard_floor, ground_rock_face]")
    text = text.replace("  g: {{{material}}}", f"  library: {LIBRARY}")
    path.write_text(text.format() + CALIBRATE)
    (tmp_path / "stops.csv").write_text("x\n60\n")
    assert len(load_project(path).calibrate.fit) == 3

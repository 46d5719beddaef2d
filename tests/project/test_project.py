"""Tests of the project file: loading, normalisation, round trip and error lines."""

import copy
import json
import math
import pickle
from typing import Literal

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pydantic import BaseModel, ConfigDict, Field, model_validator

from rockfall_design.engine.columns import CONTACT_HOP_RATIO
from rockfall_design.errors import ExitCode, InputError, ProjectError, RockfallError
from rockfall_design.project import (
    Project,
    SizeSpec,
    load_project,
    load_project_text,
)

EXAMPLE = """\
name: Standard slope
description: ""
slope:
  points: [[0, 100], [30, 60], [60, 30], [80, 20], [120, 15], [200, 12]]
  materials: talus
materials:
  talus:
    impact_model: spang
    restitution: 0.35
    friction: 0.58
    rolling_resistance: 0.3
    velocity_scaling: false
    velocity_scaling_k: 9.144
    roughness_deg: 5
    scatter: {restitution: 0.05, friction: 0.05, rolling_resistance: 0.02}
rocks:
  count: 1000
  seed: 42
  density: 2650
  radius: 0.5
  release:
    x: 1
    height: 0
    velocity: [0.6, -0.8]
    spin: 0
    weight: 1
analysis:
  stations: [80]
  percentiles: [50, 95, 99]
  envelope_points: 201
protect:
  x: 150
engine:
  v_contact: 0.5
  v_stop: 0.05
  max_events: 10000
  max_chord_deg: 5.0
"""

MINIMAL = """\
name: Minimal
slope:
  points: [[0, 10], [10, 0]]
  materials: rock
materials:
  rock: {restitution: 0.3, friction: 0.5}
rocks:
  mass: 100
  release: {x: 0}
"""


def line_of(text: str, needle: str, occurrence: int = 1) -> int:
    """1-based line of the ``occurrence``-th line containing ``needle``."""
    hits = [i for i, line in enumerate(text.splitlines(), start=1) if needle in line]
    assert len(hits) >= occurrence, f"{needle!r} not in text"
    return hits[occurrence - 1]


def edit(old: str, new: str, text: str = EXAMPLE) -> str:
    assert text.count(old) == 1, f"{old!r} must occur once"
    return text.replace(old, new)


def load_error(text: str) -> ProjectError:
    with pytest.raises(ProjectError) as info:
        load_project_text(text, source="p.yaml")
    message = str(info.value)
    assert "\n" not in message and "\r" not in message
    return info.value


def assert_error(text: str, line: int | None, key: str, *fragments: str) -> ProjectError:
    err = load_error(text)
    prefix = "p.yaml" if line is None else f"p.yaml:{line}"
    prefix += f": {key}: " if key else ": "
    assert str(err).startswith(prefix), f"{str(err)!r} does not start with {prefix!r}"
    for fragment in fragments:
        assert fragment in err.message, f"{fragment!r} not in {err.message!r}"
    assert err.line == line and err.key == key and err.file == "p.yaml"
    return err


# --------------------------------------------------------------------------------------
# Loading and normalisation
# --------------------------------------------------------------------------------------


def test_example_loads_and_normalises():
    project = load_project_text(EXAMPLE)
    assert project.name == "Standard slope"
    assert project.source == "<string>"
    assert project.slope.points[3] == (80.0, 20.0)
    assert project.slope.n_segments == 5
    assert project.slope.materials == ["talus"] * 5
    talus = project.materials["talus"]
    assert talus.impact_model == "spang"
    assert talus.tangential_restitution is None
    assert talus.scatter.rolling_resistance == 0.02
    assert talus.roughness_deg == 5.0 and isinstance(talus.roughness_deg, float)
    rocks = project.rocks
    assert (rocks.count, rocks.seed, rocks.density) == (1000, 42, 2650.0)
    assert rocks.size_quantity == "radius"
    assert rocks.size == SizeSpec(kind="fixed", a=0.5, b=0.5)
    assert rocks.volume is None and rocks.mass is None
    assert len(rocks.release) == 1
    zone = rocks.release[0]
    assert zone.x == (1.0, 1.0)
    assert zone.velocity == (0.6, -0.8)
    assert zone.spin == 0.0 and zone.weight == 1.0
    assert project.analysis.stations == [80.0]
    assert project.protect is not None and project.protect.x == 150.0
    assert project.engine.max_events == 10000


def test_defaults_are_filled_in():
    project = load_project_text(MINIMAL)
    assert project.description == ""
    rock = project.materials["rock"]
    assert rock.impact_model == "spang"
    assert rock.rolling_resistance == 0.0
    assert rock.velocity_scaling is False and rock.velocity_scaling_k == 9.144
    assert rock.scatter.restitution == rock.scatter.friction == 0.0
    assert project.rocks.count == 1000 and project.rocks.seed == 0
    assert project.rocks.density == 2650.0
    assert project.rocks.size_quantity == "mass"
    zone = project.rocks.release[0]
    assert (zone.x, zone.height, zone.velocity, zone.spin, zone.weight) == (
        (0.0, 0.0),
        0.0,
        (0.0, 0.0),
        0.0,
        1.0,
    )
    assert project.analysis.stations == []
    assert project.analysis.percentiles == [50.0, 95.0, 99.0]
    assert project.analysis.envelope_points == 201
    assert project.protect is None
    engine = project.engine
    assert (engine.v_contact, engine.v_stop, engine.max_events, engine.max_chord_deg,
            engine.contact_hop_ratio) == (0.05, 0.05, 10000, 5.0, CONTACT_HOP_RATIO)


def test_long_forms_and_distributions():
    text = edit("  materials: rock\n", "  materials: [rock]\n", MINIMAL)
    text = edit("  mass: 100\n", "  volume: {lognormal: [0.2, 0.5]}\n", text)
    text = edit(
        "  release: {x: 0}\n",
        "  release:\n  - {x: [0, 5], spin: rolling}\n  - {x: 10, weight: 2}\n",
        text,
    )
    text = edit(
        "  rock: {restitution: 0.3, friction: 0.5}\n",
        "  rock: {impact_model: rn_rt, restitution: 0.3, tangential_restitution: 0.8,"
        " friction: 0.5}\n",
        text,
    )
    project = load_project_text(text)
    assert project.slope.materials == ["rock"]
    assert project.rocks.size_quantity == "volume"
    assert project.rocks.size == SizeSpec(kind="lognormal", a=0.2, b=0.5)
    assert [z.x for z in project.rocks.release] == [(0.0, 5.0), (10.0, 10.0)]
    assert project.rocks.release[0].spin == "rolling"
    assert project.materials["rock"].tangential_restitution == 0.8
    again = load_project_text(yaml.safe_dump(project.resolved_dict()))
    assert again.resolved_dict() == project.resolved_dict()


@pytest.mark.parametrize(
    ("size", "expected"),
    [
        ("2.5", SizeSpec(kind="fixed", a=2.5, b=2.5)),
        ("{uniform: [0.2, 0.4]}", SizeSpec(kind="uniform", a=0.2, b=0.4)),
        ("{normal: [0.5, 0]}", SizeSpec(kind="normal", a=0.5, b=0.0)),
    ],
)
def test_size_forms(size, expected):
    project = load_project_text(edit("  mass: 100\n", f"  radius: {size}\n", MINIMAL))
    assert project.rocks.radius == expected
    assert project.rocks.size == expected


def test_per_segment_materials():
    text = edit("  materials: talus\n", "  materials: [talus, talus, scree, talus, scree]\n")
    text = edit(
        "materials:\n  talus:\n",
        "materials:\n  scree: {restitution: 0.2, friction: 0.7}\n  talus:\n",
        text,
    )
    project = load_project_text(text)
    assert project.slope.materials == ["talus", "talus", "scree", "talus", "scree"]


def test_empty_optional_sections_mean_defaults():
    project = load_project_text(MINIMAL + "analysis:\nengine:\nprotect:\n")
    assert project.analysis.percentiles == [50.0, 95.0, 99.0]
    assert project.engine.v_stop == 0.05
    assert project.protect is None


def test_scientific_notation_and_dates():
    text = edit("  mass: 100\n", "  mass: 1e2\n", MINIMAL)
    text = edit("name: Minimal\n", "name: 2024-05-01\n", text)
    project = load_project_text(text)
    assert project.rocks.mass == SizeSpec(kind="fixed", a=100.0, b=100.0)
    assert project.name == "2024-05-01"


def test_yaml_merge_keys_are_supported():
    text = edit(
        "materials:\n  rock: {restitution: 0.3, friction: 0.5}\n",
        "materials:\n  base: &base {restitution: 0.3, friction: 0.5}\n"
        "  rock:\n    <<: *base\n    friction: 0.6\n",
        MINIMAL,
    )
    project = load_project_text(text)
    assert project.materials["rock"].friction == 0.6
    assert project.materials["rock"].restitution == 0.3
    bad = edit("    friction: 0.6\n", "    friction: 0.6\n    restitution: 2\n", text)
    assert_error(bad, line_of(bad, "restitution: 2"), "materials.rock.restitution", "<= 1")


def test_load_project_from_file(tmp_path):
    path = tmp_path / "project.yaml"
    path.write_text(EXAMPLE, encoding="utf-8")
    project = load_project(path)
    assert project.source == str(path)
    assert project.resolved_dict() == load_project_text(EXAMPLE).resolved_dict()


def test_missing_file_names_the_file(tmp_path):
    path = tmp_path / "nope.yaml"
    with pytest.raises(ProjectError) as info:
        load_project(path)
    assert str(info.value).startswith(f"{path}: cannot read file")
    assert info.value.exit_code == ExitCode.BAD_INPUT


def test_file_error_locations(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(edit("  density: 2650\n", "  density: 0\n"), encoding="utf-8")
    with pytest.raises(ProjectError) as info:
        load_project(str(path))
    assert str(info.value).startswith(f"{path}:{line_of(EXAMPLE, 'density')}: rocks.density: ")


def test_json_schema_is_available():
    schema = Project.model_json_schema()
    json.dumps(schema)
    assert "rocks" in schema["properties"]


# --------------------------------------------------------------------------------------
# Reproducibility record
# --------------------------------------------------------------------------------------


def test_resolved_dict_round_trips_through_yaml():
    resolved = load_project_text(EXAMPLE).resolved_dict()
    json.dumps(resolved, allow_nan=False)
    again = load_project_text(yaml.safe_dump(resolved, sort_keys=False))
    assert again.resolved_dict() == resolved


def test_resolved_hash_is_stable_and_sensitive():
    first = load_project_text(EXAMPLE).resolved_hash()
    # (int(first, 16) >= 0 could not fail: it raised or held.) A sha256 in hex:
    assert len(first) == 64 and set(first) <= set("0123456789abcdef")
    assert load_project_text(EXAMPLE).resolved_hash() == first
    # the same project written differently (defaults spelt out or not, 1 vs 1.0)
    spelt = edit("  density: 2650\n", "  density: 2650.0\n")
    assert load_project_text(spelt).resolved_hash() == first
    resolved = load_project_text(EXAMPLE).resolved_dict()
    assert load_project_text(yaml.safe_dump(resolved)).resolved_hash() == first
    changed = edit("  seed: 42\n", "  seed: 43\n")
    assert load_project_text(changed).resolved_hash() != first


# --------------------------------------------------------------------------------------
# Errors: one line, with file, line and key path
# --------------------------------------------------------------------------------------


def test_project_error_format():
    err = ProjectError("a.yaml", 3, "rocks.count", "bad\nthing")
    assert str(err) == "a.yaml:3: rocks.count: bad thing"
    assert str(ProjectError("a.yaml", None, "", "empty")) == "a.yaml: empty"
    assert str(ProjectError("a.yaml", 7, "", "broken")) == "a.yaml:7: broken"
    assert isinstance(err, InputError) and isinstance(err, RockfallError)
    assert err.exit_code == ExitCode.BAD_INPUT == 2
    copy_ = pickle.loads(pickle.dumps(err))
    assert str(copy_) == str(err) and copy_.line == 3


def test_exit_codes():
    assert [int(c) for c in ExitCode] == [0, 1, 2, 3, 130]
    assert RockfallError("x", exit_code=ExitCode.PLUGIN_FAULT).exit_code == 3


def test_malformed_yaml():
    text = edit("  seed: 42\n", "  seed: [42\n")
    err = assert_error(text, line_of(text, "density"), "", "invalid YAML", "column")
    assert err.key == ""


def test_malformed_yaml_bad_indentation():
    text = edit("  count: 1000\n", "   count: 1000\n")
    err = load_error(text)
    assert err.line in (line_of(text, "count"), line_of(text, "seed")) and "invalid YAML" in str(
        err
    )


def test_empty_file_and_non_mapping():
    assert_error("", 1, "", "empty")
    assert_error("# just a comment\n", 1, "", "empty")
    assert_error("- a\n- b\n", 1, "", "expected a mapping")


def test_unknown_key_did_you_mean():
    text = edit("  radius: 0.5\n", "  radus: 0.5\n")
    assert_error(
        text, line_of(text, "radus"), "rocks.radus", "unknown key 'radus'", "did you mean 'radius'?"
    )


def test_unknown_top_level_key():
    text = EXAMPLE + "protection:\n  x: 3\n"
    assert_error(text, line_of(text, "protection"), "protection", "did you mean 'protect'?")


def test_unknown_key_without_close_match():
    text = edit("    roughness_deg: 5\n", "    roughness_deg: 5\n    zzz: 1\n")
    assert_error(
        text, line_of(text, "zzz"), "materials.talus.zzz", "unknown key 'zzz'", "expected one of"
    )


def test_wrong_type_string_for_number():
    text = edit("    restitution: 0.35\n", '    restitution: "0.5"\n')
    assert_error(
        text,
        line_of(text, '"0.5"'),
        "materials.talus.restitution",
        "expected a number",
        "string '0.5'",
    )


def test_wrong_type_list_for_mapping():
    text = edit("  x: 150\n", "  x: [150, 160]\n")
    assert_error(text, line_of(text, "[150, 160]"), "protect.x", "expected a number")


def test_wrong_type_section():
    text = edit("protect:\n  x: 150\n", "protect: 150\n")
    assert_error(text, line_of(text, "protect: 150"), "protect", "expected a mapping")


def test_bool_for_number():
    text = edit("  density: 2650\n", "  density: true\n")
    assert_error(text, line_of(text, "density"), "rocks.density", "expected a number", "boolean")


def test_number_for_bool():
    text = edit("    velocity_scaling: false\n", "    velocity_scaling: 0\n")
    assert_error(
        text,
        line_of(text, "velocity_scaling:"),
        "materials.talus.velocity_scaling",
        "expected true or false",
    )


def test_missing_required_key():
    text = edit("    friction: 0.58\n", "")
    assert_error(text, line_of(text, "  talus:"), "materials.talus.friction", "missing")


def test_missing_top_level_key():
    text = edit("name: Standard slope\n", "")
    assert_error(text, 1, "name", "missing")


@pytest.mark.parametrize("value", ["-1", "0"])
def test_non_positive_radius(value):
    text = edit("  radius: 0.5\n", f"  radius: {value}\n")
    assert_error(
        text, line_of(text, "radius"), "rocks.radius", f"expected a number > 0, got {value}"
    )


def test_bad_uniform_distribution():
    text = edit("  radius: 0.5\n", "  radius: {uniform: [0.5, 0.2]}\n")
    assert_error(text, line_of(text, "radius"), "rocks.radius.uniform", "min <= max")


def test_unknown_distribution():
    text = edit("  radius: 0.5\n", "  radius: {lognormall: [0.5, 0.2]}\n")
    assert_error(
        text, line_of(text, "radius"), "rocks.radius.lognormall", "did you mean 'lognormal'?"
    )


def test_zero_density():
    text = edit("  density: 2650\n", "  density: 0\n")
    assert_error(text, line_of(text, "density"), "rocks.density", "expected a number >= 100, got 0")


def test_zero_count():
    text = edit("  count: 1000\n", "  count: 0\n")
    assert_error(text, line_of(text, "count"), "rocks.count", "expected an integer >= 1, got 0")


def test_fractional_count():
    text = edit("  count: 1000\n", "  count: 10.5\n")
    assert_error(text, line_of(text, "count"), "rocks.count", "expected an integer")


def test_restitution_above_one():
    text = edit("    restitution: 0.35\n", "    restitution: 1.2\n")
    assert_error(
        text,
        line_of(text, "restitution: 1.2"),
        "materials.talus.restitution",
        "expected a number <= 1, got 1.2",
    )


def test_negative_friction():
    text = edit("    friction: 0.58\n", "    friction: -0.1\n")
    assert_error(
        text,
        line_of(text, "friction: -0.1"),
        "materials.talus.friction",
        "expected a number >= 0, got -0.1",
    )


def test_bad_impact_model():
    text = edit("    impact_model: spang\n", "    impact_model: spnag\n")
    assert_error(
        text,
        line_of(text, "impact_model"),
        "materials.talus.impact_model",
        "expected one of spang, rn_rt",
        "did you mean 'spang'?",
    )


def test_x_not_strictly_increasing():
    text = edit("[80, 20]", "[60, 20]")
    assert_error(text, line_of(text, "points:"), "slope.points[3]", "strictly")


def test_x_not_strictly_increasing_block_style():
    text = edit(
        "  points: [[0, 100], [30, 60], [60, 30], [80, 20], [120, 15], [200, 12]]\n",
        "  points:\n  - [0, 100]\n  - [30, 60]\n  - [20, 30]\n  - [200, 12]\n",
    )
    assert_error(text, line_of(text, "[20, 30]"), "slope.points[2]", "strictly")


def test_fewer_than_two_points():
    text = edit(
        "  points: [[0, 100], [30, 60], [60, 30], [80, 20], [120, 15], [200, 12]]\n",
        "  points: [[0, 100]]\n",
    )
    assert_error(text, line_of(text, "points:"), "slope.points", "at least 2 points, got 1")


def test_bad_point():
    text = edit("[30, 60]", "[30, 60, 1]")
    assert_error(text, line_of(text, "points:"), "slope.points[1]", "expected a pair [x, y]")


def test_material_count_mismatch():
    text = edit("  materials: talus\n", "  materials: [talus, talus]\n")
    assert_error(
        text,
        line_of(text, "materials: [talus"),
        "slope.materials",
        "one material name per segment (5)",
    )


def test_undefined_material_did_you_mean():
    text = edit("  materials: talus\n", "  materials: talos\n")
    assert_error(
        text,
        line_of(text, "materials: talos"),
        "slope.materials",
        "undefined material 'talos'",
        "did you mean 'talus'?",
    )


def test_undefined_material_in_list():
    text = edit(
        "  materials: talus\n",
        "  materials:\n  - talus\n  - talus\n  - scree\n  - talus\n  - talus\n",
    )
    assert_error(
        text,
        line_of(text, "- scree"),
        "slope.materials[2]",
        "undefined material 'scree'",
        "defined: talus",
    )


def test_release_outside_the_section():
    text = edit("    x: 1\n", "    x: [150, 250]\n")
    assert_error(
        text,
        line_of(text, "x: [150, 250]"),
        "rocks.release.x",
        "outside the slope section [0, 200]",
    )


def test_second_release_zone_outside_the_section():
    text = edit(
        "  release: {x: 0}\n",
        "  release:\n  - x: 0\n  - x: 5\n  - x: -3\n    weight: 2\n",
        MINIMAL,
    )
    assert_error(text, line_of(text, "x: -3"), "rocks.release[2].x", "outside")


def test_release_range_reversed():
    text = edit("    x: 1\n", "    x: [5, 1]\n")
    assert_error(text, line_of(text, "x: [5, 1]"), "rocks.release.x", "min <= max")


def test_station_outside_the_section():
    text = edit("  stations: [80]\n", "  stations: [80, 201]\n")
    assert_error(
        text, line_of(text, "stations"), "analysis.stations[1]", "station x 201 is outside"
    )


def test_protect_outside_the_section():
    text = edit("  x: 150\n", "  x: -5\n")
    assert_error(text, line_of(text, "x: -5"), "protect.x", "outside")


@pytest.mark.parametrize("value", [".nan", ".inf", "-.inf", ".NaN"])
def test_nan_and_inf_rejected(value):
    text = edit("  v_stop: 0.05\n", f"  v_stop: {value}\n")
    assert_error(text, line_of(text, "v_stop"), "engine.v_stop", "must be finite")


def test_nan_in_a_list():
    text = edit("[120, 15]", "[120, .nan]")
    assert_error(text, line_of(text, "points"), "slope.points[4][1]", "must be finite")


def test_duplicate_keys():
    text = edit("  seed: 42\n", "  seed: 42\n  count: 5\n")
    err = assert_error(text, line_of(text, "count", 2), "rocks.count", "duplicate key 'count'")
    assert f"line {line_of(text, 'count')}" in err.message


def test_duplicate_material_names():
    text = edit("rocks:\n", "  talus: {restitution: 0.1, friction: 0.2}\nrocks:\n")
    assert_error(text, line_of(text, "  talus:", 2), "materials.talus", "duplicate key")


def test_rn_rt_without_tangential_restitution():
    text = edit("    impact_model: spang\n", "    impact_model: rn_rt\n")
    assert_error(
        text,
        line_of(text, "  talus:"),
        "materials.talus.tangential_restitution",
        "required for impact_model rn_rt",
    )


def test_tangential_restitution_rejected_for_spang():
    text = edit("    friction: 0.58\n", "    friction: 0.58\n    tangential_restitution: 0.8\n")
    assert_error(
        text,
        line_of(text, "tangential_restitution"),
        "materials.talus.tangential_restitution",
        "only for impact_model rn_rt",
    )


def test_two_of_radius_volume_mass():
    text = edit("  radius: 0.5\n", "  radius: 0.5\n  mass: 300\n")
    assert_error(
        text,
        line_of(text, "mass: 300"),
        "rocks.mass",
        "only one of radius, volume, mass",
        "radius and mass",
    )


def test_none_of_radius_volume_mass():
    text = edit("  radius: 0.5\n", "")
    assert_error(text, line_of(text, "rocks:"), "rocks.radius", "one of radius")


def test_bad_spin():
    text = edit("    spin: 0\n", "    spin: rollin\n")
    assert_error(text, line_of(text, "spin"), "rocks.release.spin", "'rolling'")


def test_percentile_out_of_range():
    text = edit("  percentiles: [50, 95, 99]\n", "  percentiles: [50, 100]\n")
    assert_error(text, line_of(text, "percentiles"), "analysis.percentiles[1]", "< 100")


def test_bad_scalar_tag_is_a_yaml_error():
    text = edit("  seed: 42\n", "  seed: !!int abc\n")
    assert_error(text, line_of(text, "seed"), "", "invalid YAML")


def test_earliest_problem_in_the_file_is_reported():
    text = edit("  density: 2650\n", "  density: -1\n")
    text = edit("    restitution: 0.35\n", "    restitution: 7\n", text)
    assert_error(text, line_of(text, "restitution: 7"), "materials.talus.restitution")


def test_recursive_alias():
    text = edit("  stations: [80]\n", "  stations: &a [80, *a]\n")
    assert_error(text, line_of(text, "stations"), "analysis.stations[1]", "recursive")


# --------------------------------------------------------------------------------------
# Fuzzing: any input gives a Project or a one-line ProjectError
# --------------------------------------------------------------------------------------

EXAMPLE_DATA = yaml.safe_load(EXAMPLE)

junk = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-(10**6), max_value=10**6),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([-1, -0.5, 0, 1e308, "rolling", "0.5", "", "talus", "uniform"]),
    st.text(max_size=12),
    st.lists(st.one_of(st.integers(-3, 300), st.floats(), st.text(max_size=3)), max_size=4),
    st.dictionaries(
        st.one_of(
            st.sampled_from(["uniform", "normal", "x", "radius", "talus"]), st.text(max_size=5)
        ),
        st.one_of(st.integers(-3, 300), st.lists(st.floats(), max_size=3), st.none()),
        max_size=3,
    ),
)


def _paths(node, prefix=()):
    yield prefix
    if isinstance(node, dict):
        for key, value in node.items():
            yield from _paths(value, prefix + (key,))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            yield from _paths(value, prefix + (i,))


ALL_PATHS = [p for p in _paths(EXAMPLE_DATA) if p]


@st.composite
def mutated_projects(draw, base=None):
    """``base`` (default: EXAMPLE's data) with 1-3 keys deleted or replaced by junk."""
    data = copy.deepcopy(EXAMPLE_DATA if base is None else base)
    paths = ALL_PATHS if base is None else [p for p in _paths(base) if p]
    for _ in range(draw(st.integers(min_value=1, max_value=3))):
        path = draw(st.sampled_from(paths))
        parent = data
        try:
            for key in path[:-1]:
                parent = parent[key]
            parent[path[-1]]
        except (KeyError, IndexError, TypeError):
            continue  # an earlier mutation removed or replaced this path
        if not isinstance(parent, dict | list):
            continue  # an earlier mutation put a scalar (e.g. a string) here
        if draw(st.booleans()) and isinstance(parent, dict):
            del parent[path[-1]]
        else:
            parent[path[-1]] = draw(junk)
    return data


def _check_one(text: str) -> None:
    try:
        project = load_project_text(text, source="fuzz.yaml")
    except ProjectError as err:
        message = str(err)
        assert "\n" not in message and "\r" not in message
        assert message.startswith("fuzz.yaml")
    else:
        # (isinstance(project, Project) could not fail: that is all it returns.)
        assert project.source == "fuzz.yaml" and project.locator.line(()) is not None
        resolved = project.resolved_dict()
        json.dumps(resolved, allow_nan=False)
        assert load_project_text(yaml.safe_dump(resolved)).resolved_dict() == resolved


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated_projects())
def test_mutated_projects_fail_cleanly(data):
    _check_one(yaml.safe_dump(data, sort_keys=False))


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=200))
def test_arbitrary_text_fails_cleanly(text):
    _check_one(text)


@settings(max_examples=200, deadline=None)
@given(st.data())
def test_mutated_text_fails_cleanly(data):
    lines = EXAMPLE.splitlines(keepends=True)
    i = data.draw(st.integers(min_value=0, max_value=len(lines) - 1))
    lines[i] = data.draw(st.sampled_from(["", "  ", "\t", "- ", ": ", "{", "]", "&a", "*a"]))
    _check_one("".join(lines))


# --------------------------------------------------------------------------------------
# Plugin sections: measures and safety (kept raw), protect.allowed_fraction
# --------------------------------------------------------------------------------------

PLUGIN_SECTIONS = """\
measures:
  - type: fence
    x: 70
    height: 4.0
    capacity_kj: 1000
  - type: ditch
    x: 118
    width: 4.0
    depth: 1.5
safety:
  concept: spang
  height_factor: 2.0
  energy_factor: 1.0
  statistic: max
"""

WITH_PLUGINS = edit("protect:\n  x: 150\n", "protect:\n  x: 150\n  allowed_fraction: 0.05\n") + (
    PLUGIN_SECTIONS
)


def plugin_project(text: str = WITH_PLUGINS) -> Project:
    return load_project_text(text, source="p.yaml")


def assert_project_error(err: ProjectError, line: int | None, key: str, *fragments: str) -> None:
    prefix = "p.yaml" if line is None else f"p.yaml:{line}"
    assert str(err).startswith(f"{prefix}: {key}: "), str(err)
    assert (err.file, err.line, err.key) == ("p.yaml", line, key)
    for fragment in fragments:
        assert fragment in err.message, f"{fragment!r} not in {err.message!r}"
    assert "\n" not in str(err)


def test_measures_and_safety_are_kept_raw():
    project = plugin_project()
    assert project.measures == [
        {"type": "fence", "x": 70, "height": 4.0, "capacity_kj": 1000},
        {"type": "ditch", "x": 118, "width": 4.0, "depth": 1.5},
    ]
    assert isinstance(project.measures[0]["x"], int)  # raw: the plugin's model converts
    assert project.safety == {
        "concept": "spang",
        "height_factor": 2.0,
        "energy_factor": 1.0,
        "statistic": "max",
    }
    assert project.protect is not None and project.protect.allowed_fraction == 0.05


def test_plugin_section_defaults():
    project = load_project_text(MINIMAL + "protect: {x: 5}\n")
    assert project.measures == []
    assert project.safety == {"concept": "spang"}
    assert project.protect is not None and project.protect.allowed_fraction == 0.0
    empty = load_project_text(MINIMAL + "measures:\nsafety:\n")
    assert empty.measures == [] and empty.safety == {"concept": "spang"}
    assert load_project_text(MINIMAL + "measures: []\n").measures == []


def test_safety_concept_is_filled_in_and_listed_first():
    project = load_project_text(MINIMAL + "safety:\n  statistic: p95\n")
    assert project.safety == {"concept": "spang", "statistic": "p95"}
    assert list(project.safety) == ["concept", "statistic"]
    other = load_project_text(MINIMAL + "safety: {gamma_e: 1.2, concept: uni11211}\n")
    assert list(other.safety.items()) == [("concept", "uni11211"), ("gamma_e", 1.2)]


def test_plugin_sections_in_resolved_dict_and_hash():
    project = plugin_project()
    resolved = project.resolved_dict()
    assert resolved["measures"] == project.measures
    assert resolved["safety"] == project.safety
    assert resolved["protect"] == {"x": 150.0, "allowed_fraction": 0.05}
    json.dumps(resolved, allow_nan=False)
    again = load_project_text(yaml.safe_dump(resolved, sort_keys=False))
    assert again.resolved_dict() == resolved
    assert again.resolved_hash() == project.resolved_hash()
    changed = plugin_project(edit("    depth: 1.5\n", "    depth: 2.5\n", WITH_PLUGINS))
    assert changed.resolved_hash() != project.resolved_hash()
    reordered = plugin_project(edit("  statistic: max\n", "  statistic: p95\n", WITH_PLUGINS))
    assert reordered.resolved_hash() != project.resolved_hash()
    # resolved_dict is a copy: editing it does not change the project
    resolved["measures"][0]["x"] = 1
    assert project.measures[0]["x"] == 70


def test_allowed_fraction_out_of_range():
    text = edit("  allowed_fraction: 0.05\n", "  allowed_fraction: 1.5\n", WITH_PLUGINS)
    assert_error(text, line_of(text, "allowed_fraction"), "protect.allowed_fraction", "<= 1")
    text = edit("  allowed_fraction: 0.05\n", "  allowed_fraction: true\n", WITH_PLUGINS)
    assert_error(text, line_of(text, "allowed_fraction"), "protect.allowed_fraction", "number")


@pytest.mark.parametrize(
    ("old", "new", "needle", "key", "fragment"),
    [
        ("    x: 118\n", "    x: .nan\n", "x: .nan", "measures[1].x", "finite"),
        ("    depth: 1.5\n", "    depth: [1, -.inf]\n", "depth:", "measures[1].depth[1]", "finite"),
        ("  - type: ditch\n", "  - kind: ditch\n", "kind: ditch", "measures[1]", "'type'"),
        ("  - type: ditch\n", "  - type: 3\n", "type: 3", "measures[1].type", "measure type"),
        ("  - type: ditch\n", "  - type: ''\n", "type: ''", "measures[1].type", "empty"),
        ("    depth: 1.5\n", "    depth: {1: 2}\n", "depth:", "measures[1].depth.1", "names"),
        ("    depth: 1.5\n", "    depth: !!binary aGk=\n", "depth:", "measures[1].depth", "bytes"),
        ("  concept: spang\n", "  concept: [spang]\n", "concept:", "safety.concept", "concept"),
        ("  concept: spang\n", "  concept: ''\n", "concept:", "safety.concept", "empty"),
        (
            "  energy_factor: 1.0\n",
            "  energy_factor: .inf\n",
            "energy_",
            "safety.energy_factor",
            "finite",
        ),
    ],
)
def test_plugin_section_errors(old, new, needle, key, fragment):
    text = edit(old, new, WITH_PLUGINS)
    assert_error(text, line_of(text, needle), key, fragment)


def test_plugin_section_shape_errors():
    text = MINIMAL + "measures: {type: fence}\n"
    assert_error(text, line_of(text, "measures"), "measures", "expected a list of measures")
    text = MINIMAL + "measures:\n  - fence\n"
    assert_error(text, line_of(text, "- fence"), "measures[0]", "expected a measure")
    text = MINIMAL + "safety: spang\n"
    assert_error(text, line_of(text, "safety"), "safety", "expected a mapping")


# -- Project.error_at / unknown_name ----------------------------------------------------


def test_error_at_locates_nodes_and_missing_keys():
    project = plugin_project()
    text = WITH_PLUGINS
    err = project.error_at(("measures", 1, "width"), "too narrow")
    assert_project_error(err, line_of(text, "width: 4.0"), "measures[1].width", "too narrow")
    assert str(err) == f"p.yaml:{line_of(text, 'width: 4.0')}: measures[1].width: too narrow"
    # a missing key: the line of its nearest existing ancestor
    err = project.error_at(("measures", 0, "restitution"), "required")
    assert_project_error(err, line_of(text, "type: fence"), "measures[0].restitution")
    err = project.error_at(("safety", "gamma_e"), "unknown")
    assert_project_error(err, line_of(text, "safety:"), "safety.gamma_e")
    err = project.error_at(("measures", 5), "no such measure")
    assert_project_error(err, line_of(text, "measures:"), "measures[5]")
    # core sections too, with the paths the models use
    err = project.error_at(("rocks", "release", 0, "x"), "too far")
    assert_project_error(err, line_of(text, "    x: 1"), "rocks.release.x")
    assert isinstance(err, ProjectError) and err.exit_code == ExitCode.BAD_INPUT
    err = project.error_at((), "whole file")
    assert str(err) == "p.yaml:1: whole file"


def test_error_at_without_a_file():
    project = Project.model_validate(yaml.safe_load(MINIMAL + "measures: [{type: fence}]\n"))
    err = project.error_at(("measures", 0, "x"), "missing")
    assert str(err) == "<string>: measures[0].x: missing" and err.line is None


def test_unknown_name():
    project = plugin_project()
    available = ["berm", "ditch", "fence", "wall", "boulder_row"]
    err = project.unknown_name(("measures", 1, "type"), "fense", available, "measure type")
    assert str(err) == (
        f"p.yaml:{line_of(WITH_PLUGINS, 'type: ditch')}: measures[1].type: unknown measure "
        "type 'fense'; did you mean 'fence'? (available: berm, ditch, fence, wall, boulder_row)"
    )
    err = project.unknown_name(("safety", "concept"), "eurocode", ["spang"], "safety concept")
    assert_project_error(err, line_of(WITH_PLUGINS, "concept: spang"), "safety.concept")
    assert err.message == "unknown safety concept 'eurocode' (available: spang)"
    err = project.unknown_name(("safety", "concept"), "x", iter(()), "safety concept")
    assert err.message == "unknown safety concept 'x' (none available)"


# -- Project.validate_params ------------------------------------------------------------


class Mesh(BaseModel):
    model_config = ConfigDict(extra="forbid")

    opening_m: float = Field(0.3, gt=0.0)
    rings: int = 4


class FenceParams(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)

    x: float
    height_m: float = Field(gt=0.0, description="Nominal height (m). Measured normal to slope.")
    capacity_kj: float = Field(1000.0, ge=100.0, le=10000.0)
    posts: int = Field(3, ge=2)
    anchored: bool = True
    statistic: Literal["max", "p95", "p99"] = "max"
    note: str = ""
    spacing_m: float | None = None
    offsets_m: list[float] = []
    anchor_m: tuple[float, float] = (0.0, 0.0)
    mesh: Mesh = Mesh()
    spin: float | Literal["rolling"] = 0.0

    @model_validator(mode="after")
    def _check(self) -> "FenceParams":
        if self.note == "forbidden":
            raise ValueError("a note may not say 'forbidden'")
        return self


FENCE_TEXT = """\
measures:
  - type: fence
    x: 70
    height_m: 4
    posts: 3
    anchored: true
    statistic: max
    note: hello
    spacing_m: 2
    offsets_m: [1, 2.5]
    anchor_m: [1, 2]
    mesh:
      opening_m: 0.3
      rings: 4
    spin: rolling
"""


def fence_project(old: str = "", new: str = "") -> tuple[Project, str]:
    text = MINIMAL + (edit(old, new, FENCE_TEXT) if old else FENCE_TEXT)
    text = edit("  points: [[0, 10], [10, 0]]\n", "  points: [[0, 10], [200, 0]]\n", text)
    return load_project_text(text, source="p.yaml"), text


def validate_fence(old: str = "", new: str = "") -> tuple[FenceParams, str]:
    project, text = fence_project(old, new)
    params = project.validate_params(
        ("measures", 0), FenceParams, project.measures[0], drop=("type",)
    )
    assert isinstance(params, FenceParams)
    return params, text


def fence_error(old: str, new: str, needle: str, key: str, *fragments: str) -> ProjectError:
    project, text = fence_project(old, new)
    with pytest.raises(ProjectError) as info:
        project.validate_params(("measures", 0), FenceParams, project.measures[0], drop=("type",))
    assert_project_error(info.value, line_of(text, needle), key, *fragments)
    return info.value


def test_validate_params_valid():
    params, _ = validate_fence()
    assert params.x == 70.0 and isinstance(params.x, float)
    assert params.height_m == 4.0 and params.capacity_kj == 1000.0
    assert params.offsets_m == [1.0, 2.5] and params.anchor_m == (1.0, 2.0)
    assert params.mesh == Mesh(opening_m=0.3, rings=4)
    assert params.spin == "rolling" and params.spacing_m == 2.0
    # integral floats are integers, as in the core sections
    params, _ = validate_fence("    posts: 3\n", "    posts: 3.0\n")
    assert params.posts == 3


def test_validate_params_drop_and_safety_section():
    project = plugin_project()

    class SpangLike(BaseModel):
        model_config = ConfigDict(extra="forbid")
        height_factor: float = 2.0
        energy_factor: float = 1.0
        statistic: Literal["max", "p95", "p99"] = "max"

    params = project.validate_params(("safety",), SpangLike, project.safety, drop=("concept",))
    assert params == SpangLike(height_factor=2.0, energy_factor=1.0, statistic="max")
    with pytest.raises(ProjectError) as info:
        project.validate_params(("safety",), SpangLike, project.safety)
    assert_project_error(info.value, line_of(WITH_PLUGINS, "concept:"), "safety.concept", "unknown")


@pytest.mark.parametrize(
    ("old", "new", "needle", "key", "fragments"),
    [
        # unknown keys, with "did you mean" against the model's fields
        (
            "    posts: 3\n",
            "    post: 3\n",
            "post:",
            "measures[0].post",
            ("unknown key 'post'", "did you mean 'posts'?"),
        ),
        (
            "    posts: 3\n",
            "    colour: red\n",
            "colour",
            "measures[0].colour",
            ("unknown key 'colour'", "expected one of x, height_m, capacity_kj"),
        ),
        (
            "      rings: 4\n",
            "      ring: 4\n",
            "ring:",
            "measures[0].mesh.ring",
            ("did you mean 'rings'?",),
        ),
        # wrong types that pydantic alone would accept
        (
            "    height_m: 4\n",
            "    height_m: '4'\n",
            "height_m",
            "measures[0].height_m",
            ("expected a number, got string '4'",),
        ),
        (
            "    height_m: 4\n",
            "    height_m: true\n",
            "height_m",
            "measures[0].height_m",
            ("expected a number, got true (a boolean)",),
        ),
        (
            "    posts: 3\n",
            "    posts: false\n",
            "posts",
            "measures[0].posts",
            ("expected a number, got false",),
        ),
        (
            "    anchored: true\n",
            "    anchored: 1\n",
            "anchored",
            "measures[0].anchored",
            ("expected true or false, got 1",),
        ),
        (
            "    anchored: true\n",
            "    anchored: 'yes'\n",
            "anchored",
            "measures[0].anchored",
            ("expected true or false",),
        ),
        (
            "    spacing_m: 2\n",
            "    spacing_m: '2'\n",
            "spacing_m",
            "measures[0].spacing_m",
            ("expected a number",),
        ),
        (
            "    offsets_m: [1, 2.5]\n",
            "    offsets_m: [1, true]\n",
            "offsets_m",
            "measures[0].offsets_m[1]",
            ("expected a number, got true",),
        ),
        (
            "    anchor_m: [1, 2]\n",
            "    anchor_m: [1, '2']\n",
            "anchor_m",
            "measures[0].anchor_m[1]",
            ("expected a number, got string '2'",),
        ),
        (
            "      opening_m: 0.3\n",
            "      opening_m: '0.3'\n",
            "opening_m",
            "measures[0].mesh.opening_m",
            ("expected a number",),
        ),
        (
            "    spin: rolling\n",
            "    spin: true\n",
            "spin:",
            "measures[0].spin",
            ("expected a number",),
        ),
        # pydantic's own errors, in house style
        (
            "    height_m: 4\n",
            "    height_m: 0\n",
            "height_m",
            "measures[0].height_m",
            ("expected a number > 0, got 0",),
        ),
        (
            "    posts: 3\n",
            "    posts: 1\n",
            "posts",
            "measures[0].posts",
            ("expected an integer >= 2, got 1",),
        ),
        (
            "    posts: 3\n",
            "    posts: 2.5\n",
            "posts",
            "measures[0].posts",
            ("expected an integer, got 2.5",),
        ),
        (
            "    posts: 3\n",
            "    capacity_kj: 20000\n",
            "capacity_kj",
            "measures[0].capacity_kj",
            ("expected a number <= 10000, got 20000",),
        ),
        (
            "    statistic: max\n",
            "    statistic: maxx\n",
            "statistic",
            "measures[0].statistic",
            ("expected one of max, p95, p99, got string 'maxx'; did you mean 'max'?",),
        ),
        (
            "    note: hello\n",
            "    note: 5\n",
            "note:",
            "measures[0].note",
            ("expected a string, got 5",),
        ),
        (
            "    anchor_m: [1, 2]\n",
            "    anchor_m: [1]\n",
            "anchor_m",
            "measures[0].anchor_m",
            ("item 1 is missing",),
        ),
        (
            "    offsets_m: [1, 2.5]\n",
            "    offsets_m: 1\n",
            "offsets_m",
            "measures[0].offsets_m",
            ("expected a list",),
        ),
        (
            "      rings: 4\n",
            "      rings: 4.5\n",
            "rings",
            "measures[0].mesh.rings",
            ("expected an integer",),
        ),
        (
            "    mesh:\n      opening_m: 0.3\n      rings: 4\n",
            "    mesh: 3\n",
            "mesh:",
            "measures[0].mesh",
            ("expected a mapping",),
        ),
        (
            "    spin: rolling\n",
            "    spin: roling\n",
            "spin:",
            "measures[0].spin",
            ("expected a number or one of rolling, got string 'roling'; did you mean 'rolling'?",),
        ),
        (
            "    note: hello\n",
            "    note: forbidden\n",
            "  - type: fence",
            "measures[0]",
            ("a note may not say 'forbidden'",),
        ),
        # a missing key: the line of the measure
        (
            "    height_m: 4\n",
            "",
            "  - type: fence",
            "measures[0].height_m",
            ("required key is missing (Nominal height (m))",),
        ),
    ],
)
def test_validate_params_errors(old, new, needle, key, fragments):
    fence_error(old, new, needle, key, *fragments)


def test_validate_params_nan_anywhere():
    project, text = fence_project()
    for key, value in [("height_m", math.nan), ("offsets_m", [1.0, math.inf])]:
        data = {**project.measures[0], key: value}
        with pytest.raises(ProjectError) as info:
            project.validate_params(("measures", 0), FenceParams, data, drop=("type",))
        assert "must be finite" in info.value.message
        assert info.value.line == line_of(text, key)


def test_validate_params_reports_unknown_keys_first_then_earliest():
    # a misspelt required key: "unknown key" rather than "missing"
    fence_error(
        "    height_m: 4\n",
        "    hieght_m: 4\n",
        "hieght_m",
        "measures[0].hieght_m",
        "did you mean 'height_m'?",
    )
    # two bad values: the one earlier in the file, whichever check found it
    project, text = fence_project("    note: hello\n", "    note: 5\n")
    data = {**project.measures[0], "height_m": "tall"}
    with pytest.raises(ProjectError) as info:
        project.validate_params(("measures", 0), FenceParams, data, drop=("type",))
    assert_project_error(info.value, line_of(text, "height_m"), "measures[0].height_m", "number")


def test_validate_params_needs_a_mapping():
    project = load_project_text(MINIMAL + "measures:\n  - type: fence\n", source="p.yaml")
    with pytest.raises(ProjectError) as info:
        project.validate_params(("measures", 0), FenceParams, [1, 2])
    line = line_of(MINIMAL + "measures:\n  - type: fence\n", "- type: fence")
    assert_project_error(info.value, line, "measures[0]", "expected a mapping")


# -- Project.with_resolved_plugins ------------------------------------------------------


def test_with_resolved_plugins():
    project = plugin_project()
    measures = [
        {"type": "fence", "x": 70.0, "height": 4.0, "capacity_kj": 1000.0, "posts": 3},
        {"type": "ditch", "x": 118.0, "width": 4.0, "depth": 1.5},
    ]
    safety = {
        "height_factor": 2.0,
        "energy_factor": 1.0,
        "reach_factor": 1.0,
        "statistic": "max",
        "concept": "spang",
    }
    resolved = project.with_resolved_plugins(measures, safety)
    assert resolved is not project
    data = resolved.resolved_dict()
    assert data["measures"] == measures
    assert list(data["safety"]) == [
        "concept",
        "height_factor",
        "energy_factor",
        "reach_factor",
        "statistic",
    ]
    assert resolved.resolved_hash() != project.resolved_hash()
    # the original and the raw sections are untouched, errors still point into the file
    assert project.resolved_dict()["measures"] == project.measures
    assert resolved.measures == project.measures and resolved.safety == project.safety
    assert resolved.error_at(("measures", 1), "x").line == line_of(WITH_PLUGINS, "type: ditch")
    # the caller's data is copied
    measures[0]["x"] = 1.0
    assert resolved.resolved_dict()["measures"][0]["x"] == 70.0
    # the record is itself a valid project file
    again = load_project_text(yaml.safe_dump(data, sort_keys=False))
    assert again.resolved_dict() == data


@pytest.mark.parametrize(
    ("measures", "safety", "fragment"),
    [
        ([{"type": "fence"}], {"concept": "spang"}, "expected 2"),
        ([{"type": "fence"}, {"x": 1}], {"concept": "spang"}, "type"),
        ([{"type": "fence"}, {"type": "ditch", "x": math.nan}], {"concept": "s"}, "finite"),
        ([{"type": "fence"}, {"type": "ditch"}], {"gamma": 1}, "concept"),
    ],
)
def test_with_resolved_plugins_rejects_bad_data(measures, safety, fragment):
    with pytest.raises(ValueError, match=fragment):
        plugin_project().with_resolved_plugins(measures, safety)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_mutated_plugin_sections_fail_cleanly(data):
    base = yaml.safe_load(WITH_PLUGINS)
    paths = [p for p in _paths(base) if p and p[0] in ("measures", "safety", "protect")]
    for _ in range(data.draw(st.integers(min_value=1, max_value=3))):
        path = data.draw(st.sampled_from(paths))
        parent = base
        try:
            for key in path[:-1]:
                parent = parent[key]
            parent[path[-1]]
        except (KeyError, IndexError, TypeError):
            continue
        if not isinstance(parent, dict | list):
            continue
        parent[path[-1]] = data.draw(junk)
    _check_one(yaml.safe_dump(base, sort_keys=False))


# --------------------------------------------------------------------------------------
# The design section (shapes only; resolution against the plugins: test_design.py)
# --------------------------------------------------------------------------------------

DESIGN = """\
design:
  max_measures: 3
  residual: 5
  fresh_rocks: 4000
  fresh_seed: 11
  site:
    length_m: 120
  products:
    fence:
      RX-100: {capacity_kj: 1000, heights: [3, 4, 5], note: example}
  costs:
    model: unit_prices
    params: {fixed_per_measure: 100, barrier_per_m: {fence: {RX-100: {3: 500, 4.5: 600}}}}
  candidates:
    - type: fence
      x: [60, 110]
      product: [RX-100]
    - type: ditch
      x: [118, 130]
      width: [3, 12]
      depth: {options: [1.0, 1.5, 2.0]}
      upslope_side_deg: 45
      material: rock
"""

WITH_DESIGN = EXAMPLE + DESIGN
PARAMS_LINE = next(line + "\n" for line in DESIGN.splitlines() if "params:" in line)


def test_design_absent_is_none():
    assert load_project_text(EXAMPLE).design is None


def test_design_section_loads_raw_candidates():
    project = load_project_text(WITH_DESIGN, source="p.yaml")
    design = project.design
    assert design is not None
    assert (design.max_measures, design.fresh_rocks, design.fresh_seed) == (3, 4000, 11)
    assert design.residual == 5 and design.residual_count == 5
    assert design.residual_fraction is None
    assert design.site.length_m == 120.0
    assert design.costs.model == "unit_prices" and design.costs.file is None
    assert design.candidates == [
        {"type": "fence", "x": [60, 110], "product": ["RX-100"]},
        {
            "type": "ditch",
            "x": [118, 130],
            "width": [3, 12],
            "depth": {"options": [1.0, 1.5, 2.0]},
            "upslope_side_deg": 45,
            "material": "rock",
        },
    ]
    assert design.catalogue == {
        "fence": {"RX-100": {"capacity_kj": 1000.0, "heights": [3.0, 4.0, 5.0], "note": "example"}}
    }
    assert design.cost_params["barrier_per_m"]["fence"]["RX-100"] == {3: 500, 4.5: 600}
    err = design.products_locator.error_at(("fence", "RX-100", "heights", 1), "bad")
    assert str(err) == f"p.yaml:{line_of(WITH_DESIGN, 'RX-100: {cap')}: " + (
        "design.products.fence.RX-100.heights[1]: bad"
    )
    err = design.costs_locator.error_at(("fixed_per_measure",), "bad")
    assert (err.line, err.key) == (
        line_of(WITH_DESIGN, "params:"),
        "design.costs.params.fixed_per_measure",
    )


def test_design_defaults_and_fraction():
    text = EXAMPLE + (
        "design:\n  site: {length_m: 50}\n  costs: {params: {}}\n"
        "  candidates: [{type: fence, x: [60, 110]}]\n"
    )
    design = load_project_text(text).design
    assert design is not None
    assert (design.max_measures, design.residual, design.fresh_rocks, design.fresh_seed) == (
        2,
        0,
        None,
        None,
    )
    assert design.costs.model == "unit_prices" and design.products is None
    assert design.catalogue == {}
    text = edit("  residual: 5\n", "  residual: {fraction: 0.001}\n", WITH_DESIGN)
    design = load_project_text(text).design
    assert design is not None
    assert design.residual_fraction == 0.001 and design.residual_count is None


def test_design_round_trip_inlines_catalogues():
    project = load_project_text(WITH_DESIGN)
    resolved = project.resolved_dict()
    json.dumps(resolved, allow_nan=False)
    assert resolved["design"]["residual"] == 5
    assert resolved["design"]["costs"]["file"] is None
    again = load_project_text(yaml.safe_dump(resolved, sort_keys=False))
    assert again.resolved_dict() == resolved
    cheaper = load_project_text(edit("{3: 500,", "{3: 450,", WITH_DESIGN))
    assert cheaper.resolved_hash() != project.resolved_hash()


def _design_files(tmp_path, products: str, costs: str, design: str = DESIGN) -> str:
    (tmp_path / "catalogue_products.yaml").write_text(products)
    (tmp_path / "catalogue_costs.yaml").write_text(costs)
    text = design.replace(
        "  products:\n    fence:\n      RX-100: {capacity_kj: 1000, heights: [3, 4, 5], "
        "note: example}\n",
        "  products: catalogue_products.yaml\n",
    ).replace(
        "    params: {fixed_per_measure: 100, barrier_per_m: {fence: {RX-100: {3: 500, 4.5: "
        "600}}}}\n",
        "    file: catalogue_costs.yaml\n",
    )
    path = tmp_path / "p.yaml"
    path.write_text(EXAMPLE + text)
    return str(path)


PRODUCTS = "fence:\n  RX-100:\n    capacity_kj: 1000\n    heights: [3, 4, 5]\n"
COSTS = "fixed_per_measure: 100\nbarrier_per_m:\n  fence:\n    RX-100: {3: 500}\n"


def test_design_catalogue_files(tmp_path):
    from rockfall_design.project import load_project

    path = _design_files(tmp_path, PRODUCTS, COSTS)
    design = load_project(path).design
    assert design is not None
    assert design.catalogue["fence"]["RX-100"]["heights"] == [3.0, 4.0, 5.0]
    assert design.cost_params == {
        "fixed_per_measure": 100,
        "barrier_per_m": {"fence": {"RX-100": {3: 500}}},
    }
    shown = str(tmp_path / "catalogue_costs.yaml")
    err = design.costs_locator.error_at(("barrier_per_m", "fence", "RX-100", 3), "bad")
    assert str(err) == f"{shown}:4: barrier_per_m.fence.RX-100.3: bad"
    err = design.products_locator.error_at(("fence", "RX-100", "heights", 2), "bad")
    assert str(err) == f"{tmp_path / 'catalogue_products.yaml'}:4: fence.RX-100.heights[2]: bad"


@pytest.mark.parametrize(
    ("products", "line", "key", "fragment"),
    [
        ("fence:\n  RX-100:\n    heights: [3]\n", 2, "fence.RX-100", "'capacity_kj' is missing"),
        (
            "fence:\n  RX-100: {capacity_kj: 0, heights: [3]}\n",
            2,
            "fence.RX-100.capacity_kj",
            "> 0",
        ),
        (
            "fence:\n  RX-100:\n    capacity_kj: 10\n    heights: [3,\n      -1]\n",
            5,
            "fence.RX-100.heights[1]",
            "> 0",
        ),
        (
            "fence:\n  RX-100:\n    capacity_kj: 10\n    heights: []\n",
            4,
            "fence.RX-100.heights",
            "non-empty",
        ),
        (
            "fence:\n  RX-100: {capacity_kj: 10, heights: [3, 3]}\n",
            2,
            "fence.RX-100.heights[1]",
            "twice",
        ),
        ("fence:\n  100: {capacity_kj: 10, heights: [3]}\n", 2, "fence.100", "quote"),
        ("fence: [RX-100]\n", 1, "fence", "expected a mapping"),
        ("- fence\n", 1, "", "expected a mapping"),
        (
            "fence:\n  RX-100: {capacity_kj: 10, heights: [3]}\n  RX-100: {}\n",
            3,
            "fence.RX-100",
            "duplicate key",
        ),
    ],
)
def test_design_product_file_errors(tmp_path, products, line, key, fragment):
    from rockfall_design.project import load_project

    path = _design_files(tmp_path, products, COSTS)
    with pytest.raises(ProjectError) as info:
        load_project(path)
    err = info.value
    assert err.file == str(tmp_path / "catalogue_products.yaml")
    assert (err.line, err.key) == (line, key), str(err)
    assert fragment in err.message


def test_design_missing_and_bad_catalogue_files(tmp_path):
    from rockfall_design.project import load_project

    path = _design_files(tmp_path, PRODUCTS, COSTS)
    text = (tmp_path / "p.yaml").read_text()
    (tmp_path / "catalogue_products.yaml").unlink()
    with pytest.raises(ProjectError) as info:
        load_project(path)
    assert info.value.line == line_of(text, "products: catalogue")
    assert info.value.key == "design.products"
    assert "cannot read the product catalogue" in info.value.message
    _design_files(tmp_path, PRODUCTS, COSTS)
    (tmp_path / "catalogue_costs.yaml").unlink()
    with pytest.raises(ProjectError) as info:
        load_project(path)
    assert (info.value.line, info.value.key) == (
        line_of(text, "file: catalogue"),
        "design.costs.file",
    )
    _design_files(tmp_path, PRODUCTS, "fixed_per_measure: 100\nx: {.nan: 1}\n")
    with pytest.raises(ProjectError) as info:
        load_project(path)
    assert str(info.value).startswith(f"{tmp_path / 'catalogue_costs.yaml'}:2: x.nan: ")
    _design_files(tmp_path, PRODUCTS, "[1, 2]\n")
    with pytest.raises(ProjectError, match="catalogue_costs.yaml:1: expected a mapping"):
        load_project(path)
    _design_files(tmp_path, PRODUCTS, "# nothing\n")
    with pytest.raises(ProjectError, match="catalogue_costs.yaml:1: the cost file is empty"):
        load_project(path)
    # relative to the project file, not to the current directory
    _design_files(tmp_path, PRODUCTS, COSTS)
    assert load_project_text(text, source=path).design is not None


@pytest.mark.parametrize(
    ("old", "new", "needle", "key", "fragment"),
    [
        (
            "  max_measures: 3\n",
            "  max_measures: 0\n",
            "max_measures",
            "design.max_measures",
            ">= 1",
        ),
        ("  residual: 5\n", "  residual: -1\n", "residual", "design.residual", "integer >= 0"),
        ("  residual: 5\n", "  residual: 0.5\n", "residual", "design.residual", "{fraction: F}"),
        (
            "  residual: 5\n",
            "  residual: {fraction: 2}\n",
            "residual",
            "design.residual.fraction",
            "0..1",
        ),
        (
            "  residual: 5\n",
            "  residual: {fractoin: 0.1}\n",
            "residual",
            "design.residual.fractoin",
            "did you mean 'fraction'",
        ),
        (
            "  fresh_rocks: 4000\n",
            "  fresh_rocks: 0\n",
            "fresh_rocks",
            "design.fresh_rocks",
            ">= 1",
        ),
        ("  fresh_seed: 11\n", "  fresh_seed: x\n", "fresh_seed", "design.fresh_seed", "integer"),
        ("    length_m: 120\n", "    length_m: 0\n", "length_m", "design.site.length_m", "> 0"),
        (
            "    length_m: 120\n",
            "    lenght_m: 120\n",
            "lenght_m",
            "design.site.lenght_m",
            "did you mean 'length_m'",
        ),
        (
            "  max_measures: 3\n",
            "  max_measure: 3\n",
            "max_measure",
            "design.max_measure",
            "did you mean 'max_measures'",
        ),
        ("    model: unit_prices\n", "    model: ''\n", "model: ''", "design.costs.model", "empty"),
        (
            "    model: unit_prices\n",
            "    model: unit_prices\n    file: c.yaml\n",
            "params:",
            "design.costs.params",
            "only one of file and params",
        ),
        (
            PARAMS_LINE,
            "    params: [1]\n",
            "params:",
            "design.costs.params",
            "expected a mapping",
        ),
        (
            PARAMS_LINE,
            "",
            "costs:",
            "design.costs",
            "file: PATH",
        ),
        (
            "      RX-100: {capacity_kj: 1000, heights: [3, 4, 5], note: example}\n",
            "      RX-100: {capacity_kj: 1000, heights: [3, x]}\n",
            "RX-100: {cap",
            "design.products.fence.RX-100.heights[1]",
            "expected a number",
        ),
        (
            "    - type: fence\n",
            "    - kind: fence\n",
            "kind: fence",
            "design.candidates[0]",
            "'type'",
        ),
        (
            "    - type: fence\n",
            "    - type: 3\n",
            "type: 3",
            "design.candidates[0].type",
            "measure type",
        ),
        (
            "      x: [60, 110]\n",
            "      x: 60\n",
            "x: 60",
            "design.candidates[0].x",
            "station range [min, max]",
        ),
        (
            "      x: [60, 110]\n",
            "      x: [110, 60]\n",
            "x: [110",
            "design.candidates[0].x",
            "min < max",
        ),
        (
            "      x: [60, 110]\n",
            "      x: [60, 250]\n",
            "x: [60",
            "design.candidates[0].x",
            "outside the slope section [0, 200]",
        ),
        (
            "      x: [60, 110]\n",
            "      x: [60, true]\n",
            "x: [60",
            "design.candidates[0].x[1]",
            "expected a number",
        ),
        (
            "      x: [60, 110]\n",
            "",
            "type: fence",
            "design.candidates[0]",
            "'x' is missing",
        ),
        (
            "      product: [RX-100]\n",
            "      product: []\n",
            "product:",
            "design.candidates[0].product",
            "non-empty list",
        ),
        (
            "      product: [RX-100]\n",
            "      product: [RX-100, 3]\n",
            "product:",
            "design.candidates[0].product[1]",
            "product name",
        ),
        (
            "      product: [RX-100]\n",
            "      product: [RX-100, RX-100]\n",
            "product:",
            "design.candidates[0].product[1]",
            "twice",
        ),
        (
            "      width: [3, 12]\n",
            "      width: [12, 3]\n",
            "width:",
            "design.candidates[1].width",
            "min < max",
        ),
        (
            "      width: [3, 12]\n",
            "      width: [3, 12, 20]\n",
            "width:",
            "design.candidates[1].width",
            "{options: [...]}",
        ),
        (
            "      width: [3, 12]\n",
            "      width: [a, b]\n",
            "width:",
            "design.candidates[1].width[0]",
            "needs numbers",
        ),
        (
            "      width: [3, 12]\n",
            "      width: [3, .inf]\n",
            "width:",
            "design.candidates[1].width[1]",
            "finite",
        ),
        (
            "      width: [3, 12]\n",
            "      width:\n",
            "width:",
            "design.candidates[1].width",
            "a range [min, max] or {options",
        ),
        (
            "      depth: {options: [1.0, 1.5, 2.0]}\n",
            "      depth: {options: []}\n",
            "depth:",
            "design.candidates[1].depth.options",
            "non-empty list",
        ),
        (
            "      depth: {options: [1.0, 1.5, 2.0]}\n",
            "      depth: {option: [1]}\n",
            "depth:",
            "design.candidates[1].depth.option",
            "did you mean 'options'",
        ),
        (
            "      depth: {options: [1.0, 1.5, 2.0]}\n",
            "      depth: {}\n",
            "depth:",
            "design.candidates[1].depth",
            "'options' is missing",
        ),
        (
            "      depth: {options: [1.0, 1.5, 2.0]}\n",
            "      depth: {options: [1, [2]]}\n",
            "depth:",
            "design.candidates[1].depth.options[1]",
            "number, string or boolean",
        ),
        (
            "      depth: {options: [1.0, 1.5, 2.0]}\n",
            "      depth: {options: [1, 1]}\n",
            "depth:",
            "design.candidates[1].depth.options[1]",
            "twice",
        ),
        (
            "  candidates:\n",
            "  candidates: []\n  old_candidates:\n",
            "candidates: []",
            "design.candidates",
            "non-empty list",
        ),
    ],
)
def test_design_section_errors(old, new, needle, key, fragment):
    text = edit(old, new, WITH_DESIGN)
    if "old_candidates" in new:  # drop the list that followed
        text = text[: text.index("  old_candidates:")]
    assert_error(text, line_of(text, needle), key, fragment)


def test_design_needs_protect():
    text = edit("protect:\n  x: 150\n", "", WITH_DESIGN)
    assert_error(text, line_of(text, "design:"), "design", "needs protect")


def test_locator_validate_params_on_a_catalogue_file(tmp_path):
    from rockfall_design.project import Locator, load_project

    class Prices(BaseModel):
        model_config = ConfigDict(extra="forbid")
        fixed_per_measure: float = Field(ge=0)
        barrier_per_m: dict[str, dict[str, dict[float, float]]] = {}

    costs = "fixed_per_measure: 100\nbarrier_per_m:\n  fence:\n    RX-100: {3: 500, x: 1}\n"
    design = load_project(_design_files(tmp_path, PRODUCTS, costs)).design
    assert design is not None and isinstance(design.costs_locator, Locator)
    with pytest.raises(ProjectError) as info:
        design.costs_locator.validate_params((), Prices, design.cost_params)
    assert str(info.value) == (
        f"{tmp_path / 'catalogue_costs.yaml'}:4: barrier_per_m.fence.RX-100.x: "
        # a file the project names is never quoted: the key path says where
        "invalid key: expected a number, got a string"
    )
    costs = "fixed_per_measure: -1\nbarier_per_m: {}\n"
    design = load_project(_design_files(tmp_path, PRODUCTS, costs)).design
    assert design is not None
    with pytest.raises(ProjectError, match=r"catalogue_costs.yaml:2: barier_per_m: unknown key"):
        design.costs_locator.validate_params((), Prices, design.cost_params)


def test_params_problem():
    from rockfall_design.project import params_problem

    class P(BaseModel):
        model_config = ConfigDict(extra="forbid")
        width: float = Field(gt=0)
        flag: bool = False

    assert params_problem(P, {"width": 1}) is None
    assert params_problem(P, {"width": -1}) == (("width",), "expected a number > 0, got -1")
    assert params_problem(P, {"width": True}) == (
        ("width",),
        "expected a number, got true (a boolean)",
    )
    assert params_problem(P, {"width": 1, "widht": 2})[0] == ("widht",)


# --------------------------------------------------------------------------------------
# Writing YAML the loader reads back (design.yaml, --repeat)
# --------------------------------------------------------------------------------------

_scalars = st.one_of(
    st.text(max_size=10),
    st.sampled_from(["1e3", "-2E-3", "1_000", "2024-05-01", "true", "null", "~", ".inf"]),
    st.integers(-(10**9), 10**9),
    st.floats(allow_nan=False, allow_infinity=False),
    st.booleans(),
    st.none(),
)


@settings(max_examples=300, deadline=None)
@given(st.dictionaries(st.one_of(st.text(max_size=8), st.sampled_from(["1e3", "2e-1"])),
                       st.one_of(_scalars, st.lists(_scalars, max_size=3)), max_size=6))
def test_dump_yaml_is_read_back_as_written(data):
    from rockfall_design.project.yaml_file import dump_yaml, parse_yaml

    back, _ = parse_yaml(dump_yaml(data), "d.yaml")
    assert back == (data or {}) or (back is None and not data)


def test_a_product_named_like_a_number_stays_a_string():
    from rockfall_design.project import dump_yaml

    text = dump_yaml({"product": "1e3", "material": "2e-1"})
    assert yaml.safe_load(text) == {"product": "1e3", "material": "2e-1"}
    assert "'1e3'" in text  # PyYAML's safe_dump would leave it plain, read as 1000.0

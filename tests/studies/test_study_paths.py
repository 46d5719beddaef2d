"""The study's interface: inputs set by their path, and the scenarios of a study."""

import numpy as np
import pytest

from rockfall_design.errors import ExitCode, ProjectError
from rockfall_design.project import load_project_text
from rockfall_design.studies import (
    PathError,
    check_study,
    parse_path,
    scenario_seed,
    scenarios,
    with_values,
)

BASE = """\
name: paths
slope:
  points: [[0, 100], [30, 60], [60, 30], [80, 20], [120, 15], [200, 12]]
  materials: talus
materials:
  talus: {restitution: 0.35, friction: 0.58, rolling_resistance: 0.3}
rocks:
  count: 50
  seed: 4
  volume: {lognormal: [1.0, 0.3]}
  release: {x: 1, velocity: [0.6, -0.8]}
analysis:
  stations: [80]
protect:
  x: 150
"""

STUDY = BASE + """\
study:
  vary:
    materials.talus.restitution: [0.28, 0.32, 0.36]
    release[0].x: {range: [1, 5], levels: 3}
"""


def project(text: str = STUDY):
    return load_project_text(text, "p.yaml")


def line_of(text: str, needle: str) -> int:
    return next(i for i, line in enumerate(text.splitlines(), 1) if needle in line)


# ---- paths --------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("path", "keys"),
    [
        ("materials.talus.restitution", ("materials", "talus", "restitution")),
        ("rocks.volume.lognormal.0", ("rocks", "volume", "lognormal", 0)),
        ("release[0].x", ("release", 0, "x")),
        ("rocks.release[0].velocity[1]", ("rocks", "release", 0, "velocity", 1)),
    ],
)
def test_parse_path(path, keys):
    assert parse_path(path) == keys


@pytest.mark.parametrize("path", ["", "a..b", "a[b]", "a.[0]", "a]"])
def test_parse_path_refuses_malformed(path):
    with pytest.raises(PathError):
        parse_path(path)


def test_with_values_sets_each_form_of_path():
    p = project()
    q = with_values(p, {
        "materials.talus.restitution": 0.3,
        "rocks.volume.lognormal.0": 2.0,
        "release[0].x": 4,
    })
    assert q.materials["talus"].restitution == 0.3
    assert (q.rocks.volume.kind, q.rocks.volume.a, q.rocks.volume.b) == ("lognormal", 2.0, 0.3)
    assert q.rocks.release[0].x == (4.0, 4.0)
    assert q.study is None  # a scenario is a plain project
    assert q.source == "p.yaml"
    # the original is untouched, and unvaried inputs are as they were
    assert p.materials["talus"].restitution == 0.35
    assert q.slope == p.slope and q.analysis == p.analysis


def test_with_values_takes_values_in_the_files_syntax():
    q = with_values(project(), {"rocks.volume": {"uniform": [0.5, 1.5]}})
    assert (q.rocks.volume.kind, q.rocks.volume.a, q.rocks.volume.b) == ("uniform", 0.5, 1.5)


def test_with_values_without_values_is_the_same_project():
    p = project()
    q = with_values(p, {})
    resolved = p.resolved_dict()
    resolved.pop("study")
    assert q.resolved_dict() == resolved


@pytest.mark.parametrize(
    ("path", "value", "words"),
    [
        ("materials.talus.restitution", 1.2, ["value 1.2", "expected a number <= 1"]),
        ("materials.talus.restitution", "high", ["string 'high'", "expected a number"]),
        ("release[0].x", 500, ["outside the slope section"]),
        ("rocks.volume.lognormal.0", -1, ["median > 0"]),
        ("materials.tals.restitution", 0.3, ["not an input", "did you mean 'talus'"]),
        ("rocks.release[3].x", 1, ["index 3 is out of range"]),
        ("rocks.radius.lognormal.0", 1, ["single value"]),
        ("matrials.talus.restitution", 0.3, ["no section", "did you mean 'materials'"]),
    ],
)
def test_bad_path_or_value_is_one_line_at_the_study_line(path, value, words):
    text = BASE + f"study:\n  vary:\n    {path}: [1]\n"
    p = project(text)
    with pytest.raises(ProjectError) as info:
        with_values(p, {path: value})
    err = info.value
    assert err.exit_code == ExitCode.BAD_INPUT
    assert err.key == f"study.vary.{path}"
    assert err.line == line_of(text, f"{path}:")
    message = str(err)
    assert "\n" not in message
    for word in words:
        assert word in message


def test_values_valid_alone_but_not_together_are_named():
    # a uniform size whose minimum and maximum are varied separately
    text = BASE.replace("volume: {lognormal: [1.0, 0.3]}", "volume: {uniform: [0.5, 1.0]}")
    p = project(text)
    with pytest.raises(ProjectError, match="do not fit together"):
        with_values(p, {"rocks.volume.uniform.0": 0.9, "rocks.volume.uniform.1": 0.8})


def test_check_study_reports_a_bad_level_before_any_run():
    text = STUDY.replace("[0.28, 0.32, 0.36]", "[0.28, 0.32, 1.36]")
    with pytest.raises(ProjectError, match="value 1.36") as info:
        check_study(project(text))
    assert info.value.line == line_of(text, "materials.talus.restitution:")
    check_study(project())  # the good study passes


# ---- the study section ------------------------------------------------------------------


@pytest.mark.parametrize(
    ("study", "words"),
    [
        ("  vary: {a.b: []}\n", "at least one value"),
        ("  vary: {a.b: [1, 1]}\n", "listed twice"),
        ("  vary: {a.b: {range: [2, 1], levels: 3}}\n", "lo < hi"),
        ("  vary: {a.b: {range: [1, 2]}}\n", "needs levels"),
        ("  vary: {a.b: 3}\n", "expected a list of values"),
        ("  vary: {a.b: [1]}\n  scenarios: grd\n", "expected grid"),
        ("  vary: {a.b: [1]}\n  scenarios: {sample: sobol, n: 5}\n", "latin_hypercube"),
        ("  vary: {a.b: [1]}\n  scenarios: {sample: latin_hypercube, n: 1}\n", ">= 2"),
        ("  vary: {}\n", "at least 1"),
        ("  vary: {a.b: [1]}\n  scenarios: {sample: latin_hypercube, m: 5}\n", "unknown key 'm'"),
        ("  vary: {a.b: [1]}\n  scenarios: {sample: latin_hypercube, n: 5, seed: -1}\n",
         "seed: expected an integer >= 0"),
    ],
)
def test_bad_study_section(study, words):
    with pytest.raises(ProjectError, match=words) as info:
        project(BASE + "study:\n" + study)
    assert info.value.key.startswith("study")


@pytest.mark.parametrize("scenarios_", ["grid", "{sample: latin_hypercube, n: 5, seed: 2}"])
def test_the_record_of_a_study_loads_back(scenarios_):
    from rockfall_design.project import dump_yaml

    p = project(STUDY.replace("release[0].x: {range: [1, 5], levels: 3}",
                              "release[0].x: {range: [1, 5], levels: 3}\n  scenarios: "
                              + scenarios_))
    again = load_project_text(dump_yaml(p.resolved_dict()), "again.yaml")
    assert again.resolved_dict() == p.resolved_dict()
    assert again.study == p.study


def test_a_project_without_study_has_the_same_record():
    # the record (and hash) of files without a study do not mention it
    assert "study" not in project(BASE).resolved_dict()


# ---- scenarios ----------------------------------------------------------------------------


def test_grid_is_every_combination_last_input_fastest():
    sc = scenarios(project().study, run_seed=7)
    assert [s.index for s in sc] == list(range(9))
    assert [tuple(s.values.values()) for s in sc] == [
        (e, x) for e in (0.28, 0.32, 0.36) for x in (1.0, 3.0, 5.0)
    ]
    assert all(list(s.values) == ["materials.talus.restitution", "release[0].x"] for s in sc)


def test_scenario_seeds_are_spawned_from_the_run_seed():
    sc = scenarios(project().study, run_seed=7)
    expected = [
        int(child.generate_state(1, np.uint64)[0]) >> 11
        for child in np.random.SeedSequence(7).spawn(9)
    ]
    assert [s.seed for s in sc] == expected
    assert len(set(expected)) == 9
    assert all(0 <= s < 2**53 for s in expected)
    # a scenario's seed depends on the run seed and its index only
    assert scenario_seed(7, 4) == sc[4].seed
    assert [s.seed for s in scenarios(project().study, run_seed=8)] != expected


def test_latin_hypercube_sample():
    spec = {
        "vary": {"r": {"range": [0.2, 0.4]}, "v": [0.5, 1.0, 2.0]},
        "scenarios": {"sample": "latin_hypercube", "n": 30, "seed": 3},
    }
    sc = scenarios(spec, run_seed=1)
    assert len(sc) == 30
    r = np.array([s.values["r"] for s in sc])
    assert np.all((0.2 <= r) & (r <= 0.4))
    # a Latin hypercube puts one point in each of the n strata of every input
    strata = np.floor((r - 0.2) / 0.2 * 30).astype(int)
    assert sorted(strata) == list(range(30))
    v = [s.values["v"] for s in sc]
    assert {x: v.count(x) for x in (0.5, 1.0, 2.0)} == {0.5: 10, 1.0: 10, 2.0: 10}
    # reproducible from the sample's seed; another seed, another sample
    assert scenarios(spec, run_seed=1) == sc
    other = {**spec, "scenarios": {**spec["scenarios"], "seed": 4}}
    assert [s.values for s in scenarios(other, run_seed=1)] != [s.values for s in sc]


def test_common_seeds_give_every_scenario_the_run_seed():
    p = project(STUDY + "  seeds: common\n")
    assert [s.seed for s in scenarios(p.study, run_seed=7)] == [7] * 9
    with pytest.raises(ProjectError, match="expected one of independent, common"):
        project(STUDY + "  seeds: same\n")

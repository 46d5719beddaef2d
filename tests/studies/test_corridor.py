"""Corridors: a project file with several sections, each run as an ordinary project."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rockfall_design.cli.program import main
from rockfall_design.errors import InputError, ProjectError
from rockfall_design.project import (
    Corridor,
    Project,
    load_corridor,
    load_corridor_text,
    load_project,
    load_project_text,
    section_seed,
)

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "projects" / "corridor_two_sections.yaml"

# Two small sections; line numbers below are those of this text.
CORRIDOR = """\
name: Two cuts
materials:
  talus: {restitution: 0.25, friction: 0.6, rolling_resistance: 0.6}
rocks:
  count: 40
  seed: 3
  radius: 0.4
safety: {concept: spang}
sections:
  - name: north
    slope: {points: [[0, 30], [40, 0], [80, -1]], materials: talus}
    rocks: {release: {x: [1, 3]}}
    protect: {x: 70}
  - name: south
    slope: {points: [[0, 20], [30, 0], [60, -1]], materials: talus}
    rocks: {release: {x: 1}, volume: 0.2}
    protect: {x: 50}
    measures:
      - {type: fence, x: 20, height: 3, capacity_kj: 1000}
"""


def _corridor(text: str = CORRIDOR) -> Corridor:
    corridor = load_corridor_text(text, "c.yaml")
    assert isinstance(corridor, Corridor)
    return corridor


def _error(text: str) -> str:
    with pytest.raises(ProjectError) as info:
        load_corridor_text(text, "c.yaml")
    return str(info.value)


def test_sections_are_complete_projects_with_the_shared_keys_merged():
    corridor = _corridor()
    assert corridor.name == "Two cuts" and corridor.seed == 3
    north, south = corridor.sections
    assert [s.name for s in corridor.sections] == ["north", "south"]
    assert isinstance(north.project, Project) and north.project.name == "Two cuts / north"
    assert north.project.materials == south.project.materials  # shared
    assert north.project.rocks.count == 40 and north.project.rocks.radius is not None
    # a section's size replaces the shared one (only one of radius, volume, mass)
    assert south.project.rocks.radius is None and south.project.rocks.volume is not None
    assert north.project.protect.x == 70 and south.project.protect.x == 50
    assert north.project.measures == [] and south.project.measures[0]["x"] == 20


def test_each_section_has_its_own_seed_derived_from_the_run_seed_and_index():
    corridor = _corridor()
    seeds = [s.seed for s in corridor.sections]
    assert seeds == [section_seed(3, 0), section_seed(3, 1)]
    assert len(set(seeds)) == 2 and 3 not in seeds
    assert corridor.section_seeds(9) == [section_seed(9, 0), section_seed(9, 1)]
    assert section_seed(9, 0) != section_seed(3, 0)
    assert all(0 <= s < 2**32 for s in seeds)


def test_a_file_without_sections_loads_as_the_project_it_is():
    text = EXAMPLE.read_text().split("sections:")[0]  # no slope: a plain project fails
    with pytest.raises(ProjectError, match="slope"):
        load_corridor_text(text, "p.yaml")
    plain = (ROOT / "projects" / "standard_slope.yaml").read_text()
    assert load_corridor_text(plain, "p.yaml") == load_project_text(plain, "p.yaml")


def test_load_project_refuses_a_corridor_by_name():
    with pytest.raises(ProjectError, match=r"corridor_two_sections.yaml:\d+: sections: .*"
                       "load_corridor"):
        load_project(EXAMPLE)


@pytest.mark.parametrize(("change", "expected"), [
    (("protect: {x: 50}", "protect: {x: 500}"),
     "c.yaml:17: sections[1].protect.x: x 500 is outside the slope section [0, 60] m"),
    (("    protect: {x: 70}\n", "    protect: {x: 70}\n    protcet: 1\n"),
     "c.yaml:14: sections[0].protcet: unknown key; did you mean 'protect'?"),
    (("name: south", "name: north"),
     "c.yaml:14: sections[1].name: section name 'north' is given twice (first in sections[0])"),
    (("    rocks: {release: {x: [1, 3]}}", "    rocks: {release: {x: [1, 3]}, seed: 4}"),
     "c.yaml:12: sections[0].rocks.seed: a section's seed derives from the corridor's"),
    (("sections:\n", "slope: {points: [[0, 1], [1, 0]], materials: talus}\nsections:\n"),
     "c.yaml:9: slope: with sections:, each section has its own slope"),
    (("    slope: {points: [[0, 30], [40, 0], [80, -1]], materials: talus}\n", ""),
     "c.yaml:10: sections[0].slope: required key is missing"),
    (("friction: 0.6", "friction: -0.6"), "c.yaml:3: materials.talus.friction: expected"),
    (("[[0, 20], [30, 0], [60, -1]]", "[[0, 20], [30, 0], [20, -1]]"),
     "c.yaml:15: sections[1].slope.points"),
])
def test_errors_name_the_line_and_key_where_they_are_written(change, expected):
    old, new = change
    assert old in CORRIDOR
    assert _error(CORRIDOR.replace(old, new, 1)).startswith(expected)


def test_sections_must_be_a_list_of_named_mappings():
    head = CORRIDOR.split("sections:")[0]
    assert _error(head + "sections: []\n").startswith("c.yaml:9: sections: expected a non-empty")
    assert "sections[0]: expected a mapping" in _error(head + "sections: [1]\n")
    assert "sections[0].name: every section needs a name" in _error(
        head + "sections:\n  - {slope: {points: [[0, 1], [1, 0]]}}\n")
    two = CORRIDOR.replace("name: north", "name: a b").replace("name: south", "name: a_b")
    assert "give the same directory name 'a_b'" in _error(two)


def test_plugin_parameters_of_a_section_are_located_in_the_section(capsys):
    text = CORRIDOR.replace("height: 3", "height: -3")
    path = ROOT / "tests" / "_corridor_bad.yaml"
    try:
        path.write_text(text)
        assert main(["simulate", str(path), "--json", "--workers", "1"]) == 2
    finally:
        path.unlink()
    err = capsys.readouterr().err
    assert "_corridor_bad.yaml:19: sections[1].measures[0].height:" in err


def _json(capsys) -> dict:
    return json.loads(capsys.readouterr().out)


def test_simulate_runs_every_section_as_its_own_project(tmp_path, capsys):
    path = tmp_path / "c.yaml"
    path.write_text(CORRIDOR)
    assert main(["simulate", str(path), "--json", "--out", str(tmp_path / "out"),
                 "--workers", "1"]) == 0
    out = _json(capsys)
    assert out["name"] == "Two cuts" and out["command"] == "simulate" and out["seed"] == 3
    assert [s["name"] for s in out["sections"]] == ["north", "south"]
    assert [s["index"] for s in out["sections"]] == [0, 1]
    assert [s["seed"] for s in out["sections"]] == [section_seed(3, 0), section_seed(3, 1)]
    totals = out["totals"]
    assert totals["sections"] == 2 and totals["rocks"] == 80
    assert totals["reaching"] == sum(s["protect"]["reaching"] for s in out["sections"])
    # Each section's block is the JSON of its project run alone with its seed.
    corridor = load_corridor(path)
    for section, block in zip(corridor.sections, out["sections"], strict=True):
        alone = tmp_path / f"{section.slug}.yaml"
        from rockfall_design.project import dump_yaml

        alone.write_text(dump_yaml(section.project.resolved_dict()))
        assert main(["simulate", str(alone), "--json"]) == 0
        single = _json(capsys)
        for key in ("stations", "stops", "protect", "rocks", "seed", "events"):
            assert block[key] == single[key], key
        recorded = json.loads((tmp_path / "out" / section.slug / "summary.json").read_text())
        assert recorded["run"]["seed"] == section.seed
    written = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert written["totals"] == totals


def test_study_runs_every_section_as_its_own_study(tmp_path, capsys):
    path = tmp_path / "c.yaml"
    study = "study:\n  vary:\n    materials.talus.restitution: [0.2, 0.3]\n"
    path.write_text(CORRIDOR.replace("sections:", study + "sections:"))
    assert main(["study", str(path), "--json", "--workers", "1",
                 "--out", str(tmp_path / "out")]) == 0
    out = _json(capsys)
    assert out["command"] == "study" and [s["name"] for s in out["sections"]] == ["north", "south"]
    assert out["totals"]["scenarios"] == 4 and out["totals"]["rocks"] == 4 * 40
    # Each section's block is the study of its project alone with its seed.
    corridor = load_corridor(path)
    from rockfall_design.project import dump_yaml

    for section, block in zip(corridor.sections, out["sections"], strict=True):
        assert block["seed"] == section.seed and len(block["scenarios"]) == 2
        alone = tmp_path / f"{section.slug}.yaml"
        alone.write_text(dump_yaml(section.project.resolved_dict()))
        assert main(["study", str(alone), "--json", "--workers", "1"]) == 0
        single = _json(capsys)
        assert block["scenarios"] == single["scenarios"]
        assert block["sensitivity"] == single["sensitivity"]
        assert (tmp_path / "out" / section.slug / "scenarios.csv").is_file()
    assert json.loads((tmp_path / "out" / "summary.json").read_text())["totals"] == out["totals"]


@pytest.mark.slow  # an end-to-end run of a few seconds: CI runs it with -m slow
def test_a_corridor_study_heeds_pool_and_draws_the_envelopes(tmp_path, capsys, monkeypatch):
    import importlib

    executors = importlib.import_module("rockfall_design.studies.executors")
    pools = []
    for name in ("_on_pool", "_on_threads"):
        real = getattr(executors, name)

        def spy(*a, _real=real, _name=name, **k):
            pools.append(_name)
            return _real(*a, **k)

        monkeypatch.setattr(executors, name, spy)
    path = tmp_path / "c.yaml"
    study = "study:\n  vary:\n    materials.talus.restitution: [0.2, 0.3]\n"
    path.write_text(CORRIDOR.replace("sections:", study + "sections:"))
    runs = []
    for pool in ("threads", "processes"):
        assert main(["study", str(path), "--json", "--workers", "2", "--pool", pool,
                     "--plot", str(tmp_path / pool)]) == 0
        out = _json(capsys)
        runs.append([block["scenarios"] for block in out["sections"]])
        for name in ("north", "south"):
            assert (tmp_path / pool / name / "study_envelopes.png").stat().st_size > 0
    assert runs[0] == runs[1]
    assert pools == ["_on_threads"] * 2 + ["_on_pool"] * 2  # each section, each pool


def test_seed_option_derives_every_section_seed(tmp_path, capsys):
    path = tmp_path / "c.yaml"
    path.write_text(CORRIDOR)
    assert main(["simulate", str(path), "--json", "--seed", "8", "--rocks", "10",
                 "--workers", "1"]) == 0
    out = _json(capsys)
    assert out["seed"] == 8
    assert [s["seed"] for s in out["sections"]] == [section_seed(8, 0), section_seed(8, 1)]
    assert out["totals"]["rocks"] == 20


def test_check_holds_only_if_every_section_holds(tmp_path, capsys):
    path = tmp_path / "c.yaml"
    path.write_text(CORRIDOR.replace("capacity_kj: 1000", "capacity_kj: 1"))
    assert main(["check", str(path), "--json", "--workers", "1"]) == 1
    out = _json(capsys)
    assert out["totals"]["ok"] is False
    assert out["totals"]["failures"] and all(
        f.startswith("south: ") for f in out["totals"]["failures"])
    assert out["sections"][0]["ok"] is True and out["sections"][1]["ok"] is False
    assert main(["check", str(path), "--workers", "1"]) == 1  # the terminal report
    text = capsys.readouterr().out
    assert "section 2 of 2: south" in text and "total" in text


def test_optimise_a_corridor_writes_a_design_per_section_that_check_accepts(tmp_path, capsys):
    out_dir = tmp_path / "out"
    assert main(["optimise", str(EXAMPLE), "--json", "--out", str(out_dir)]) == 0
    out = _json(capsys)
    totals = out["totals"]
    assert totals["ok"] is True and totals["currency"] == "EUR"
    costs = []
    for block in out["sections"]:
        best = next(a for a in block["alternatives"] if a["name"] == block["best"]["name"])
        costs.append(best["cost"])
    assert totals["cost"] == pytest.approx(sum(costs))
    assert totals["failures"] == []
    for name in ("km_12.1", "km_12.4"):
        design = out_dir / name / "design.yaml"
        assert main(["check", str(design), "--json"]) == 0
        assert _json(capsys)["ok"] is True
    assert json.loads((out_dir / "summary.json").read_text())["totals"] == totals


def test_a_corridor_design_across_scenarios_in_every_section(tmp_path, capsys):
    text = EXAMPLE.read_text().replace(
        "\ndesign:\n", "\nstudy:\n  vary:\n    materials.talus.restitution: [0.2, 0.3]\n"
        "  scenarios: grid\ndesign:\n  scenarios: all\n")
    text = text.replace("catalogue_", str(EXAMPLE.parent / "catalogue_"))
    path = tmp_path / "c.yaml"
    path.write_text(text)
    out_dir = tmp_path / "out"
    assert main(["optimise", str(path), "--json", "--out", str(out_dir)]) == 0
    out = _json(capsys)
    assert out["totals"]["ok"] is True
    for block in out["sections"]:
        assert block["scenarios"]["required"] == 2 and block["scenarios"]["of"] == 2
        assert block["scenarios"]["binding"]["index"] in (0, 1)
    design = out_dir / "km_12.4" / "design.yaml"
    assert main(["check", str(design), "--scenarios", "--json", "--workers", "1"]) == 0
    assert _json(capsys)["holds_in"] == 2


@pytest.mark.parametrize("command", ["simulate", "check"])
def test_sections_give_the_same_numbers_and_files_on_a_pool(tmp_path, capsys, command):
    path = tmp_path / "c.yaml"
    path.write_text(CORRIDOR)
    runs = {}
    for workers in ("1", "2"):
        out_dir = tmp_path / f"out{workers}"
        assert main([command, str(path), "--json", "--workers", workers,
                     "--out", str(out_dir)]) in (0, 1)
        out = _json(capsys)
        for block in out["sections"]:
            block.pop("runtime_s")
        runs[workers] = out
        for name in ("north", "south"):
            for table in ("rocks.csv", "crossings.csv"):
                runs[(workers, name, table)] = (out_dir / name / table).read_text()
    assert runs["1"] == runs["2"]
    for name in ("north", "south"):
        for table in ("rocks.csv", "crossings.csv"):
            assert runs[("1", name, table)] == runs[("2", name, table)]


def test_workers_need_a_corridor_or_scenarios(capsys):
    plain = str(ROOT / "projects" / "standard_slope.yaml")
    assert main(["simulate", plain, "--workers", "2"]) == 2
    assert "sections of a corridor" in capsys.readouterr().err


def test_the_api_takes_one_section_at_a_time():
    import rockfall_design as rd
    from rockfall_design.errors import InputError

    corridor = rd.load_corridor(EXAMPLE)
    with pytest.raises(InputError, match="section by section"):
        rd.simulate(corridor)
    result = rd.simulate(corridor.sections[1].project, rocks=20)
    assert result.seed == corridor.sections[1].seed


def _without_times(obj: object) -> object:
    """A JSON object without its wall times (they differ between runs)."""
    if isinstance(obj, dict):
        return {k: _without_times(v) for k, v in obj.items() if k != "runtime_s"}
    if isinstance(obj, list):
        return [_without_times(v) for v in obj]
    return obj


@pytest.mark.parametrize("command", ["simulate", "check"])
def test_the_api_runs_a_corridor_as_the_command_line_does(tmp_path, capsys, command):
    import rockfall_design as rd

    path = tmp_path / "c.yaml"
    path.write_text(CORRIDOR.replace("capacity_kj: 1000", "capacity_kj: 1"))
    main([command, str(path), "--json", "--workers", "1", "--seed", "11"])
    cli = _json(capsys)
    summary, results = rd.run_corridor(path, command, seed=11)
    assert _without_times(summary.to_json()) == _without_times(cli)
    assert len(results) == 2 and [b.name for b in summary.sections] == ["north", "south"]
    if command == "check":
        assert summary.ok is False and results[0].ok and not results[1].ok
    with pytest.raises(InputError, match="a corridor runs"):
        rd.run_corridor(path, "calibrate")


def test_the_api_refuses_a_single_project_as_a_corridor():
    import rockfall_design as rd

    with pytest.raises(InputError, match="not a corridor"):
        rd.run_corridor(ROOT / "projects" / "standard_slope.yaml")

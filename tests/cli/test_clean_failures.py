"""Clean failures (issue 27, item 9): one line, the right exit code, the real reason.

--plot and --report into one directory work together; a factor that would
overflow is an input error at its key; unknown --block names and blocked
concepts say so; the study's memory guard counts the scenarios there are; a
corridor section's directory cannot take the name of the corridor's
summary; a cut-short DXF says so; design.max_rocks below the search rocks is
refused.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from rockfall_design.cli.program import main

ROOT = Path(__file__).resolve().parents[2]
PROJECTS = ROOT / "projects"


def one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


def with_safety(directory: Path, safety: str) -> Path:
    """quarry_fence_ditch.yaml with its ``safety:`` section replaced by ``safety``."""
    text = (PROJECTS / "quarry_fence_ditch.yaml").read_text()
    start = text.index("safety:\n")
    end = text.index("\n", text.index("statistic:", start))
    path = directory / "project.yaml"
    path.write_text(text[:start] + safety + text[end:])
    return path


@pytest.mark.parametrize("command, project", [
    ("simulate", "standard_slope.yaml"),
    # check's seven figures as plot files and in its report (8 s): the slow set;
    # simulate's run in the fast one.
    pytest.param("check", "quarry_fence_ditch.yaml", marks=pytest.mark.slow),
])
@pytest.mark.parametrize("formats", ["svg", pytest.param("svg,png", marks=pytest.mark.slow)])
def test_plot_and_report_into_one_folder_work_together(tmp_path, capsys, command, project,
                                                       formats):
    both = tmp_path / "both"
    code = main([command, str(PROJECTS / project), "--rocks", "30", "--plot", str(both),
                 "--report", str(both), "--plot-format", formats, "--json"])
    err = capsys.readouterr().err
    assert code in (0, 1) and "Traceback" not in err, err
    names = {p.name for p in both.iterdir()}
    assert {"report.html", "report.md", "profile.svg", "envelopes.svg", "stops.svg"} <= names
    if "png" in formats:
        assert "profile.png" in names
    assert "profile.svg" in (both / "report.md").read_text()


@pytest.mark.parametrize("safety, key, bound", [
    ("safety: {concept: uni11211, gamma_tr: 1e200}", "safety.gamma_tr", "<= 10"),
    ("safety: {concept: uni11211, gamma_volf: 1e200, gamma_gamma: 1e200}", "safety.gamma_volf",
     "<= 10"),
    ("safety: {concept: uni11211, f_min_m: 1e300}", "safety.f_min_m", "<= 100"),
    ("safety: {concept: spang, energy_factor: 1e308}", "safety.energy_factor", "<= 100"),
    ("safety: {concept: spang, height_factor: 1e308}", "safety.height_factor", "<= 100"),
])
def test_a_factor_that_would_overflow_is_an_input_error_at_its_key(tmp_path, capsys, safety,
                                                                    key, bound):
    path = with_safety(tmp_path, safety)
    assert main(["check", str(path), "--rocks", "20", "--json"]) == 2
    err = one_line(capsys)
    assert f"{key}: expected a number {bound}" in err and "plugin" not in err, err


def test_an_unknown_block_name_is_refused(capsys):
    code = main(["check", str(PROJECTS / "quarry_fence_ditch.yaml"), "--rocks", "10",
                 "--block", "no-such-plugin"])
    err = one_line(capsys)
    assert code == 2 and "--block no-such-plugin: no installed plugin has this name" in err, err
    assert main(["plugins", "--block", "spnag"]) == 2
    assert "did you mean 'spang'?" in one_line(capsys)


def test_a_blocked_concept_says_blocked(capsys):
    code = main(["check", str(PROJECTS / "quarry_fence_ditch.yaml"), "--rocks", "10",
                 "--block", "spang"])
    err = one_line(capsys)
    assert code == 2, err
    assert "safety.concept: safety concept 'spang' is provided by" in err and "blocked" in err


def test_a_blocked_cost_model_says_blocked(capsys):
    code = main(["optimise", str(PROJECTS / "design_ditch_or_fence.yaml"), "--rocks", "50",
                 "--block", "unit_prices"])
    err = one_line(capsys)
    assert code == 2 and "design.costs.model: cost model 'unit_prices'" in err, err
    assert "blocked" in err


def test_the_study_memory_guard_counts_the_scenarios_there_are(capsys, monkeypatch):
    from rockfall_design.run import simulation

    monkeypatch.setattr(simulation, "simulation_memory", lambda project, n: 2**50)
    code = main(["study", str(PROJECTS / "study_talus.yaml"), "--rocks", "20",
                 "--workers", "100000"])
    err = one_line(capsys)
    assert code == 2 and "9 scenarios of 20 rocks at once" in err, err
    assert "100000" not in err.replace(",", "")


def test_a_corridor_section_cannot_take_the_summary_name(tmp_path, capsys):
    text = (PROJECTS / "corridor_two_sections.yaml").read_text()
    text = text.replace("  - name: km 12.1", "  - name: summary.json")
    text = text.replace("catalogue_", f"{PROJECTS}/catalogue_")
    path = tmp_path / "corridor.yaml"
    path.write_text(text)
    code = main(["simulate", str(path), "--rocks", "10", "--out", str(tmp_path / "out")])
    err = one_line(capsys)
    assert code == 2 and "sections[0].name" in err and "summary.json" in err, err
    assert "directory" in err and not (tmp_path / "out").exists()


def test_a_cut_short_dxf_says_so(tmp_path, capsys):
    ezdxf = pytest.importorskip("ezdxf", reason="ezdxf (the [dxf] extra) is not installed")
    doc = ezdxf.new()
    doc.modelspace().add_lwpolyline([(0, 100), (60, 30), (200, 12)],
                                    dxfattribs={"layer": "SECTION"})
    whole = tmp_path / "whole.dxf"
    doc.saveas(whole)
    text = whole.read_text()
    (tmp_path / "section.dxf").write_text(text[:100])
    project = tmp_path / "project.yaml"
    project.write_text("name: Drawing\nslope: {dxf: section.dxf, layer: SECTION, materials: "
                       "talus}\nmaterials:\n  talus: {restitution: 0.35, friction: 0.58}\n"
                       "rocks:\n  radius: 0.5\n  release: {x: 1}\n")
    assert main(["simulate", str(project), "--rocks", "5"]) == 2
    err = one_line(capsys)
    assert "section.dxf" in err and "cut short" in err and "StopIteration" not in err, err


def test_max_rocks_below_the_search_rocks_is_refused(tmp_path, capsys):
    text = (PROJECTS / "design_ditch_or_fence.yaml").read_text()
    text = text.replace("  max_measures: 1", "  max_measures: 1\n  max_rocks: 1")
    text = text.replace("catalogue_", f"{PROJECTS}/catalogue_")
    path = tmp_path / "project.yaml"
    path.write_text(text)
    assert main(["optimise", str(path), "--rocks", "100", "--json"]) == 2
    err = one_line(capsys)
    assert "design.max_rocks: expected at least the 100 rocks of the search" in err, err
    assert main(["optimise", str(PROJECTS / "design_ditch_or_fence.yaml"), "--rocks", "100",
                 "--max-rocks", "5", "--json"]) == 2
    assert "--max-rocks 5" in one_line(capsys)
    from rockfall_design import optimise
    from rockfall_design.errors import ProjectError

    with pytest.raises(ProjectError, match="design.max_rocks"):
        optimise(path, rocks=100)


def test_json_of_a_check_is_still_valid(capsys):
    assert main(["check", str(PROJECTS / "quarry_fence_ditch.yaml"), "--rocks", "20",
                 "--json"]) in (0, 1)
    json.loads(capsys.readouterr().out)


def test_candidates_inside_the_protected_zone_are_refused_at_their_key(tmp_path, capsys):
    text = (PROJECTS / "design_ditch_or_fence.yaml").read_text()
    # by pattern: the project's stations change with its design
    text = re.sub(r"protect:\n  x: [0-9.]+", "protect:\n  x: 150", text, count=1)
    text = re.sub(r"\n      x: \[[0-9., ]+\]", "\n      x: [151, 170]", text, count=1)
    text = text.replace("catalogue_", f"{PROJECTS}/catalogue_")
    path = tmp_path / "project.yaml"
    path.write_text(text)
    assert main(["optimise", str(path), "--rocks", "100", "--json"]) == 2
    err = one_line(capsys)
    assert "design.candidates[0].x: station range [151, 170] lies inside the protected zone" \
        in err, err

"""Outputs never touch the inputs, nor files the program did not write (issue 27, item 1).

An output set that would overwrite or remove a file the run reads (the
project, its survey, library, catalogues, a summary to repeat) is refused
before any work, one line, exit code 2, every file as it was. A stale result
is removed only if the manifest of its directory lists it as written by the
program and unchanged since.
"""

from __future__ import annotations

import json
import os
import re
import shutil
from pathlib import Path

import pytest

from rockfall_design.cli.program import main
from rockfall_design.report.outputs import OutputSet
from rockfall_design.report.staging import MANIFEST

ROOT = Path(__file__).resolve().parents[2]
PROJECTS = ROOT / "projects"


def one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


def snapshot(directory: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(directory.iterdir()) if p.is_file()}


def design_project(directory: Path) -> Path:
    """design_ditch_or_fence.yaml with its catalogues, copied into ``directory``."""
    for name in ("design_ditch_or_fence.yaml", "catalogue_products.yaml",
                 "catalogue_costs.yaml"):
        shutil.copy(PROJECTS / name, directory / name)
    return directory / "design_ditch_or_fence.yaml"


def test_optimise_out_into_the_project_folder_is_refused(tmp_path, capsys, monkeypatch):
    project = design_project(tmp_path)
    (tmp_path / "design.yaml").write_bytes(project.read_bytes())
    before = snapshot(tmp_path)
    monkeypatch.chdir(tmp_path)
    ran = []
    import rockfall_design.api as api

    monkeypatch.setattr(api, "optimise", lambda *a, **k: ran.append(1))
    code = main(["optimise", "design.yaml", "--rocks", "200", "--out", "."])
    err = one_line(capsys)
    assert code == 2, err
    assert "design.yaml" in err and "project file" in err and "reads" in err, err
    assert ran == []  # refused before any work
    assert snapshot(tmp_path) == before


def test_simulate_out_over_the_survey_csv_is_refused(tmp_path, capsys):
    shutil.copy(PROJECTS / "materials.yaml", tmp_path / "materials.yaml")
    shutil.copy(PROJECTS / "survey_section.csv", tmp_path / "rocks.csv")
    text = (PROJECTS / "survey_slope.yaml").read_text().replace(
        "csv: survey_section.csv", "csv: rocks.csv")
    (tmp_path / "project.yaml").write_text(text)
    before = snapshot(tmp_path)
    code = main(["simulate", str(tmp_path / "project.yaml"), "--rocks", "20",
                 "--out", str(tmp_path)])
    err = one_line(capsys)
    assert code == 2, err
    assert "rocks.csv" in err and "survey section" in err, err
    assert snapshot(tmp_path) == before
    # and the next run still works
    assert main(["simulate", str(tmp_path / "project.yaml"), "--rocks", "20", "--json"]) == 0


def test_a_link_to_the_materials_library_is_refused(tmp_path, capsys):
    shutil.copy(PROJECTS / "materials.yaml", tmp_path / "materials.yaml")
    shutil.copy(PROJECTS / "survey_section.csv", tmp_path / "survey_section.csv")
    shutil.copy(PROJECTS / "survey_slope.yaml", tmp_path / "project.yaml")
    out = tmp_path / "out"
    out.mkdir()
    os.symlink(tmp_path / "materials.yaml", out / "summary.json")
    library = (tmp_path / "materials.yaml").read_bytes()
    code = main(["simulate", str(tmp_path / "project.yaml"), "--rocks", "20", "--out", str(out)])
    err = one_line(capsys)
    assert code == 2 and "materials library" in err, err
    assert (tmp_path / "materials.yaml").read_bytes() == library
    assert sorted(p.name for p in out.iterdir()) == ["summary.json"]


def test_a_hard_link_to_the_cost_catalogue_is_refused(tmp_path, capsys):
    project = design_project(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    os.link(tmp_path / "catalogue_costs.yaml", out / "alternatives.csv")
    costs = (tmp_path / "catalogue_costs.yaml").read_bytes()
    code = main(["optimise", str(project), "--rocks", "200", "--out", str(out)])
    err = one_line(capsys)
    assert code == 2 and "cost file" in err, err
    assert (tmp_path / "catalogue_costs.yaml").read_bytes() == costs


def test_repeat_into_the_folder_of_its_summary_is_refused(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["simulate", str(PROJECTS / "standard_slope.yaml"), "--rocks", "20",
                 "--out", str(out), "--json"]) == 0
    capsys.readouterr()
    before = snapshot(out)
    code = main(["simulate", "--repeat", str(out / "summary.json"), "--out", str(out)])
    err = one_line(capsys)
    assert code == 2 and "summary to repeat" in err, err
    assert snapshot(out) == before


def hopeless(directory: Path) -> Path:
    """A design project no family can meet (fences upslope of the release)."""
    text = (PROJECTS / "design_ditch_or_fence.yaml").read_text()
    text = text[: text.index("    - type: ditch")]
    # by pattern: the project's stations change with its design
    text = re.sub(r"\n      x: \[[0-9., ]+\]", "\n      x: [2, 10]", text, count=1)
    text = re.sub(r"protect:\n  x: [0-9.]+", "protect:\n  x: 50", text, count=1)
    text = text.replace("catalogue_", f"{PROJECTS}/catalogue_")
    assert "x: [2, 10]" in text and "protect:\n  x: 50" in text
    path = directory / "hopeless.yaml"
    path.write_text(text)
    return path


def test_optimise_without_a_design_keeps_the_users_own_figures(tmp_path, capsys):
    project = hopeless(tmp_path)
    plot = tmp_path / "figs"
    plot.mkdir()
    (plot / "profile.png").write_bytes(b"\x89PNG the user's own drawing")
    code = main(["optimise", str(project), "--rocks", "200", "--plot", str(plot), "--json"])
    assert code == 1 and json.loads(capsys.readouterr().out)["best"] is None
    assert (plot / "profile.png").read_bytes() == b"\x89PNG the user's own drawing"
    assert (plot / "alternatives.png").exists()


def test_a_stale_result_is_removed_only_as_it_was_written(tmp_path):
    with OutputSet() as files:
        files.write_text(tmp_path / "a.yaml", "ours\n")
        files.write_text(tmp_path / "b.yaml", "ours too\n")
    manifest = json.loads((tmp_path / MANIFEST).read_text())
    assert sorted(manifest["files"]) == ["a.yaml", "b.yaml"]
    (tmp_path / "b.yaml").write_text("edited by the user since\n")
    (tmp_path / "c.yaml").write_text("the user's\n")
    with OutputSet() as files:
        for name in ("a.yaml", "b.yaml", "c.yaml"):
            files.remove(tmp_path / name)
        files.write_text(tmp_path / "d.json", "{}\n")
    assert not (tmp_path / "a.yaml").exists()
    assert (tmp_path / "b.yaml").read_text() == "edited by the user since\n"
    assert (tmp_path / "c.yaml").read_text() == "the user's\n"
    assert sorted(json.loads((tmp_path / MANIFEST).read_text())["files"]) == ["d.json"]


@pytest.mark.parametrize("damage", ["", "not json", '{"files": 3}', "[]"])
def test_a_damaged_manifest_lists_nothing(tmp_path, damage):
    with OutputSet() as files:
        files.write_text(tmp_path / "a.yaml", "ours\n")
    (tmp_path / MANIFEST).write_text(damage)
    with OutputSet() as files:
        files.remove(tmp_path / "a.yaml")
    assert (tmp_path / "a.yaml").read_text() == "ours\n"

"""Nothing echoed, nothing injected (issue 27, item 10).

An error about a file the project names (a survey, a materials library, a
summary to repeat) names the file, line and column, never what the file
holds: the path may point at /etc/passwd or a key file. Project text is
stripped of control characters before it reaches a terminal, and report.md
escapes it as report.html does.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rockfall_design.cli.program import main
from rockfall_design.project import load_project

ROOT = Path(__file__).resolve().parents[2]
PROJECTS = ROOT / "projects"
SECRET = "sk_live_0123456789abcdef"


def one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


def survey_project(directory: Path, csv: str | None = None, library: str | None = None) -> Path:
    text = (PROJECTS / "survey_slope.yaml").read_text()
    csv = csv or str(PROJECTS / "survey_section.csv")
    library = library or str(PROJECTS / "materials.yaml")
    text = text.replace("csv: survey_section.csv", f"csv: {csv}")
    text = text.replace("library: materials.yaml", f"library: {library}")
    path = directory / "project.yaml"
    path.write_text(text)
    return path


@pytest.fixture
def secrets(tmp_path) -> Path:
    path = tmp_path / ".env"
    path.write_text(f"SECRET_KEY={SECRET}\nDEBUG=1\n")
    return path


@pytest.fixture
def passwd(tmp_path) -> Path:
    """A file shaped as /etc/passwd (the real one may be absent)."""
    path = tmp_path / "passwd"
    path.write_text(f"root:x:0:0:{SECRET}:/root:/bin/bash\ndaemon:x:1:1::/usr/sbin:/bin/sh\n")
    return path


@pytest.mark.parametrize("which", ["csv", "library"])
@pytest.mark.parametrize("target", ["secrets", "passwd"])
def test_a_foreign_file_is_not_echoed(tmp_path, capsys, request, which, target):
    path = request.getfixturevalue(target)
    project = survey_project(tmp_path, **{which: str(path)})
    code = main(["simulate", str(project), "--rocks", "5"])
    err = one_line(capsys)
    assert code == 2, err
    assert str(path) in err and ":1:" in err, err
    assert SECRET not in err and "root:x" not in err and "SECRET_KEY" not in err


def test_a_bad_value_in_a_survey_is_located_not_quoted(tmp_path, capsys):
    csv = tmp_path / "section.csv"
    csv.write_text(f"x,y,material\n0,100,talus\n30,{SECRET},talus\n")
    code = main(["simulate", str(survey_project(tmp_path, csv=str(csv))), "--rocks", "5"])
    err = one_line(capsys)
    assert code == 2 and f"{csv}:3: y: expected a number" in err, err
    assert SECRET not in err


def test_a_library_of_key_value_pairs_is_not_echoed(tmp_path, capsys):
    library = tmp_path / "keys.yaml"
    library.write_text(f"api_key: {SECRET}\n")
    code = main(["simulate", str(survey_project(tmp_path, library=str(library))), "--rocks", "5"])
    err = one_line(capsys)
    assert code == 2 and str(library) in err, err
    assert SECRET not in err


@pytest.mark.parametrize("edit", [
    lambda s: s["run"].update(seed=SECRET),
    lambda s: s["run"].update(rocks=SECRET),
    lambda s: s["run"]["project"]["analysis"].update(envelope_points=SECRET),
    lambda s: s["run"]["project"]["rocks"].update(count=SECRET),
], ids=["seed", "rocks", "envelope_points", "count"])
def test_an_edited_summary_is_not_echoed(tmp_path, capsys, edit):
    out = tmp_path / "out"
    assert main(["simulate", str(PROJECTS / "standard_slope.yaml"), "--rocks", "10",
                 "--out", str(out), "--json"]) == 0
    capsys.readouterr()
    summary = json.loads((out / "summary.json").read_text())
    edit(summary)
    edited = tmp_path / "edited.json"
    edited.write_text(json.dumps(summary))
    code = main(["simulate", "--repeat", str(edited), "--json"])
    err = one_line(capsys)
    assert code == 2 and str(edited) in err, err
    assert SECRET not in err


EVIL_NAME = "Evil \x1b]0;pwned\x07\x1b[2J<script>alert(1)</script>"
EVIL_TEXT = "line one \x1b[31mred\n<iframe src=x></iframe> \u202eexe.txt"


def evil_project(directory: Path) -> Path:
    text = (PROJECTS / "quarry_fence_ditch.yaml").read_text()
    lines = []
    for line in text.splitlines():
        if line.startswith("name:"):
            line = "name: " + json.dumps(EVIL_NAME)
        elif line.startswith("description:"):
            line = "description: " + json.dumps(EVIL_TEXT)
        elif line.strip() == "stations: [50, 90, 115]":
            # One station: its passage figure's title carries the name as the
            # three did, and report.html draws two figures fewer.
            line = line.replace("[50, 90, 115]", "[90]")
        lines.append(line)
    path = directory / "evil.yaml"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_control_characters_of_a_project_never_reach_the_terminal(tmp_path, capsys):
    project = load_project(evil_project(tmp_path))
    assert project.name == "Evil ]0;pwned[2J<script>alert(1)</script>"
    assert project.description == "line one [31mred\n<iframe src=x></iframe> exe.txt"
    for command in ("simulate", "check"):
        main([command, str(tmp_path / "evil.yaml"), "--rocks", "20"])
        captured = capsys.readouterr()
        assert "Evil" in captured.out
        assert "\x1b" not in captured.out + captured.err and "\x07" not in captured.out


def test_an_error_line_has_no_control_characters(tmp_path, capsys):
    path = tmp_path / "bad.yaml"
    path.write_text("name: x\nslope: {points: [[0, 1], [1, 0]], materials: talus}\n"
                    "materials: {\"\\e[2Jtalus\": {restitution: 2}}\n")
    assert main(["simulate", str(path)]) == 2
    err = one_line(capsys)
    assert "\x1b" not in err


def test_report_md_escapes_the_project_text(tmp_path, capsys):
    report = tmp_path / "report"
    assert main(["check", str(evil_project(tmp_path)), "--rocks", "20", "--report",
                 str(report), "--json"]) in (0, 1)
    md = (report / "report.md").read_text()
    html = (report / "report.html").read_text()
    for text in (md, html):
        assert "<script>" not in text and "<iframe" not in text
        assert "\x1b" not in text
    assert "&lt;script>alert(1)&lt;/script>" in md

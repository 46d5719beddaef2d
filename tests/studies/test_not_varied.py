"""Paths a study may not vary are refused at their key (issue 27, item 4).

``name`` and ``description`` cannot change a scenario's result; the study
sets each scenario's seed itself and runs every scenario with the run's
rock count. Varying them used to run every scenario with the same rocks,
record the values as applied and rank their "effect" (noise).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rockfall_design.cli.program import main
from rockfall_design.errors import ProjectError
from rockfall_design.project import load_project
from rockfall_design.studies.paths import with_values

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "projects" / "study_talus.yaml"


def varying(tmp_path: Path, line: str) -> Path:
    text = STUDY.read_text().replace("    rocks.volume: [0.5, 1.0, 2.0]", f"    {line}")
    path = tmp_path / "study.yaml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("line, key", [
    ("name: [a, b]", "study.vary.name"),
    ("description: [a, b]", "study.vary.description"),
    ("rocks.seed: [1, 2]", "study.vary.rocks.seed"),
    ("rocks.count: [10, 20]", "study.vary.rocks.count"),
])
@pytest.mark.parametrize("command", ["study", "simulate"])
def test_a_path_that_cannot_be_applied_is_refused_at_its_key(tmp_path, capsys, line, key,
                                                             command):
    path = varying(tmp_path, line)
    code = main([command, str(path), "--rocks", "10", "--json"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert f"study.yaml:32: {key}: cannot be varied" in err


def test_with_values_refuses_them_too():
    project = load_project(STUDY)
    with pytest.raises(ProjectError, match="rocks.seed: cannot be varied"):
        with_values(project, {"rocks.seed": 3})
    # what may vary still does
    assert with_values(project, {"rocks.density": 2700}).rocks.density == 2700

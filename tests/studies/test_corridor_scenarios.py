"""Corridors: check --scenarios (every section over its study's scenarios), the section headings."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rockfall_design.cli.program import main
from rockfall_design.project import dump_yaml, load_corridor, section_seed
from rockfall_design.report.staging import MANIFEST

from .test_corridor import CORRIDOR

STUDY = "study:\n  vary:\n    materials.talus.restitution: [0.2, 0.3]\nsections:"


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "c.yaml"
    path.write_text(text)
    return path


def _json(capsys) -> dict:
    return json.loads(capsys.readouterr().out)


def _drop_runtime(summary: dict) -> dict:
    for s in summary["scenarios"]:
        s.pop("runtime_s", None)
    return summary


@pytest.mark.slow  # an end-to-end run of a few seconds: CI runs it with -m slow
def test_every_section_is_checked_over_its_scenarios_as_alone(tmp_path, capsys):
    path = _write(tmp_path, CORRIDOR.replace("sections:", STUDY))
    out_dir, plot = tmp_path / "out", tmp_path / "plot"
    assert main(["check", str(path), "--scenarios", "--json", "--workers", "1",
                 "--out", str(out_dir), "--plot", str(plot)]) == 0
    out = _json(capsys)
    assert out["command"] == "check" and out["scenarios"] is True and out["seed"] == 3
    assert [s["name"] for s in out["sections"]] == ["north", "south"]
    assert [s["seed"] for s in out["sections"]] == [section_seed(3, 0), section_seed(3, 1)]
    totals = out["totals"]
    assert totals["sections"] == 2 and totals["scenarios"] == 4 and totals["rocks"] == 4 * 40
    assert totals["ok"] is True and totals["failures"] == []
    margins = [(b["binding"]["margin"], b["name"]) for b in out["sections"]
               if b["binding"]["margin"] is not None]
    assert (totals["binding"]["margin"], totals["binding"]["section"]) == min(margins)
    # each section's block is check --scenarios of its project alone, with its seed
    corridor = load_corridor(path)
    for section, block in zip(corridor.sections, out["sections"], strict=True):
        alone = tmp_path / f"{section.slug}.yaml"
        alone.write_text(dump_yaml(section.project.resolved_dict()))
        assert main(["check", str(alone), "--scenarios", "--json", "--workers", "1"]) == 0
        single = _drop_runtime(_json(capsys))
        assert {k: v for k, v in _drop_runtime(block).items()
                if k not in ("name", "index")} == single
        recorded = json.loads((out_dir / section.slug / "summary.json").read_text())
        assert recorded["seed"] == section.seed and recorded["of"] == 2
        names = {p.name for p in (plot / section.slug).iterdir()} - {MANIFEST}
        # and, where rocks met them, a distribution figure per station and measure
        passing = {n for n in names if n.startswith("passing_")}
        assert names - passing == {
            "profile.png", "envelopes.png", "stops.png", "margins.png"}
    assert json.loads((out_dir / "summary.json").read_text())["totals"] == totals


def test_the_corridor_fails_when_a_section_holds_in_too_few_scenarios(tmp_path, capsys):
    # a 1 kJ fence holds no rock of the south section in any scenario
    weak = CORRIDOR.replace("sections:", STUDY).replace("capacity_kj: 1000", "capacity_kj: 1")
    path = _write(tmp_path, weak)
    assert main(["check", str(path), "--scenarios", "--json", "--workers", "1"]) == 1
    out = _json(capsys)
    north, south = out["sections"]
    assert north["ok"] is True and south["ok"] is False and south["holds_in"] == 0
    assert out["totals"]["ok"] is False and out["totals"]["binding"]["section"] == "south"
    assert out["totals"]["failures"] and all(
        f.startswith("south: scenario ") for f in out["totals"]["failures"])
    assert main(["check", str(path), "--scenarios", "--workers", "1"]) == 1
    text = capsys.readouterr().out
    assert "section 2 of 2: south" in text and "Design holds in 0 of 2 scenarios" in text
    assert "The corridor fails" in text and "total" in text


def test_a_corridor_without_a_study_is_one_line_and_writes_nothing(tmp_path, capsys):
    path = _write(tmp_path, CORRIDOR)
    out_dir = tmp_path / "out"
    assert main(["check", str(path), "--scenarios", "--out", str(out_dir)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "c.yaml: check --scenarios needs a study: section" in err
    assert not out_dir.exists()


def test_the_section_heading_names_the_seed_the_section_ran_with(tmp_path, capsys):
    path = _write(tmp_path, CORRIDOR)
    assert main(["simulate", str(path), "--seed", "8", "--rocks", "10", "--workers", "1"]) == 0
    text = capsys.readouterr().out
    assert f"north (seed {section_seed(8, 0)})" in text
    assert f"south (seed {section_seed(8, 1)})" in text

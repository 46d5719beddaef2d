"""check --scenarios --plot and --report: the binding scenario in full, every scenario's margin."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rockfall_design.cli.program import main
from rockfall_design.project import load_project

from ..optimiser.test_across import study_text

FIGURES = ("profile", "envelopes", "stops", "margins")


def _json(capsys) -> dict:
    return json.loads(capsys.readouterr().out)


def _weak(tmp_path: Path, seed: int, share: str = "all") -> Path:
    """The four scenarios of test_across with a 300 kJ fence: the big rocks (1, 3) strain it."""
    path = tmp_path / "p.yaml"
    path.write_text(study_text(seed, share).replace("capacity_kj: 1000", "capacity_kj: 300"))
    return path


@pytest.mark.slow  # an end-to-end run of a few seconds: CI runs it with -m slow
def test_plot_and_report_show_the_binding_scenario_and_every_margin(tmp_path, capsys):
    # What is asserted holds whichever scenario binds and whatever the verdict.
    path = _weak(tmp_path, 3, "{share: 0.5}")
    plot, report = tmp_path / "plot", tmp_path / "report"
    code = main(["check", str(path), "--scenarios", "--json", "--workers", "1", "--rocks",
                 "200", "--plot", str(plot),
                 "--report", str(report), "--out", str(tmp_path / "out")])
    out = _json(capsys)
    assert code == (0 if out["ok"] else 1)
    assert json.loads((tmp_path / "out" / "summary.json").read_text()) == out
    for stem in FIGURES:
        assert (plot / f"{stem}.png").stat().st_size > 0
        assert (report / f"{stem}.svg").is_file()
    b = out["binding"]
    # a share of 0.5 requires 2 of the 4: the scenario of the second largest margin decides
    assert out["required"] == 2
    assert b["margin"] == sorted((s["margin"] for s in out["scenarios"]), reverse=True)[1]
    md = (report / "report.md").read_text()
    html = (report / "report.html").read_text()
    # the result: the count against the required, and the binding scenario named
    assert (f"it holds in {out['holds_in']} of 4 scenarios" in md
            and f"required: {out['required']}" in md)
    assert f"Binding: scenario {b['index']}" in md
    # a row per scenario, the binding one marked, then its check tables in full
    assert "### Scenarios: 4" in md
    rows = [line for line in md.splitlines() if line.startswith("| * | ")]
    assert len(rows) == 1 and rows[0].startswith(f"| * | {b['index']} | ")
    head = f"Binding scenario {b['index']} ("
    assert f"### {head}" in md and "Measures and their checks" in md
    for s in out["scenarios"]:
        assert str(s["seed"]) in md
    # figures: the margins, then the binding scenario's own
    assert md.index("(margins.svg)") < md.index("(profile.svg)")
    # ... and one distribution figure per station and measure (passing_*.svg)
    passing = list(report.glob("passing_*.svg"))
    assert passing and html.count("<svg") == 4 + len(passing)
    assert ('<p id="verdict" class="verdict ok">Holds with confidence' in html) == (
        out["verdict"]["state"] == "holds with confidence")
    assert "<link" not in html and "<script" not in html and 'src="http' not in html


def test_the_figures_are_of_the_same_rocks_as_the_binding_scenario_checked(tmp_path, capsys,
                                                                            registry):
    from rockfall_design.cli.scenario_commands import ScenariosCheckResult
    from rockfall_design.studies.scenario_checks import check_across

    project = load_project(_weak(tmp_path, 4))
    found = check_across(project, registry, rocks=120)
    result = ScenariosCheckResult(project, found, registry)
    summary = found.to_json()
    drawn = dict(result.binding_check.summary)
    block = next(s for s in summary["scenarios"] if s["index"] == summary["binding"]["index"])
    block = {k: v for k, v in block.items() if k not in ("index", "values", "margin",
                                                         "binds_at", "runtime_s")}
    drawn.pop("runtime_s")
    assert drawn == block
    # and the distributions at every station and barrier of the binding scenario
    names = set(result.figures())
    assert set(FIGURES) <= names
    assert all(n.startswith("passing_") for n in names - set(FIGURES))


def test_margins_figure_marks_the_binding_scenario_and_the_count_required():
    from rockfall_design.report.design_figures import margins_figure

    scenarios = [
        {"index": 0, "values": {"materials.talus.restitution": 0.2}, "margin": 0.4,
         "binds_at": "fence: height_factor", "ok": True, "holds_with_confidence": True},
        {"index": 1, "values": {"materials.talus.restitution": 0.3}, "margin": -0.1,
         "binds_at": "residual", "ok": False, "holds_with_confidence": False},
        {"index": 2, "values": {}, "margin": None, "binds_at": "", "ok": True,
         "holds_with_confidence": True},
    ]
    fig = margins_figure(scenarios, required=2, binding=1, title="t")
    ax, strip = fig.axes
    labels = [t.get_text() for t in ax.get_yticklabels()]
    assert labels == ["#0 talus.restitution = 0.2", "* #1 talus.restitution = 0.3",
                      "#2 as written"]
    assert [round(p.get_width(), 6) for p in ax.patches] == [40.0, -10.0, 0.0]
    texts = [t.get_text() for t in ax.texts]
    assert "no check to bind" in texts[2] and "(binding)" in texts[1]
    assert any("required: 2 of 3" in t.get_text() for t in strip.texts)
    assert "holds in 2 of 3" in strip.get_xlabel()


def test_a_project_without_a_study_is_one_line_and_writes_nothing(tmp_path, capsys):
    path = tmp_path / "p.yaml"
    text = study_text().split("study:\n")[0] + "design:" + study_text().split("design:", 1)[1]
    path.write_text(text.replace("  scenarios: all\n", ""))
    plot = tmp_path / "plot"
    assert main(["check", str(path), "--scenarios", "--plot", str(plot),
                 "--report", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "needs a study: section" in err
    assert not plot.exists() and not (tmp_path / "r").exists()

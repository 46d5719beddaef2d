"""The public Python API: results, tables, figures and reports, as a notebook uses them."""

from __future__ import annotations

import json
import re
from pathlib import Path

import matplotlib
import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

import rockfall_design as rd
from rockfall_design.cli.program import main
from rockfall_design.errors import ProjectError

ROOT = Path(__file__).resolve().parents[1]
PROJECTS = ROOT / "projects"
STANDARD = PROJECTS / "standard_slope.yaml"
QUARRY = PROJECTS / "quarry_fence_ditch.yaml"
TWO_ZONES = PROJECTS / "design_two_zones.yaml"
#: A design project that optimises in seconds (tests/data/design_small.yaml), for the tests of
#: what an optimisation hands over rather than of what it designs.
SMALL_DESIGN = ROOT / "tests" / "data" / "design_small.yaml"


@pytest.fixture(scope="module")
def two_zones(python_page_run):
    """The issue's example: optimise design_two_zones, seed 1.

    The Python page's own run of it (docs/python.md; conftest's ``python_page_run``,
    which test_docs.py checks too), not a second one: half a minute to a minute on two
    cores, so the tests that use it are in the ``slow`` set (``python -m pytest -m slow``,
    run by .ci/run). The page asks for 1,000 rocks, the issue for 2,000: either is below
    the 5,073 rocks the search takes at least for a residual of 0.1 % (its first look at
    the default budget of 400,000 rocks; 4,603 at the 50,000 of before), so the run is
    the same.
    """
    r = python_page_run.namespace["r"]
    assert isinstance(r, rd.OptimiseResult) and r.project.name == \
        rd.load_project(TWO_ZONES).name and r.seed == 1
    assert r.summary["search_rocks"] == 5073
    return r


@pytest.mark.slow
def test_the_python_page_block_runs(python_page_run):
    """The Python page's block runs as written (conftest's ``python_page_run``).

    It is here, beside the tests that read the same run (``two_zones``), so that
    pytest-xdist's ``--dist loadscope`` gives them one worker and one run of it.
    """
    assert isinstance(python_page_run.namespace["r"].plot(), Figure)
    assert (python_page_run.folder / "report" / "report.html").is_file()


def _without_runtime(d: dict) -> dict:
    return {k: v for k, v in d.items() if k != "runtime_s"}


def test_the_api_is_exported():
    for name in ("load_project", "simulate", "check", "optimise", "SimulationResult",
                 "CheckResult", "OptimiseResult"):
        assert name in rd.__all__ and getattr(rd, name).__doc__


def test_load_project_validates_the_plugin_sections(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text(QUARRY.read_text().replace("type: fence", "type: fense"))
    with pytest.raises(ProjectError, match="did you mean 'fence'"):
        rd.load_project(bad)


def test_simulate_rocks_is_one_row_per_rock():
    r = rd.simulate(rd.load_project(STANDARD), rocks=150, seed=3)
    assert isinstance(r.rocks, pd.DataFrame) and len(r.rocks) == 150
    assert r.rocks["rock"].tolist() == list(range(150))
    assert len(r.crossings) == 150 * len(r.project.analysis.stations)
    assert r.stations["x_m"].tolist() == [80.0]
    assert r.stations.loc[0, "crossings"] == r.summary["stations"][0]["crossings"]
    assert "passing_height_p95_m" in r.stations and "energy_max_kj" in r.stations
    assert r.seed == 3 and r.n_rocks == 150


def test_summary_is_the_json_of_the_command(capsys):
    r = rd.simulate(STANDARD, rocks=120, seed=5)
    assert main(["simulate", str(STANDARD), "--rocks", "120", "--seed", "5", "--json"]) == 0
    assert _without_runtime(json.loads(capsys.readouterr().out)) == \
        _without_runtime(json.loads(json.dumps(r.summary)))
    c = rd.check(QUARRY, rocks=120, seed=5)
    assert main(["check", str(QUARRY), "--rocks", "120", "--seed", "5", "--json"]) == 0
    assert _without_runtime(json.loads(capsys.readouterr().out)) == \
        _without_runtime(json.loads(json.dumps(c.summary)))


def test_check_tables():
    c = rd.check(QUARRY, rocks=200, seed=2)
    assert c.ok is c.summary["ok"]
    assert c.measures["type"].tolist() == ["fence", "ditch"]
    assert c.measures.columns[-1] == "ok"
    assert {"height_factor", "energy_factor", "reach_factor"} <= set(c.measures.columns)
    assert set(c.checks["check"]) == {"height_factor", "energy_factor", "reach_factor"}
    assert (c.checks["target"] > 0).all()
    assert len(c.rocks) == 200 and "caught_by_measure" in c.rocks
    assert len(c.outcomes) == 2 * 200


@pytest.mark.slow
@pytest.mark.parametrize("backend", ["svg", "pdf"])
def test_plot_leaves_the_backend_as_it_was(backend, two_zones):
    previous = matplotlib.get_backend()
    matplotlib.use(backend)
    try:
        for fig in (two_zones.plot(), two_zones.plot("profile"),
                    rd.simulate(STANDARD, rocks=60).plot("envelopes")):
            assert isinstance(fig, Figure)
        assert matplotlib.get_backend() == backend
    finally:
        matplotlib.use(previous)


@pytest.mark.slow
def test_the_issues_done_when(two_zones):
    r = two_zones
    assert r.best is not None and r.best == r.summary["best"]
    assert r.summary["best_name"] == r.best["name"]
    assert isinstance(r.alternatives, pd.DataFrame)
    assert len(r.alternatives) == len(r.summary["alternatives"])
    assert r.alternatives["chosen"].sum() == 1
    assert isinstance(r.plot(), Figure)
    assert r.design is not None and r.design.summary["measures"]
    assert len(r.design.summary["measures"]) == len(r.best["measures"])


@pytest.mark.slow
def test_alternatives_one_column_per_check_rounded(two_zones):
    a = two_zones.alternatives
    # design_two_zones is designed to UNI 11211 (design height and energy, braking)
    assert {"design_height", "design_energy", "design_height_bound"} <= set(a)
    # A design with two measures gets a column per check of its second measure.
    two = [alt for alt in two_zones.summary["alternatives"]
           if alt["checks"] and len(alt["measures"]) == 2]
    assert ({"design_height_2", "design_energy_2"} <= set(a)) is bool(two)
    for col in [c for c in a if c.startswith(("design_height", "design_energy"))]:
        values = a[col].dropna()
        assert (values == values.round(2)).all()
    assert str(a["cost"].dtype) == "Int64"
    assert a.columns[-1] == "checks"  # the packed column of earlier files, kept last


def test_alternatives_tolerate_new_keys():
    from rockfall_design.report.tables import alternatives_frame

    summary = {"best": "a", "alternatives": [
        {"name": "a", "cost": 1234.567, "feasible": True, "measures": [
            {"type": "fence", "x": 10.0, "height": 3.0, "capacity_kj": 1000.0}],
         "checks": [{"name": "design_energy", "value": 812.66, "target": 1000.0, "ok": True,
                     "unit": "kJ", "bound": 850.2},
                    {"name": "height_factor", "value": 2.0456, "target": 2.0, "ok": True,
                     "unit": "-"}],
         "residual": 0, "new_key": 0.123456, "nested": {"ignored": True}}]}
    f = alternatives_frame(summary)
    row = f.iloc[0]
    assert row["cost"] == 1235 and row["design_energy"] == 813
    assert row["design_energy_bound"] == 850 and row["height_factor"] == 2.05
    assert row["new_key"] == 0.1235 and "nested" not in f
    assert row["measures"] == "fence 3 m 1,000 kJ @ 10 m"


def test_stops_figure_says_why_no_rock_stops():
    from rockfall_design.engine.columns import CAUGHT, EXIT_DOWNSLOPE, STATUS_NAMES
    from rockfall_design.report.figures import no_stop_reason

    counts = np.zeros(len(STATUS_NAMES), int)
    counts[CAUGHT] = 40
    assert no_stop_reason(counts) == "all 40 rocks were caught by the measures"
    counts[EXIT_DOWNSLOPE] = 10
    assert no_stop_reason(counts) == ("of 50 rocks, 10 left the section downslope and 40 "
                                      "were caught by the measures")
    # The quarry's fence, moved up the slope to x = 100 m, catches most rocks of this
    # small run (a few may come to rest above it).
    from rockfall_design.project import load_project_text

    text = QUARRY.read_text().replace("x: 117                # m", "x: 100                # m")
    c = rd.check(load_project_text(text, str(QUARRY)), rocks=100, seed=7)
    stops = c.summary["stops"]
    assert stops["caught"] > stops["stopped"]
    # Not an empty plot (issue 36): the caught rocks are drawn where the fence caught
    # them, in its colour, and the title says how every rock ended.
    ax = c.plot_stops().axes[0]
    assert f"{c.summary['stops']['caught']} caught by a barrier" in ax.get_title()
    assert any(label.startswith("held by fence") for label in ax.get_legend_handles_labels()[1])
    # Every rock that ended on the section is drawn: where it rests or where it was caught.
    assert sum(b.get_height() for bars in ax.containers for b in bars) == \
        stops["caught"] + stops["stopped"]


def test_barriers_are_annotated_with_product_height_and_capacity():
    c = rd.check(QUARRY, rocks=50, seed=1)
    texts = [t.get_text() for t in c.plot_profile().axes[0].texts]
    assert any(t.startswith("fence") and "6 m" in t and "2000 kJ" in t for t in texts)
    assert any(t.startswith("ditch") for t in texts)


def test_envelopes_only_where_enough_rocks_pass(tmp_path):
    r = rd.simulate(STANDARD, rocks=80, seed=1)
    env = r.envelopes
    fig = r.plot_envelopes(min_rocks=50)
    height = fig.axes[0].lines[0].get_ydata()
    few = env["crossings"].to_numpy() < 50
    assert few.any() and np.isnan(height[few]).all()
    assert np.isfinite(height[~few]).any()
    assert "at least 50 rocks" in fig.axes[0].get_title()
    # The default comes from the project, which validates it.
    text = STANDARD.read_text().replace("analysis:", "analysis:\n  min_rocks_envelope: 0", 1)
    bad = tmp_path / "bad.yaml"
    bad.write_text(text)
    with pytest.raises(ProjectError, match="min_rocks_envelope"):
        rd.load_project(bad)


@pytest.mark.slow  # an optimisation of a small design: CI runs it with -m slow
def test_report_of_optimise_is_self_contained(tmp_path, capsys):
    out = tmp_path / "report"
    code = main(["optimise", str(SMALL_DESIGN), "--rocks", "400",
                 "--report", str(out), "--out", str(tmp_path / "o"), "--json"])
    assert code in (0, 1)
    summary = json.loads(capsys.readouterr().out)
    csv = pd.read_csv(tmp_path / "o" / "alternatives.csv")
    assert len(csv) == len(summary["alternatives"])
    assert {"family", "cost", "residual", "checks"} <= set(csv.columns)
    assert {c["name"] for a in summary["alternatives"] for c in a["checks"]} <= set(csv.columns)
    html = (out / "report.html").read_text(encoding="utf-8")
    md = (out / "report.md").read_text(encoding="utf-8")
    # Self-contained: no file or URL is loaded from outside the page (a figure's
    # rasterised rock paths are a data: image inside its SVG).
    assert not re.search(r"""(src|href)\s*=\s*["'](?!#|data:image/png;base64,)""", html)
    assert "url(http" not in html and "<link" not in html and "<script" not in html
    # profile, envelopes, stops, alternatives, and a distribution figure per station
    # and measure of the chosen design (passing_*.svg)
    passing = len(list(out.glob("passing_*.svg")))
    assert bool(passing) is bool(summary["best"])
    n_figures = 4 + passing if summary["best"] else 1
    assert html.count("<svg") == n_figures and html.count("<figure") == n_figures
    for alt in summary["alternatives"]:
        assert alt["name"] in html and alt["name"] in md
    assert "seed" in html and str(summary["seed"]) in html
    assert "Alternatives" in html and "Method and run" in html and "Project inputs" in html
    for ref in re.findall(r"\]\(([^)]+\.svg)\)", md):
        assert (out / ref).is_file()
    assert len(re.findall(r"\]\(([^)]+\.svg)\)", md)) == n_figures
    if summary["best"]:
        assert "Chosen design" in html and "Measures and their checks" in html


@pytest.mark.slow  # an end-to-end run of a few seconds: CI runs it with -m slow
def test_report_of_simulate_and_check(tmp_path):
    r = rd.simulate(STANDARD, rocks=60, seed=2)
    written = r.save_report(tmp_path / "s")
    assert {p.name for p in written} >= {"report.html", "report.md", "profile.svg"}
    c = rd.check(QUARRY, rocks=60, seed=2)
    c.save_report(tmp_path / "c")
    html = (tmp_path / "c" / "report.html").read_text(encoding="utf-8")
    assert "height_factor" in html and "target" in html
    states = "Holds with confidence|Holds on point values only|Fails|Untested"
    assert re.search(rf'<p id="verdict" class="verdict \w+">({states}): ', html)


def test_report_shows_confidence_bounds_when_the_summary_has_them(tmp_path):
    from rockfall_design.judge.records import CheckSummary
    from rockfall_design.report.documents import render_html, render_markdown, report_context

    c = rd.check(QUARRY, rocks=60, seed=2)
    # The report reads the check's record: a saved summary with bounds, read back.
    saved = c.summary
    saved["measures"][0]["checks"][0]["bound"] = 1.2345
    saved["protect"]["upper_fraction"] = 0.0123
    c.record = CheckSummary.from_json(saved)
    ctx = report_context(c, figures={})
    html, md = render_html(ctx), render_markdown(ctx)
    for text in (html, md):
        assert "bound" in text and "1.23" in text and "upper confidence bound 1.23 %" in text


# Slow set: four figures in two formats (6 s); PNG and SVG are written in the fast set
# (tests/cli/test_cli.py, test_clean_failures.py), PDF of a figure by this test alone.
@pytest.mark.slow
def test_plot_format_writes_each_format(tmp_path, capsys):
    figs = tmp_path / "figs"
    assert main(["simulate", str(STANDARD), "--rocks", "40", "--plot", str(figs),
                 "--plot-format", "svg,pdf", "--json"]) == 0
    names = sorted(p.name for p in figs.iterdir() if p.name != ".rockfall-design-outputs.json")
    # and the distributions at the project's one analysis station
    assert names == sorted(f"{n}.{e}" for n in ("profile", "envelopes", "stops",
                                                "passing_station_1")
                           for e in ("svg", "pdf"))
    assert (figs / "profile.pdf").read_bytes().startswith(b"%PDF")
    with pytest.raises(SystemExit) as exc:
        main(["simulate", str(STANDARD), "--plot", str(figs), "--plot-format", "gif"])
    assert exc.value.code == 2
    assert "png, svg, pdf" in capsys.readouterr().err


def test_terminal_report_is_not_wrapped_at_80_columns_in_a_pipe(capsys, monkeypatch):
    from rockfall_design.report import print_check

    c = rd.check(QUARRY, rocks=100, seed=7)
    monkeypatch.delenv("COLUMNS", raising=False)
    print_check(c.summary)
    lines = capsys.readouterr().out.splitlines()
    detail = c.summary["measures"][0]["checks"][0]["detail"]
    assert any(detail in line for line in lines)  # one line, not wrapped
    assert max(len(line) for line in lines) > 80
    # A width the user asks for is kept.
    monkeypatch.setenv("COLUMNS", "70")
    print_check(c.summary)
    assert max(len(line) for line in capsys.readouterr().out.splitlines()) <= 70


def test_no_pyplot_and_no_backend_switch_in_a_fresh_process():
    import subprocess
    import sys

    code = (
        "import sys, matplotlib\n"
        "matplotlib.use('svg')\n"
        "import rockfall_design as rd\n"
        "from rockfall_design.optimiser import optimise as search  # the driver\n"
        "assert rd.optimise is not search and callable(rd.optimise)\n"
        "assert rd.optimise.__module__ == 'rockfall_design.api'\n"
        f"r = rd.check({str(QUARRY)!r}, rocks=30, seed=1)\n"
        "figs = [r.plot(), r.plot('envelopes'), r.plot('stops')]\n"
        "assert figs[0]._repr_png_().startswith(b'\\x89PNG')\n"
        "assert 'matplotlib.pyplot' not in sys.modules, 'pyplot was imported'\n"
        "assert matplotlib.get_backend() == 'svg', matplotlib.get_backend()\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)


@pytest.mark.slow  # an optimisation of a small design: CI runs it with -m slow
def test_progress_callbacks():
    done: list[int] = []
    rd.simulate(STANDARD, rocks=50, progress=done.append)
    assert done and done[-1] == 50
    stages: list[str] = []
    rd.optimise(SMALL_DESIGN, rocks=200,
                progress=lambda stage, k, n: stages.append(stage))
    assert {"search", "check"} <= set(stages)

"""calibrate --report and compare --report: the calibration's section of the report.

Few rocks and replicates (seconds); the report is what --json says, rendered
by the templates the other commands' reports use, with the project's text
escaped in both files.
"""

from __future__ import annotations

import dataclasses
import html as html_lib
import re

import pytest

import rockfall_design as rd
from rockfall_design.calibration.document import report_context
from rockfall_design.cli import main
from rockfall_design.report.documents import render_html, render_markdown
from rockfall_design.report.staging import MANIFEST

from .calibration_helpers import SITE, observed_stops, write_site

PATH = "materials.soil.restitution"


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    directory = tmp_path_factory.mktemp("site")
    return write_site(directory, observed_stops(40, seed=1))


@pytest.fixture(scope="module")
def result(site):
    return rd.calibrate(site, workers=1, bootstrap=4, rocks=60)


def _cells(html: str) -> list[list[str]]:
    """Every table row of report.html as its cells' text."""
    return [[html_lib.unescape(c) for c in re.findall(r"<td[^>]*>(.*?)</td>", r, re.S)]
            for r in re.findall(r"<tr[^>]*>(.*?)</tr>", html, re.S)]


def _row(rows: list[list[str]], first: str) -> list[str]:
    return next(r for r in rows if r and r[0] == first)


def test_calibrate_report_says_what_json_says(site, tmp_path, capsys):
    rep = tmp_path / "rep"
    code = main(["calibrate", str(site), "--workers", "1", "--bootstrap", "4", "--rocks", "60",
                 "--json", "--report", str(rep)])
    assert code == 0
    import json

    summary = json.loads(capsys.readouterr().out)
    names = sorted(p.name for p in rep.iterdir() if p.name != MANIFEST)
    assert names == ["calibration_cloud.svg", "calibration_stops.svg", "report.html",
                     "report.md"]
    html = (rep / "report.html").read_text()
    md = (rep / "report.md").read_text()
    # Self-contained: the figures inline, nothing fetched from elsewhere.
    assert html.count("<svg") >= 2 and "<script" not in html and "src=" not in html
    assert "![Figure 1 (calibration_stops)](calibration_stops.svg)" in md
    rows = _cells(html)
    (p,) = summary["parameters"]
    assert _row(rows, PATH)[1:4] == [f"{p['value']:.3g}", f"{p['low']:.3g}", f"{p['high']:.3g}"]
    assert _row(rows, PATH)[7] == "yes"
    fit = summary["fit"]
    assert f"p = {fit['ks_pvalue']:.3g}" in html and f"D = {fit['ks_statistic']:.3f}" in html
    assert f"distance {fit['distance']:.2f} m" in html
    bench = summary["levels"][0]
    assert _row(rows, "bench")[3:6] == [f"{bench['observed_share']:.2f}",
                                        f"{bench['low']:.2f} .. {bench['high']:.2f}",
                                        f"{bench['simulated_share']:.2f}"]
    # What repeats the run: version, seed, the observed file and its hash, the command.
    assert _row(rows, "seed")[1] == str(summary["method"]["seed"])
    assert _row(rows, "observations")[1].startswith(str(site.parent / "stops.csv"))
    assert re.search(r"sha256 of the file \| [0-9a-f]{64}", md)
    assert f"--seed {summary['method']['seed']} --rocks 60 --bootstrap 4" in md
    assert rd.__version__ in _row(rows, "program")[1]
    # Every observed stop is in the report.
    xs = (site.parent / "stops.csv").read_text().split()[1:]
    assert all(f"{float(x):g}" in md for x in xs)
    assert "Observed blocks" in md and "40" in _row(rows, "observed blocks")[1]


def test_an_input_not_pinned_down_is_flagged_and_headlined(result):
    loose = [dataclasses.replace(result.parameters[0], identified=False, width_share=0.9)]
    ctx = report_context(dataclasses.replace(result, parameters=loose), figures={})
    assert "not pinned down" in ctx.verdict and PATH in ctx.verdict
    assert ctx.verdict_state == "fit with warnings"
    assert any("not identified" in f for f in ctx.failures)
    html = render_html(ctx)
    row = _row(_cells(html), PATH)
    assert row[5] == "90 %" and row[7] == "NO: not pinned down"
    assert 'class="verdict warn"' in html


def test_two_inputs_get_their_correlation(result):
    problem = dataclasses.replace(result.problem, paths=(PATH, "materials.soil.friction"),
                                  low=(0.05, 0.2), high=(0.7, 0.9))
    two = dataclasses.replace(
        result, problem=problem,
        parameters=[result.parameters[0],
                    dataclasses.replace(result.parameters[0], path="materials.soil.friction")],
        correlation=[[1.0, 0.77], [0.77, 1.0]])
    md = render_markdown(report_context(two, figures={}))
    assert "Correlation of the fitted inputs" in md and "| +0.77 |" in md


def test_project_text_is_escaped_in_both_files(tmp_path):
    bad = "<script>alert(1)</script> a|b"
    text = SITE.replace("name: site", f"name: '{bad}'\ndescription: '<iframe src=x>'")
    text = text.replace("bench: [20.5, 29]", "'<b>bench|</b>': [20.5, 29]")
    write_site(tmp_path, observed_stops(20, seed=2))
    (tmp_path / "site.yaml").write_text(text)
    result = rd.calibrate(tmp_path / "site.yaml", workers=1, bootstrap=0, rocks=40)
    paths = result.save_report(tmp_path / "rep")
    assert {p.name for p in paths} >= {"report.html", "report.md"}
    html = (tmp_path / "rep" / "report.html").read_text()
    md = (tmp_path / "rep" / "report.md").read_text()
    for raw in ("<script>", "<iframe", "<b>bench"):
        assert raw not in html and raw not in md
    assert html_lib.escape("<script>alert(1)</script>", quote=False) in html
    assert "&lt;script>alert(1)&lt;/script> a|b" in md  # the title, as report.md escapes it
    assert "&lt;b>bench\\|&lt;/b>" in md  # a table cell: its pipe escaped too
    # No bootstrap: no interval, and the headline says so.
    assert "no bootstrap" in result.report_context({}).verdict


def test_compare_report_and_plot_in_one_folder(site, tmp_path):
    # As the other commands: --report and --plot may share a folder; the SVG is written once.
    out = tmp_path / "both"
    code = main(["compare", str(site), "--observed", str(site.parent / "stops.csv"),
                 "--rocks", "80", "--report", str(out), "--plot", str(out),
                 "--plot-format", "svg,png"])
    assert code == 0
    names = sorted(p.name for p in out.iterdir() if p.name != MANIFEST)
    assert names == ["calibration_stops.png", "calibration_stops.svg", "report.html",
                     "report.md"]
    html = (out / "report.html").read_text()
    assert "rockfall comparison" in html and "Fitted inputs" not in html
    assert "fair test of the prediction" in html
    assert "rockfall-design compare" in html and "--rocks 80" in html

"""report.pdf: printed from report.html by Chromium, nothing cut, every table's headers in it.

The text of the PDF is read back with pypdf: every column header of every table
of the report and every verdict (the design's and each check's) must be in it;
a column lost past the page's edge would be missing. Needs Playwright (the pdf
extra) and a Chromium (/usr/bin/chromium or ROCKFALL_DESIGN_CHROMIUM); without
them the test skips and says why, and fails when CI asks for the browser tests
(ROCKFALL_DESIGN_BROWSER_TESTS=1), as tests/serve/test_browser.py does.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import unicodedata
from collections.abc import Iterator
from pathlib import Path

import pytest

import rockfall_design as rd
from rockfall_design.cli.program import main
from rockfall_design.report import documents
from rockfall_design.report.documents import report_context
from rockfall_design.report.pdf import pdf_unavailable

ROOT = Path(__file__).resolve().parents[2]
PROJECTS = ROOT / "projects"
REQUIRED = os.environ.get("ROCKFALL_DESIGN_BROWSER_TESTS") == "1"


def _pdf_or_skip() -> None:
    why = pdf_unavailable()
    if why is None and not Path(os.environ.get("ROCKFALL_DESIGN_CHROMIUM",
                                               "/usr/bin/chromium")).exists():
        why = "no Chromium at /usr/bin/chromium (apt-get install chromium)"
    if why is not None:
        if REQUIRED:
            pytest.fail(f"ROCKFALL_DESIGN_BROWSER_TESTS=1 but {why}")
        pytest.skip(why)


def _squeezed(text: str) -> str:
    """Text without whitespace, ligatures undone: a header wrapped over lines still matches."""
    return re.sub(r"\s+", "", unicodedata.normalize("NFKC", text))


def _pdf_text(path: Path) -> tuple[str, list[tuple[float, float]]]:
    from pypdf import PdfReader

    reader = PdfReader(str(path))
    sizes = [(float(p.mediabox.width), float(p.mediabox.height)) for p in reader.pages]
    return "\n".join(p.extract_text() for p in reader.pages), sizes


@pytest.fixture(scope="module", autouse=True)
def _pdf_asked() -> Iterator[None]:
    """report.pdf printed in this module, which the suite's conftest turns off elsewhere."""
    with pytest.MonkeyPatch.context() as mp:
        mp.delenv("ROCKFALL_DESIGN_PDF", raising=False)
        yield


@pytest.fixture(scope="module")
def printed(tmp_path_factory):
    _pdf_or_skip()
    out = tmp_path_factory.mktemp("pdf")
    args = ["check", str(PROJECTS / "quarry_fence_ditch.yaml"), "--rocks", "300", "--seed",
            "5", "--report", str(out), "--json"]
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        assert main(args) == 0
    result = rd.check(PROJECTS / "quarry_fence_ditch.yaml", rocks=300, seed=5)
    return out, result


@pytest.fixture(scope="module")
def pdf_read(printed) -> tuple[str, list[tuple[float, float]]]:
    """The printed PDF's text and page sizes, read once: pypdf takes seconds per read."""
    out, _ = printed
    return _pdf_text(out / "report.pdf")


def test_the_pdf_is_a4_with_page_numbers_and_the_project_on_every_page(printed, pdf_read):
    _, result = printed
    text, sizes = pdf_read
    a4 = {(595.0, 842.0), (842.0, 595.0)}  # points, portrait and landscape
    assert all((round(w), round(h)) in a4 for w, h in sizes), sizes
    pages = len(sizes)
    assert pages >= 2
    for k in range(1, pages + 1):
        assert f"page {k} of {pages}" in text
    assert text.count(f"{result.project.name}: rockfall report") == pages


def test_every_table_header_and_every_verdict_is_in_the_pdf(printed, pdf_read):
    _, result = printed
    text, _ = pdf_read
    flat = _squeezed(text)
    ctx = report_context(result, {})
    tables = [ctx.run, *ctx.inputs, *ctx.results, *ctx.design_values]
    assert len(tables) >= 10
    missing = [(t.title, c) for t in tables for c in t.columns
               if c and _squeezed(c) not in flat]
    assert not missing, missing
    summary = result.summary
    assert _squeezed(summary["verdict"]["headline"]) in flat
    for m in summary["measures"]:
        for c in m["checks"]:
            assert _squeezed(c["state"]) in flat
    # The last column of the widest table (the ground materials) made it onto the page.
    materials = next(t for t in ctx.inputs if t.title == "Ground materials")
    assert _squeezed(materials.columns[-1]) in flat


def test_without_the_pdf_extra_the_report_is_written_and_says_how_to_get_it(tmp_path,
                                                                            monkeypatch):
    monkeypatch.setattr(documents, "pdf_unavailable",
                        lambda: "report.pdf not written: Playwright is not installed; "
                        "install the pdf extra")
    err = io.StringIO()
    args = ["simulate", str(PROJECTS / "standard_slope.yaml"), "--rocks", "100",
            "--report", str(tmp_path), "--json"]
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        assert main(args) == 0
    assert (tmp_path / "report.html").exists() and (tmp_path / "report.md").exists()
    assert not (tmp_path / "report.pdf").exists()
    lines = [line for line in err.getvalue().splitlines() if "report.pdf" in line]
    assert len(lines) == 1 and "pdf extra" in lines[0]
    html = (tmp_path / "report.html").read_text()
    assert "Model and limits" in html  # simulate's report too


def _tables(ctx) -> list:
    """Every table of a report's context (objects with a title and columns), wherever it sits."""
    found = []
    for value in ctx.template_values().values():
        for item in value if isinstance(value, list) else [value]:
            if hasattr(item, "columns") and hasattr(item, "title"):
                found.append(item)
    return found


# Slow set: a run, its report, a Chromium print and a pypdf read each (11 and 22 s);
# the printing path and the every-header check run on check's report above.
@pytest.mark.slow
@pytest.mark.parametrize(("command", "project"), [
    ("simulate", PROJECTS / "standard_slope.yaml"),
    ("optimise", ROOT / "tests" / "data" / "design_small.yaml"),
])
def test_the_pdf_of_simulate_and_optimise_holds_every_table_header(tmp_path, command,
                                                                    project):
    """Not only check's report: every column header of simulate's and optimise's reports
    is in their PDFs (issue 36: "every report has ... a PDF whose text holds every table's
    headers")."""
    _pdf_or_skip()
    run = getattr(rd, command)
    result = run(project, seed=5, **({"rocks": 150} if command == "simulate" else {}))
    result.save_report(tmp_path)  # the command line's --report writes the same files
    text, _ = _pdf_text(tmp_path / "report.pdf")
    flat = _squeezed(text)
    tables = _tables(report_context(result, {}))
    assert tables
    missing = [(t.title, c) for t in tables for c in t.columns if c and _squeezed(c) not in flat]
    assert not missing, missing
    assert "Modelandlimits" in flat

"""A served check's files, drawn as asked for: report.html with its SVGs, a PNG alone."""

from __future__ import annotations

from pathlib import Path

import pytest

import rockfall_design as rd
from rockfall_design.project import load_project_text
from rockfall_design.serve import reports

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def drawn(monkeypatch) -> dict[str, list]:
    """The figures the app's report code asks to write as PNG and as SVG, in order.

    Recorded, not drawn: which drawings a request costs is the question here;
    what the files hold, tests/serve/test_api.py and test_browser.py.
    """
    calls: dict[str, list] = {"png": [], "svg": []}

    def write_figure(fig, fh, fmt):
        calls[fmt].append(fig)
        fh.write(b"\x89PNG\r\n\x1a\n")

    def svg_document(fig):
        calls["svg"].append(fig)
        return '<?xml version="1.0"?>\n<svg xmlns="http://www.w3.org/2000/svg"></svg>\n'

    monkeypatch.setattr(reports, "write_figure", write_figure)
    monkeypatch.setattr(reports, "svg_document", svg_document)
    return calls


def test_a_png_is_drawn_on_its_request_and_the_report_with_its_svgs(drawn):
    text = (ROOT / "projects" / "quarry_fence_ditch.yaml").read_text(encoding="utf-8")
    assert "stations: [50, 90, 115]" in text  # one station: fewer figures to make
    project = load_project_text(text.replace("stations: [50, 90, 115]", "stations: [90]"),
                                "quarry.yaml", base_dir=ROOT / "projects")
    result = rd.check(project, rocks=30, seed=3)
    files = reports.lazy_files(result)
    assert set(files) == set(reports.report_names(result))
    png = files["profile.png"]()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(drawn["png"]) == 1 and not drawn["svg"]  # that figure only, as PNG only
    assert files["profile.png"]() == png and len(drawn["png"]) == 1  # kept
    html = files["report.html"]()
    assert b"<svg" in html
    # Every figure of the report (the passage figures too) once as SVG, no more PNGs.
    figures = len(drawn["svg"])
    assert figures >= 4 and len(drawn["png"]) == 1
    assert files["stops.svg"]().startswith(b"<?xml") and len(drawn["svg"]) == figures
    files["envelopes.png"]()
    assert len(drawn["png"]) == 2 and len(drawn["svg"]) == figures
    # The same figure objects for both: drawn once (result.figures()) per result.
    assert drawn["png"][0] in drawn["svg"]

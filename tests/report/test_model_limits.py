"""The model's limits: a docs page, and the same words in every check and optimise report."""

from __future__ import annotations

from pathlib import Path

from rockfall_design.report.documents import MODEL_LIMITS

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "docs" / "model-and-limits.md"


def _words(text: str) -> str:
    return " ".join(text.split())


def test_the_page_carries_every_bullet_of_the_reports_section_word_for_word():
    page = _words(PAGE.read_text(encoding="utf-8"))
    for heading, items in MODEL_LIMITS:
        assert f"## {heading}" in page
        for item in items:
            assert _words(item) in page, item


def test_the_page_names_what_is_left_out_and_the_standards():
    page = _words(PAGE.read_text(encoding="utf-8"))
    for needle in ("2-D", "sphere", "fragmentation", "trees", "braking distance",
                   "residual height", "MEL", "SEL", "EAD 340059", "ETAG 027", "UNI 11211-4",
                   "Spang & Rautenstrauch (1988)", "height_factor", "gamma_e"):
        assert needle in page, needle


def test_the_readme_links_the_page():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert "(docs/model-and-limits.md)" in readme


def test_the_section_is_in_the_reports_of_check_and_optimise():
    from rockfall_design.report.context import LimitsPart, ReportContext
    from rockfall_design.report.documents import render_markdown
    from rockfall_design.report.sections import Table

    context = ReportContext(title="t", project="p", description="", command="check",
                            version="0", generated="now", run=Table("", ["item", "value"], []),
                            inputs=[],
                            limits=[LimitsPart(h, list(i)) for h, i in MODEL_LIMITS])
    md = render_markdown(context)
    assert "## Model and limits" in md
    for heading, items in MODEL_LIMITS:
        assert f"### {heading}" in md
        assert all(f"- {item}" in md for item in items)

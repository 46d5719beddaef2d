"""report.pdf: report.html printed by Chromium (A4, page numbers, a header on every page).

Why Chromium and not WeasyPrint: report.html is what the engineer reads on
screen, in a browser; printing it with a browser engine gives the same
layout, fonts and SVG rendering on paper, from the one template, and the
print CSS written for it (``@page``, landscape pages for wide tables, a
table's header on every page) is the CSS a reader's own browser applies
when they print the HTML. Chromium is already the engine of the browser
app's test (``tests/serve/test_browser.py``), which CI installs from
Debian, and Playwright already drives it there; WeasyPrint would be a
second layout engine with its own CSS subset and a stack of native
libraries (Pango, HarfBuzz, fontconfig) to keep in step. The price: the
PDF needs a Chromium on the machine (Debian's ``chromium``, any Chrome or
Chromium named by ``ROCKFALL_DESIGN_CHROMIUM``, or Playwright's own) and
the ``pdf`` extra (``pip install "rockfall-design[pdf]"``, Playwright).
Without them ``--report`` writes report.html and report.md and says in one
line how to get the PDF (:func:`pdf_unavailable`).

Figures stay vectors: they are inline SVG in the HTML, and Chromium prints
SVG as paths and text.
"""

from __future__ import annotations

import html
import os
import shutil
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

__all__ = ["chromium_path", "pdf_turned_off", "pdf_unavailable", "html_to_pdf", "PDF_HINT"]

#: How to get the PDF, said when it cannot be made.
PDF_HINT = ('install the pdf extra (pip install "rockfall-design[pdf]") and a Chromium '
            "(apt-get install chromium, or set ROCKFALL_DESIGN_CHROMIUM to a Chrome or "
            "Chromium)")

#: Where Debian and others put Chromium, tried in order after ROCKFALL_DESIGN_CHROMIUM.
_CANDIDATES = ("/usr/bin/chromium", "/usr/bin/chromium-browser", "/usr/bin/google-chrome")


def chromium_path() -> str | None:
    """The Chromium to print with: ``ROCKFALL_DESIGN_CHROMIUM``, a system one, or None.

    None means Playwright's own browser, if it has downloaded one.
    """
    named = os.environ.get("ROCKFALL_DESIGN_CHROMIUM")
    if named:
        return named
    for path in _CANDIDATES:
        if Path(path).exists():
            return path
    for name in ("chromium", "chromium-browser", "google-chrome"):
        found = shutil.which(name)
        if found:
            return found
    return None


def pdf_turned_off() -> bool:
    """True where ``ROCKFALL_DESIGN_PDF=0``: --report writes the HTML and Markdown only.

    Printing starts a Chromium (seconds each time): a batch of many reports,
    or a test suite that does not look at the PDF, turns it off. Nothing is
    said then (it was asked for); a report.pdf of an earlier run is removed,
    as when the PDF cannot be made.
    """
    return os.environ.get("ROCKFALL_DESIGN_PDF", "").strip() == "0"


def pdf_unavailable() -> str | None:
    """Why report.pdf cannot be made here (one line), or None when it can be tried."""
    try:
        import playwright.sync_api  # noqa: F401  (only asked whether it is there)
    except ImportError:
        return f"report.pdf not written: Playwright is not installed; {PDF_HINT}"
    named = os.environ.get("ROCKFALL_DESIGN_CHROMIUM")
    if named and not Path(named).exists():
        return (f"report.pdf not written: no Chromium at ROCKFALL_DESIGN_CHROMIUM={named}; "
                f"{PDF_HINT}")
    return None


def _header(project: str, generated: str) -> str:
    """Playwright's header template: the project on the left, the date on the right."""
    style = ("font-size:7.5px;color:#555;width:100%;margin:0 12mm;display:flex;"
             "justify-content:space-between;font-family:Helvetica,Arial,sans-serif")
    return (f'<div style="{style}"><span>{html.escape(project)}: rockfall report</span>'
            f"<span>{html.escape(generated)}</span></div>")


def _footer() -> str:
    """Playwright's footer template: page N of M, centred."""
    style = ("font-size:7.5px;color:#555;width:100%;text-align:center;"
             "font-family:Helvetica,Arial,sans-serif")
    return (f'<div style="{style}">page <span class="pageNumber"></span> of '
            '<span class="totalPages"></span></div>')


def _print(document: str, project: str, generated: str) -> bytes:
    """Chromium's print of ``document`` (HTML text) to PDF bytes (runs Playwright's sync API)."""
    from playwright.sync_api import sync_playwright  # the pdf extra: loaded on use

    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=chromium_path(),
                                     args=["--no-sandbox", "--disable-gpu"])
        try:
            page = browser.new_page()
            page.set_content(document, wait_until="load")
            page.emulate_media(media="print")
            return page.pdf(format="A4", print_background=True, prefer_css_page_size=True,
                            display_header_footer=True,
                            header_template=_header(project, generated),
                            footer_template=_footer(),
                            margin={"top": "18mm", "bottom": "16mm", "left": "12mm",
                                    "right": "12mm"})
        finally:
            browser.close()


def html_to_pdf(document: str, project: str, generated: str) -> bytes:
    """report.html as a PDF: A4, the project and date on every page, page N of M.

    Parameters
    ----------
    document : str
        The self-contained HTML (report.html).
    project : str
        The project's name, for the header.
    generated : str
        When the report was made, for the header.

    Returns
    -------
    bytes

    Raises
    ------
    RuntimeError
        Chromium could not be started or could not print; the message says
        why and how to get the PDF.

    Notes
    -----
    Playwright's sync API refuses to run inside a running asyncio loop (a
    notebook's); the print runs on a thread of its own, which has none.
    """
    with ThreadPoolExecutor(max_workers=1) as pool:
        try:
            return pool.submit(_print, document, project, generated).result()
        except Exception as exc:  # Playwright's errors are its own classes: said in one line
            first = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
            raise RuntimeError(f"report.pdf not written: Chromium could not print it "
                               f"({first}); {PDF_HINT}") from None

"""The report and figures of a check or optimise started from the page.

The command line writes ``--report DIR/report.html`` through
:func:`rockfall_design.report.documents.report_context` and
:func:`~rockfall_design.report.documents.render_html` from a result of
:mod:`rockfall_design.results`; the app makes its report from the same
result objects with the same code, and offers every figure for download.
"""

from __future__ import annotations

import io
import threading
from collections.abc import Callable

from ..report.documents import render_html, report_context
from ..report.formats import inline_svg, svg_document, write_figure
from ..results import CheckResult, OptimiseResult

#: Figure formats the page offers for download.
DOWNLOAD_FORMATS = ("png", "svg")

_MEDIA = {".html": "text/html; charset=utf-8", ".png": "image/png",
          ".svg": "image/svg+xml", ".yaml": "application/yaml", ".csv": "text/csv"}


def media_type(name: str) -> str:
    """The media type of a downloadable file, by its suffix."""
    for suffix, media in _MEDIA.items():
        if name.endswith(suffix):
            return media
    return "application/octet-stream"


def report_files(result: CheckResult | OptimiseResult) -> dict[str, bytes]:
    """``report.html`` (as ``--report`` writes it) and every figure as PNG and SVG."""
    figures = result.figures()  # made once, for the report and the downloads
    # Each figure rendered once as SVG: the download and report.html's inline copy are
    # the same text (rendering was most of a served report's time: three per figure).
    documents = {name: svg_document(fig) for name, fig in figures.items()}
    ctx = report_context(result, figures)
    svgs = {name: inline_svg(doc) for name, doc in documents.items()}
    files = {"report.html": render_html(ctx, svgs=svgs).encode("utf-8")}
    for name, fig in figures.items():
        files[f"{name}.svg"] = documents[name].encode("utf-8")
        buf = io.BytesIO()
        # Through --plot's own writer: the same file as the command line's (a
        # figure laid out to fit its page is not cropped "tight", which drew it
        # twice: 0.9-1.7 s against 0.8-1.1 s for a passage figure's PNG).
        write_figure(fig, buf, "png")
        files[f"{name}.png"] = buf.getvalue()
    return files


def report_names(result: CheckResult | OptimiseResult) -> list[str]:
    """The names :func:`report_files` will give, without drawing anything."""
    names = ["profile", "envelopes", "stops"]
    if isinstance(result, OptimiseResult):
        names = ["alternatives"] + (names if result.result.best is not None else [])
    return ["report.html"] + [f"{n}.{f}" for n in names for f in DOWNLOAD_FORMATS]


def lazy_files(result: CheckResult | OptimiseResult) -> dict[str, Callable[[], bytes]]:
    """A loader per file of :func:`report_names`: drawn together on the first request."""
    cache: dict[str, bytes] = {}
    lock = threading.Lock()

    def loader(name: str) -> Callable[[], bytes]:
        def load() -> bytes:
            with lock:
                if not cache:
                    cache.update(report_files(result))
            return cache[name]
        return load

    return {name: loader(name) for name in report_names(result)}

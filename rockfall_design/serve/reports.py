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
from typing import TYPE_CHECKING

from ..report.documents import render_html, report_context
from ..report.formats import inline_svg, svg_document, write_figure
from ..results import CheckResult, OptimiseResult

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

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
    """``report.html`` (as ``--report`` writes it) and every offered figure as PNG and SVG.

    All of :func:`report_names` at once; the app draws them as they are
    asked for (:func:`lazy_files`).
    """
    drawn = _Drawn(result)
    return {name: drawn.file(name) for name in report_names(result)}


class _Drawn:
    """The files of one result, each drawn on its first request and kept.

    ``report.html`` and the SVGs come together: each figure is rendered once
    as SVG, for its download and report.html's inline copy (rendering was
    most of a served report's time: three per figure). A PNG is drawn when it
    is asked for: the page offers few of them, and drawing every figure as PNG
    with the report (the passage figures too, which are not offered) took
    half of the first request's 16 s for a check of design_two_zones
    (300 rocks, load 3, 2026-11-28). Not thread-safe: :func:`lazy_files`
    holds a lock.
    """

    def __init__(self, result: CheckResult | OptimiseResult) -> None:
        self.result = result
        self.cache: dict[str, bytes] = {}
        self.figures: dict[str, Figure] | None = None

    def file(self, name: str) -> bytes:
        if name not in self.cache:
            if name.endswith(".png"):
                self._png(name[: -len(".png")])
            else:
                self._report()
        return self.cache[name]

    def _drawings(self) -> dict[str, Figure]:
        if self.figures is None:
            self.figures = self.result.figures()  # made once, for the report and downloads
        return self.figures

    def _report(self) -> None:
        figures = self._drawings()
        documents = {name: svg_document(fig) for name, fig in figures.items()}
        ctx = report_context(self.result, figures)
        svgs = {name: inline_svg(doc) for name, doc in documents.items()}
        self.cache["report.html"] = render_html(ctx, svgs=svgs).encode("utf-8")
        for name, doc in documents.items():
            self.cache[f"{name}.svg"] = doc.encode("utf-8")

    def _png(self, stem: str) -> None:
        buf = io.BytesIO()
        # Through --plot's own writer: the same file as the command line's (a
        # figure laid out to fit its page is not cropped "tight", which drew it
        # twice: 0.9-1.7 s against 0.8-1.1 s for a passage figure's PNG).
        write_figure(self._drawings()[stem], buf, "png")
        self.cache[f"{stem}.png"] = buf.getvalue()


def report_names(result: CheckResult | OptimiseResult) -> list[str]:
    """The names :func:`report_files` will give, without drawing anything."""
    names = ["profile", "envelopes", "stops"]
    if isinstance(result, OptimiseResult):
        names = ["alternatives"] + (names if result.result.best is not None else [])
    return ["report.html"] + [f"{n}.{f}" for n in names for f in DOWNLOAD_FORMATS]


def lazy_files(result: CheckResult | OptimiseResult) -> dict[str, Callable[[], bytes]]:
    """A loader per file of :func:`report_names`: each drawn on its first request.

    report.html and the SVGs are drawn together; a PNG alone (:class:`_Drawn`).
    """
    drawn = _Drawn(result)
    lock = threading.Lock()

    def loader(name: str) -> Callable[[], bytes]:
        def load() -> bytes:
            with lock:
                return drawn.file(name)
        return load

    return {name: loader(name) for name in report_names(result)}

"""Figures to files: the formats, and the one writer of every figure file.

Light on purpose: no matplotlib import here (a figure brings its own), so
that ``--plot-format`` checks its words while the arguments are parsed, and
a command writes the figures a result drew without importing the drawing
modules itself.
"""

from __future__ import annotations

import io
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from .outputs import OutputSet

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = ["CAPTIONS", "FIGURE_FORMATS", "figure_svg", "inline_svg", "save_figures",
           "laid_out", "svg_document", "write_figure"]

#: File formats the figures can be written in (``--plot-format``): those
#: matplotlib writes without extra software, raster PNG and vector SVG and PDF.
FIGURE_FORMATS = ("png", "svg", "pdf")


#: One sentence per figure, for reports.
CAPTIONS = {
    "profile": "Slope section (x and elevation in m, equal scales) with a sample of rock "
    "centre paths, the rest positions, the analysis stations, the protected zone and the "
    "measures (barriers with product, height and capacity).",
    "envelopes": "Envelopes along the section of the passing height of the rock centre above "
    "the ground (m), of the total kinetic energy (kJ) and of the translational speed (m/s), "
    "over the rocks passing each point downslope for the first time; drawn only where enough "
    "rocks pass (bottom: how many). Each barrier's heights and energies (nominal height, "
    "capacity and any other figure its product gives) are ticks at its station.",
    "stops": "Where the rocks ended along the section (count per bin): at rest, or held by a "
    "measure where it held them (a colour per measure); the rocks that left the section are "
    "a hatched bar beyond its end, with their count; the title says how every rock ended. "
    "The ground below.",
    "alternatives": "The optimiser's alternatives: cost of the cheapest design of each family "
    "(admissible ones coloured, the chosen one marked), with the rocks still reaching the "
    "protected zone and the check that binds or fails.",
    "margins": "The design's margin in every scenario of the study: the smallest relative "
    "slack of a check or of the residual with the confidence bounds in place (%, negative "
    "where it fails), with what binds; green where the design holds on the point values "
    "(hatched: not with the confidence bounds), red where it fails; * the binding scenario "
    "(the one that decides the count required: with every scenario required, the least "
    "margin). Below: the scenarios it holds in against the number required.",
}


def save_figures(
    figures: Mapping[str, Figure],
    directory: str | Path,
    formats: Sequence[str] = ("png",),
    outputs: OutputSet | None = None,
) -> list[Path]:
    """Write every figure as ``directory/NAME.FORMAT`` for each format.

    Parameters
    ----------
    figures : mapping of str to Figure
    directory : path
    formats : sequence of str
        Some of :data:`FIGURE_FORMATS`.
    outputs : OutputSet, optional
        The command's output set: the files land when it commits. Without
        one they land together on return.

    Returns
    -------
    list of Path
        The files written, in order.
    """
    if outputs is None:
        with OutputSet() as own:
            return save_figures(figures, directory, formats, own)
    out = Path(directory)
    written: list[Path] = []
    for fmt in formats:
        if fmt not in FIGURE_FORMATS:
            raise ValueError(f"unknown figure format {fmt!r}; use one of "
                             f"{', '.join(FIGURE_FORMATS)}")
    for name, fig in figures.items():
        with laid_out(fig):  # one layout for all the figure's formats
            for fmt in formats:
                path = out / f"{name}.{fmt}"

                def writer(fh: io.BufferedWriter, fig: Figure = fig, fmt: str = fmt) -> None:
                    write_figure(fig, fh, fmt)

                outputs.write_with(path, writer)
                written.append(path)
    return written


#: Fixed metadata per format, so that the same run writes the same bytes.
_FIXED_METADATA = {"svg": {"Date": None}, "pdf": {"CreationDate": None}}


#: Resolution of every figure file (dots per inch); a figure's layout is made for it.
DPI = 150

#: ``id`` of the figures inside :func:`laid_out` now: laid out by their engine.
_LAID_OUT: set[int] = set()


@contextmanager
def laid_out(fig: Figure) -> Iterator[None]:
    """Lay out ``fig`` once, for :data:`DPI`, and keep it so while the block writes it.

    matplotlib runs a figure's layout engine (the constrained layout of the
    report's figures) at every ``savefig``, in a draw of its own before the
    draw that writes the file: a figure written as SVG and PNG was drawn four
    times. Inside this block the layout is made once and the engine set
    aside, so each file is one draw; on leaving, the figure has its engine
    and resolution back, and lays itself out again if drawn again (a
    notebook's display, a later change). A figure without an engine, or
    inside another such block, is left as it is.
    """
    engine = fig.get_layout_engine()
    if engine is None:
        yield
        return
    import matplotlib  # loaded already with the figure

    dpi = fig.get_dpi()
    fig.set_dpi(DPI)
    try:
        # The words as drawn (a RockfallFigure's literal texts) before they are
        # measured: text between two "$" measures otherwise as mathematics.
        prepare = getattr(fig, "prepare_texts", None)
        if prepare is not None:
            prepare()
        if fig.axes:
            try:
                engine.execute(fig)
            except ValueError:  # as matplotlib's own draw: a layout that cannot be made is left
                pass
        with matplotlib.rc_context({"figure.autolayout": False,
                                    "figure.constrained_layout.use": False}):
            fig.set_layout_engine(None)
        _LAID_OUT.add(id(fig))
        yield
    finally:
        _LAID_OUT.discard(id(fig))
        fig.set_layout_engine(engine)
        fig.set_dpi(dpi)


def write_figure(fig: Figure, fh: IO[Any], fmt: str) -> None:
    """Write ``fig`` in ``fmt`` to ``fh``: the one place the figures' file settings live."""
    with laid_out(fig):
        _save(fig, fh, fmt)


def _save(fig: Figure, fh: IO[Any], fmt: str) -> None:
    """``fig.savefig`` with the files' settings; ``fig`` laid out already (:func:`laid_out`)."""
    # A figure with a layout engine (the constrained layout) already fits its
    # page; cropping it "tight" costs a second full draw for a few points of
    # margin: 53 s against 40 s for a simulate's six figures in PNG and SVG
    # (load 14, alternated runs). A figure laid out by hand with margins that
    # hold its texts says so (``fits_page``, the passage panels): cropping one
    # cost 1.5 s against 0.5 s for a passage figure's SVG (2026-11-28, quiet),
    # and the crop only took off a few millimetres of white.
    fits = id(fig) in _LAID_OUT or getattr(fig, "fits_page", False)
    tight = None if fits else "tight"
    # An SVG's words as <text>, not as a path per glyph (matplotlib's default):
    # a report's figures are searchable and selectable in the HTML and its PDF,
    # a fifth smaller, and written in about half the time (a check report's
    # seven SVGs, 300 rocks: 14.7-15.7 s against 7.3-9.7 s, load 4). They name
    # DejaVu Sans, matplotlib's font, which Debian's fontconfig brings.
    import matplotlib  # heavy, and loaded already with the figure: kept out of parsing

    with matplotlib.rc_context({"svg.fonttype": "none"}):
        fig.savefig(fh, format=fmt, dpi=DPI, bbox_inches=tight,
                    metadata=_FIXED_METADATA.get(fmt, {}))


def svg_document(fig: Figure) -> str:
    """The figure as a whole SVG file's text, as :func:`save_figures` writes it."""
    buf = io.StringIO()
    write_figure(fig, buf, "svg")
    return buf.getvalue()


def inline_svg(document: str) -> str:
    """An SVG file's text without its XML prolog and DOCTYPE, for inline use in HTML."""
    start = document.find("<svg")
    return document[start:] if start >= 0 else document


def figure_svg(fig: Figure) -> str:
    """The figure as an SVG document (text), for embedding in an HTML report."""
    return inline_svg(svg_document(fig))

"""Figures to files: the formats, and the one writer of every figure file.

Light on purpose: no matplotlib import here (a figure brings its own), so
that ``--plot-format`` checks its words while the arguments are parsed, and
a command writes the figures a result drew without importing the drawing
modules itself.
"""

from __future__ import annotations

import io
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from .outputs import OutputSet

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = ["FIGURE_FORMATS", "save_figures", "write_figure"]

#: File formats the figures can be written in (``--plot-format``): those
#: matplotlib writes without extra software, raster PNG and vector SVG and PDF.
FIGURE_FORMATS = ("png", "svg", "pdf")


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
    for name, fig in figures.items():
        for fmt in formats:
            if fmt not in FIGURE_FORMATS:
                raise ValueError(f"unknown figure format {fmt!r}; use one of "
                                 f"{', '.join(FIGURE_FORMATS)}")
            path = out / f"{name}.{fmt}"

            def writer(fh: io.BufferedWriter, fig: Figure = fig, fmt: str = fmt) -> None:
                write_figure(fig, fh, fmt)

            outputs.write_with(path, writer)
            written.append(path)
    return written


#: Fixed metadata per format, so that the same run writes the same bytes.
_FIXED_METADATA = {"svg": {"Date": None}, "pdf": {"CreationDate": None}}


def write_figure(fig: Figure, fh: IO[Any], fmt: str) -> None:
    """Write ``fig`` in ``fmt`` to ``fh``: the one place the figures' file settings live."""
    # A figure with a layout engine (the constrained layout) already fits its
    # page; cropping it "tight" costs a second full draw for a few points of
    # margin: 53 s against 40 s for a simulate's six figures in PNG and SVG
    # (load 14, alternated runs). The fixed grids (passage panels) are cropped.
    tight = "tight" if fig.get_layout_engine() is None else None
    fig.savefig(fh, format=fmt, dpi=150, bbox_inches=tight,
                metadata=_FIXED_METADATA.get(fmt, {}))

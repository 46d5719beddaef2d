"""The distributions at one place of the section: a station or a barrier.

One figure per place: for each quantity of
:data:`rockfall_design.run.passages.QUANTITIES` (passing height vertical and
normal to the slope, translational and angular speed, translational,
rotational and total energy), a histogram of the rocks that passed (counts,
left axis) and their empirical cumulative distribution (right axis), with
the measure's figures drawn on them (its nominal and residual heights, its
capacity, SEL or MEL where the product gives them). matplotlib Figures, no
pyplot, as :mod:`.figures` draws them.

See Also
--------
rockfall_design.run.passages : the quantities and how a barrier's are derived.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from matplotlib.figure import Figure

from ..run.passages import QUANTITIES, Passages
from .figures import RockfallFigure

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes

__all__ = ["passage_figure", "passage_name", "PASSAGE_CAPTION"]

_BAR = "#95a5a6"
_ECDF = "#1f5fa8"
_MARK_COLOURS = ("#c0392b", "#d35400", "#8e44ad", "#16a085")

#: The caption of every passage figure in a report (its place is in the title).
PASSAGE_CAPTION = (
    "The rocks passing one place (first passage downslope at a station; the first meeting "
    "at a barrier): for each quantity a histogram (rocks per bin, left axis) and the "
    "empirical cumulative distribution (share of the rocks at or below, right axis), with "
    "the measure's figures as vertical lines (its heights on both passing heights, its "
    "energies on the total energy). Heights of the rock centre in m (normal to the slope: "
    "h cos of the ground's inclination there), speeds in m/s and rad/s, energies in kJ.")


def passage_name(p: Passages) -> str:
    """The figure's name (and file stem): ``passing_station_1``, ``passing_measure_2``.

    Numbered from 1 in the order of ``analysis.stations`` or ``measures:``.
    """
    return f"passing_{p.place}_{p.index + 1}"


#: Steps of the empirical CDF drawn at most (see :func:`_panel`).
_ECDF_POINTS = 1000


def _panel(ax: Axes, values: np.ndarray, what: str, unit: str,
           marks: list[tuple[str, float]]) -> None:
    """One quantity: histogram, empirical CDF on a twin axis, the marks as lines."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    ax.set_xlabel(f"{what} ({unit})", fontsize=8)
    ax.tick_params(labelsize=7)
    if v.size == 0:
        ax.text(0.5, 0.5, "no rock", transform=ax.transAxes, ha="center", va="center")
        return
    top = max([float(v.max())] + [m for _, m in marks])
    bins = np.linspace(min(0.0, float(v.min())), top * 1.02 if top > 0 else 1.0, 31)
    # One filled outline and one set of white separators, not a patch per bar
    # (ax.hist): 31 bars in 7 panels of 3 to 5 figures were a thousand artists,
    # a third of the time a report took to build its figures.
    counts, edges = np.histogram(v, bins=bins)
    ax.stairs(counts, edges, fill=True, color=_BAR)
    ax.vlines(edges[1:-1], 0, np.maximum(counts[:-1], counts[1:]), colors="white",
              linewidth=0.4)
    ax.set_ylabel("rocks", fontsize=7)
    cdf = ax.twinx()
    xs = np.sort(v)
    share = np.arange(1, xs.size + 1) / xs.size
    if xs.size > _ECDF_POINTS:
        # Through 1,000 of its steps (each the same share of the rocks apart): the
        # line a page shows is the same, and a step per rock of 50,000 made every
        # report's SVG and PDF megabytes heavy and slow to draw and print.
        keep = np.unique(np.linspace(0, xs.size - 1, _ECDF_POINTS).round().astype(int))
        xs, share = xs[keep], share[keep]
    cdf.step(xs, share, where="post", color=_ECDF, lw=1.2)
    cdf.set_ylim(0, 1.02)
    cdf.set_ylabel("share at or below", fontsize=7, color=_ECDF)
    cdf.tick_params(labelsize=7, colors=_ECDF)
    p95 = float(np.percentile(v, 95))
    cdf.axvline(p95, color=_ECDF, ls=":", lw=0.9)
    cdf.text(p95, 0.03, f" p95 {p95:.3g}", color=_ECDF, fontsize=7, rotation=90,
             va="bottom", ha="right")
    for k, (label, value) in enumerate(marks):
        colour = _MARK_COLOURS[k % len(_MARK_COLOURS)]
        cdf.axvline(value, color=colour, lw=1.6)
        cdf.text(value, 0.97, f" {label}", color=colour, fontsize=7, rotation=90,
                 va="top", ha="right")
    ax.grid(alpha=0.3)


def passage_figure(p: Passages, project: str = "") -> Figure:
    """Histograms and empirical CDFs of every quantity at one place.

    Parameters
    ----------
    p : Passages
        The rocks passing the place, with the marks of the measure there.
    project : str
        The project's name, for the title.

    Returns
    -------
    matplotlib.figure.Figure
        Seven panels (:data:`~rockfall_design.run.passages.QUANTITIES`) and a
        box that says where and how many rocks.
    """
    # A fixed grid, not the constrained layout: the panels are alike and their
    # labels short, and the layout engine's measuring of 14 axes' texts was
    # most of the time a report took (3 to 5 such figures per run).
    fig = RockfallFigure(figsize=(11, 12))
    fig.subplots_adjust(left=0.07, right=0.93, bottom=0.05, top=0.94, wspace=0.38,
                        hspace=0.32)
    fig.fits_page = True  # these margins hold every label: written without a crop
    axes = fig.subplots(4, 2).ravel()
    for ax, (key, what, unit) in zip(axes, QUANTITIES, strict=False):
        marks = [(m.label, m.value) for m in p.marks if m.quantity == key]
        _panel(ax, p.values[key], what, unit, marks)
    info = axes[-1]
    info.axis("off")
    lines = [p.label, f"x = {p.x:g} m, ground inclined {p.slope_deg:.1f} deg",
             f"{p.rocks:,} rocks " + ("met it" if p.place == "measure" else "passed it")]
    if p.marks:
        lines.append("lines: " + "; ".join(dict.fromkeys(m.label for m in p.marks)))
    if p.rocks == 0:
        lines.append("no rock got here: no distribution to show")
    info.text(0.02, 0.95, "\n".join(lines), va="top", ha="left", fontsize=9,
              transform=info.transAxes, wrap=True)
    head = f"{project}: " if project else ""
    fig.suptitle(f"{head}distributions at the {p.label}", fontsize=11)
    return fig

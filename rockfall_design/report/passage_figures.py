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
from matplotlib.markers import TICKRIGHT
from matplotlib.ticker import MaxNLocator
from matplotlib.transforms import blended_transform_factory

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
    """One quantity: histogram, empirical CDF on a right-hand scale, the marks as lines.

    The CDF is drawn on the histogram's own axes, scaled so that a share of 1
    sits at 1/1.02 of the height (the right-hand scale runs from 0 to 1.02),
    and its scale is drawn at the right edge by :func:`_share_scale`.
    """
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
    # The counts' axis as matplotlib's autoscale would set it (0 to the tallest
    # bar plus its 5 % margin), fixed so that the CDF drawn on it leaves it be.
    height = max(float(counts.max()), 1.0) * 1.05
    ax.set_ylim(0, height)
    per_share = height / 1.02  # counts' units per unit of share
    xs = np.sort(v)
    share = np.arange(1, xs.size + 1) / xs.size
    if xs.size > _ECDF_POINTS:
        # Through 1,000 of its steps (each the same share of the rocks apart): the
        # line a page shows is the same, and a step per rock of 50,000 made every
        # report's SVG and PDF megabytes heavy and slow to draw and print.
        keep = np.unique(np.linspace(0, xs.size - 1, _ECDF_POINTS).round().astype(int))
        xs, share = xs[keep], share[keep]
    ax.step(xs, share * per_share, where="post", color=_ECDF, lw=1.2)
    _share_scale(ax, per_share)
    # Texts at a height in the axes' fraction: 0.03 and 0.97 of the share scale.
    along = blended_transform_factory(ax.transData, ax.transAxes)
    p95 = float(np.percentile(v, 95))
    ax.axvline(p95, color=_ECDF, ls=":", lw=0.9)
    ax.text(p95, 0.03 / 1.02, f" p95 {p95:.3g}", color=_ECDF, fontsize=7, rotation=90,
            va="bottom", ha="right", transform=along)
    for k, (label, value) in enumerate(marks):
        colour = _MARK_COLOURS[k % len(_MARK_COLOURS)]
        ax.axvline(value, color=colour, lw=1.6)
        ax.text(value, 0.97 / 1.02, f" {label}", color=colour, fontsize=7, rotation=90,
                va="top", ha="right", transform=along)
    # At most five ticks an axis, at steps of 1, 2 or 5: enough to read a panel
    # 3 in wide, and each tick is five artists to make and draw. With
    # matplotlib's default of up to nine and the twin axes, four figures took
    # 2.27 s to write as SVG against 1.06 s with both changes (CPU medians as in
    # _share_scale); the ticks are about half of that.
    ax.xaxis.set_major_locator(MaxNLocator(nbins=5, steps=[1, 2, 5, 10]))
    ax.yaxis.set_major_locator(MaxNLocator(nbins=5, steps=[1, 2, 5, 10], integer=True))
    ax.grid(alpha=0.3)


#: The right-hand scale's ticks: shares of the rocks at or below.
_SHARE_TICKS = (0.0, 0.2, 0.4, 0.6, 0.8, 1.0)


def _share_scale(ax: Axes, per_share: float) -> None:
    """The CDF's scale at the right edge of ``ax``: ticks, their shares and its label.

    Drawn as a few plain artists, in the look of a matplotlib axis (ticks of
    3.5 pt out, labels 3.5 pt beyond, the label 4 pt beyond those), rather
    than as a twin axes: a twin is a whole second Axes per panel, and the
    seven twins of a passage figure were 40 % of the time it took to build and
    a sixth of the time to write as SVG (a check report's four figures: 1.45 s
    to build and 2.80 s to write against 0.85 s and 2.35 s; CPU time, medians
    of 9 in each of three alternated processes, 2026-11-28).
    """
    edge = blended_transform_factory(ax.transAxes, ax.transData)
    heights = [s * per_share for s in _SHARE_TICKS]
    ax.plot([1.0] * len(heights), heights, ls="none", marker=TICKRIGHT, ms=3.5, mew=0.8,
            color=_ECDF, transform=edge, clip_on=False)
    for s, y in zip(_SHARE_TICKS, heights, strict=True):
        ax.annotate(f"{s:.1f}", (1.0, y), xycoords=edge, xytext=(7.0, 0.0),
                    textcoords="offset points", fontsize=7, color=_ECDF, ha="left",
                    va="center", annotation_clip=False)
    # 7 pt of tick and gap, 11 pt for a label "0.0" at 7 pt, 4 pt of label pad.
    ax.annotate("share at or below", (1.0, 0.5), xycoords="axes fraction",
                xytext=(22.0, 0.0), textcoords="offset points", fontsize=7, color=_ECDF,
                rotation=90, ha="left", va="center", annotation_clip=False)


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

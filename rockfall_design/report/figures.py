"""Figures of a run, a check and an optimisation, as matplotlib Figure objects.

Every function here builds a :class:`matplotlib.figure.Figure` directly,
without pyplot: no backend is chosen or switched and no global figure state
is touched, so the figures work the same in a script, a test and a notebook
with the inline backend (where a returned Figure displays itself). Saving is
``fig.savefig``, which picks a canvas for the file format on its own;
:func:`save_figures` writes them through a command's output set.

Units are the same on every figure: x and elevation in m, passing height of
the rock centre above the ground in m, kinetic energy in kJ, cost in the
cost model's currency.
"""

from __future__ import annotations

import io
import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib import colormaps
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure

from ..engine.columns import STOPPED
from ..plugins.manager import plugin_code
from ..plugins.measure import Barrier
from ..run.passages import property_marks
from ..run.summary import EndCounts
from .formats import (
    CAPTIONS,
    FIGURE_FORMATS,
    save_figures,
)

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes

    from ..judge.evaluation import Evaluation
    from ..run.simulation import SimulationRun
    from ..run.streamed import StreamedRun

__all__ = [
    "RockfallFigure",
    "literal_texts",
    "FIGURE_FORMATS",
    "CAPTIONS",
    "DEFAULT_MIN_ROCKS_ENVELOPE",
    "profile_figure",
    "envelopes_figure",
    "stops_figure",
    "run_figures",
    "save_figures",
    "no_stop_reason",
]


#: Envelope points passed by fewer rocks than this are not drawn (when the
#: project does not say otherwise): a percentile of a handful of rocks is noise.
DEFAULT_MIN_ROCKS_ENVELOPE = 30

class RockfallFigure(Figure):
    """A matplotlib Figure that shows itself in a notebook without pyplot.

    IPython displays a plain Figure as an image only once pyplot has set up
    its inline backend; a figure built without pyplot (as here, to leave the
    backend alone) would show as ``<Figure size ...>``. ``_repr_png_`` lets
    IPython draw it either way; when the inline backend is active, its own
    formatter for Figures takes precedence, so a figure is never shown twice.
    """

    #: True for a figure whose margins are set by hand to hold every text:
    #: written as it is, not cropped "tight" (which draws it a second time).
    fits_page: bool = False

    def draw(self, renderer: Any) -> None:
        """Draw the figure, its words drawn as written (see :func:`literal_texts`)."""
        literal_texts(self)
        super().draw(renderer)

    def prepare_texts(self) -> None:
        """Words drawn as written, set before a layout measures them (:func:`.formats.laid_out`)."""
        literal_texts(self)

    def _repr_png_(self) -> bytes:
        buf = io.BytesIO()
        self.savefig(buf, format="png", dpi=100, bbox_inches="tight")
        return buf.getvalue()


def literal_texts(fig: Figure) -> None:
    """Draw every title, label, annotation and legend entry of ``fig`` as written.

    Matplotlib reads text between two ``$`` as mathematics: a project named
    "Budget: $5 to $10 per m" came out as "Budget: 5*to*10", and
    ``$\\undefinedmacro{x}$`` stopped the drawing with a parse error. The
    words of these figures come from the user's files (project, level,
    product and measure names), and none of the program's own uses
    mathematics, so every text is drawn literally, except the tick labels
    and the axes' offset texts, which matplotlib's formatters write as
    mathematics themselves (10 to a power on a log axis).
    """
    from matplotlib.axis import Axis
    from matplotlib.text import Text

    # A walk of the artists that steps over each axis' ticks (taking only the
    # axis label): the ticks are most of a figure's artists, their labels are
    # the formatters' own, and walking them all (``findobj``) took seconds per
    # report figure of 14 axes.
    stack = list(fig.get_children())
    while stack:
        artist = stack.pop()
        if isinstance(artist, Axis):
            artist.label.set_parse_math(False)
            continue
        if isinstance(artist, Text):
            artist.set_parse_math(False)
        stack.extend(artist.get_children())


_GROUND_FILL = "#d9cfc1"
_GROUND_LINE = "#5b4a36"
_STATION = "#1f5fa8"
_MEASURE = "#1e8449"
_PROTECT = "#e8a0a0"
_FOREST = "#3b7d3b"  # forested segments, shaded up to the stem height


# ---- pieces ---------------------------------------------------------------------


def _ground(ax: Axes, section: Any) -> None:
    ymin = section.y.min() - 0.05 * max(np.ptp(section.y), 1.0)
    ax.fill_between(section.x, section.y, ymin, color=_GROUND_FILL, zorder=1)
    ax.plot(section.x, section.y, color=_GROUND_LINE, lw=1.5, zorder=3, label="ground")
    ax.set_ylim(bottom=ymin)


def _forest(ax: Axes, run: SimulationRun | StreamedRun) -> None:
    """Shade the forested segments up to their stem height, with what the forest did."""
    section = run.section
    counts = run.forest_counts()
    if counts is None:
        return
    label = (f"forest: {counts[0]:,} of {run.n:,} rocks met stems, "
             f"{counts[1]:,} stopped by it")
    for k, mi in enumerate(section.segment_material):
        mat = section.materials[mi]
        if mat.stems_per_ha <= 0.0:
            continue
        xs, ys = section.x[k:k + 2], section.y[k:k + 2]
        ax.fill_between(xs, ys, ys + mat.tree_height_m, color=_FOREST, alpha=0.3, lw=0,
                        zorder=2, label=label)
        label = None


def _marks(ax: Axes, run: SimulationRun | StreamedRun, label: bool = True) -> None:
    """Analysis stations (dashed) and the protected zone (shaded)."""
    for j, xs in enumerate(run.stations):
        ax.axvline(xs, color=_STATION, ls="--", lw=0.9, zorder=2,
                   label="analysis station" if (label and j == 0) else None)
    if run.project.protect is not None:
        ax.axvspan(run.project.protect.x, run.section.x[-1], color=_PROTECT, alpha=0.25,
                   zorder=0, label="protected zone" if label else None)


def _measure_text(placed: Any) -> str:
    """What a barrier is, for its annotation: the measure's label without its station.

    The label is the plugin's (``fence RX-100 (3 m, 1000 kJ)``); a label that
    does not give the height and capacity gets them from the footprint, so
    every barrier on a figure says how high it is and what it takes.
    """

    text = str(placed.label).split(" at x = ")[0]
    fp = placed.footprint
    if isinstance(fp, Barrier):
        extra = []
        if " m" not in text:
            extra.append(f"{fp.height_m:.3g} m")
        if "kJ" not in text and math.isfinite(fp.capacity_kj):
            extra.append(f"{fp.capacity_kj:,.0f} kJ")
        if extra:
            text += " (" + ", ".join(extra) + ")"
    return text


def _draw_measures(ax: Axes, evaluation: Evaluation, label: bool = True,
                   annotate: bool = True) -> None:
    """Barriers as bars of their height; edited ground over the original (dashed)."""

    sec0 = evaluation.original_section
    ax.plot(sec0.x, sec0.y, color=_GROUND_LINE, lw=0.9, ls="--", zorder=3,
            label="original ground" if label else None)
    first = True
    section = evaluation.run.section
    for p in evaluation.placed:
        fp = p.footprint
        if isinstance(fp, Barrier):
            yg = float(section.ground_height(fp.x))
            # Where a rock's centre passes over: a fence's nominal height is normal to
            # the slope, so its top stands higher above the ground vertically.
            top = yg + fp.vertical_height_m
            ax.plot([fp.x, fp.x], [yg, top], color=_MEASURE, lw=3.0, zorder=6,
                    solid_capstyle="butt", label="barrier" if (label and first) else None)
            first = False
            anchor = (fp.x, top)
        else:
            ax.axvspan(fp.catch_from, fp.catch_to, color=_MEASURE, alpha=0.12, zorder=0)
            anchor = (fp.catch_from, float(section.ground_height(fp.catch_from)))
        if annotate:
            ax.annotate(_measure_text(p), anchor, textcoords="offset points", xytext=(4, 6),
                        fontsize=7, color=_MEASURE, zorder=7,
                        bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": "none",
                              "alpha": 0.7})


def _measure_lines(ax: Axes, evaluation: Evaluation | None) -> None:
    """A vertical line at each measure's station (for the envelope panels)."""
    if evaluation is None:
        return

    for p in evaluation.placed:
        fp = p.footprint
        ax.axvline(fp.x if isinstance(fp, Barrier) else fp.catch_from, color=_MEASURE,
                   lw=1.2, alpha=0.8)


# ---- the figures ----------------------------------------------------------------


def profile_figure(run: SimulationRun | StreamedRun,
                   evaluation: Evaluation | None = None) -> Figure:
    """The slope section with a sample of paths, rest positions, stations and measures.

    Parameters
    ----------
    run : SimulationRun or StreamedRun
        The run; its ``trajectories`` (kept with ``n_trajectories``) are drawn.
    evaluation : Evaluation, optional
        A check of measures: barriers are drawn with product, height (m) and
        capacity (kJ), ditches and berms as their catch area over the
        original ground.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = RockfallFigure(figsize=(11, 5.5), layout="constrained")
    ax = fig.add_subplot()
    _ground(ax, run.section)
    _forest(ax, run)
    paths = run.paths()
    if paths:
        # One collection, rasterised in SVG and PDF: hundreds of paths as vector
        # lines made the report's files heavy and slow to draw, print and read,
        # and at 150 dpi the raster is as sharp as the page shows them.
        ax.add_collection(LineCollection(
            [np.column_stack((x, y)) for x, y in paths], linewidths=0.6, alpha=0.55,
            colors="#c0392b", zorder=4, label="rock centre paths", rasterized=True))
        ax.autoscale_view()
    n_stopped = EndCounts.of(run.ends()).stopped
    rest_x, rest_y = run.rest_positions()
    if rest_x.size:
        ax.plot(rest_x, rest_y, "k.", ms=2, alpha=0.4, zorder=5, rasterized=True,
                label="rest positions" if rest_x.size == n_stopped
                else f"rest positions (first {rest_x.size:,} of {n_stopped:,})")
    _marks(ax, run)
    if evaluation is not None:
        _draw_measures(ax, evaluation)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("elevation (m)")
    ax.set_title(f"{run.project.name}: slope section and {len(paths)} of "
                 f"{run.n:,} paths")
    ax.set_aspect("equal", adjustable="box")
    ax.legend(loc="upper right", fontsize=8)
    ax.grid(alpha=0.3)
    return fig


def _figure_marks(axes: Mapping[str, Axes], evaluation: Evaluation | None) -> None:
    """Each measure's figures at its station: heights on the height panel, energies on the
    energy panel (read from its design properties by their units, see
    :func:`rockfall_design.run.passages.property_marks`)."""
    if evaluation is None:
        return

    panel = {"passing_height_m": "height", "energy_kj": "energy"}
    for p in evaluation.placed:
        if not isinstance(p.footprint, Barrier):
            continue
        x = float(p.footprint.x)
        # Plugin code (checked when the measure was placed): what it prints goes to stderr.
        with plugin_code():
            properties = p.measure.design_properties()
        for m in property_marks(properties):
            ax = axes.get(panel.get(m.quantity, ""))
            if ax is None:
                continue
            ax.plot([x], [m.value], marker="_", ms=16, mew=2.5, color=_MEASURE, zorder=6)
            ax.annotate(m.label, (x, m.value), textcoords="offset points", xytext=(6, 2),
                        fontsize=7, color=_MEASURE, zorder=7)


def envelopes_figure(
    run: SimulationRun | StreamedRun,
    evaluation: Evaluation | None = None,
    min_rocks: int | None = None,
) -> Figure:
    """Envelopes of passing height (m), energy (kJ) and speed (m/s) along x, and rocks passing.

    Parameters
    ----------
    run : SimulationRun or StreamedRun
    evaluation : Evaluation, optional
        Measures are marked by a vertical line at their station, and each
        barrier's heights and energies (nominal height, capacity, and any
        other the product gives) as a tick at its station on those panels.
    min_rocks : int, optional
        Points passed by fewer rocks are left out of the envelopes (default:
        the project's ``analysis.min_rocks_envelope``, else
        :data:`DEFAULT_MIN_ROCKS_ENVELOPE`). The bottom panel shows the count.

    Returns
    -------
    matplotlib.figure.Figure
        The speed panel only where the run recorded speeds along the section.
    """
    if min_rocks is None:
        min_rocks = int(getattr(run.project.analysis, "min_rocks_envelope",
                                DEFAULT_MIN_ROCKS_ENVELOPE))
    env = run.envelopes()
    x = env["x_m"].to_numpy()
    count = env["crossings"].to_numpy()
    enough = count >= min_rocks

    def masked(col: str) -> np.ndarray:
        return np.where(enough, env[col].to_numpy(dtype=float), np.nan)

    panels = [("height", "m", "passing height of the\nrock centre above ground (m)"),
              ("energy", "kj", "total kinetic energy (kJ)")]
    if "speed_max_ms" in env:
        panels.append(("speed", "ms", "translational speed (m/s)"))
    fig = RockfallFigure(figsize=(11, 3.0 * len(panels) + 2), layout="constrained")
    axes = fig.subplots(len(panels) + 1, 1, sharex=True,
                        gridspec_kw={"height_ratios": [3] * len(panels) + [1.4]})
    *tops, a3 = axes
    pcts = [c[len("height_p"):-len("_m")] for c in env.columns if c.startswith("height_p")]
    colors = colormaps["viridis"](np.linspace(0.15, 0.85, max(len(pcts), 1)))
    for ax, (name, unit, ylabel) in zip(tops, panels, strict=True):
        ax.plot(x, masked(f"{name}_max_{unit}"), color="k", lw=1.4, label="max")
        for c, q in zip(colors, pcts, strict=False):
            ax.plot(x, masked(f"{name}_p{q}_{unit}"), color=c, lw=1.0,
                    label=f"p{q.replace('_', '.')}")
        ax.set_ylabel(ylabel)
        if enough.any():
            ax.legend(loc="upper right", fontsize=8)
    _figure_marks({name: ax for ax, (name, _, _) in zip(tops, panels, strict=True)}, evaluation)
    a3.fill_between(x, count, step="mid", color="#95a5a6", alpha=0.6, label="rocks passing")
    a3.axhline(min_rocks, color="#c0392b", lw=0.9, ls=":",
               label=f"minimum for an envelope ({min_rocks})")
    for ax in axes:
        _marks(ax, run, label=False)
        _measure_lines(ax, evaluation)
        ax.grid(alpha=0.3)
    if not enough.any():
        tops[0].text(0.5, 0.5, f"no point of the section is passed by {min_rocks} rocks or "
                     "more", transform=tops[0].transAxes, ha="center", va="center",
                     fontsize=10)
    a3.legend(loc="upper right", fontsize=8)
    a3.set_ylim(bottom=0)
    a3.set_ylabel("rocks passing")
    a3.set_xlabel("x (m)")
    over = int(env.attrs.get("rocks", run.n))  # a decision's run: its first rocks again
    tops[0].set_title(f"{run.project.name}: envelopes over {over:,} rocks (first passage "
                      f"downslope), drawn where at least {min_rocks} rocks pass")
    return fig


def no_stop_reason(counts: EndCounts | Mapping[str, int] | Sequence[int] | np.ndarray) -> str:
    """Why no rock came to rest on the section, from the counts of end states.

    Parameters
    ----------
    counts : EndCounts, mapping of str to int, or array of int
        Rocks per end state (:class:`~rockfall_design.run.summary.EndCounts`), by
        name (``SimulationRun.ends()``), or indexed by the engine's status codes
        (``SimulationRun.status_counts()``).

    Returns
    -------
    str
        ``"all 500 rocks left the section downslope"``, ``"all 500 rocks were
        caught by the measures"`` or the mix, e.g. ``"of 500 rocks, 300 left
        the section downslope and 200 were caught by the measures"``.
    """
    ends = counts if isinstance(counts, EndCounts) else EndCounts.of(
        counts if isinstance(counts, Mapping) else np.asarray(counts))
    n = ends.total
    parts = [(ends.exit_downslope, "left the section downslope"),
             (ends.exit_upslope, "left the section upslope"),
             (ends.caught, "were caught by the measures"),
             (ends.unresolved, "reached the event limit (unresolved)")]
    parts = [(k, what) for k, what in parts if k]
    if len(parts) == 1:
        return f"all {n:,} rocks {parts[0][1]}"
    text = [f"{k:,} {what}" for k, what in parts]
    return f"of {n:,} rocks, " + ", ".join(text[:-1]) + " and " + text[-1]


def _rest_layers(run: SimulationRun | StreamedRun, evaluation: Evaluation | None,
                 bins: np.ndarray) -> list[tuple[str, np.ndarray, str]]:
    """Where the rocks ended, a layer per measure: (label, counts per bin, colour).

    Without an evaluation, one layer: the rocks at rest. With one, the rocks
    each measure holds where it holds them (a fence's at its station, a
    ditch's in it; ``Evaluation.caught_by_measure``), a colour per measure,
    and the rocks at rest that no measure holds in grey.
    """
    if evaluation is None:
        counts = run.stop_counts(len(bins) - 1)
        return [("rocks at rest", counts, "#7f8c8d")] if counts.sum() else []
    r = evaluation.run.result
    by = evaluation.caught_by_measure()
    layers = []
    free = (by < 0) & (r.status == STOPPED)
    counts = np.histogram(r.x_end[free], bins=bins)[0]
    if counts.sum():
        layers.append(("at rest, held by no measure", counts, "#7f8c8d"))
    colours = colormaps["tab10"](np.arange(10))
    for k, p in enumerate(evaluation.placed):
        held = by == p.index
        if held.any():
            # A caught rock's centre ends at the barrier (clipped into the plot).
            x = np.clip(r.x_end[held], bins[0], bins[-1])
            layers.append((f"held by {p.label}", np.histogram(x, bins=bins)[0],
                           colours[k % 10]))
    return layers


def _leavers(ax: Axes, counts: EndCounts, bins: np.ndarray, n: int) -> None:
    """Bars beyond the section's ends for the rocks that left it, saying how many."""
    width = float(bins[1] - bins[0])
    for k, x, side in ((counts.exit_downslope, bins[-1], "downslope"),
                       (counts.exit_upslope, bins[0] - width, "upslope")):
        if not k:
            continue
        ax.bar(x, k, width=width, align="edge", color="white", edgecolor="#c0392b",
               hatch="//", label=f"left the section {side}")
        ax.annotate(f"{k:,} of {n:,} left\nthe section {side}",
                    (x + width / 2, k), textcoords="offset points", xytext=(0, 4),
                    ha="right" if side == "downslope" else "left", va="bottom", fontsize=8,
                    color="#c0392b")


def stops_figure(run: SimulationRun | StreamedRun,
                 evaluation: Evaluation | None = None) -> Figure:
    """Where the rocks end: at rest, held by each measure (a colour each), or gone.

    Rocks at rest are counted per bin along x; with measures, the rocks a
    measure holds are drawn where it holds them in its own colour (a fence's
    catch at its station); rocks that left the section are a hatched bar
    beyond its end, with their count. The title says how every rock ended,
    so that a run where every rock leaves (or is caught) is not an empty plot.

    Returns
    -------
    matplotlib.figure.Figure
    """
    counts = EndCounts.of(run.ends())
    fig = RockfallFigure(figsize=(11, 6), layout="constrained")
    a1, a2 = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    sec = run.section
    bins = np.linspace(sec.x[0], sec.x[-1], 81)
    bottom = np.zeros(len(bins) - 1)
    for label, k, colour in _rest_layers(run, evaluation, bins):
        a1.bar(bins[:-1], k, width=np.diff(bins), align="edge", bottom=bottom, color=colour,
               edgecolor="white", label=label)
        bottom = bottom + k
    _leavers(a1, counts, bins, run.n)
    if not counts.stopped and not counts.caught:
        a1.text(0.5, 0.5, f"No rock came to rest on the section:\n{no_stop_reason(counts)}.",
                transform=a1.transAxes, ha="center", va="center", fontsize=11, zorder=5,
                bbox={"boxstyle": "round,pad=0.4", "fc": "white", "ec": "#999999"})
    a1.set_ylabel("rocks (per bin)")
    a1.set_title(f"{run.project.name}: where the rocks ended: {_ends_text(counts)}",
                 fontsize=10)
    _marks(a1, run)
    a1.grid(alpha=0.3)
    a1.set_ylim(0, max(a1.get_ylim()[1], 1.0) * 1.15)  # room for the leavers' count
    handles, _ = a1.get_legend_handles_labels()
    if handles:
        a1.legend(loc="upper left", fontsize=8)
    _ground(a2, sec)
    if evaluation is not None:
        _draw_measures(a2, evaluation, label=False, annotate=False)
    a2.set_xlabel("x (m)")
    a2.set_ylabel("elevation (m)")
    return fig


def _ends_text(counts: EndCounts) -> str:
    """'600 at rest, 380 caught by measures, 20 left downslope' (the non-zero ones)."""
    parts = [(counts.stopped, "at rest on the section"),
             (counts.caught, "caught by a barrier"),
             (counts.exit_downslope, "left downslope"),
             (counts.exit_upslope, "left upslope"),
             (counts.unresolved, "unresolved")]
    return ", ".join(f"{k:,} {what}" for k, what in parts if k) or "no rock"


def run_figures(
    run: SimulationRun | StreamedRun,
    evaluation: Evaluation | None = None,
    min_rocks: int | None = None,
) -> dict[str, Figure]:
    """The three figures of a run (or a check): profile, envelopes, stops, by name."""
    return {
        "profile": profile_figure(run, evaluation),
        "envelopes": envelopes_figure(run, evaluation, min_rocks),
        "stops": stops_figure(run, evaluation),
    }

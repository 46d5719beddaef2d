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
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure

from ..engine.trajectory import end_counts

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes

    from ..judge.evaluation import Evaluation
    from ..run.simulation import Study
    from ..run.streamed import StreamedStudy
    from .outputs import OutputSet

__all__ = [
    "RockfallFigure",
    "FIGURE_FORMATS",
    "CAPTIONS",
    "DEFAULT_MIN_ROCKS_ENVELOPE",
    "profile_figure",
    "envelopes_figure",
    "stops_figure",
    "study_figures",
    "save_figures",
    "no_stop_reason",
]

#: File formats the figures can be written in (``--plot-format``).
FIGURE_FORMATS = ("png", "svg", "pdf")

#: Envelope points passed by fewer rocks than this are not drawn (when the
#: project does not say otherwise): a percentile of a handful of rocks is noise.
DEFAULT_MIN_ROCKS_ENVELOPE = 30

#: One sentence per figure, for reports.
CAPTIONS = {
    "profile": "Slope section (x and elevation in m, equal scales) with a sample of rock "
    "centre paths, the rest positions, the analysis stations, the protected zone and the "
    "measures (barriers with product, height and capacity).",
    "envelopes": "Envelopes along the section of the passing height of the rock centre above "
    "the ground (m) and of the total kinetic energy (kJ), over the rocks passing each point "
    "downslope for the first time; drawn only where enough rocks pass (bottom: how many).",
    "stops": "Where the rocks come to rest along the section (count per bin), with the ground "
    "below; the title says how the other rocks ended.",
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


class RockfallFigure(Figure):
    """A matplotlib Figure that shows itself in a notebook without pyplot.

    IPython displays a plain Figure as an image only once pyplot has set up
    its inline backend; a figure built without pyplot (as here, to leave the
    backend alone) would show as ``<Figure size ...>``. ``_repr_png_`` lets
    IPython draw it either way; when the inline backend is active, its own
    formatter for Figures takes precedence, so a figure is never shown twice.
    """

    def _repr_png_(self) -> bytes:
        buf = io.BytesIO()
        self.savefig(buf, format="png", dpi=100, bbox_inches="tight")
        return buf.getvalue()


_GROUND_FILL = "#d9cfc1"
_GROUND_LINE = "#5b4a36"
_STATION = "#1f5fa8"
_MEASURE = "#1e8449"
_PROTECT = "#e8a0a0"


# ---- pieces ---------------------------------------------------------------------


def _ground(ax: Axes, section: Any) -> None:
    ymin = section.y.min() - 0.05 * max(np.ptp(section.y), 1.0)
    ax.fill_between(section.x, section.y, ymin, color=_GROUND_FILL, zorder=1)
    ax.plot(section.x, section.y, color=_GROUND_LINE, lw=1.5, zorder=3, label="ground")
    ax.set_ylim(bottom=ymin)


def _marks(ax: Axes, study: Study | StreamedStudy, label: bool = True) -> None:
    """Analysis stations (dashed) and the protected zone (shaded)."""
    for j, xs in enumerate(study.stations):
        ax.axvline(xs, color=_STATION, ls="--", lw=0.9, zorder=2,
                   label="analysis station" if (label and j == 0) else None)
    if study.project.protect is not None:
        ax.axvspan(study.project.protect.x, study.section.x[-1], color=_PROTECT, alpha=0.25,
                   zorder=0, label="protected zone" if label else None)


def _measure_text(placed: Any) -> str:
    """What a barrier is, for its annotation: the measure's label without its station.

    The label is the plugin's (``fence RX-100 (3 m, 1000 kJ)``); a label that
    does not give the height and capacity gets them from the footprint, so
    every barrier on a figure says how high it is and what it takes.
    """
    from ..plugins.measure import Barrier

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
    from ..plugins.measure import Barrier

    sec0 = evaluation.original_section
    ax.plot(sec0.x, sec0.y, color=_GROUND_LINE, lw=0.9, ls="--", zorder=3,
            label="original ground" if label else None)
    first = True
    section = evaluation.study.section
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
    from ..plugins.measure import Barrier

    for p in evaluation.placed:
        fp = p.footprint
        ax.axvline(fp.x if isinstance(fp, Barrier) else fp.catch_from, color=_MEASURE,
                   lw=1.2, alpha=0.8)


# ---- the figures ----------------------------------------------------------------


def profile_figure(study: Study | StreamedStudy, evaluation: Evaluation | None = None) -> Figure:
    """The slope section with a sample of paths, rest positions, stations and measures.

    Parameters
    ----------
    study : Study or StreamedStudy
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
    _ground(ax, study.section)
    paths = study.paths()
    for k, (x, y) in enumerate(paths):
        ax.plot(x, y, lw=0.6, alpha=0.55, color="#c0392b", zorder=4,
                label="rock centre paths" if k == 0 else None)
    n_stopped = study.ends()["stopped"]
    rest_x, rest_y = study.rest_positions()
    if rest_x.size:
        ax.plot(rest_x, rest_y, "k.", ms=2, alpha=0.4, zorder=5,
                label="rest positions" if rest_x.size == n_stopped
                else f"rest positions (first {rest_x.size:,} of {n_stopped:,})")
    _marks(ax, study)
    if evaluation is not None:
        _draw_measures(ax, evaluation)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("elevation (m)")
    ax.set_title(f"{study.project.name}: slope section and {len(paths)} of "
                 f"{study.n:,} paths")
    ax.set_aspect("equal", adjustable="box")
    ax.legend(loc="upper right", fontsize=8)
    ax.grid(alpha=0.3)
    return fig


def envelopes_figure(
    study: Study | StreamedStudy,
    evaluation: Evaluation | None = None,
    min_rocks: int | None = None,
) -> Figure:
    """Envelopes of passing height (m) and energy (kJ) along x, and how many rocks pass.

    Parameters
    ----------
    study : Study or StreamedStudy
    evaluation : Evaluation, optional
        Measures are marked by a vertical line at their station.
    min_rocks : int, optional
        Points passed by fewer rocks are left out of the envelopes (default:
        the project's ``analysis.min_rocks_envelope``, else
        :data:`DEFAULT_MIN_ROCKS_ENVELOPE`). The bottom panel shows the count.

    Returns
    -------
    matplotlib.figure.Figure
    """
    if min_rocks is None:
        min_rocks = int(getattr(study.project.analysis, "min_rocks_envelope",
                                DEFAULT_MIN_ROCKS_ENVELOPE))
    env = study.envelopes()
    x = env["x_m"].to_numpy()
    count = env["crossings"].to_numpy()
    enough = count >= min_rocks

    def masked(col: str) -> np.ndarray:
        return np.where(enough, env[col].to_numpy(dtype=float), np.nan)

    fig = RockfallFigure(figsize=(11, 8), layout="constrained")
    a1, a2, a3 = fig.subplots(3, 1, sharex=True, gridspec_kw={"height_ratios": [3, 3, 1.4]})
    pcts = [c for c in env.columns if c.startswith("height_p")]
    a1.plot(x, masked("height_max_m"), color="k", lw=1.4, label="max")
    a2.plot(x, masked("energy_max_kj"), color="k", lw=1.4, label="max")
    colors = colormaps["viridis"](np.linspace(0.15, 0.85, max(len(pcts), 1)))
    for c, col in zip(colors, pcts, strict=False):
        q = col[len("height_p"):-len("_m")].replace("_", ".")
        a1.plot(x, masked(col), color=c, lw=1.0, label=f"p{q}")
        a2.plot(x, masked(col.replace("height", "energy")[:-2] + "_kj"), color=c, lw=1.0,
                label=f"p{q}")
    a3.fill_between(x, count, step="mid", color="#95a5a6", alpha=0.6, label="rocks passing")
    a3.axhline(min_rocks, color="#c0392b", lw=0.9, ls=":",
               label=f"minimum for an envelope ({min_rocks})")
    for ax in (a1, a2, a3):
        _marks(ax, study, label=False)
        _measure_lines(ax, evaluation)
        ax.grid(alpha=0.3)
    for ax in (a1, a2):
        if np.isfinite(masked("height_max_m")).any():
            ax.legend(loc="upper right", fontsize=8)
    if not enough.any():
        a1.text(0.5, 0.5, f"no point of the section is passed by {min_rocks} rocks or more",
                transform=a1.transAxes, ha="center", va="center", fontsize=10)
    a3.legend(loc="upper right", fontsize=8)
    a3.set_ylim(bottom=0)
    a1.set_ylabel("passing height of the\nrock centre above ground (m)")
    a2.set_ylabel("total kinetic energy (kJ)")
    a3.set_ylabel("rocks passing")
    a3.set_xlabel("x (m)")
    a1.set_title(f"{study.project.name}: envelopes over {study.n:,} rocks (first passage "
                 f"downslope), drawn where at least {min_rocks} rocks pass")
    return fig


def no_stop_reason(counts: Mapping[str, int] | Sequence[int] | np.ndarray) -> str:
    """Why no rock came to rest on the section, from the counts of end states.

    Parameters
    ----------
    counts : mapping of str to int, or array of int
        Rocks per end state by name (``Study.ends()``), or indexed by the
        engine's status codes (``Study.status_counts()``).

    Returns
    -------
    str
        ``"all 500 rocks left the section downslope"``, ``"all 500 rocks were
        caught by the measures"`` or the mix, e.g. ``"of 500 rocks, 300 left
        the section downslope and 200 were caught by the measures"``.
    """
    ends = dict(counts) if isinstance(counts, Mapping) else end_counts(np.asarray(counts))
    n = sum(ends.values())
    parts = [(ends["exit_downslope"], "left the section downslope"),
             (ends["exit_upslope"], "left the section upslope"),
             (ends["caught"], "were caught by the measures"),
             (ends["unresolved"], "reached the event limit (unresolved)")]
    parts = [(k, what) for k, what in parts if k]
    if len(parts) == 1:
        return f"all {n:,} rocks {parts[0][1]}"
    text = [f"{k:,} {what}" for k, what in parts]
    return f"of {n:,} rocks, " + ", ".join(text[:-1]) + " and " + text[-1]


def stops_figure(study: Study | StreamedStudy, evaluation: Evaluation | None = None) -> Figure:
    """Where the rocks come to rest (a histogram along x) over the ground.

    When no rock comes to rest the histogram says so and why (every rock left
    the section, was caught by the measures, or a mix), instead of staying empty.

    Returns
    -------
    matplotlib.figure.Figure
    """
    counts = study.ends()
    n_stopped = counts["stopped"]
    fig = RockfallFigure(figsize=(11, 6), layout="constrained")
    a1, a2 = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    sec = study.section
    bins = np.linspace(sec.x[0], sec.x[-1], 81)
    if n_stopped:
        a1.bar(bins[:-1], study.stop_counts(80), width=np.diff(bins), align="edge",
               color="#7f8c8d", edgecolor="white", label="rocks at rest")
        others = []
        if counts["exit_downslope"]:
            others.append(f"{counts['exit_downslope']:,} left the section downslope")
        if counts["caught"]:
            others.append(f"{counts['caught']:,} were caught by the measures")
        title = f"rest positions of {n_stopped:,} of {study.n:,} rocks"
        if others:
            title += "; " + ", ".join(others)
    else:
        reason = no_stop_reason(counts)
        title = f"no rock came to rest on the section: {reason}"
        a1.text(0.5, 0.5, f"No rock came to rest on the section:\n{reason}.",
                transform=a1.transAxes, ha="center", va="center", fontsize=11, zorder=5,
                bbox={"boxstyle": "round,pad=0.4", "fc": "white", "ec": "#999999"})
        a1.set_ylim(0, 1)
        a1.set_yticks([])
    a1.set_ylabel("rocks at rest (per bin)")
    a1.set_title(f"{study.project.name}: {title}")
    _marks(a1, study)
    a1.grid(alpha=0.3)
    handles, _ = a1.get_legend_handles_labels()
    if handles:
        a1.legend(loc="upper left", fontsize=8)
    _ground(a2, sec)
    if evaluation is not None:
        _draw_measures(a2, evaluation, label=False, annotate=False)
    a2.set_xlabel("x (m)")
    a2.set_ylabel("elevation (m)")
    return fig


def study_figures(
    study: Study | StreamedStudy,
    evaluation: Evaluation | None = None,
    min_rocks: int | None = None,
) -> dict[str, Figure]:
    """The three figures of a run (or a check): profile, envelopes, stops, by name."""
    return {
        "profile": profile_figure(study, evaluation),
        "envelopes": envelopes_figure(study, evaluation, min_rocks),
        "stops": stops_figure(study, evaluation),
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
    from .outputs import OutputSet

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
                # Fixed metadata, so that the same run writes the same bytes.
                meta = {"svg": {"Date": None}, "pdf": {"CreationDate": None}}.get(fmt, {})
                fig.savefig(fh, format=fmt, dpi=150, bbox_inches="tight", metadata=meta)

            outputs.write_with(path, writer)
            written.append(path)
    return written


def figure_svg(fig: Figure) -> str:
    """The figure as an SVG document (text), for embedding in an HTML report."""
    buf = io.StringIO()
    fig.savefig(buf, format="svg", bbox_inches="tight", metadata={"Date": None})
    text = buf.getvalue()
    # Inline SVG in HTML needs no XML prolog or DOCTYPE.
    start = text.find("<svg")
    return text[start:] if start >= 0 else text

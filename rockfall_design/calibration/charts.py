"""Figures of a calibration or a comparison (matplotlib Figures, no pyplot).

- :func:`stops_figure`: the observed and simulated stop positions, as
  empirical cumulative distributions (left) and histograms (right), with
  the levels shaded;
- :func:`cloud_figure`: the bootstrap cloud of the fitted parameters (a
  histogram of each on the diagonal, each pair below it), the best fit and
  the intervals marked.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure

from ..report.figures import RockfallFigure
from .uncertainty import FittedParameter

__all__ = ["CAPTIONS", "cloud_figure", "stops_figure"]

CAPTIONS = {
    "calibration_stops": "Observed and simulated stop positions along the section (m): "
    "empirical cumulative distributions (left) and histograms as densities (right); the "
    "levels shaded. Simulated rocks that left the section are counted at its end.",
    "calibration_cloud": "The bootstrap cloud of the fitted parameters: each replicate "
    "refitted to a resample of the observations with its own simulation seed; the best fit "
    "(star) and the intervals (dashed).",
}

_OBS = "#1f4e79"
_SIM = "#c55a11"


def stops_figure(observed: np.ndarray, simulated: np.ndarray,
                 levels: Mapping[str, tuple[float, float]] | None = None,
                 title: str = "") -> Figure:
    """ECDF and histogram of observed and simulated stop stations (m)."""
    fig = RockfallFigure(figsize=(10, 4))
    ax1, ax2 = fig.subplots(1, 2)
    for ax in (ax1, ax2):
        for i, (name, (lo, hi)) in enumerate((levels or {}).items()):
            ax.axvspan(lo, hi, color="0.85" if i % 2 == 0 else "0.92", zorder=0)
            ax.text(0.5 * (lo + hi), 1.0, str(name), ha="center", va="bottom",
                    transform=ax.get_xaxis_transform(), fontsize=8)
    for x, colour, label in ((observed, _OBS, f"observed ({len(observed)})"),
                             (simulated, _SIM, f"simulated ({len(simulated):,})")):
        xs = np.sort(x)
        ax1.step(xs, np.arange(1, xs.size + 1) / xs.size, where="post", color=colour,
                 label=label)
    ax1.set_xlabel("stop position x (m)")
    ax1.set_ylabel("share of blocks stopped before x")
    ax1.set_ylim(0, 1.02)
    ax1.legend(loc="lower right", fontsize=8)
    both = np.concatenate([observed, simulated])
    bins = np.histogram_bin_edges(both, bins=min(40, max(10, len(observed) // 2)))
    ax2.hist(simulated, bins=bins, density=True, color=_SIM, alpha=0.45, label="simulated")
    ax2.hist(observed, bins=bins, density=True, histtype="step", color=_OBS, linewidth=1.8,
             label="observed")
    ax2.set_xlabel("stop position x (m)")
    ax2.set_ylabel("density (1/m)")
    ax2.legend(fontsize=8)
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


def cloud_figure(paths: Sequence[str], replicates: np.ndarray,
                 parameters: Sequence[FittedParameter]) -> Figure:
    """The bootstrap replicates of the fitted parameters, each pair and each alone.

    Parameters
    ----------
    paths
        The fitted inputs.
    replicates
        (B, d) refitted values.
    parameters
        :func:`~.uncertainty.summarise`'s entries (value, low, high, range).
    """
    d = len(paths)
    fig = RockfallFigure(figsize=(2.6 * d + 1.2, 2.4 * d + 0.8))
    axes = np.atleast_2d(fig.subplots(d, d, squeeze=False))
    short = [p.split(".", 1)[-1] if p.startswith("materials.") else p for p in paths]
    for i in range(d):
        for j in range(d):
            ax = axes[i, j]
            if j > i:
                ax.set_axis_off()
                continue
            pi, pj = parameters[i], parameters[j]
            if i == j:
                if len(replicates):
                    ax.hist(replicates[:, i], bins=15, range=tuple(pi.range), color=_SIM,
                            alpha=0.6)
                ax.axvline(pi.value, color="k")
                for end in (pi.low, pi.high):
                    if end is not None:
                        ax.axvline(end, color="k", linestyle="--", linewidth=0.8)
                ax.set_xlim(*pi.range)
                ax.set_yticks([])
            else:
                if len(replicates):
                    ax.scatter(replicates[:, j], replicates[:, i], s=8, color=_SIM, alpha=0.6)
                ax.plot([pj.value], [pi.value], marker="*", color="k", markersize=10)
                ax.set_xlim(*pj.range)
                ax.set_ylim(*pi.range)
            if i == d - 1:
                ax.set_xlabel(short[j], fontsize=8)
            if j == 0 and i > 0:
                ax.set_ylabel(short[i], fontsize=8)
    fig.suptitle(f"bootstrap cloud ({len(replicates)} replicates)", fontsize=10)
    fig.tight_layout()
    return fig

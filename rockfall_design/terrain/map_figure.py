"""The corridor's map: hillshade, road, sections coloured by design, measures along the contour."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .dem import Dem
from .mapping import MapMeasure
from .road import CorridorMap

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = ["corridor_map"]

#: Sun of the hillshade: from the north-west, 45 deg high (the cartographic
#: convention: Imhof, Cartographic Relief Presentation, 1982).
SUN_AZIMUTH_DEG, SUN_ALTITUDE_DEG = 315.0, 45.0


def corridor_map(dem: Dem, where: CorridorMap, designs: Sequence[str],
                 measures: Sequence[MapMeasure], title: str = "") -> Figure:
    """The map figure of a corridor's design.

    Parameters
    ----------
    dem
        The corridor's DEM (hillshaded in grey).
    where
        Where the sections lie.
    designs
        Each section's design in words (``fence RX-100``; ``none``), in order:
        the section lines are coloured by it.
    measures
        The chosen measures, drawn as thick lines labelled product and height.
    title
        The figure's title.
    """
    # matplotlib is heavy: loaded when a map is drawn, not by every command that
    # can draw one (study's corridor commands import this module).
    from matplotlib.colors import LightSource
    from matplotlib.figure import Figure

    fig = Figure(figsize=(9, 7.5))
    ax = fig.add_subplot()
    e0, e1, n0, n1 = dem.extent
    shade = LightSource(SUN_AZIMUTH_DEG, SUN_ALTITUDE_DEG).hillshade(
        np.nan_to_num(dem.z, nan=float(np.nanmin(dem.z))), vert_exag=1.0, dx=dem.dx, dy=dem.dy)
    ax.imshow(shade, cmap="gray", extent=(e0 - dem.dx / 2, e1 + dem.dx / 2,
                                          n0 - dem.dy / 2, n1 + dem.dy / 2), origin="upper")
    ax.contour(np.linspace(e0, e1, dem.shape[1]), np.linspace(n1, n0, dem.shape[0]), dem.z,
               levels=20, colors="0.35", linewidths=0.4, alpha=0.6)
    ax.plot(where.road[:, 0], where.road[:, 1], color="black", lw=2.5, label="road")
    kinds = sorted(set(designs))
    palette = _colours(kinds)
    for road_section, design in zip(where.sections, designs, strict=True):
        ax.plot(road_section.line[:, 0], road_section.line[:, 1], color=palette[design], lw=1.2)
    for kind in kinds:
        ax.plot([], [], color=palette[kind], lw=2, label=f"section: {kind}")
    for measure in measures:
        a = measure.attributes
        ax.plot(measure.line[:, 0], measure.line[:, 1], color="crimson", lw=3.5,
                solid_capstyle="butt")
        mid = measure.line.mean(axis=0)
        text = " ".join(str(v) for v in (a.get("product"), _height(a.get("height_m"))) if v)
        ax.annotate(text or a.get("type", ""), mid, fontsize=6, color="crimson",
                    xytext=(3, 3), textcoords="offset points")
    if measures:
        ax.plot([], [], color="crimson", lw=3.5, label="chosen measure")
    ax.set_aspect("equal")
    ax.set_xlabel(f"E (m, {dem.crs_name})")
    ax.set_ylabel("N (m)")
    ax.ticklabel_format(useOffset=False, style="plain")
    ax.legend(loc="upper right", fontsize=7, framealpha=0.85)
    ax.set_title(title or "Corridor design on the map")
    return fig


def _height(value: Any) -> str:
    return "" if value is None else f"{float(value):g} m"


def _colours(kinds: Sequence[str]) -> Mapping[str, Any]:
    from matplotlib import colormaps  # heavy: see corridor_map

    cmap = colormaps["tab10"]
    out: dict[str, Any] = {}
    for i, kind in enumerate(k for k in kinds if k != "none"):
        out[kind] = cmap(i % 10)
    out["none"] = "0.2"
    return out

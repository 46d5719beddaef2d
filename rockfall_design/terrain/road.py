"""A corridor along a road: sections every spacing, each traced up its fall line.

The road (a map polyline) is cut into equal shares of at most ``spacing_m``;
at the middle of each share the fall line is walked up the slope (steepest
ascent, :func:`~.fall_line.trace_fall_line`) to a ridge, a flat or the
raster's edge, and down below the road for ``below_m`` (the runout that
the protected zone must see). The section is that line, upper end first;
the road lies at ``road_x`` along it, and the section stands for its share
of the road (``length_m``).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from .cover import read_layer
from .cut import TerrainSection
from .dem import Dem
from .extra import TerrainError, require
from .fall_line import DEFAULT_FLAT_DEG, trace_fall_line

__all__ = ["CorridorMap", "RoadSection", "read_road", "road_sections"]


@dataclass(frozen=True)
class RoadSection:
    """One section of a road corridor on the map.

    Attributes
    ----------
    station
        Distance (m) along the road of the section's road point.
    length_m
        The share of the road the section stands for (m).
    line
        The section's map line (E, N) (m), upper end first.
    road_x
        Where the road crosses the section (m along ``line``).
    section
        The section cut from the DEM (None until cut).
    """

    station: float
    length_m: float
    line: np.ndarray
    road_x: float
    section: TerrainSection | None = None


@dataclass(frozen=True)
class CorridorMap:
    """Where a corridor's sections lie on the map: for the map figure and the GeoPackage.

    Attributes
    ----------
    dem
        The DEM's file.
    crs_wkt
        The DEM's CRS.
    road
        The road's map line (E, N) (m).
    sections
        One :class:`RoadSection` per corridor section, in order (cut).
    """

    dem: str
    crs_wkt: str
    road: np.ndarray
    sections: tuple[RoadSection, ...]


def read_road(path: str | os.PathLike[str], dem_wkt: str = "") -> np.ndarray:
    """The road's map line (E, N) (m) from the first line feature of a vector layer."""
    shown = os.fspath(path)
    _, geometries, _ = read_layer(path, "road", dem_wkt)
    shapely = require("shapely", f"reading the road {shown}")
    for geometry in geometries:
        if geometry is not None and geometry.geom_type in ("LineString", "MultiLineString"):
            if geometry.geom_type == "MultiLineString":
                geometry = shapely.line_merge(geometry)
                if geometry.geom_type != "LineString":
                    raise TerrainError(shown, "the road's parts do not join into one line")
            return np.asarray(geometry.coords, dtype=float)[:, :2]
    raise TerrainError(shown, "no line feature: expected the road as a LineString")


def road_sections(dem: Dem, road: np.ndarray, spacing_m: float, *, below_m: float = 20.0,
                  max_length_m: float = 1000.0, flat_deg: float = DEFAULT_FLAT_DEG,
                  smooth_px: float = 1.0) -> list[RoadSection]:
    """The sections of a corridor along ``road``.

    Parameters
    ----------
    dem
        The terrain.
    road
        The road's map line (E, N) (m), shape (k, 2).
    spacing_m
        Largest share of the road per section (m).
    below_m
        Length (m) of the section below the road.
    max_length_m
        Longest ascent from the road (m).
    flat_deg
        The ascent ends where the ground is flatter (deg).
    smooth_px
        Smoothing of the gradient (pixels).

    Raises
    ------
    TerrainError
        A road point off the raster or on ground too flat to have a fall line.
    """
    seg = np.hypot(*np.diff(road, axis=0).T)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    count = max(1, math.ceil(cum[-1] / spacing_m - 1e-9))
    share = cum[-1] / count
    out = []
    for k in range(count):
        station = (k + 0.5) * share
        p = (float(np.interp(station, cum, road[:, 0])),
             float(np.interp(station, cum, road[:, 1])))
        what = f"the fall line at {station:.1f} m along the road"
        up = trace_fall_line(dem, p, ascend=True, flat_deg=flat_deg, max_length_m=max_length_m,
                             smooth_px=smooth_px, what=what)
        try:
            below = trace_fall_line(dem, p, flat_deg=flat_deg, max_length_m=below_m,
                                    smooth_px=smooth_px, what=what, edge_ok=True).points[1:]
        except TerrainError:  # flat below the road: the section ends at the road
            below = np.empty((0, 2))
        line = np.concatenate([up.points[::-1], below])
        out.append(RoadSection(station=station, length_m=share, line=line,
                               road_x=up.length))
    return out

"""The design back on the map: measures as line features, and the map figure.

A measure chosen at station x of a section lies on the map at the section
line's point at x; it is drawn as a line along the contour there (across
the fall line) as long as the share of the road the section stands for, so
that the measures of neighbouring sections join up along the slope. The
features go to a GeoPackage (any GIS opens it) in the DEM's CRS.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .extra import TerrainError, require
from .road import RoadSection

__all__ = ["MapMeasure", "measure_line", "write_layer"]


@dataclass(frozen=True)
class MapMeasure:
    """One chosen measure on the map, with the attributes of its feature.

    Attributes
    ----------
    line
        Map vertices (E, N) (m) of the measure along the contour.
    attributes
        ``type``, ``product``, ``height_m``, ``capacity_kj``, ``cost``,
        ``section``, ``station_m`` (the road station), ``x_m`` (along the section).
    """

    line: np.ndarray
    attributes: dict[str, Any]


def measure_line(road_section: RoadSection, x: float) -> np.ndarray:
    """The map line (2 points, m) of a measure at station ``x`` of a corridor section.

    Centred on the section line at ``x``, across the line's direction there,
    as long as the section's share of the road.
    """
    section = road_section.section
    assert section is not None
    centre = section.map_point(x)
    d = section.direction(x)
    across = np.array([-d[1], d[0]]) * 0.5 * road_section.length_m
    return np.array([centre - across, centre + across])


def write_layer(path: str | os.PathLike[str], geometries: Sequence[Any],
                attributes: Mapping[str, Sequence[Any]], geometry_type: str,
                crs_wkt: str, layer: str | None = None) -> None:
    """Write shapely geometries and their attributes as a vector layer (GPKG, GeoJSON).

    Parameters
    ----------
    path
        The file; its suffix picks the driver (``.gpkg`` GeoPackage,
        ``.geojson`` GeoJSON).
    geometries
        shapely geometries, one per feature.
    attributes
        Name -> one value per feature (text, numbers; None is null).
    geometry_type
        ``LineString``, ``Polygon``, ...
    crs_wkt
        The layer's CRS (the DEM's).
    layer
        The layer's name (default the file's stem).
    """
    pyogrio = require("pyogrio", f"writing {os.fspath(path)}")
    shapely = require("shapely", f"writing {os.fspath(path)}")
    names = list(attributes)
    data = []
    for name in names:
        values = list(attributes[name])
        if all(isinstance(v, int | float) and not isinstance(v, bool) or v is None
               for v in values) and any(v is not None for v in values):
            data.append(np.array([np.nan if v is None else float(v) for v in values]))
        else:
            data.append(np.array(["" if v is None else str(v) for v in values], dtype=object))
    driver = "GeoJSON" if str(path).lower().endswith((".geojson", ".json")) else "GPKG"
    try:
        pyogrio.raw.write(path, np.array([shapely.to_wkb(g) for g in geometries], dtype=object),
                          data, names, geometry_type=geometry_type, crs=crs_wkt or None,
                          driver=driver, layer=layer)
    except Exception as exc:  # noqa: BLE001 - GDAL's errors writing a file
        reason = " ".join(str(exc).split())[:160] or type(exc).__name__
        raise TerrainError(os.fspath(path), f"cannot write the layer: {reason}") from None


def chosen_measures(where: Any, blocks: Sequence[Mapping[str, Any]]) -> list[MapMeasure]:
    """The measures of each section's chosen design, on the map.

    Parameters
    ----------
    where
        The corridor's :class:`~.road.CorridorMap`.
    blocks
        The sections' JSON objects of ``optimise`` (``best``: the chosen
        design with its ``measures`` and ``cost``; None without a design), in order.

    Returns
    -------
    list of MapMeasure
        One per measure of every chosen design. ``cost`` is the whole design's
        cost of that section (a design of several measures repeats it).
    """
    out = []
    for road_section, block in zip(where.sections, blocks, strict=True):
        best = block.get("best")
        if not best:
            continue
        for measure in best.get("measures", []):
            x = float(measure["x"])
            out.append(MapMeasure(measure_line(road_section, x), {
                "type": str(measure.get("type", "")),
                "product": measure.get("product"),
                "height_m": measure.get("height"),
                "capacity_kj": measure.get("capacity_kj"),
                "cost": best.get("cost"),
                "section": str(block.get("name", "")),
                "station_m": round(road_section.station, 3),
                "x_m": x,
            }))
    return out


def write_measures(path: str | os.PathLike[str], measures: Sequence[MapMeasure],
                   crs_wkt: str) -> None:
    """Write the measures as a line layer ``measures`` (GeoPackage or GeoJSON)."""
    shapely = require("shapely", f"writing {os.fspath(path)}")
    keys = ("type", "product", "height_m", "capacity_kj", "cost", "section", "station_m", "x_m")
    attributes = {k: [m.attributes.get(k) for m in measures] for k in keys}
    write_layer(path, [shapely.LineString(m.line) for m in measures], attributes,
                "LineString", crs_wkt, layer="measures")

"""Materials and release zones from the map, cut along a section.

- Materials: a land-cover raster (each pixel a class number) or a polygon
  layer (GeoPackage, GeoJSON, Shapefile; an attribute per polygon), with a
  table class -> material in the project. The class is read at every sample
  of the section (the raster's pixel that holds it, or the polygon that
  contains it), the section keeps a vertex wherever the class changes, and
  each segment gets the material of its class.
- Release zones: where the ground is steeper than a threshold angle, or
  inside the polygons of a layer.

A threshold of 45-55 deg is the common rule for rockfall source areas on a
DEM (Loye et al. 2009, Nat. Hazards Earth Syst. Sci. 9, 1643-1653: slopes
steeper than the threshold of the slope-angle distribution's "cliff" mode).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from .cut import TerrainSection, simplify_vertical
from .extra import TerrainError, require

__all__ = ["same_crs", "classes_from_polygons", "classes_from_raster", "inside_polygons",
           "release_ranges", "with_materials"]


def same_crs(shown: str, crs_wkt: str, dem_wkt: str, what: str) -> None:
    """A map layer must be in the DEM's CRS (no silent reprojection of a design input)."""
    if not crs_wkt or not dem_wkt:
        return
    pyproj = require("pyproj", f"comparing the CRS of {shown}")
    mine, theirs = pyproj.CRS.from_user_input(crs_wkt), pyproj.CRS.from_user_input(dem_wkt)
    if not mine.equals(theirs, ignore_axis_order=True):
        raise TerrainError(
            shown, f"the {what} is in {mine.to_string()}, the DEM in {theirs.to_string()}: "
            "give both in the same projected CRS")


def classes_from_raster(path: str | os.PathLike[str], east: np.ndarray, north: np.ndarray,
                        dem_wkt: str = "") -> list[Any]:
    """The land-cover class (an int, or None at no data) at every map point.

    Parameters
    ----------
    path
        A one-band raster of class numbers in the DEM's CRS.
    east, north
        Map coordinates (m) of the section's samples.
    dem_wkt
        The DEM's CRS, which the raster must share.
    """
    shown = os.fspath(path)
    rasterio = require("rasterio", f"reading the land-cover raster {shown}")
    try:
        with rasterio.open(path) as src:
            same_crs(shown, src.crs.to_wkt() if src.crs else "", dem_wkt, "land-cover raster")
            inverse = ~src.transform
            band = src.read(1, masked=True)
        # the pixel that holds each point (the inverse affine transform, floored)
        x, y = np.asarray(east, dtype=float), np.asarray(north, dtype=float)
        cols = inverse.a * x + inverse.b * y + inverse.c
        rows = inverse.d * x + inverse.e * y + inverse.f
    except TerrainError:
        raise
    except Exception as exc:  # noqa: BLE001 - GDAL's errors on a foreign or damaged file
        reason = " ".join(str(exc).split())[:160] or type(exc).__name__
        raise TerrainError(shown, f"not a raster that can be read: {reason}") from None
    rows = np.floor(rows).astype(np.intp)
    cols = np.floor(cols).astype(np.intp)
    out: list[Any] = []
    for k, (i, j) in enumerate(zip(rows, cols, strict=True)):
        if not (0 <= i < band.shape[0] and 0 <= j < band.shape[1]):
            raise TerrainError(shown, f"the section's point ({east[k]:.2f}, {north[k]:.2f}) "
                               "is off the land-cover raster")
        value = band[i, j]
        out.append(None if np.ma.is_masked(value) else int(value))
    return out


def read_layer(path: str | os.PathLike[str], what: str,
               dem_wkt: str) -> tuple[dict[str, Any], list[Any], list[Any]]:
    """A vector layer's metadata, geometries (shapely) and field columns, in the DEM's CRS.

    One line naming the file where GDAL cannot read it or its CRS is not the
    DEM's (``what`` names the layer in that line).
    """
    shown = os.fspath(path)
    pyogrio = require("pyogrio", f"reading the {what} {shown}")
    shapely = require("shapely", f"reading the {what} {shown}")
    try:
        meta, _, wkb, fields = pyogrio.raw.read(path)
    except Exception as exc:  # noqa: BLE001 - GDAL's errors on a foreign or damaged file
        reason = " ".join(str(exc).split())[:160] or type(exc).__name__
        raise TerrainError(shown, f"not a vector layer that can be read: {reason}") from None
    same_crs(shown, meta.get("crs") or "", dem_wkt, what)
    return meta, list(shapely.from_wkb(wkb)), list(fields)


def _read_polygons(path: str | os.PathLike[str], attribute: str | None,
                   dem_wkt: str) -> tuple[list[Any], list[Any]]:
    """The polygons of a layer and their attribute values (None without attribute)."""
    shown = os.fspath(path)
    meta, shapes, fields = read_layer(path, "polygon layer", dem_wkt)
    names = list(meta["fields"])
    if attribute is None:
        return shapes, [True] * len(shapes)
    if attribute not in names:
        raise TerrainError(shown, f"no attribute {attribute!r}; the layer has "
                           f"{', '.join(names) or 'no attributes'}")
    values = fields[names.index(attribute)]
    return shapes, [v.item() if hasattr(v, "item") else v for v in values]


def classes_from_polygons(path: str | os.PathLike[str], attribute: str | None,
                          east: np.ndarray, north: np.ndarray, dem_wkt: str = "") -> list[Any]:
    """The attribute of the polygon holding each map point (None outside every polygon).

    Where polygons overlap, the first in the layer wins.
    """
    shapely = require("shapely", "reading polygons")
    shapes, values = _read_polygons(path, attribute, dem_wkt)
    out: list[Any] = [None] * len(east)
    free = np.ones(len(east), dtype=bool)
    for shape, value in zip(shapes, values, strict=True):
        if shape is None or shape.is_empty:
            continue
        hit = free & shapely.contains_xy(shape, east, north)
        for k in np.flatnonzero(hit):
            out[k] = value
        free &= ~hit
    return out


def inside_polygons(path: str | os.PathLike[str], east: np.ndarray, north: np.ndarray,
                    dem_wkt: str = "") -> np.ndarray:
    """True for map points inside any polygon of the layer."""
    return np.array([v is not None for v in
                     classes_from_polygons(path, None, east, north, dem_wkt)], dtype=bool)


def with_materials(section: TerrainSection, classes: list[Any], table: Mapping[Any, str],
                   default: str | None, tolerance: float, shown: str) -> tuple[
                       TerrainSection, list[str]]:
    """The section with a vertex at every change of material, and a material per segment.

    Parameters
    ----------
    section
        The section (its dense samples are those ``classes`` were read at).
    classes
        The class at every dense sample.
    table
        Class -> material name.
    default
        The material of a class not in the table (and of no data); None: an error.
    tolerance
        The vertical tolerance (m) of the simplification.
    shown
        The map layer's name, for messages.
    """
    names = []
    for k, value in enumerate(classes):
        name = table.get(value, table.get(str(value)) if value is not None else None)
        if name is None:
            name = default
        if name is None:
            e, n = section.map_point(section.dense_x[k])
            what = "no data" if value is None else f"class {value!r}"
            raise TerrainError(
                shown, f"{what} at {section.dense_x[k]:.1f} m along the section "
                f"({e:.2f}, {n:.2f}) has no material: add it to the classes, or give a default")
        names.append(name)
    change = np.zeros(len(names), dtype=bool)
    change[1:] = [a != b for a, b in zip(names[:-1], names[1:], strict=True)]
    keep = simplify_vertical(section.dense_x, section.dense_z, tolerance, change)
    materials = [names[k] for k in keep[:-1]]
    return replace(section, x=section.dense_x[keep], z=section.dense_z[keep]), materials


def release_ranges(section: TerrainSection, *, steeper_than_deg: float | None = None,
                   inside: np.ndarray | None = None, min_length_m: float = 0.0) -> list[
                       tuple[float, float]]:
    """Stretches (x from, x to) (m) of the section that release rocks.

    Parameters
    ----------
    section
        The section (its dense samples).
    steeper_than_deg
        Release where the ground between two samples is steeper than this (deg).
    inside
        Or: a mask of the dense samples inside release polygons.
    min_length_m
        Stretches shorter than this are dropped (m).
    """
    x, z = section.dense_x, section.dense_z
    if steeper_than_deg is not None:
        angle = np.degrees(np.arctan2(np.abs(np.diff(z)), np.diff(x)))
        seg = angle > steeper_than_deg
    else:
        assert inside is not None
        seg = inside[:-1] & inside[1:]
    ranges: list[tuple[float, float]] = []
    k = 0
    while k < len(seg):
        if not seg[k]:
            k += 1
            continue
        j = k
        while j + 1 < len(seg) and seg[j + 1]:
            j += 1
        if x[j + 1] - x[k] >= min_length_m:
            ranges.append((float(x[k]), float(x[j + 1])))
        k = j + 1
    return ranges

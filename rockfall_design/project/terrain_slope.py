"""Project keys that take the slope from the terrain: a DEM, a point cloud, map layers.

``slope: {dem: terrain.tif, line: [[E, N], ...]}`` or ``slope: {dem: ...,
fall_line: {from: [E, N]}}`` cuts the section from a DEM;
``slope: {points: scan.laz, line: ..., swath_m: 1.0}`` from a point cloud.
``slope.materials`` is a name, or a map layer with a class -> material table;
a release zone of ``rocks.release`` may give ``steeper_than_deg`` or
``polygons`` instead of ``x``. :func:`terrain_slope` turns all of it into the
inline points, materials and release zones the schema validates (see
:mod:`rockfall_design.terrain` and docs/terrain.md); the geospatial
libraries are those of the extra ``[terrain]``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ProjectError
from ..terrain.cloud import DEFAULT_PERCENTILE, cloud_section
from ..terrain.cover import (
    classes_from_polygons,
    classes_from_raster,
    inside_polygons,
    release_ranges,
    with_materials,
)
from ..terrain.cut import DEFAULT_TOLERANCE_M, TerrainSection, cut_section
from ..terrain.dem import Dem, read_dem
from ..terrain.fall_line import DEFAULT_FLAT_DEG, trace_fall_line
from .messages import describe, did_you_mean

__all__ = ["check_keys", "cover_materials", "is_terrain_slope", "map_file", "map_line",
           "positive", "terrain_slope", "terrain_zones"]

Error = Callable[[Sequence[Any], str], ProjectError]

DEM_KEYS = ("dem", "line", "fall_line", "spacing_m", "tolerance_m", "materials")
CLOUD_KEYS = ("points", "line", "swath_m", "bin_m", "percentile", "tolerance_m", "materials")
FALL_KEYS = ("from", "stop", "flat_deg", "max_length_m")
COVER_KEYS = ("raster", "polygons", "attribute", "classes", "default")
ZONE_KEYS = ("steeper_than_deg", "polygons", "min_length_m")


def is_terrain_slope(slope: Any) -> bool:
    """True for ``slope:`` from a DEM or a point cloud file."""
    return isinstance(slope, dict) and ("dem" in slope or isinstance(slope.get("points"), str))


def check_keys(value: dict, allowed: Sequence[str], at: tuple, error: Error) -> None:
    """An unknown key of ``value`` (at key path ``at``) is an error, with "did you mean"."""
    for key in value:
        if key not in allowed:
            hint = (did_you_mean(key, allowed) if isinstance(key, str) else "") or (
                f"; expected one of {', '.join(allowed)}")
            raise error(at + (key,), f"unknown key {key!r}{hint}")


def positive(value: Any, at: tuple, error: Error, *, low: float = 0.0,
             strict: bool = True) -> float:
    """A finite number above ``low`` (or at least it, unless ``strict``)."""
    ok = isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)
    if not ok or (value <= low if strict else value < low):
        sign = ">" if strict else ">="
        raise error(at, f"expected a number {sign} {low:g}, got {describe(value)}")
    return float(value)


def map_line(value: Any, at: tuple, error: Error, least: int = 2) -> np.ndarray:
    """A list of at least ``least`` map points [E, N] as an array (k, 2)."""
    ok = isinstance(value, list) and len(value) >= least and all(
        isinstance(p, list) and len(p) == 2 and all(
            isinstance(c, int | float) and not isinstance(c, bool) and math.isfinite(c)
            for c in p) for p in value)
    if not ok:
        what = "a map point [E, N]" if least == 1 else "a map line: a list of points [E, N]"
        raise error(at, f"expected {what} (m, in the DEM's CRS), got {describe(value)}")
    return np.array(value, dtype=float)


def map_file(value: Any, at: tuple, error: Error, base_dir: Path, what: str) -> Path:
    """A file named at ``at``, relative to ``base_dir``."""
    if not isinstance(value, str) or not value.strip():
        raise error(at, f"expected the file name of {what}, got {describe(value)}")
    path = Path(value).expanduser()
    return path if path.is_absolute() else base_dir / path


def terrain_slope(slope: dict, error: Error, base_dir: Path) -> tuple[dict, TerrainSection,
                                                                       str]:
    """``slope:`` from a DEM or a point cloud -> inline points and materials.

    Parameters
    ----------
    slope
        The ``slope:`` mapping as written.
    error
        Makes a located error: ``error(key path, message)``.
    base_dir
        Directory the named files are relative to.

    Returns
    -------
    tuple
        ``{points, materials}``, the section (with its map line) and the
        DEM's CRS as WKT ("" for a point cloud).
    """
    cloud = "dem" not in slope
    check_keys(slope, CLOUD_KEYS if cloud else DEM_KEYS, ("slope",), error)
    tolerance = positive(slope.get("tolerance_m", DEFAULT_TOLERANCE_M), ("slope", "tolerance_m"),
                        error, strict=False)
    if cloud:
        if "line" not in slope or "swath_m" not in slope:
            raise error(("slope",), "a section from a point cloud needs line: and swath_m:")
        path = map_file(slope["points"], ("slope", "points"), error, base_dir, "a point cloud")
        section = cloud_section(
            path, map_line(slope["line"], ("slope", "line"), error),
            swath_m=positive(slope["swath_m"], ("slope", "swath_m"), error),
            bin_m=positive(slope.get("bin_m", 1.0), ("slope", "bin_m"), error),
            percentile=positive(slope.get("percentile", DEFAULT_PERCENTILE),
                               ("slope", "percentile"), error, strict=False),
            tolerance=tolerance, shown=str(path))
        crs = ""
    else:
        dem = read_dem(map_file(slope["dem"], ("slope", "dem"), error, base_dir, "a DEM"))
        section = _dem_section(dem, slope, tolerance, error)
        crs = dem.crs_wkt
    materials = slope.get("materials")
    if materials is None:
        raise error(("slope",), "no materials for the section: give slope.materials (a name, "
                    "or a map layer: {raster: ..., classes: {...}} or {polygons: ..., "
                    "attribute: ..., classes: {...}})")
    if isinstance(materials, dict):
        section, names = cover_materials(section, materials, tolerance, crs, error, base_dir,
                                         ("slope", "materials"))
        return {"points": section.points(), "materials": names}, section, crs
    return {"points": section.points(), "materials": materials}, section, crs


def _dem_section(dem: Dem, slope: dict, tolerance: float, error: Error) -> TerrainSection:
    spacing = slope.get("spacing_m")
    step = None if spacing is None else positive(spacing, ("slope", "spacing_m"), error)
    if ("line" in slope) == ("fall_line" in slope):
        raise error(("slope",), "give the section's map line (line:) or where its fall line "
                    "starts (fall_line: {from: [E, N]}), one of them")
    if "line" in slope:
        line = map_line(slope["line"], ("slope", "line"), error)
        return cut_section(dem, line, spacing=step, tolerance=tolerance, what="slope.line")
    fall = slope["fall_line"]
    at = ("slope", "fall_line")
    if not isinstance(fall, dict) or "from" not in fall:
        raise error(at, f"expected {{from: [E, N]}} (and stop:, flat_deg:, max_length_m:), "
                    f"got {describe(fall)}")
    check_keys(fall, FALL_KEYS, at, error)
    start = map_line([fall["from"]], at + ("from",), error, least=1)[0]
    stop = (None if fall.get("stop") is None
            else map_line(fall["stop"], at + ("stop",), error))
    path = trace_fall_line(
        dem, (float(start[0]), float(start[1])), stop_line=stop,
        flat_deg=positive(fall.get("flat_deg", DEFAULT_FLAT_DEG), at + ("flat_deg",), error),
        max_length_m=positive(fall.get("max_length_m", 5000.0), at + ("max_length_m",), error),
        what="slope.fall_line")
    return cut_section(dem, path.points, spacing=step, tolerance=tolerance,
                       what="the fall line", vertices=False, orient=False)


def cover_materials(section: TerrainSection, spec: dict, tolerance: float, crs: str,
                    error: Error, base_dir: Path, at: tuple) -> tuple[TerrainSection, list[str]]:
    """Materials from a map layer ``spec`` (at key path ``at``): the section and its names."""
    check_keys(spec, COVER_KEYS, at, error)
    if ("raster" in spec) == ("polygons" in spec):
        raise error(at, "give the materials' map layer as raster: or polygons:, one of them")
    table = spec.get("classes", {})
    if not isinstance(table, dict) or not all(isinstance(v, str) for v in table.values()):
        raise error(at + ("classes",), f"expected a mapping class -> material name, got "
                    f"{describe(table)}")
    default = spec.get("default")
    where = section.map_point(section.dense_x)
    if "raster" in spec:
        path = map_file(spec["raster"], at + ("raster",), error, base_dir, "a land-cover raster")
        classes = classes_from_raster(path, where[:, 0], where[:, 1], crs)
    else:
        path = map_file(spec["polygons"], at + ("polygons",), error, base_dir, "a polygon layer")
        attribute = spec.get("attribute")
        if not isinstance(attribute, str):
            raise error(at + ("attribute",), "name the polygons' attribute that holds the class")
        classes = classes_from_polygons(path, attribute, where[:, 0], where[:, 1], crs)
    return with_materials(section, classes, table, default, tolerance, str(path))


def terrain_zones(release: Any, section: TerrainSection, crs: str, error: Error,
                  base_dir: Path, at_key: tuple = ("rocks", "release")) -> Any:
    """``rocks.release`` with zones by slope angle or polygons expanded to x ranges.

    A zone ``{steeper_than_deg: 45, ...}`` (or ``{polygons: release.gpkg, ...}``)
    becomes one zone per stretch of the section that qualifies, each with
    the zone's other keys and its ``weight`` (default 1) shared in
    proportion to the stretch's length.
    """
    zones = release if isinstance(release, list) else [release]
    out: list[Any] = []
    for i, zone in enumerate(zones):
        at = at_key + ((i,) if isinstance(release, list) else ())
        if not isinstance(zone, dict) or not any(k in zone for k in ZONE_KEYS[:2]):
            out.append(zone)
            continue
        if "x" in zone:
            raise error(at + ("x",), "give x: or the terrain's release (steeper_than_deg:, "
                        "polygons:), not both")
        rest = {k: v for k, v in zone.items() if k not in ZONE_KEYS}
        low = positive(zone.get("min_length_m", 0.0), at + ("min_length_m",), error, strict=False)
        if "steeper_than_deg" in zone:
            deg = positive(zone["steeper_than_deg"], at + ("steeper_than_deg",), error)
            ranges = release_ranges(section, steeper_than_deg=deg, min_length_m=low)
            why = f"no stretch of the section is steeper than {deg:g} deg"
        else:
            path = map_file(zone["polygons"], at + ("polygons",), error, base_dir,
                            "a polygon layer")
            where = section.map_point(section.dense_x)
            ranges = release_ranges(section, inside=inside_polygons(
                path, where[:, 0], where[:, 1], crs), min_length_m=low)
            why = f"the section crosses no polygon of {path}"
        if not ranges:
            raise error(at, f"{why}: no release zone")
        total = sum(b - a for a, b in ranges)
        weight = float(zone.get("weight", 1.0))
        out += [{**rest, "x": [round(a, 4), round(b, 4)],
                 "weight": weight * (b - a) / total} for a, b in ranges]
    return out if isinstance(release, list) or len(out) != 1 else out[0]

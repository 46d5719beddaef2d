"""``corridor: {dem: ..., road: ..., spacing_m: 20}``: a corridor's sections from the terrain.

The key is expanded into the ``sections:`` of an ordinary corridor (see
:mod:`.corridor`): one section every share of the road (at most
``spacing_m``), each the fall line from the road up to its top and
``below_road_m`` below it, cut from the DEM, with materials from the map,
its release zones where the ground is steeper than ``release.steeper_than_deg``
(or inside ``release.polygons``), its protected zone at the road, its share
of the road as ``design.site.length_m`` and the design candidates placed by
their distance above the road (``x_above_road_m: [a, b]``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from ..errors import ProjectError
from ..terrain.cut import DEFAULT_TOLERANCE_M, cut_section
from ..terrain.dem import read_dem
from ..terrain.fall_line import DEFAULT_FLAT_DEG
from ..terrain.road import CorridorMap, RoadSection, read_road, road_sections
from .messages import describe
from .terrain_slope import (
    check_keys,
    cover_materials,
    map_file,
    map_line,
    positive,
    terrain_zones,
)

__all__ = ["CORRIDOR_KEYS", "terrain_corridor"]

Error = Callable[[Sequence[Any], str], ProjectError]

CORRIDOR_KEYS = ("dem", "road", "spacing_m", "below_road_m", "max_length_m", "flat_deg",
                 "tolerance_m", "materials", "release", "candidates", "stations_above_road_m")


def terrain_corridor(data: dict, error: Error, base_dir: Path) -> tuple[dict, CorridorMap]:
    """A project file's data with ``corridor:`` replaced by the ``sections:`` it gives.

    Parameters
    ----------
    data
        The project file as parsed; not modified.
    error
        Makes a located error: ``error(key path, message)``.
    base_dir
        Directory the named files are relative to.

    Returns
    -------
    tuple
        The data with ``sections`` (and without ``corridor``), and where the
        sections lie on the map.
    """
    spec = data["corridor"]
    at = ("corridor",)
    if not isinstance(spec, dict):
        raise error(at, f"expected a mapping (dem:, road:, spacing_m:, ...), got {describe(spec)}")
    if "sections" in data:
        raise error(at, "give the sections (sections:) or the corridor along a road "
                    "(corridor:), not both")
    check_keys(spec, CORRIDOR_KEYS, at, error)
    for key in ("dem", "road", "spacing_m", "materials", "release"):
        if key not in spec:
            raise error(at, f"required key {key!r} is missing")
    dem = read_dem(map_file(spec["dem"], at + ("dem",), error, base_dir, "a DEM"))
    road_value = spec["road"]
    if isinstance(road_value, str):
        road = read_road(map_file(road_value, at + ("road",), error, base_dir, "a road"),
                         dem.crs_wkt)
    else:
        road = map_line(road_value, at + ("road",), error)
    number = {k: positive(spec[k], at + (k,), error) for k in
              ("spacing_m", "below_road_m", "max_length_m", "flat_deg") if k in spec}
    tolerance = positive(spec.get("tolerance_m", DEFAULT_TOLERANCE_M), at + ("tolerance_m",),
                         error, strict=False)
    laid = road_sections(dem, road, number["spacing_m"],
                         below_m=number.get("below_road_m", 20.0),
                         max_length_m=number.get("max_length_m", 1000.0),
                         flat_deg=number.get("flat_deg", DEFAULT_FLAT_DEG))
    sections, cut = [], []
    for where in laid:
        item, where = _section(spec, where, dem, tolerance, error, base_dir)
        sections.append(item)
        cut.append(where)
    out = {key: value for key, value in data.items() if key != "corridor"}
    out["sections"] = sections
    return out, CorridorMap(dem.shown, dem.crs_wkt, road, tuple(cut))


def _section(spec: dict, where: RoadSection, dem: Any, tolerance: float, error: Error,
             base_dir: Path) -> tuple[dict, RoadSection]:
    """One section's project data from its map line."""
    name = f"km {where.station / 1000:.3f}"
    shared = error

    def error(path: Sequence[Any], message: str) -> ProjectError:  # noqa: F811 - named
        return shared(path, f"section {name} (from the road at {where.station:.1f} m): "
                      f"{message}")

    section = cut_section(dem, where.line, tolerance=tolerance, vertices=False, orient=False,
                          what=f"the section at {where.station:.1f} m along the road",
                          keep_at=[where.road_x])
    materials: Any = spec["materials"]
    if isinstance(materials, dict):
        section, materials = cover_materials(section, materials, tolerance, dem.crs_wkt,
                                             error, base_dir, ("corridor", "materials"))
    release = terrain_zones(spec["release"], section, dem.crs_wkt, error, base_dir,
                            ("corridor", "release"))
    road_x = where.road_x
    candidates = []
    for i, template in enumerate(spec.get("candidates") or []):
        at = ("corridor", "candidates", i)
        if not isinstance(template, dict) or "x_above_road_m" not in template:
            raise error(at, "expected a candidate with x_above_road_m: [a, b] (m above the "
                        "road, along the section) in place of x")
        low, high = map_line([template["x_above_road_m"]], at + ("x_above_road_m",), error,
                             least=1)[0]
        x0, x1 = max(road_x - float(high), 0.0), road_x - float(low)
        if x1 > x0:
            candidates.append({**{k: v for k, v in template.items() if k != "x_above_road_m"},
                               "x": [round(float(x0), 3), round(float(x1), 3)]})
    above = spec.get("stations_above_road_m", [1.0])
    stations = sorted({round(road_x - float(a), 3) for a in above if 0 < road_x - float(a)})
    item = {"name": name,
            "description": f"fall line from the road at {where.station:.1f} m",
            "slope": {"points": section.points(), "materials": materials},
            "rocks": {"release": release},
            "analysis": {"stations": stations},
            "protect": {"x": round(float(road_x), 3)},
            "design": {"site": {"length_m": round(float(where.length_m), 3)},
                       **({"candidates": candidates} if candidates else {})}}
    return item, replace(where, section=section)

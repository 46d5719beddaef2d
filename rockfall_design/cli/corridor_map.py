"""A corridor along a road on a DEM: its design back on the map (files of ``optimise``).

With ``--out DIR``: ``DIR/measures.gpkg``, the chosen measures as line
features (type, product, height, capacity, cost, section, station); with
``--plot DIR``: ``DIR/map.<format>``, the map figure; with ``--report DIR``:
``DIR/map.png`` beside the sections' reports. Written with the corridor's
other files, as one set.
"""

from __future__ import annotations

import argparse
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..api import chosen_measures, corridor_map, read_dem, write_measures

if TYPE_CHECKING:  # pragma: no cover
    from ..project import Corridor
    from ..report.outputs import OutputSet

__all__ = ["MEASURES_FILE", "map_files", "write_map"]

#: The measures' GeoPackage under --out.
MEASURES_FILE = "measures.gpkg"


def _figures(args: argparse.Namespace) -> dict[Path, str]:
    """The map figure's files and their formats (one file where --plot and --report meet)."""
    out = {args.plot / f"map.{fmt}": fmt for fmt in args.plot_format} if args.plot else {}
    if getattr(args, "report", None):
        out.setdefault(args.report / "map.png", "png")
    return out


def map_files(args: argparse.Namespace) -> list[Path]:
    """The files the map writes for these options (reserved before the run)."""
    return ([args.out / MEASURES_FILE] if args.out else []) + list(_figures(args))


def _design_words(block: Mapping[str, Any]) -> str:
    best = block.get("best")
    if not best:
        return "none"
    parts = [" ".join(str(v) for v in (m.get("type"), m.get("product")) if v)
             for m in best.get("measures", [])]
    return " + ".join(parts) or "no measure needed"


def write_map(args: argparse.Namespace, corridor: Corridor, files: OutputSet,
              blocks: Sequence[Mapping[str, Any]]) -> None:
    """Write the map files of :func:`map_files` from the sections' ``optimise`` JSON."""
    where = corridor.map
    measures = chosen_measures(where, blocks)
    if args.out:
        with tempfile.TemporaryDirectory() as scratch:
            # GDAL writes to a path of its own; the set then writes the bytes as one file.
            path = Path(scratch) / MEASURES_FILE
            write_measures(path, measures, where.crs_wkt)
            data = path.read_bytes()
        files.write_with(args.out / MEASURES_FILE, lambda fh: fh.write(data))
    targets = _figures(args).items()
    if targets:
        fig = corridor_map(read_dem(where.dem), where, [_design_words(b) for b in blocks],
                           measures, title=f"{corridor.name}: chosen measures")
        for path, fmt in targets:
            files.write_with(path, lambda fh, fmt=fmt: fig.savefig(
                fh, format=fmt, dpi=150, bbox_inches="tight"))

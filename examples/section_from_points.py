"""A 2-D slope section for a project, cut from terrain points (map coordinates).

Published rockfall experiments and site surveys give the terrain as points:
a laser or photogrammetric scan, a grid exported as easting, northing,
height (XYZ), the heights recorded beneath a tracked block. A project needs a
section instead: stations x along the slope and their heights. This script
takes the points that lie within a narrow corridor on either side of the
section's trace on the map (the polyline of easting, northing vertices that
``stops_from_points.py`` uses, from the top of the slope down, the first vertex
at x = 0), groups them in bins of station, and writes one point per bin: the
bin's middle station and the median height of its points (the median, so that
a shrub or a lying block in the scan does not lift the ground). The output is
the CSV that ``slope: {csv: FILE}`` reads (``x, y, material``)::

    python examples/section_from_points.py terrain.xyz trace.csv section.csv

Run it with ``-h`` for its options: the columns of the terrain file, the
corridor's half-width, the bin length, and the material of each stretch of
the section (one name, or a new name from a given station on). Bins without
points are left out (the section is straight between its neighbours), and the
script says how many points it used. Check the section against the site
before calibrating on it: a 2-D calibration is only as good as the section.
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from stops_from_points import stations  # noqa: E402  (a sibling script)


def section(points: np.ndarray, trace: np.ndarray, corridor: float,
            step: float) -> tuple[np.ndarray, np.ndarray, int]:
    """Stations and ground heights of a section cut from terrain points.

    Parameters
    ----------
    points
        (n, 3) easting, northing, height (m).
    trace
        (k, 2) vertices of the section's trace on the map (m), k >= 2.
    corridor
        Half-width (m) of the strip of points used, either side of the trace.
    step
        Length (m) of the bins of station.

    Returns
    -------
    (x, y, used)
        The middle station of every bin that holds points (m, increasing),
        the median height of its points (m), and how many points were used.
    """
    x, d = stations(points[:, :2], trace)
    keep = d <= corridor
    x, z = x[keep], points[keep, 2]
    if len(x) == 0:
        return np.empty(0), np.empty(0), 0
    b = np.floor(x / step).astype(np.int64)
    bins = np.unique(b)
    heights = np.array([np.median(z[b == i]) for i in bins])
    return (bins + 0.5) * step, heights, int(keep.sum())


def materials_at(x: np.ndarray, default: str, zones: list[tuple[float, str]]) -> list[str]:
    """The material of the segment that starts at each station.

    ``zones`` are (station, name): from that station on, ``name``; before
    the first, ``default``.
    """
    out = []
    for xi in x:
        name = default
        for start, zone in sorted(zones):
            if xi >= start:
                name = zone
        out.append(name)
    return out


def _read_points(path: str, columns: tuple[int, int, int]) -> np.ndarray:
    """Terrain points from a CSV (with or without a header) or a whitespace file."""
    rows = []
    with open(path, encoding="utf-8") as fh:
        for line in fh:
            parts = line.replace(",", " ").replace(";", " ").split()
            if not parts or parts[0].startswith("#"):
                continue
            try:
                rows.append([float(parts[c]) for c in columns])
            except (ValueError, IndexError):
                if rows:  # a header is allowed only before the first point
                    raise SystemExit(f"{path}: not a point: {line.strip()!r}") from None
    if not rows:
        raise SystemExit(f"{path}: no terrain points")
    return np.array(rows)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("terrain", help="terrain points: easting, northing, height (the user's own "
                    "download; CSV or whitespace-separated)")
    ap.add_argument("trace", help="CSV of the section's trace on the map: columns e, n")
    ap.add_argument("out", help="the section CSV to write (slope: {csv: FILE})")
    ap.add_argument("--columns", default="0,1,2",
                    help="0-based columns of easting, northing, height (default 0,1,2)")
    ap.add_argument("--corridor", type=float, default=2.0,
                    help="use points within this distance (m) of the trace (default 2)")
    ap.add_argument("--step", type=float, default=2.0,
                    help="length of the bins of station (m, default 2)")
    ap.add_argument("--material", default="ground",
                    help="material of the section's segments (default ground)")
    ap.add_argument("--zone", nargs=2, action="append", default=[], metavar=("X", "NAME"),
                    help="from station X (m) on, material NAME (repeatable)")
    args = ap.parse_args(argv)

    columns = tuple(int(c) for c in args.columns.split(","))
    if len(columns) != 3:
        ap.error("--columns takes three column numbers: easting, northing, height")
    points = _read_points(args.terrain, columns)  # type: ignore[arg-type]
    with open(args.trace, newline="", encoding="utf-8") as fh:
        trace = np.array([[float(r["e"]), float(r["n"])] for r in csv.DictReader(fh)])
    x, y, used = section(points, trace, args.corridor, args.step)
    if len(x) < 2:
        sys.stderr.write(f"{used} terrain points within {args.corridor:g} m of the trace: "
                         "too few for a section (widen --corridor?)\n")
        return 2
    zones = [(float(s), name) for s, name in args.zone]
    names = materials_at(x, args.material, zones)
    with open(args.out, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(["x", "y", "material"])
        for i, (xi, yi) in enumerate(zip(x, y, strict=True)):
            # the material of a row is that of the segment to the next point
            w.writerow([f"{xi:.2f}", f"{yi:.3f}", names[i] if i < len(x) - 1 else ""])
    sys.stderr.write(f"{used} of {len(points)} terrain points within {args.corridor:g} m of "
                     f"the trace: {len(x)} section points, x {x[0]:.1f} to {x[-1]:.1f} m, "
                     f"written to {args.out}\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

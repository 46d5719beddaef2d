"""Observed stops for ``calibrate`` from surveyed deposit points (map coordinates).

Field campaigns and published experiment datasets give where each block came
to rest as map coordinates (easting, northing), often with its volume or
mass. ``calibrate`` needs the station x along the 2-D section instead. This
script projects each point onto the section's trace on the map (a polyline
of easting, northing vertices, the first vertex at x = 0), keeps the points
that lie within a corridor on either side of it, and writes the CSV that
``calibrate:`` reads (``x`` and, if the input has it, ``volume_m3`` or
``mass_kg``)::

    python examples/stops_from_points.py deposits.csv trace.csv stops.csv \\
        --e E --n N --volume VOLUME_COLUMN --corridor 15

``deposits.csv``: the user's own download (any CSV with a header; name its
columns with --e, --n and --volume or --mass). ``trace.csv``: the section's
trace, columns ``e,n``, from the top of the slope down. The station of a
point is the distance along the trace to its foot on it (horizontal, as the
section's x). Points farther than --corridor (m) from the trace are left out
and counted on stderr: a 2-D calibration is only as good as the corridor's
likeness to the section.
"""

from __future__ import annotations

import argparse
import csv
import sys

import numpy as np


def stations(points: np.ndarray, trace: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Station along ``trace`` (m) and distance from it (m) of each point.

    Parameters
    ----------
    points
        (n, 2) easting, northing (m).
    trace
        (k, 2) vertices of the section's trace (m), k >= 2.

    Returns
    -------
    (x, d)
        The distance along the trace to each point's nearest foot on it, and
        the distance from the point to that foot.
    """
    a, b = trace[:-1], trace[1:]
    seg = b - a
    length = np.hypot(seg[:, 0], seg[:, 1])
    start = np.concatenate([[0.0], np.cumsum(length)[:-1]])
    # every point against every segment: the foot clamped to the segment
    rel = points[:, None, :] - a[None, :, :]
    t = np.clip(np.einsum("nkj,kj->nk", rel, seg) / (length**2)[None, :], 0.0, 1.0)
    foot = a[None, :, :] + t[..., None] * seg[None, :, :]
    dist = np.hypot(*(points[:, None, :] - foot).transpose(2, 0, 1))
    best = np.argmin(dist, axis=1)
    rows = np.arange(len(points))
    return start[best] + t[rows, best] * length[best], dist[rows, best]


def _read(path: str) -> list[dict[str, str]]:
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("deposits", help="CSV of the deposit points (the user's download)")
    ap.add_argument("trace", help="CSV of the section's trace on the map: columns e, n")
    ap.add_argument("out", help="the stops CSV to write (calibrate.observed)")
    ap.add_argument("--e", default="e", help="easting column of the deposits (default e)")
    ap.add_argument("--n", default="n", help="northing column of the deposits (default n)")
    size = ap.add_mutually_exclusive_group()
    size.add_argument("--volume", metavar="COLUMN", help="block volume column (m3)")
    size.add_argument("--mass", metavar="COLUMN", help="block mass column (kg)")
    ap.add_argument("--corridor", type=float, default=15.0,
                    help="keep points within this distance (m) of the trace (default 15)")
    args = ap.parse_args()

    deposits = _read(args.deposits)
    trace = np.array([[float(r["e"]), float(r["n"])] for r in _read(args.trace)])
    points = np.array([[float(r[args.e]), float(r[args.n])] for r in deposits])
    x, d = stations(points, trace)
    keep = d <= args.corridor
    column = ("volume_m3", args.volume) if args.volume else ("mass_kg", args.mass) \
        if args.mass else None
    with open(args.out, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(["x"] + ([column[0]] if column else []))
        for row, xi, k in zip(deposits, x, keep, strict=True):
            if k:
                w.writerow([f"{xi:.2f}"] + ([row[column[1]]] if column else []))
    sys.stderr.write(f"{int(keep.sum())} of {len(points)} points within {args.corridor:g} m of "
                     f"the trace written to {args.out}\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""A section from a point cloud (LAS/LAZ): ground points in a swath, a low percentile per bin.

The ground points (ASPRS class 2; every point where the cloud is not
classified) within half the swath width of the map line are projected onto
it and binned along it; each bin's height is a low percentile of its points
(by default the 10th), which keeps to the ground under a few points of
low vegetation or noise left in the ground class. Empty bins are bridged by
the polyline; a gap of more than :data:`MAX_GAP_BINS` bins is an error naming
the station.
"""

from __future__ import annotations

import os

import numpy as np

from .cut import TerrainSection, simplify_vertical
from .extra import TerrainError, require

__all__ = ["DEFAULT_PERCENTILE", "GROUND_CLASS", "MAX_GAP_BINS", "cloud_section"]

#: ASPRS LAS 1.4 class code of ground points (ASPRS LAS Specification 1.4 R15, table 17).
GROUND_CLASS = 2
#: The percentile (%) of each bin's heights taken as the ground: low, so
#: that vegetation and noise left in the ground class do not lift the
#: section. ILLUSTRATIVE default; state yours (``percentile:``).
DEFAULT_PERCENTILE = 10.0
#: Most empty bins in a row bridged by a straight segment.
MAX_GAP_BINS = 5


def cloud_section(path: str | os.PathLike[str], line: np.ndarray, *, swath_m: float,
                  bin_m: float = 1.0, percentile: float = DEFAULT_PERCENTILE,
                  tolerance: float = 0.05, shown: str | None = None) -> TerrainSection:
    """The section of a LAS/LAZ point cloud along a map polyline.

    Parameters
    ----------
    path
        The point cloud (its coordinates in a projected CRS in metres, as the line's).
    line
        Map vertices (E, N) (m), shape (k, 2).
    swath_m
        Width (m) of the band around the line whose points count.
    bin_m
        Bin length along the line (m).
    percentile
        The bin's height is this percentile (%) of its points' heights.
    tolerance
        Vertical tolerance (m) of the simplified section.
    shown
        The file's name in messages.

    Raises
    ------
    TerrainError
        Unreadable file, no points in the swath, a gap of empty bins.
    """
    shown = os.fspath(path) if shown is None else shown
    laspy = require("laspy", f"reading the point cloud {shown}")
    try:
        las = laspy.read(path)
        xyz = np.column_stack([np.asarray(las.x), np.asarray(las.y), np.asarray(las.z)])
        classes = np.asarray(las.classification)
    except Exception as exc:  # noqa: BLE001 - laspy's errors on a foreign or damaged file
        reason = " ".join(str(exc).split())[:160] or type(exc).__name__
        raise TerrainError(shown, f"not a point cloud that can be read: {reason}") from None
    if (classes == GROUND_CLASS).any():
        xyz = xyz[classes == GROUND_CLASS]
    line = np.asarray(line, dtype=float)
    s, d = _along_across(xyz[:, :2], line)
    cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(line, axis=0).T))])
    near = (np.abs(d) <= 0.5 * swath_m) & (s >= 0) & (s <= cum[-1])
    if not near.any():
        raise TerrainError(shown, f"no ground point within {swath_m:g} m of the line")
    s, z = s[near], xyz[near, 2]
    edges = np.arange(0.0, cum[-1] + bin_m, bin_m)
    which = np.clip(np.digitize(s, edges) - 1, 0, len(edges) - 2)
    centres, heights = [], []
    for b in range(len(edges) - 1):
        mine = which == b
        if mine.any():
            x_b, z_b = _bin_ground(s[mine], z[mine], percentile)
            centres.append(x_b)
            heights.append(z_b)
    x, h = np.array(centres), np.array(heights)
    gaps = np.flatnonzero(np.diff(x) > (MAX_GAP_BINS + 1) * bin_m)
    if len(gaps):
        raise TerrainError(shown, f"no ground point from {x[gaps[0]]:.1f} to "
                           f"{x[gaps[0] + 1]:.1f} m along the line (a gap of more than "
                           f"{MAX_GAP_BINS} bins): widen swath_m or bin_m")
    if len(x) < 2:
        raise TerrainError(shown, "fewer than two bins hold ground points")
    if h[-1] > h[0]:  # x runs downslope
        line, h = line[::-1], h[::-1]
        x = cum[-1] - x[::-1]
        cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(line, axis=0).T))])
    x0 = x[0]  # the section starts at the first bin
    keep = simplify_vertical(x, h, tolerance)
    e, n = np.interp(x0, cum, line[:, 0]), np.interp(x0, cum, line[:, 1])
    line_x = np.concatenate([[0.0], cum[cum > x0] - x0])
    line_e = np.concatenate([[e], line[cum > x0, 0]])
    line_n = np.concatenate([[n], line[cum > x0, 1]])
    return TerrainSection(x=x[keep] - x0, z=h[keep], line_x=line_x, line_e=line_e,
                          line_n=line_n, dense_x=x - x0, dense_z=h)


def _bin_ground(s: np.ndarray, z: np.ndarray, percentile: float) -> tuple[float, float]:
    """A bin's station (the mean of its points', m) and ground height there (m).

    The heights are detrended first (a least-squares line along the bin):
    on a slope, a percentile of the raw heights would take the bin's lower
    end, not its middle (on 1 m bins at 27 deg, 0.2 m low). The ground is
    the fitted line at the mean station plus the percentile of the residuals.
    """
    centre = float(s.mean())
    if len(s) < 3 or np.ptp(s) < 1e-6:
        return centre, float(np.percentile(z, percentile))
    slope, intercept = np.polyfit(s - centre, z, 1)
    residual = z - (intercept + slope * (s - centre))
    return centre, float(intercept + np.percentile(residual, percentile))


def _along_across(points: np.ndarray, line: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distance along the polyline (m) of each point's nearest foot, and its offset (m)."""
    best_d = np.full(len(points), np.inf)
    best_s = np.zeros(len(points))
    start = 0.0
    last = len(line) - 2
    for k, (a, b) in enumerate(zip(line[:-1], line[1:], strict=True)):
        ab = b - a
        length = float(np.hypot(*ab))
        # beyond the line's ends the station runs on (below 0, above the length),
        # so that points past an end are not counted at the end itself
        t = np.clip(((points - a) @ ab) / length**2, -np.inf if k == 0 else 0.0,
                    np.inf if k == last else 1.0)
        foot = a + t[:, None] * ab
        rel = points - foot
        dist = np.hypot(rel[:, 0], rel[:, 1])
        better = dist < np.abs(best_d)
        side = np.sign(ab[0] * rel[:, 1] - ab[1] * rel[:, 0])
        best_d = np.where(better, side * dist, best_d)
        best_s = np.where(better, start + t * length, best_s)
        start += length
    return best_s, best_d

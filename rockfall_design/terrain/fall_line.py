"""The fall line: the path of steepest descent (or ascent) on a DEM.

A gradient walk on the smoothed, continuous gradient field of :class:`~.dem.Dem`
(:meth:`~.dem.Dem.gradient`), integrated with the midpoint (second-order
Runge-Kutta) rule in steps of half a pixel: the path follows the terrain's
fall line without turning at every pixel edge, as a D8 path (one of eight
neighbours) or the raw gradient of the bilinear surface would. It stops

- where the ground is flat (slope below ``flat_deg``) or the path turns back
  on itself (a pit, or a ridge when tracing upwards),
- where it crosses a stop line (the road),
- after ``max_length_m``,
- at the raster's edge or at no data (an error for a descent, which must
  reach its stop; the natural top for an ascent from a road).

References
----------
Tarboton, D. G. (1997). A new method for the determination of flow
directions and upslope areas in grid digital elevation models. Water
Resources Research 33(2), 309-319 (D-infinity: flow along the steepest
downward slope in any direction, not one of eight).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

# Defined beside the command line's other numbers, which --help shows without this room.
from ..limits import DEFAULT_FLAT_DEG
from .dem import Dem
from .extra import TerrainError

__all__ = ["DEFAULT_FLAT_DEG", "FallLine", "trace_fall_line"]


#: Most steps of one trace (at half a pixel, 20 km on a 1 m DEM).
MAX_STEPS = 40_000


@dataclass(frozen=True)
class FallLine:
    """A traced path: map points (E, N) (m) in the order walked, and why it ended.

    ``stop`` is one of ``flat``, ``line``, ``length``, ``edge``.
    """

    points: np.ndarray
    stop: str

    @property
    def length(self) -> float:
        """Horizontal length (m)."""
        return float(np.hypot(*np.diff(self.points, axis=0).T).sum())


def _crossing(p: np.ndarray, q: np.ndarray, line: np.ndarray) -> np.ndarray | None:
    """Where the step p -> q first crosses the polyline ``line``, or None."""
    a, b = line[:-1], line[1:]
    d, e = q - p, b - a
    den = d[0] * e[:, 1] - d[1] * e[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = ((a[:, 0] - p[0]) * e[:, 1] - (a[:, 1] - p[1]) * e[:, 0]) / den
        u = ((a[:, 0] - p[0]) * d[1] - (a[:, 1] - p[1]) * d[0]) / den
    hit = (den != 0) & (t >= 0) & (t <= 1) & (u >= 0) & (u <= 1)
    if not hit.any():
        return None
    return p + np.min(t[hit]) * d


def trace_fall_line(dem: Dem, start: tuple[float, float], *, ascend: bool = False,
                    stop_line: np.ndarray | None = None, flat_deg: float = DEFAULT_FLAT_DEG,
                    max_length_m: float = 5_000.0, smooth_px: float = 1.0,
                    step_m: float | None = None, what: str = "the fall line",
                    edge_ok: bool = False) -> FallLine:
    """Follow the steepest descent (or ascent) from ``start``.

    Parameters
    ----------
    dem
        The terrain.
    start
        Map point (E, N) (m) where the path starts.
    ascend
        Walk up (from a road to the release area) instead of down.
    stop_line
        A map polyline (E, N) (m), shape (k, 2), where the path ends when it crosses it.
    flat_deg
        The path ends where the slope is below this angle (deg).
    max_length_m
        The path ends after this horizontal length (m).
    smooth_px
        Gaussian smoothing of the gradient field (pixels).
    step_m
        Step length (m); default half the DEM's resolution.
    what
        The path's name in messages.
    edge_ok
        A descent may end at the raster's edge (the runout below a road).

    Returns
    -------
    FallLine

    Raises
    ------
    TerrainError
        The start is off the raster or at no data; a descent leaves the
        raster or meets no data before it stops.

    Notes
    -----
    With unit direction ``d(p) = -g(p)/|g(p)|`` (``+`` when ascending), a step
    is ``p' = p + h d(p + h d(p) / 2)``.
    """
    dem.check_points(start[0], start[1], f"the start of {what}")
    h = 0.5 * dem.resolution if step_m is None else float(step_m)
    line = None if stop_line is None else np.asarray(stop_line, dtype=float)
    path, stop = _walk(dem, np.asarray(start, dtype=float), h, 1.0 if ascend else -1.0,
                       math.tan(math.radians(flat_deg)), line, max_length_m, smooth_px)
    if stop == "edge" and not (ascend or edge_ok):
        p = path[-1]
        raise TerrainError(
            dem.shown, f"{what} from ({start[0]:.2f}, {start[1]:.2f}) leaves the raster or "
            f"meets no data at ({p[0]:.2f}, {p[1]:.2f}) before it stops: give a stop line, "
            "or a DEM that covers the slope down to its foot")
    if len(path) < 2:
        raise TerrainError(
            dem.shown, f"{what} from ({start[0]:.2f}, {start[1]:.2f}) does not start: the "
            f"ground there is flat (below {flat_deg:g} deg) or at the raster's edge")
    return FallLine(np.array(path), stop)


def _walk(dem: Dem, start: np.ndarray, h: float, sign: float, flat: float,
          line: np.ndarray | None, max_length_m: float,
          smooth_px: float) -> tuple[list[np.ndarray], str]:
    """The midpoint-rule walk of :func:`trace_fall_line`: its points and why it stopped.

    ``sign`` is +1 up the gradient, -1 down; ``flat`` the gradient's norm (-)
    below which the ground is flat.
    """

    def direction(p: np.ndarray) -> np.ndarray | None:
        g = dem.gradient_at(float(p[0]), float(p[1]), smooth_px)
        if g is None:
            return None
        norm = math.hypot(*g)
        if not math.isfinite(norm):
            return None
        if norm < flat:
            return np.array([np.nan, np.nan])
        return np.array([sign * g[0] / norm, sign * g[1] / norm])

    path = [start]
    walked, stop = 0.0, "length"
    for _ in range(MAX_STEPS):
        p = path[-1]
        d = direction(p)
        mid = d if d is None or np.isnan(d[0]) else direction(p + 0.5 * h * d)
        if mid is None:
            return path, "edge"
        if np.isnan(mid[0]):
            return path, "flat"
        q = p + h * mid
        if not dem.inside(q[0], q[1]):
            return path, "edge"
        if len(path) >= 3 and np.hypot(*(q - path[-2])) < 0.5 * h:
            return path, "flat"  # turned back on itself: a pit (or a ridge, walking up)
        if line is not None and (hit := _crossing(p, q, line)) is not None:
            path.append(hit)
            return path, "line"
        path.append(q)
        walked += h
        if walked >= max_length_m:
            break
    return path, stop

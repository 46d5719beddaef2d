"""A section along a map line: heights at a spacing, simplified within a vertical tolerance.

The line is sampled at a spacing (by default the DEM's resolution) and at
its own vertices; x is the horizontal length along the line from its upper
end (the line is turned round where it was drawn uphill, so that x runs
downslope as the slope section requires). The dense profile is then thinned
by Douglas-Peucker in the vertical: every dropped sample lies within the
stated tolerance (m) of the kept polyline, so the section the engine sees is
the sampled ground to within that tolerance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# Defined beside the command line's other numbers, which --help shows without this room.
from ..limits import DEFAULT_TOLERANCE_M
from .dem import Dem
from .extra import TerrainError

__all__ = ["DEFAULT_TOLERANCE_M", "TerrainSection", "cut_section", "line_stations",
           "simplify_vertical"]



@dataclass(frozen=True)
class TerrainSection:
    """A section cut from the terrain, with the map position of every x.

    Attributes
    ----------
    x, z
        The section's vertices: horizontal length along the line (m, from 0)
        and height (m).
    line_x, line_e, line_n
        The map line, upper end first: cumulative length (m) and map
        coordinates (m) of its vertices; :meth:`map_point` interpolates them.
    keep
        Indices into the dense samples that were kept (for materials cut at
        the same stations).
    dense_x, dense_z
        The samples before simplification (m).
    """

    x: np.ndarray
    z: np.ndarray
    line_x: np.ndarray
    line_e: np.ndarray
    line_n: np.ndarray
    dense_x: np.ndarray
    dense_z: np.ndarray

    def map_point(self, x: float | np.ndarray) -> np.ndarray:
        """Map coordinates (E, N) (m) of section stations ``x`` (m), shape (..., 2)."""
        return np.stack([np.interp(x, self.line_x, self.line_e),
                         np.interp(x, self.line_x, self.line_n)], -1)

    def direction(self, x: float) -> np.ndarray:
        """Unit map vector (E, N) of the line at station ``x`` (downslope)."""
        k = int(np.clip(np.searchsorted(self.line_x, x, side="right") - 1, 0,
                        len(self.line_x) - 2))
        d = np.array([self.line_e[k + 1] - self.line_e[k], self.line_n[k + 1] - self.line_n[k]])
        return d / np.hypot(*d)

    def points(self) -> list[list[float]]:
        """The vertices as the project's ``slope.points`` ([x, y], m)."""
        return [[round(float(a), 4), round(float(b), 4)] for a, b in zip(self.x, self.z,
                                                                          strict=True)]


def line_stations(line_e: np.ndarray, line_n: np.ndarray, spacing: float,
                  vertices: bool = True) -> np.ndarray:
    """Stations (m along the line) at ``spacing``, the ends and (if ``vertices``) the corners."""
    seg = np.hypot(np.diff(line_e), np.diff(line_n))
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    stations = np.arange(0.0, cum[-1], spacing)
    parts = [stations, [cum[-1]]] + ([cum] if vertices else [])
    return np.unique(np.concatenate(parts))


def simplify_vertical(x: np.ndarray, z: np.ndarray, tolerance: float,
                      keep: np.ndarray | None = None) -> np.ndarray:
    """Indices of the points kept by Douglas-Peucker with the vertical distance.

    Parameters
    ----------
    x, z
        The dense profile (m), x increasing.
    tolerance
        Largest vertical distance (m) of a dropped point from the kept polyline.
    keep
        Boolean mask of points that must stay (material boundaries).

    Returns
    -------
    numpy.ndarray
        Sorted indices, first and last included.

    References
    ----------
    Douglas, D. H. and Peucker, T. K. (1973). Algorithms for the reduction of
    the number of points required to represent a digitized line or its
    caricature. Cartographica 10(2), 112-122. (Here the distance is vertical:
    the section's heights, not its shape in the plane, are to be kept.)
    """
    n = len(x)
    kept = np.zeros(n, dtype=bool)
    kept[[0, n - 1]] = True
    if keep is not None:
        kept |= keep
    fixed = np.flatnonzero(kept)
    stack = list(zip(fixed[:-1].tolist(), fixed[1:].tolist(), strict=True))
    while stack:
        a, b = stack.pop()
        if b - a < 2:
            continue
        inner = slice(a + 1, b)
        chord = z[a] + (z[b] - z[a]) * (x[inner] - x[a]) / (x[b] - x[a])
        off = np.abs(z[inner] - chord)
        k = int(np.argmax(off))
        if off[k] > tolerance:
            m = a + 1 + k
            kept[m] = True
            stack += [(a, m), (m, b)]
    return np.flatnonzero(kept)


def cut_section(dem: Dem, line: np.ndarray, *, spacing: float | None = None,
                tolerance: float = DEFAULT_TOLERANCE_M, what: str = "the line",
                vertices: bool = True, orient: bool = True,
                keep_at: np.ndarray | None = None) -> TerrainSection:
    """The section of ``dem`` along a map polyline.

    Parameters
    ----------
    dem
        The terrain.
    line
        Map vertices (E, N) (m), shape (k, 2), k >= 2.
    spacing
        Sampling step along the line (m); default the DEM's resolution.
    tolerance
        Vertical tolerance (m) of the simplification (0 keeps every sample).
    what
        The line's name in messages.
    vertices
        Sample at the line's own vertices too (a drawn line: yes; a traced
        fall line of half-pixel steps: no).
    orient
        Turn the line round if its lower end comes first.
    keep_at
        Stations (m, along the oriented line) that must be vertices (where a
        material changes).

    Raises
    ------
    TerrainError
        A point of the line off the raster, or at no data (naming it).
    """
    line = np.asarray(line, dtype=float)
    if line.ndim != 2 or line.shape[0] < 2 or line.shape[1] != 2:
        raise TerrainError(dem.shown, f"{what}: expected at least two points [E, N]")
    seg = np.hypot(*np.diff(line, axis=0).T)
    if np.any(seg <= 0):
        k = int(np.argmin(seg > 0)) + 1
        raise TerrainError(dem.shown, f"{what}: point {k + 1} repeats point {k}")
    bad = ~dem.inside(line[:, 0], line[:, 1])
    bad |= ~np.isfinite(dem.height(line[:, 0], line[:, 1]))
    if bad.any():  # checked at once (a traced line has hundreds); the first one named
        k = int(np.argmax(bad))
        dem.check_points(line[k, 0], line[k, 1], f"point {k + 1} of {what}")
    step = dem.resolution if spacing is None else float(spacing)
    if orient and dem.height(*line[-1]) > dem.height(*line[0]):
        line = line[::-1]
    cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(line, axis=0).T))])
    s = line_stations(line[:, 0], line[:, 1], step, vertices)
    if keep_at is not None and len(keep_at):
        s = np.unique(np.concatenate([s, np.clip(keep_at, 0.0, cum[-1])]))
    e, n = np.interp(s, cum, line[:, 0]), np.interp(s, cum, line[:, 1])
    z = dem.height(e, n)
    if not np.isfinite(z).all():  # a hole between the line's (checked) vertices
        k = int(np.argmin(np.isfinite(z)))
        raise TerrainError(
            dem.shown, f"no data at {s[k]:.1f} m along {what} ({e[k]:.2f}, {n[k]:.2f}): the "
            "DEM has a hole there; fill it or move the line")
    keep = None if keep_at is None else np.isin(s, keep_at)
    idx = simplify_vertical(s, z, tolerance, keep)
    return TerrainSection(x=s[idx], z=z[idx], line_x=cum, line_e=line[:, 0],
                          line_n=line[:, 1], dense_x=s, dense_z=z)

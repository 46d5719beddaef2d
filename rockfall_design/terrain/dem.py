"""A digital elevation model: heights and gradients on its bilinear surface.

The DEM is read once with rasterio (band 1) into a :class:`Dem`: heights in
metres on a north-up grid of pixels, no-data as NaN. Heights between pixel
centres are bilinear, so a section cut from a plane DEM is the plane. Only a
projected CRS in metres is accepted: a section's x is a length along the
ground in metres, which degrees are not.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .extra import TerrainError, require

__all__ = ["MAX_DEM_PIXELS", "Dem", "read_dem"]

#: Most pixels of a DEM read whole: 25 million float64 heights are 200 MB, a
#: 5 km x 5 km tile at 1 m. A larger DEM is to be cut to the site first
#: (gdal_translate -projwin). A memory guard, not a published figure.
MAX_DEM_PIXELS = 25_000_000


@dataclass
class Dem:
    """Heights of a north-up DEM, with the bilinear surface through its pixel centres.

    Attributes
    ----------
    shown
        The file as named to the user (for messages).
    z
        Heights (m), shape (rows, cols), row 0 the northernmost; NaN = no data.
    west, north
        Map coordinates (m) of the raster's upper-left corner (not its first centre).
    dx, dy
        Pixel width (east) and height (north), both > 0 (m).
    crs_wkt
        The CRS as WKT ("" for an analytic DEM made in memory).
    crs_name
        The CRS's short name for messages (``EPSG:25832``).
    """

    shown: str
    z: np.ndarray
    west: float
    north: float
    dx: float
    dy: float
    crs_wkt: str = ""
    crs_name: str = ""
    _gradients: dict[float, tuple[np.ndarray, np.ndarray]] = field(
        default_factory=dict, repr=False)

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols)."""
        return self.z.shape  # type: ignore[return-value]

    @property
    def resolution(self) -> float:
        """The smaller pixel size (m): the default sampling step along a line."""
        return min(self.dx, self.dy)

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(east min, east max, north min, north max) of the pixel centres (m)."""
        rows, cols = self.shape
        return (self.west + 0.5 * self.dx, self.west + (cols - 0.5) * self.dx,
                self.north - (rows - 0.5) * self.dy, self.north - 0.5 * self.dy)

    def fractional(self, east: Any, north: Any) -> tuple[np.ndarray, np.ndarray]:
        """Fractional (row, col) of map points, 0 at the first pixel centre."""
        col = (np.asarray(east, dtype=float) - self.west) / self.dx - 0.5
        row = (self.north - np.asarray(north, dtype=float)) / self.dy - 0.5
        return row, col

    def inside(self, east: Any, north: Any) -> np.ndarray:
        """True where a point lies within the pixel centres (where heights are bilinear)."""
        row, col = self.fractional(east, north)
        rows, cols = self.shape
        eps = 1e-9
        return (row >= -eps) & (row <= rows - 1 + eps) & (col >= -eps) & (col <= cols - 1 + eps)

    def _cells(self, east: Any, north: Any) -> tuple[np.ndarray, ...]:
        row, col = self.fractional(east, north)
        rows, cols = self.shape
        row = np.clip(row, 0.0, rows - 1.0)
        col = np.clip(col, 0.0, cols - 1.0)
        i = np.minimum(np.floor(row).astype(np.intp), max(rows - 2, 0))
        j = np.minimum(np.floor(col).astype(np.intp), max(cols - 2, 0))
        return i, j, row - i, col - j

    def bilinear(self, grid: np.ndarray, east: Any, north: Any) -> np.ndarray:
        """``grid`` (shaped as :attr:`z`) interpolated bilinearly at map points.

        Notes
        -----
        With fractional row ``i + t`` and column ``j + s`` the value is
        ``(1-t)(1-s) g[i,j] + (1-t) s g[i,j+1] + t (1-s) g[i+1,j] + t s g[i+1,j+1]``;
        NaN where any of the four is no data. Points off the raster are
        clamped to its edge: check them with :meth:`inside` first.
        """
        i, j, t, s = self._cells(east, north)
        i1 = np.minimum(i + 1, self.shape[0] - 1)
        j1 = np.minimum(j + 1, self.shape[1] - 1)
        return ((1 - t) * ((1 - s) * grid[i, j] + s * grid[i, j1])
                + t * ((1 - s) * grid[i1, j] + s * grid[i1, j1]))

    def height(self, east: Any, north: Any) -> np.ndarray:
        """Bilinear heights (m) at map points (NaN at no data)."""
        return self.bilinear(self.z, east, north)

    def gradient(self, east: Any, north: Any, smooth_px: float = 1.0) -> np.ndarray:
        """The smoothed gradient (dz/dE, dz/dN) (-) at map points, shape (..., 2).

        The gradient is taken at the pixel centres by central differences of
        the heights smoothed with a Gaussian of ``smooth_px`` pixels (none for
        0), then interpolated bilinearly: it varies continuously, so a path
        that follows it does not turn at every pixel edge as the gradient of
        the bilinear surface itself (constant per cell along one axis) does.

        References
        ----------
        Burrough, P. A. and McDonnell, R. A. (1998). Principles of Geographical
        Information Systems, ch. 8 (slope from finite differences on a grid).
        """
        key = float(smooth_px)
        if key not in self._gradients:
            z = self.z
            if key > 0:
                from scipy.ndimage import gaussian_filter

                z = gaussian_filter(z, key, mode="nearest")
            d_row, d_col = np.gradient(z)
            # rows run south: dz/dN = -dz/drow / dy
            self._gradients[key] = (d_col / self.dx, -d_row / self.dy)
        ge, gn = self._gradients[key]
        return np.stack([self.bilinear(ge, east, north), self.bilinear(gn, east, north)], -1)

    def gradient_at(self, east: float, north: float,
                    smooth_px: float = 1.0) -> tuple[float, float] | None:
        """:meth:`gradient` at one point, in plain floats; None off the raster.

        The walk of a fall line asks this a thousand times per path: scalar
        arithmetic here is a hundred times quicker than numpy's on 1-element arrays.
        """
        if float(smooth_px) not in self._gradients:
            self.gradient(self.west + 0.5 * self.dx, self.north - 0.5 * self.dy, smooth_px)
        ge, gn = self._gradients[float(smooth_px)]
        rows, cols = self.shape
        row = (self.north - north) / self.dy - 0.5
        col = (east - self.west) / self.dx - 0.5
        if not (-1e-9 <= row <= rows - 1 + 1e-9 and -1e-9 <= col <= cols - 1 + 1e-9):
            return None
        i = min(max(int(row), 0), rows - 2)
        j = min(max(int(col), 0), cols - 2)
        t, s = row - i, col - j
        out = []
        for g in (ge, gn):
            out.append((1 - t) * ((1 - s) * g[i, j] + s * g[i, j + 1])
                       + t * ((1 - s) * g[i + 1, j] + s * g[i + 1, j + 1]))
        return float(out[0]), float(out[1])

    def check_points(self, east: Any, north: Any, what: str) -> None:
        """Raise one line naming the file and the first point off the raster or at no data.

        Parameters
        ----------
        east, north
            Map coordinates (m).
        what
            The points' name in the message (``point 3 of the line``).
        """
        east = np.atleast_1d(np.asarray(east, dtype=float))
        north = np.atleast_1d(np.asarray(north, dtype=float))
        inside = self.inside(east, north)
        if not inside.all():
            k = int(np.argmin(inside))
            e0, e1, n0, n1 = self.extent
            raise TerrainError(
                self.shown,
                f"{what} ({east[k]:.2f}, {north[k]:.2f}) is off the raster (pixel centres: "
                f"E {e0:.2f} to {e1:.2f}, N {n0:.2f} to {n1:.2f} in {self.crs_name or 'its CRS'})")
        heights = self.height(east, north)
        if not np.isfinite(heights).all():
            k = int(np.argmin(np.isfinite(heights)))
            raise TerrainError(
                self.shown, f"no data at {what} ({east[k]:.2f}, {north[k]:.2f}): the DEM has a "
                "hole there; fill it or move the line")


def read_dem(path: str | os.PathLike[str], shown: str | None = None) -> Dem:
    """Read band 1 of a raster as a :class:`Dem` (projected CRS in metres only).

    Parameters
    ----------
    path
        The raster (GeoTIFF or any format rasterio reads).
    shown
        The file's name in messages (default ``path``).

    Returns
    -------
    Dem

    Raises
    ------
    TerrainError
        One line naming the file: unreadable, no CRS, a geographic CRS or one
        not in metres, a rotated grid, too many pixels, or no data at all.
    """
    shown = os.fspath(path) if shown is None else shown
    rasterio = require("rasterio", f"reading the DEM {shown}")
    if not Path(path).is_file():
        raise TerrainError(shown, "cannot read the DEM: no such file")
    try:
        with rasterio.open(path) as src:
            crs, transform, count = src.crs, src.transform, src.count
            rows, cols = src.height, src.width
            _check_grid(shown, crs, transform, rows, cols, count)
            band = src.read(1, masked=True)
    except TerrainError:
        raise
    except Exception as exc:  # noqa: BLE001 - GDAL's errors on a foreign or damaged file
        reason = " ".join(str(exc).split())[:160] or type(exc).__name__
        raise TerrainError(shown, f"not a raster that can be read: {reason}") from None
    z = np.ma.filled(band.astype(np.float64), np.nan)
    z[~np.isfinite(z)] = np.nan
    if not np.isfinite(z).any():
        raise TerrainError(shown, "the DEM holds no data (every pixel is no-data)")
    west, north, dx, dy = transform.c, transform.f, transform.a, -transform.e
    if dy < 0:  # south-up: flipped so that row 0 is the northernmost
        z, north, dy = z[::-1], north + rows * transform.e, -dy
    return Dem(shown, z, float(west), float(north), float(dx), float(dy),
               crs.to_wkt(), crs.to_string())


def _check_grid(shown: str, crs: Any, transform: Any, rows: int, cols: int, count: int) -> None:
    """The checks of a DEM's georeference before its pixels are read."""
    if count < 1:
        raise TerrainError(shown, "the raster has no band")
    if crs is None:
        raise TerrainError(shown, "the DEM has no CRS; give it a projected CRS in metres")
    if crs.is_geographic or not crs.is_projected:
        raise TerrainError(
            shown, f"the DEM's CRS {crs.to_string()} is geographic (degrees): reproject it to "
            "a projected CRS in metres (gdalwarp -t_srs EPSG:... ), e.g. the local UTM zone")
    unit, factor = crs.linear_units_factor
    if not math.isclose(factor, 1.0):
        raise TerrainError(
            shown, f"the DEM's CRS {crs.to_string()} is in {unit}; give it in metres")
    if transform.b != 0 or transform.d != 0:
        raise TerrainError(shown, "the DEM's grid is rotated; warp it north-up first")
    if transform.a <= 0 or transform.e == 0:
        raise TerrainError(shown, "the DEM's pixel size is not positive")
    if rows < 2 or cols < 2:
        raise TerrainError(shown, f"the DEM has {rows} x {cols} pixels; at least 2 x 2 needed")
    if rows * cols > MAX_DEM_PIXELS:
        raise TerrainError(
            shown, f"the DEM has {rows * cols:,} pixels, more than {MAX_DEM_PIXELS:,}: cut it "
            "to the site first (gdal_translate -projwin)")

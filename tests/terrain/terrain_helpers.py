"""Analytic DEMs for the terrain tests, written as small GeoTIFFs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rasterio
from affine import Affine

from rockfall_design.terrain.dem import Dem

#: A projected CRS in metres (ETRS89 / UTM 32N) for the analytic DEMs.
CRS = "EPSG:25832"
#: Upper-left corner of the analytic DEMs: UTM-like coordinates, far from 0.
WEST, NORTH = 500_000.0, 5_200_000.0


def grid(rows: int, cols: int, res: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Map coordinates (E, N) of the pixel centres of a DEM at (WEST, NORTH)."""
    east = WEST + (np.arange(cols) + 0.5) * res
    north = NORTH - (np.arange(rows) + 0.5) * res
    return np.meshgrid(east, north)


def write_dem(path: Path, z: np.ndarray, res: float = 1.0, crs: str | None = CRS,
              nodata: float | None = -9999.0) -> Path:
    """Write heights ``z`` (rows from north) as a float32 GeoTIFF."""
    with rasterio.open(path, "w", driver="GTiff", height=z.shape[0], width=z.shape[1],
                       count=1, dtype="float32", crs=crs, nodata=nodata,
                       transform=Affine.translation(WEST, NORTH) @ Affine.scale(res, -res)) as dst:
        dst.write(np.where(np.isnan(z), nodata if nodata is not None else np.nan, z)
                  .astype("float32"), 1)
    return path


def memory_dem(z: np.ndarray, res: float = 1.0) -> Dem:
    """The same DEM in memory (float64 heights, exactly as given)."""
    return Dem("memory", np.asarray(z, dtype=float), WEST, NORTH, res, res, "", CRS)

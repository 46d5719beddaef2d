"""Write the SYNTHETIC example terrain of examples/terrain/ (seeded, reproducible).

    python examples/terrain/make_synthetic_terrain.py

A made-up hillside in ETRS89 / UTM 32N (EPSG:25832), 2 m pixels, 600 m x
500 m: a flat valley bottom, an 8 deg floor with a road on it, a 32 deg talus slope, a rock
cliff of 60-70 deg whose height varies along the valley, gullies, and an
upper slope of 28 deg; roughness from a seeded, smoothed random field. It is
NOT a survey of any real place (see README.txt). Also written: the road
(road.gpkg) and the land cover (cover.gpkg: meadow, forest, rock polygons).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rasterio
import shapely
from affine import Affine
from scipy.ndimage import gaussian_filter

from rockfall_design.terrain.mapping import write_layer

HERE = Path(__file__).parent
CRS = "EPSG:25832"
WEST, SOUTH = 600_000.0, 5_150_000.0
RES = 2.0
COLS, ROWS = 300, 250  # 600 m east, 500 m north (uphill)


def profile(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Height (m) above the valley bottom at (u east, v north of the south edge), m.

    The slope angle changes at breaks (valley bottom 1 deg, floor 8 deg, talus
    32 deg, the cliff 60-70 deg, the upper slope 28 deg) whose places vary
    along the valley; the height is the exact integral of tan(angle) up to v.
    """
    cliff_foot = 170.0 + 15.0 * np.sin(2 * np.pi * u / 500.0)
    cliff_height = 25.0 + 15.0 * np.sin(2 * np.pi * u / 300.0 + 1.0)  # 10 to 40 m
    cliff_deg = 65.0 + 5.0 * np.cos(2 * np.pi * u / 250.0)
    cliff_top = cliff_foot + cliff_height / np.tan(np.radians(cliff_deg))
    breaks = [np.zeros_like(u), np.full_like(u, 25.0), np.full_like(u, 80.0), cliff_foot,
              cliff_top, np.full_like(u, np.inf)]
    angles = [np.full_like(u, 1.0), np.full_like(u, 8.0), np.full_like(u, 32.0), cliff_deg,
              np.full_like(u, 28.0)]
    z = np.zeros_like(v)
    for k, angle in enumerate(angles):
        z += np.tan(np.radians(angle)) * np.clip(v - breaks[k], 0.0, breaks[k + 1] - breaks[k])
    return z


def heights() -> np.ndarray:
    """Heights (m), row 0 the northernmost (the top of the slope)."""
    u = (np.arange(COLS) + 0.5) * RES
    v = (np.arange(ROWS) + 0.5) * RES
    uu, vv = np.meshgrid(u, v)  # rows from the south here
    z = 600.0 + profile(uu, vv)
    for centre, depth in ((140.0, 6.0), (420.0, 9.0)):  # two gullies down the slope
        z -= depth * np.exp(-((uu - centre) / 18.0) ** 2) * np.clip((vv - 60.0) / 150.0, 0, 1)
    rng = np.random.default_rng(20261127)
    # about 0.25 m of roughness over ~6 m: bumps, not hollows that trap a fall line
    z += 0.25 * gaussian_filter(rng.standard_normal(z.shape), 3.0) / 0.094
    return z[::-1]


def main() -> None:
    z = heights().astype("float32")
    north = SOUTH + ROWS * RES
    with rasterio.open(HERE / "valley_dem.tif", "w", driver="GTiff", height=ROWS, width=COLS,
                       count=1, dtype="float32", crs=CRS, nodata=-9999.0, compress="deflate",
                       predictor=3, transform=Affine.translation(WEST, north)
                       @ Affine.scale(RES, -RES)) as dst:
        dst.write(z, 1)
    u = np.linspace(20.0, 580.0, 57)
    road = shapely.LineString(np.column_stack([WEST + u, SOUTH + 50.0 + 8.0 * np.sin(
        2 * np.pi * u / 400.0)]))
    write_layer(HERE / "road.gpkg", [road], {"name": ["valley road"]}, "LineString", CRS)
    box = shapely.box
    polygons = [box(WEST, SOUTH, WEST + 600, SOUTH + 80),                  # valley floor
                box(WEST + 150, SOUTH + 90, WEST + 350, SOUTH + 160),      # a wood on the talus
                box(WEST, SOUTH + 175, WEST + 600, SOUTH + 500)]           # rock above the foot
    write_layer(HERE / "cover.gpkg", polygons, {"cover": ["meadow", "forest", "rock"]},
                "Polygon", CRS)


if __name__ == "__main__":
    main()

"""Terrain: slope sections from a terrain model, and the design back on the map.

With the optional extra ``terrain`` (``pip install 'rockfall-design[terrain]'``):

- :mod:`.dem`: a DEM (GeoTIFF, any raster rasterio reads) in a projected CRS,
  heights and gradients on its bilinear surface;
- :mod:`.cut`: a section along a map line, heights at a spacing, simplified
  within a vertical tolerance;
- :mod:`.fall_line`: the path of steepest descent (or ascent) on the DEM;
- :mod:`.cover`: materials along a section from a land-cover raster or a
  polygon layer, release zones from the slope angle or polygons;
- :mod:`.cloud`: a section from a point cloud (LAS/LAZ);
- :mod:`.road`: a corridor of sections along a road, each traced up its fall line;
- :mod:`.mapping`: the chosen measures as map lines (GeoPackage) and the map figure.

The geospatial libraries are imported inside the functions that use them
(:func:`.extra.require`): the core install does not have them, and a project
without a terrain model never pays for importing them.
"""

from .extra import TerrainError, require

__all__ = ["TerrainError", "require"]

"""Sections and fall lines on analytic surfaces: a plane, a cone, a valley."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from rockfall_design.terrain import TerrainError
from rockfall_design.terrain.cut import cut_section, simplify_vertical
from rockfall_design.terrain.dem import read_dem
from rockfall_design.terrain.fall_line import trace_fall_line

from .terrain_helpers import NORTH, WEST, grid, memory_dem, write_dem


def plane(e: np.ndarray, n: np.ndarray) -> np.ndarray:
    return 800.0 + 0.45 * (e - WEST) - 0.3 * (n - NORTH)


def test_a_section_of_a_plane_dem_is_the_plane_within_a_millimetre(tmp_path):
    e, n = grid(120, 150, res=2.0)
    dem = read_dem(write_dem(tmp_path / "plane.tif", plane(e, n), res=2.0))
    line = np.array([[WEST + 20.3, NORTH - 200.7], [WEST + 250.2, NORTH - 30.1],
                     [WEST + 120.0, NORTH - 10.0]])
    section = cut_section(dem, line, spacing=1.3)
    x = np.linspace(0, section.x[-1], 2001)
    where = section.map_point(x)
    # float32 GeoTIFF: heights near 900 m hold ~0.1 mm
    assert_allclose(np.interp(x, section.x, section.z), plane(where[:, 0], where[:, 1]),
                    atol=1e-3)
    assert section.z[0] >= section.z[-1]  # x runs downslope
    assert np.all(np.diff(section.x) > 0)
    # a plane's polyline simplifies to its corners (3 line vertices)
    assert len(section.x) == 3


def test_the_fall_line_on_a_cone_follows_its_generatrix_within_a_pixel():
    e, n = grid(201, 201)
    apex = np.array([WEST + 100.5, NORTH - 100.5])
    z = 1000.0 - 0.6 * np.hypot(e - apex[0], n - apex[1])
    dem = memory_dem(z)
    for angle in (0.3, 1.9, 4.0):
        start = apex + 15.0 * np.array([np.cos(angle), np.sin(angle)])
        path = trace_fall_line(dem, tuple(start), max_length_m=70.0).points
        rel = path - apex
        u = np.array([np.cos(angle), np.sin(angle)])
        off = np.abs(rel[:, 0] * u[1] - rel[:, 1] * u[0])
        assert off.max() < 1.0  # one pixel
        assert np.all(np.diff(rel @ u) > 0)  # outwards, downhill
        # walked up, the same line back to the apex (a peak: stops flat)
        up = trace_fall_line(dem, tuple(path[-1]), ascend=True)
        assert up.stop == "flat"
        assert np.hypot(*(up.points[-1] - apex)) < 2.0


def test_a_fall_line_on_a_valley_flank_reaches_the_thalweg_and_follows_it():
    e, n = grid(200, 200)
    axis = WEST + 100.0
    z = 500.0 + 0.7 * np.abs(e - axis) + 0.1 * (n - NORTH)
    dem = memory_dem(z)
    fl = trace_fall_line(dem, (axis + 40.0, NORTH - 50.0), max_length_m=150.0)
    tail = fl.points[-30:]
    assert np.abs(tail[:, 0] - axis).max() < 1.0
    assert np.all(np.diff(tail[:, 1]) < 0)  # down the valley, southwards


def test_a_fall_line_stops_at_a_road_line():
    e, n = grid(100, 100)
    dem = memory_dem(300.0 + 0.5 * (n - NORTH))  # falls to the south
    road = np.array([[WEST, NORTH - 70.0], [WEST + 100, NORTH - 75.0]])
    fl = trace_fall_line(dem, (WEST + 50.0, NORTH - 10.0), stop_line=road)
    assert fl.stop == "line"
    assert_allclose(fl.points[-1], [WEST + 50.0, NORTH - 72.5], atol=1e-6)


@given(st.floats(-1.5, 1.5), st.floats(-1.5, 1.5),
       st.lists(st.tuples(st.floats(2, 98), st.floats(2, 78)), min_size=2, max_size=5,
                unique=True),
       st.floats(0.3, 3.0))
@settings(max_examples=40, deadline=None)
def test_any_line_across_a_plane_gives_the_plane(a, b, corners, spacing):
    e, n = grid(80, 100)
    dem = memory_dem(100.0 + a * (e - WEST) + b * (n - NORTH))
    line = np.array([[WEST + x, NORTH - y] for x, y in corners])
    if np.any(np.hypot(*np.diff(line, axis=0).T) < 1e-3):
        return
    section = cut_section(dem, line, spacing=spacing, tolerance=0.0)
    where = section.map_point(section.dense_x)
    expect = 100.0 + a * (where[:, 0] - WEST) + b * (where[:, 1] - NORTH)
    assert np.abs(section.dense_z - expect).max() < 1e-6
    assert np.all(np.diff(section.x) > 0) and section.x[0] == 0.0


@given(st.lists(st.floats(-50, 50), min_size=3, max_size=60),
       st.floats(0.0, 2.0))
@settings(max_examples=60, deadline=None)
def test_simplification_keeps_every_sample_within_the_tolerance(heights, tolerance):
    x = np.arange(len(heights), dtype=float)
    z = np.asarray(heights)
    kept = simplify_vertical(x, z, tolerance)
    assert kept[0] == 0 and kept[-1] == len(x) - 1
    assert np.abs(np.interp(x, x[kept], z[kept]) - z).max() <= tolerance + 1e-9


def test_bad_rasters_say_one_line_naming_the_file(tmp_path):
    e, n = grid(20, 20)
    z = plane(e, n)
    geo = write_dem(tmp_path / "geo.tif", z, crs="EPSG:4326")
    with pytest.raises(TerrainError, match=r"geo.tif: .*geographic"):
        read_dem(geo)
    bad = tmp_path / "bad.tif"
    bad.write_bytes(b"II*\x00 not a tiff")
    with pytest.raises(TerrainError, match=r"bad.tif: not a raster"):
        read_dem(bad)
    none = write_dem(tmp_path / "nocrs.tif", z, crs=None)
    with pytest.raises(TerrainError, match="no CRS"):
        read_dem(none)
    z[5, 5] = np.nan
    holes = read_dem(write_dem(tmp_path / "holes.tif", z))
    with pytest.raises(TerrainError, match=r"holes.tif: no data at .* along the line"):
        cut_section(holes, np.array([[WEST + 1, NORTH - 5.5], [WEST + 15, NORTH - 5.5]]))
    with pytest.raises(TerrainError, match=r"point 2 of the line .* is off the raster"):
        cut_section(holes, np.array([[WEST + 1, NORTH - 1], [WEST + 50, NORTH - 5]]))


def test_a_missing_library_of_the_extra_names_the_extra():
    from rockfall_design.terrain import require

    with pytest.raises(TerrainError, match=r"needs no_such_gis_module, of the optional extra "
                       r"\[terrain\]: python -m pip install 'rockfall-design\[terrain\]'"):
        require("no_such_gis_module", "reading the DEM x.tif")

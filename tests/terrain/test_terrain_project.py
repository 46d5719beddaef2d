"""Project files that take their slope from the terrain, and the section command."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import laspy
import numpy as np
import pytest
import shapely
from numpy.testing import assert_allclose

from rockfall_design.cli.program import main
from rockfall_design.project import load_corridor, load_project
from rockfall_design.terrain.mapping import write_layer

from .terrain_helpers import CRS, NORTH, WEST, grid, write_dem

ROOT = Path(__file__).resolve().parents[2]
MATERIALS = """
materials:
  talus: {restitution: 0.3, friction: 0.6, rolling_resistance: 0.5}
  forest: {restitution: 0.2, friction: 0.7, rolling_resistance: 0.8}
  rock: {restitution: 0.45, friction: 0.5, rolling_resistance: 0.3}
rocks: {count: 20, seed: 3, radius: 0.3, release: {steeper_than_deg: 45, height: 0.5}}
"""


def slope_dem(path: Path) -> Path:
    """A slope falling to the south: 30 deg, with a 60 deg band from 40 to 60 m south."""
    e, n = grid(120, 60)
    v = NORTH - n  # metres south of the north edge
    rise = np.where((v > 40) & (v < 60), np.tan(np.radians(60)), np.tan(np.radians(30)))
    z = 900.0 - np.cumsum(rise, axis=0) * 1.0
    return write_dem(path, z)


def test_a_slope_from_a_dem_line_with_polygon_materials_and_release_by_angle(tmp_path):
    slope_dem(tmp_path / "dem.tif")
    forest = shapely.box(WEST, NORTH - 120, WEST + 60, NORTH - 80)
    write_layer(tmp_path / "cover.gpkg", [forest], {"cover": ["wood"]}, "Polygon", CRS)
    (tmp_path / "p.yaml").write_text(f"""
name: from a DEM
slope:
  dem: dem.tif
  line: [[{WEST + 30}, {NORTH - 110}], [{WEST + 30}, {NORTH - 5}]]
  materials: {{polygons: cover.gpkg, attribute: cover, classes: {{wood: forest}},
               default: talus}}
protect: {{x: 100}}
{MATERIALS}""")
    project = load_project(tmp_path / "p.yaml")
    points = np.array(project.slope.points)
    assert points[0, 1] > points[-1, 1]  # drawn uphill, turned round: x runs down
    assert_allclose(points[0, 0], 0.0)
    assert set(project.slope.materials) == {"talus", "forest"}
    # the forest starts 80 m south of the edge: 75 m along the line from its top at 5 m
    first_forest = project.slope.materials.index("forest")
    assert_allclose(points[first_forest, 0], 75.0, atol=1.0)
    zones = project.rocks.release
    assert len(zones) == 1
    assert_allclose(zones[0].x, (35.0, 55.0), atol=1.5)  # the 60 deg band


def test_a_slope_down_the_fall_line_stops_at_the_road(tmp_path):
    slope_dem(tmp_path / "dem.tif")
    (tmp_path / "p.yaml").write_text(f"""
name: t
slope:
  dem: dem.tif
  fall_line: {{from: [{WEST + 20.3}, {NORTH - 10}], stop: [[{WEST}, {NORTH - 100}],
                                                          [{WEST + 60}, {NORTH - 100}]]}}
  materials: talus
protect: {{x: 85}}
{MATERIALS}""")
    project = load_project(tmp_path / "p.yaml")
    points = np.array(project.slope.points)
    assert_allclose(points[-1, 0], 90.0, atol=0.01)  # 10 m to 100 m south, straight down
    assert np.all(np.diff(points[:, 1]) < 0)


def test_a_slope_from_a_point_cloud_takes_the_ground_and_a_low_percentile(tmp_path):
    rng = np.random.default_rng(7)
    count = 20_000
    e = WEST + rng.uniform(0, 40, count)
    n = NORTH - rng.uniform(0, 80, count)
    ground = 500.0 + 0.5 * (n - NORTH + 80)  # falls to the south at 26.6 deg
    z = ground + rng.normal(0, 0.02, count)
    cls = np.full(count, 2, dtype=np.uint8)
    bushes = rng.random(count) < 0.3  # vegetation points, 0.5-3 m above the ground
    z[bushes] += rng.uniform(0.5, 3.0, bushes.sum())
    cls[bushes] = 4
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.offsets = [WEST, NORTH - 100, 0.0]
    header.scales = [0.001, 0.001, 0.001]
    las = laspy.LasData(header)
    las.x, las.y, las.z, las.classification = e, n, z, cls
    las.write(tmp_path / "scan.laz")  # compressed: lazrs
    (tmp_path / "p.yaml").write_text(f"""
name: t
slope: {{points: scan.laz, line: [[{WEST + 20}, {NORTH - 2}], [{WEST + 20}, {NORTH - 78}]],
         swath_m: 2.0, materials: talus}}
protect: {{x: 60}}
{MATERIALS.replace("steeper_than_deg: 45", "x: [0, 5]")}""")
    project = load_project(tmp_path / "p.yaml")
    points = np.array(project.slope.points)
    # the first bin's station is the mean of its points', near 2.5 m south
    start = 500.0 + 0.5 * (80 - 2.5)
    assert abs(points[0, 1] - start) < 0.3
    # along the section, ground within noise (10th percentile of N(0, 2 cm): -2.6 cm),
    # not lifted by 30 % of points in bushes 0.5-3 m high
    drop = points[0, 1] - points[:, 1]
    assert np.abs(drop - 0.5 * points[:, 0]).max() < 0.06



def test_a_corridor_along_a_road_gives_sections_with_their_share(tmp_path, capsys):
    slope_dem(tmp_path / "dem.tif")
    road = shapely.LineString([(WEST + 2, NORTH - 100), (WEST + 58, NORTH - 100)])
    write_layer(tmp_path / "road.gpkg", [road], {"name": ["road"]}, "LineString", CRS)
    (tmp_path / "c.yaml").write_text(f"""
name: corridor
corridor:
  dem: dem.tif
  road: road.gpkg
  spacing_m: 20
  below_road_m: 10
  materials: talus
  release: {{steeper_than_deg: 45, height: 0.5}}
  candidates: [{{type: fence, x_above_road_m: [5, 30], product: [RX-050]}}]
{MATERIALS.split("rocks:")[0]}rocks: {{count: 20, seed: 3, radius: 0.3}}
design: {{residual: {{fraction: 0.05}}, products: {ROOT / "projects/catalogue_products.yaml"},
         costs: {{model: unit_prices, file: {ROOT / "projects/catalogue_costs.yaml"}}}}}
""")
    corridor = load_corridor(tmp_path / "c.yaml")
    assert len(corridor.sections) == 3
    assert corridor.map is not None
    for section, where in zip(corridor.sections, corridor.map.sections, strict=True):
        p = section.project
        assert_allclose(p.design.site.length_m, 56.0 / 3, atol=1e-3)
        assert_allclose(p.protect.x, where.road_x, atol=1e-3)
        assert p.slope.x_range[1] == pytest.approx(where.road_x + 10.0, abs=0.6)
        assert_allclose(p.rocks.release[0].x, (where.road_x - 60, where.road_x - 40), atol=1.5)
    # every section's block says where along the road it is and the road it stands for
    code = main(["simulate", str(tmp_path / "c.yaml"), "--workers", "1", "--json"])
    blocks = json.loads(capsys.readouterr().out)["sections"]
    assert code == 0
    stations = [b["road"]["station_m"] for b in blocks]
    assert stations == pytest.approx([28 / 3, 28, 140 / 3], abs=1e-3)
    assert all(b["road"]["length_m"] == pytest.approx(56 / 3, abs=1e-3) for b in blocks)


def run(argv: list[str], capsys: pytest.CaptureFixture) -> tuple[int, str]:
    code = main(argv)
    return code, capsys.readouterr().err


def test_the_section_command_writes_a_survey_csv(tmp_path, capsys):
    dem = slope_dem(tmp_path / "dem.tif")
    code, err = run(["section", str(dem), "--fall-line", f"{WEST + 30},{NORTH - 5}", "--out",
                     str(tmp_path / "s.csv"), "--plot", str(tmp_path / "s.png")], capsys)
    assert code == 2 and "leaves the raster" in err  # the slope runs on to the raster's edge
    code, err = run(["section", str(dem), "--fall-line", f"{WEST + 30},{NORTH - 5}", "--stop",
                     f"{WEST},{NORTH - 100}", f"{WEST + 60},{NORTH - 100}", "--out",
                     str(tmp_path / "s.csv"), "--plot", str(tmp_path / "s.png")], capsys)
    assert code == 0, err
    rows = (tmp_path / "s.csv").read_text().splitlines()
    assert rows[2] == "x,y"
    assert rows[-1].startswith("95.0000,")  # from 5 m to 100 m south
    assert (tmp_path / "s.png").stat().st_size > 1000


@pytest.mark.parametrize("case", ["geographic", "off", "not a raster", "no extra", "plot"])
def test_bad_terrain_input_is_one_line_and_exit_2(tmp_path, capsys, monkeypatch, case):
    e, n = grid(20, 20)
    dem = write_dem(tmp_path / "dem.tif", 100 + 0.5 * (n - NORTH),
                    crs="EPSG:4326" if case == "geographic" else CRS)
    if case == "not a raster":
        dem.write_text("not a raster\n")
    if case == "no extra":
        monkeypatch.setitem(sys.modules, "rasterio", None)  # import fails: not installed
    point = f"{WEST + 500},{NORTH - 5}" if case == "off" else f"{WEST + 5},{NORTH - 5}"
    plot = ["--plot", str(tmp_path / "s.xyz")] if case == "plot" else []
    code, err = run(["section", str(dem), "--fall-line", point, "--out",
                     str(tmp_path / "s.csv")] + plot, capsys)
    assert code == 2
    assert len(err.strip().splitlines()) == 1
    expected = {"geographic": "is geographic", "off": "is off the raster",
                "not a raster": "not a raster that can be read",
                "no extra": "optional extra [terrain]",
                "plot": "expected a file ending in .png, .svg, .pdf"}[case]
    assert expected in err
    assert "dem.tif" in err or case in ("no extra", "plot")
    assert not (tmp_path / "s.csv").exists()


def test_materials_from_a_land_cover_raster_and_release_from_polygons(tmp_path):
    slope_dem(tmp_path / "dem.tif")
    e, n = grid(120, 60)
    classes = np.where(NORTH - n > 70, 2.0, 1.0)  # class 2 from 70 m south of the edge
    write_dem(tmp_path / "cover.tif", classes, nodata=None)
    source = shapely.box(WEST, NORTH - 30, WEST + 60, NORTH - 20)
    write_layer(tmp_path / "release.gpkg", [source], {"name": ["scarp"]}, "Polygon", CRS)
    (tmp_path / "p.yaml").write_text(f"""
name: t
slope:
  dem: dem.tif
  line: [[{WEST + 30}, {NORTH - 5}], [{WEST + 30}, {NORTH - 110}]]
  materials: {{raster: cover.tif, classes: {{1: talus, 2: forest}}}}
protect: {{x: 100}}
{MATERIALS.replace("steeper_than_deg: 45", "polygons: release.gpkg")}""")
    project = load_project(tmp_path / "p.yaml")
    points = np.array(project.slope.points)
    change = project.slope.materials.index("forest")
    assert_allclose(points[change, 0], 65.0, atol=1.0)  # 70 m south, the line from 5 m
    assert set(project.slope.materials[:change]) == {"talus"}
    assert set(project.slope.materials[change:]) == {"forest"}
    (zone,) = project.rocks.release
    assert_allclose(zone.x, (15.0, 25.0), atol=1.0)


def test_a_class_without_material_names_the_class_and_the_station(tmp_path):
    slope_dem(tmp_path / "dem.tif")
    e, n = grid(120, 60)
    write_dem(tmp_path / "cover.tif", np.where(NORTH - n > 70, 7.0, 1.0), nodata=None)
    (tmp_path / "p.yaml").write_text(f"""
name: t
slope:
  dem: dem.tif
  line: [[{WEST + 30}, {NORTH - 5}], [{WEST + 30}, {NORTH - 110}]]
  materials: {{raster: cover.tif, classes: {{1: talus}}}}
protect: {{x: 100}}
{MATERIALS}""")
    with pytest.raises(Exception, match=r"cover.tif: class 7 at 6\d\.\d m along the section "
                       r"\(.*\) has no material"):
        load_project(tmp_path / "p.yaml")

"""Tests of the built-in measures (plugins/rockfall_design_builtins/measures/).

Geometry and excavation areas are compared with values worked out by hand
(closed forms or the shoelace formula on hand-listed vertices).
"""

from __future__ import annotations

import math
from importlib.metadata import entry_points

import numpy as np
import pluggy
import pytest
from numpy.testing import assert_allclose
from pydantic import ValidationError
from rockfall_design_builtins import measures as builtin
from rockfall_design_builtins.measures import (
    Berm,
    BoulderRow,
    Ditch,
    Fence,
    ProtectionForest,
    Wall,
    cut_and_fill,
)
from rockfall_design_builtins.measures import berm as berm_module
from rockfall_design_builtins.measures import boulder_row as boulder_row_module
from rockfall_design_builtins.measures import ditch as ditch_module
from rockfall_design_builtins.measures import fence as fence_module
from rockfall_design_builtins.measures import protection_forest as forest_module
from rockfall_design_builtins.measures import wall as wall_module

from rockfall_design import Barrier, BarrierBehaviour, ProfileEdit, ProtectiveMeasure
from rockfall_design.engine import Material, Section
from rockfall_design.plugins import hookspecs

ALL = [Fence, Wall, Ditch, Berm, BoulderRow, ProtectionForest]

SIMPLE = [[0, 100], [30, 60], [60, 30], [80, 20], [120, 15], [200, 12]]


def make_section(points) -> Section:
    pts = np.asarray(points, dtype=float)
    return Section(pts[:, 0], pts[:, 1], np.zeros(len(pts) - 1, dtype=int), (Material(),))


@pytest.fixture
def simple() -> Section:
    return make_section(SIMPLE)


def build(cls: type[ProtectiveMeasure], **params) -> ProtectiveMeasure:
    return cls(cls.Params(**params))


def shoelace(poly) -> float:
    p = np.asarray(poly, dtype=float)
    x, y = p[:, 0], p[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def check_edit(edit: ProfileEdit, section: Section) -> None:
    """The edit's vertices increase in x and meet the original ground at both ends."""
    pts = np.asarray(edit.points, dtype=float)
    assert pts.ndim == 2 and pts.shape[1] == 2
    assert np.all(np.diff(pts[:, 0]) > 0)
    assert_allclose(pts[0, 0], edit.x_start)
    assert_allclose(pts[-1, 0], edit.x_end)
    assert_allclose(pts[0, 1], section.ground_height(edit.x_start), atol=1e-12)
    assert_allclose(pts[-1, 1], section.ground_height(edit.x_end), atol=1e-12)
    assert section.x[0] <= edit.x_start < edit.x_end <= section.x[-1]
    assert edit.x_start <= edit.catch_from < edit.catch_to <= edit.x_end


# ---------------------------------------------------------------------------
# registration and the common contract
# ---------------------------------------------------------------------------


def test_each_module_registers_its_one_measure_through_a_fresh_plugin_manager():
    pm = pluggy.PluginManager(hookspecs.PROJECT_NAME)
    pm.add_hookspecs(hookspecs)
    modules = [berm_module, boulder_row_module, ditch_module, fence_module, forest_module,
               wall_module]
    for module in modules:
        pm.register(module, name=module.__name__)
    pm.check_pending()
    results = pm.hook.rockfall_design_measures()
    assert all(len(result) == 1 for result in results)  # one measure per module
    classes = [c for result in results for c in result]
    assert sorted(c.kind for c in classes) == ["berm", "boulder_row", "ditch", "fence",
                                               "protection_forest", "wall"]
    assert all(issubclass(c, ProtectiveMeasure) for c in classes)
    # The package only names the classes: registering it registers nothing.
    assert not hasattr(builtin, "rockfall_design_measures")


def test_every_builtin_measure_and_cost_model_has_its_own_entry_point():
    eps = {ep.name: ep.value for ep in entry_points(group="rockfall_design")}
    for kind in ("fence", "wall", "ditch", "berm", "boulder_row", "protection_forest"):
        assert eps[kind] == f"rockfall_design_builtins.measures.{kind}"
    assert eps["unit_prices"] == "rockfall_design_builtins.costs.unit_prices"


@pytest.mark.parametrize("cls", ALL, ids=lambda c: c.kind)
def test_example_validates_and_fits_the_simple_section(cls, simple):
    measure = cls(cls.Params(**cls.example))
    assert "type" not in cls.example
    assert cls.summary
    fp = measure.footprint(simple)
    assert isinstance(fp, Barrier | ProfileEdit)
    if isinstance(fp, ProfileEdit):
        check_edit(fp, simple)
    q = measure.quantities(simple)
    assert q and all(math.isfinite(v) for v in q.values())
    props = measure.design_properties()
    assert props and set(props) <= {"height_m", "capacity_kj", "width_m", "depth_m"}
    assert f"x = {measure.x:g} m" in measure.label()


@pytest.mark.parametrize("cls", ALL, ids=lambda c: c.kind)
def test_params_are_documented_with_units(cls):
    for name, info in cls.Params.model_fields.items():
        assert info.description, f"{cls.kind}.{name} has no description"
        if name not in ("material", "product"):
            assert "(" in info.description and ")" in info.description, (cls.kind, name)


@pytest.mark.parametrize("cls", ALL, ids=lambda c: c.kind)
def test_design_variables_are_parameters_with_bounds(cls):
    fields = cls.Params.model_fields
    assert "x" in cls.design_variables
    assert all(math.isnan(b) for b in cls.design_variables["x"])
    for name, (low, high) in cls.design_variables.items():
        assert name in fields
        if name != "x":
            assert 0 < low < high
            cls.Params(**{**cls.example, name: low})
            cls.Params(**{**cls.example, name: high})


@pytest.mark.parametrize("cls", ALL, ids=lambda c: c.kind)
def test_params_reject_unknown_keys(cls):
    with pytest.raises(ValidationError, match="Extra inputs are not permitted"):
        cls.Params(**cls.example, colour="red")
    with pytest.raises(ValidationError):
        cls.Params(**{k: v for k, v in cls.example.items() if k != "x"})


@pytest.mark.parametrize(
    "cls, key, value",
    [
        (Fence, "height", 0.0),
        (Fence, "height", -1.0),
        (Fence, "capacity_kj", 0.0),
        (Fence, "capacity_kj", math.inf),
        (Fence, "x", math.nan),
        (Wall, "restitution", 1.5),
        (Wall, "restitution", -0.1),
        (Wall, "thickness", 0.0),
        (Wall, "capacity_kj", -5.0),
        (BoulderRow, "gap_ratio", 1.0),
        (BoulderRow, "gap_ratio", -0.1),
        (BoulderRow, "block_size", 0.0),
        (BoulderRow, "density", 0.0),
        (Ditch, "width", 0.0),
        (Ditch, "depth", -1.0),
        (Ditch, "upslope_side_deg", 85.0),
        (Ditch, "downslope_side_deg", 5.0),
        (Berm, "width", 0.0),
        (Berm, "cut_face_deg", 20.0),
        (Berm, "cut_face_deg", 90.0),
    ],
)
def test_params_reject_out_of_range_values(cls, key, value):
    with pytest.raises(ValidationError, match=key):
        cls.Params(**{**cls.example, key: value})


def test_params_are_frozen():
    p = Fence.Params(**Fence.example)
    with pytest.raises(ValidationError):
        p.height = 5.0


# ---------------------------------------------------------------------------
# barriers
# ---------------------------------------------------------------------------


def test_fence_footprint_and_quantities(simple):
    fence = build(Fence, x=70.0, height=4.0, capacity_kj=1000.0, product="RX-100")
    # x = 70 m stands on the segment (60, 30)-(80, 20): cos = 20 / hypot(20, 10).
    cos = 20.0 / math.hypot(20.0, 10.0)
    fp = fence.footprint(simple)
    assert fp == Barrier(
        x=70.0, height_m=4.0, capacity_kj=1000.0, behaviour=BarrierBehaviour.NET,
        slope_cos=cos, height_normal=True, sel_kj=math.nan, elongation_sel_m=math.nan,
        elongation_mel_m=math.nan,
    )
    # The nominal height is normal to the slope: the vertical top is higher.
    assert_allclose(fp.vertical_height_m, 4.0 / cos)
    assert fence.design_properties() == {"height_m": 4.0, "capacity_kj": 1000.0}
    assert fence.quantities(simple) == {
        "height_m": 4.0,
        "capacity_kj": 1000.0,
        "area_m2_per_m": 4.0,
    }
    assert "RX-100" in fence.label()


def test_fence_carries_its_ead_figures_to_the_engine_and_the_concepts(simple):
    fence = build(Fence, x=70.0, height=4.0, capacity_kj=1000.0, max_elongation_m=5.5,
                  elongation_sel_m=3.6, sel_kj=300.0, residual_height_fraction=0.6)
    fp = fence.footprint(simple)
    assert (fp.sel_kj, fp.elongation_sel_m, fp.elongation_mel_m) == (300.0, 3.6, 5.5)
    props = fence.design_properties()
    assert props["max_elongation_m"] == 5.5 and props["elongation_sel_m"] == 3.6
    assert props["sel_kj"] == 300.0
    assert_allclose(props["residual_height_m"], 2.4)
    with pytest.raises(ValidationError, match="below capacity_kj"):
        Fence.Params(x=70.0, height=4.0, capacity_kj=1000.0, sel_kj=1000.0)


def test_wall_footprint_and_quantities(simple):
    wall = build(Wall, x=100.0, height=3.0, capacity_kj=2000.0, restitution=0.3, thickness=1.5)
    assert wall.footprint(simple) == Barrier(
        x=100.0,
        height_m=3.0,
        capacity_kj=2000.0,
        behaviour=BarrierBehaviour.RIGID,
        restitution=0.3,
    )
    q = wall.quantities(simple)
    assert_allclose(q["volume_m3_per_m"], 4.5)
    assert q["height_m"] == 3.0 and q["capacity_kj"] == 2000.0
    default = Wall.Params(x=100.0, height=3.0, capacity_kj=2000.0)
    assert default.restitution == 0.2 and default.thickness == 1.0


def test_boulder_row_footprint_and_quantities(simple):
    row = build(BoulderRow, x=130.0, block_size=1.5, gap_ratio=0.2, capacity_kj=300.0)
    fp = row.footprint(simple)
    assert fp.behaviour is BarrierBehaviour.BLOCKS
    assert (fp.x, fp.height_m, fp.capacity_kj) == (130.0, 1.5, 300.0)
    assert_allclose([fp.spacing_m, fp.gap_m], [1.875, 0.375])
    q = row.quantities(simple)
    assert_allclose(q["blocks_per_m"], 1 / 1.875)
    assert_allclose(q["block_volume_m3"], 3.375)
    assert_allclose(q["block_mass_kg"], 3.375 * 2650)
    assert_allclose(q["volume_m3_per_m"], 3.375 / 1.875)
    assert q["height_m"] == 1.5


@pytest.mark.parametrize("a, g", [(1.0, 0.0), (1.5, 0.2), (2.0, 0.5), (0.8, 0.9)])
def test_boulder_row_gap_and_spacing_relations(a, g):
    row = build(BoulderRow, x=130.0, block_size=a, gap_ratio=g, capacity_kj=100.0)
    s, w = row.spacing_m, row.gap_m
    assert_allclose(s, a / (1 - g))
    assert_allclose(w, g * s)
    assert_allclose(s - w, a)  # one block and one gap per spacing
    assert_allclose(w / s, g)  # the open fraction of the row
    # blocks per metre times block length = closed fraction of the row
    assert_allclose(row.quantities(None)["blocks_per_m"] * a, 1 - g)


@pytest.mark.parametrize("cls", [Fence, Wall, BoulderRow], ids=lambda c: c.kind)
@pytest.mark.parametrize("x", [-5.0, 0.0, 200.0, 250.0])
def test_barrier_outside_the_section_is_rejected(cls, x, simple):
    measure = cls(cls.Params(**{**cls.example, "x": x}))
    with pytest.raises(ValueError, match=r"outside the section, which runs from 0 to 200 m"):
        measure.footprint(simple)


# ---------------------------------------------------------------------------
# ditch
# ---------------------------------------------------------------------------


def test_ditch_on_flat_ground_symmetric():
    flat = make_section([[0, 10], [100, 10]])
    ditch = build(Ditch, x=40.0, width=10.0, depth=2.0)
    edit = ditch.footprint(flat)
    check_edit(edit, flat)
    assert_allclose(edit.points, [[40, 10], [42, 8], [48, 8], [50, 10]], atol=1e-12)
    assert (edit.x_start, edit.x_end, edit.catch_from, edit.catch_to) == (40, 50, 40, 50)
    assert edit.material is None
    q = ditch.quantities(flat)
    assert_allclose(q["excavation_m3_per_m"], 2 * (10 - 2))  # d (W - d) for 45 deg sides
    assert q["fill_m3_per_m"] == 0.0
    assert (q["width_m"], q["depth_m"]) == (10.0, 2.0)
    assert ditch.design_properties() == {"width_m": 10.0, "depth_m": 2.0}


def test_ditch_on_flat_ground_unequal_sides():
    flat = make_section([[0, 10], [100, 10]])
    ditch = build(
        Ditch,
        x=40.0,
        width=10.0,
        depth=2.0,
        upslope_side_deg=60,
        downslope_side_deg=30,
        material="gravel",
    )
    edit = ditch.footprint(flat)
    ru, rd = 2 / math.tan(math.radians(60)), 2 / math.tan(math.radians(30))
    assert_allclose(edit.points, [[40, 10], [40 + ru, 8], [50 - rd, 8], [50, 10]])
    assert edit.material == "gravel"
    # trapezoid: depth times the mean of top and bottom widths
    assert_allclose(ditch.quantities(flat)["excavation_m3_per_m"], 2 * (10 + 10 - ru - rd) / 2)


def test_ditch_on_inclined_runout(simple):
    # ground 20 -> 15 over x 80 -> 120: y(90) = 18.75, y(100) = 17.5
    ditch = build(Ditch, x=90.0, width=10.0, depth=2.0)
    edit = ditch.footprint(simple)
    check_edit(edit, simple)
    # bottom at 17.5 - 2 = 15.5; 45 deg sides run 3.25 m and 2 m
    expected = [[90, 18.75], [93.25, 15.5], [98, 15.5], [100, 17.5]]
    assert_allclose(edit.points, expected, atol=1e-12)
    # area under the chord above 15.5 (26.25) minus the two side triangles (5.28125 + 2)
    assert_allclose(ditch.quantities(simple)["excavation_m3_per_m"], 18.96875)
    assert_allclose(shoelace(expected), 18.96875)


def test_ditch_replaces_a_ground_vertex(simple):
    # the stretch 70..90 contains the vertex (80, 20); y(70) = 25, y(90) = 18.75
    ditch = build(Ditch, x=70.0, width=20.0, depth=2.0)
    edit = ditch.footprint(simple)
    check_edit(edit, simple)
    expected = [[70, 25], [78.25, 16.75], [88, 16.75], [90, 18.75]]
    assert_allclose(edit.points, expected, atol=1e-12)
    assert 80.0 not in edit.points[:, 0]
    # original above 16.75: 57.5 + 26.25; new: triangles 34.03125 + 2
    q = ditch.quantities(simple)
    assert_allclose(q["excavation_m3_per_m"], 47.71875)
    assert_allclose(shoelace(expected + [[80, 20]]), 47.71875)
    assert q["fill_m3_per_m"] == 0.0


def test_ditch_too_narrow(simple):
    # y(94) = 18.25, bottom 16.25: the sides need 2.5 + 2 = 4.5 m of 4 m
    ditch = build(Ditch, x=90.0, width=4.0, depth=2.0)
    message = r"ditch too narrow: the side slopes need 4\.5 m of the 4 m width"
    with pytest.raises(ValueError, match=message):
        ditch.footprint(simple)
    with pytest.raises(ValueError, match="too narrow"):
        ditch.quantities(simple)


@pytest.mark.parametrize(
    "x, width, message",
    [
        (-1.0, 10.0, r"starts at x = -1 m, upslope of the section's start"),
        (195.0, 10.0, r"runs to x = 205 m, past the section's end"),
        (250.0, 10.0, r"past the section's end \(the section runs from 0 to 200 m\)"),
    ],
)
def test_ditch_outside_the_section(simple, x, width, message):
    with pytest.raises(ValueError, match=message):
        build(Ditch, x=x, width=width, depth=1.0).footprint(simple)


def test_ditch_at_the_section_ends_fits(simple):
    edit = build(Ditch, x=190.0, width=10.0, depth=1.0).footprint(simple)
    check_edit(edit, simple)
    assert edit.x_end == 200.0


# ---------------------------------------------------------------------------
# berm
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("phi", [45.0, 60.0, 85.0])
def test_berm_on_a_straight_slope_closed_form(phi):
    beta = math.radians(20.0)
    tb, tp = math.tan(beta), math.tan(math.radians(phi))
    slope = make_section([[0, 100], [200, 100 - 200 * tb]])
    width, x = 8.0, 100.0
    berm = build(Berm, x=x, width=width, cut_face_deg=phi)
    edit = berm.footprint(slope)
    check_edit(edit, slope)
    y_b = 100 - (x + width) * tb
    h = width * tb / (1 - tb / tp)  # cut height
    x_c = x - h / tp
    assert_allclose(edit.points, [[x_c, y_b + h], [x, y_b], [x + width, y_b]])
    assert (edit.catch_from, edit.catch_to, edit.x_end) == (x, x + width, x + width)
    q = berm.quantities(slope)
    assert_allclose(q["excavation_m3_per_m"], width * h / 2)  # the cut triangle
    assert_allclose(q["cut_height_m"], h)
    assert q["fill_m3_per_m"] == 0.0
    assert q["width_m"] == width
    assert berm.design_properties() == {"width_m": width}


def test_berm_face_meets_within_the_first_segment(simple):
    # y(85) = 19.375, bench at y(93) = 18.375; the ground rises 1/8 per m upslope
    berm = build(Berm, x=85.0, width=8.0, cut_face_deg=60.0)
    edit = berm.footprint(simple)
    check_edit(edit, simple)
    t = math.sqrt(3.0)
    u = 1.0 / (t - 1 / 8)  # 19.375 + u/8 = 18.375 + u t
    assert_allclose(edit.points, [[85 - u, 18.375 + u * t], [85, 18.375], [93, 18.375]])
    area = shoelace([[85 - u, 18.375 + u * t], [85, 18.375], [93, 18.375]])
    assert_allclose(berm.quantities(simple)["excavation_m3_per_m"], area)


def test_berm_face_meets_beyond_a_vertex(simple):
    # y(62) = 29, bench at y(72) = 24; the face passes above (60, 30) and meets
    # the 45 deg segment 30..60: 30 + u = 24 + (2 + u) sqrt(3), u = 60 - x_c
    berm = build(Berm, x=62.0, width=10.0, material="concrete")
    edit = berm.footprint(simple)
    check_edit(edit, simple)
    t = math.sqrt(3.0)
    u = (6 - 2 * t) / (t - 1)
    assert_allclose(edit.points, [[60 - u, 30 + u], [62, 24], [72, 24]])
    assert edit.material == "concrete"
    polygon = [[60 - u, 30 + u], [62, 24], [72, 24], [62, 29], [60, 30]]
    q = berm.quantities(simple)
    assert_allclose(q["excavation_m3_per_m"], shoelace(polygon))
    assert_allclose(q["cut_height_m"], 6 + u)


def test_berm_face_too_flat_for_the_slope():
    steep = make_section([[0, 200], [100, 200 - 100 * math.tan(math.radians(50))], [150, 0]])
    berm = build(Berm, x=50.0, width=5.0, cut_face_deg=45.0)
    with pytest.raises(ValueError, match=r"45 deg cut face from x = 50 m never meets the ground"):
        berm.footprint(steep)
    # a steeper face fits
    check_edit(build(Berm, x=50.0, width=5.0, cut_face_deg=60.0).footprint(steep), steep)


def test_berm_on_ground_that_does_not_fall():
    rising = make_section([[0, 0], [50, 0], [100, 10]])
    with pytest.raises(ValueError, match=r"ground at x = 20 m \(0 m\) is not above the bench"):
        build(Berm, x=20.0, width=5.0).footprint(rising)
    with pytest.raises(ValueError, match="is not above the bench level"):
        build(Berm, x=60.0, width=5.0).footprint(rising)


@pytest.mark.parametrize(
    "x, width, message",
    [
        (0.0, 5.0, r"berm at x = 0 m is outside the section, which runs from 0 to 200 m"),
        (-10.0, 5.0, r"outside the section"),
        (195.0, 10.0, r"runs to x = 205 m, past the section's end"),
    ],
)
def test_berm_outside_the_section(simple, x, width, message):
    with pytest.raises(ValueError, match=message):
        build(Berm, x=x, width=width).footprint(simple)


# ---------------------------------------------------------------------------
# cut and fill
# ---------------------------------------------------------------------------


def test_cut_and_fill_split_at_crossings():
    # old ground flat at 0; new ground a zig-zag crossing it: +1 / -1 triangles
    x_old, y_old = np.array([0.0, 4.0]), np.zeros(2)
    x_new, y_new = np.array([0.0, 1.0, 2.0, 3.0, 4.0]), np.array([0.0, -1.0, 0.0, 1.0, 0.0])
    cut, fill = cut_and_fill(x_old, y_old, x_new, y_new)
    assert_allclose([cut, fill], [1.0, 1.0])
    # a crossing inside an interval: d = 1 at x=0, -3 at x=4 -> root at 1
    cut, fill = cut_and_fill(x_old, y_old, np.array([0.0, 4.0]), np.array([-1.0, 3.0]))
    assert_allclose([cut, fill], [0.5, 4.5])


# ---------------------------------------------------------------------------
# protection forest
# ---------------------------------------------------------------------------


def test_protection_forest_keeps_the_ground_and_carries_its_stand(simple):
    m = build(ProtectionForest, x=25.0, length=50.0, stems_per_ha=600.0, dbh_mean_cm=30.0)
    fp = m.footprint(simple)
    check_edit(fp, simple)
    # The ground unchanged: its own vertices inside the stretch, heights on it.
    assert_allclose(fp.points[:, 0], [25.0, 30.0, 60.0, 75.0])
    assert_allclose(fp.points[:, 1], simple.ground_height(fp.points[:, 0]))
    assert fp.forest is not None and fp.forest.stems_per_ha == 600.0
    assert fp.forest.dbh_sd_cm == pytest.approx(10.0)  # a third of the mean by default
    assert (fp.catch_from, fp.catch_to) == (25.0, 75.0)


def test_protection_forest_cost_is_the_discounted_yearly_cost_per_hectare(simple):
    from rockfall_design_builtins.measures.protection_forest import present_worth_factor

    m = build(ProtectionForest, x=25.0, length=50.0, stems_per_ha=600.0, dbh_mean_cm=30.0,
              working_life_years=50.0, discount_rate=0.02)
    q = m.quantities(simple)
    # (1 - 1.02^-50) / 0.02 = 31.4236 (annuity tables).
    assert present_worth_factor(50.0, 0.02) == pytest.approx(31.4236, abs=1e-4)
    assert present_worth_factor(10.0, 0.0) == 10.0
    assert q["forest_ha_year_per_m"] == pytest.approx(50.0 / 1e4 * 31.4236, rel=1e-5)
    (bill,) = m.bill_from(q)
    assert bill.name == "forest_ha_year" and bill.name in ProtectionForest.default_prices


def test_protection_forest_spread_above_the_mean_is_refused():
    with pytest.raises(ValidationError, match="dbh_sd_cm"):
        ProtectionForest.Params(x=25.0, length=50.0, stems_per_ha=600.0, dbh_mean_cm=20.0,
                                dbh_sd_cm=25.0)

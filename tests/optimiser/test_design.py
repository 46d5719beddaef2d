"""Tests of the design section resolved against the plugins (judge.design_spec)."""

from __future__ import annotations

import types
from pathlib import Path

import pytest
from rockfall_design_builtins.costs import UnitPrices
from rockfall_design_builtins.measures import Wall, WallParams

from rockfall_design import hookimpl
from rockfall_design.errors import ProjectError
from rockfall_design.judge.candidates import CandidateSpec, Product, build_candidate_measure
from rockfall_design.judge.design_spec import DesignSpec, resolve_design
from rockfall_design.plugins import load_registry
from rockfall_design.project import load_project, load_project_text

from ..project.test_project import EXAMPLE, line_of

ROOT = Path(__file__).resolve().parents[2]

PRODUCTS = """\
fence:
  RX-100: {capacity_kj: 1000, heights: [5, 3, 4]}
  RX-250: {capacity_kj: 2500, heights: [4, 5, 6]}
product_wall:
  gabion:
    capacity_kj: 2000
    heights: [2, 3]
    thickness: 2.0
    supplier: example
"""

COSTS = """\
currency: EUR
fixed_per_measure: 15000
barrier_per_m:
  fence:
    RX-100: {3: 520, 4: 600, 5: 690}
    RX-250: {4: 880, 5: 980, 6: 1090}
  product_wall:
    gabion: {2: 900, 3: 1300}
excavation_per_m3: 25
boulder_per_m3: 110
"""

DESIGN = """\
design:
  residual: {fraction: 0.001}
  site:
    length_m: 120
  products: products.yaml
  costs:
    file: costs.yaml
  candidates:
    - type: fence
      x: [60, 110]
      product: [RX-100, RX-250]
    - type: ditch
      x: [118, 130]
      width: [3, 12]
      depth: {options: [1.0, 1.5, 2.0]}
      upslope_side_deg: 45
    - type: product_wall
      x: [100, 140]
    - type: boulder_row
      x: [150, 160]
      gap_ratio: 0.2
      capacity_kj: {options: [300, 600]}
"""

TEXT = EXAMPLE + DESIGN


class ProductWallParams(WallParams):
    product: str | None = None


class ProductWall(Wall):
    """The built-in wall with a catalogue product (a test measure)."""

    kind = "product_wall"
    Params = ProductWallParams


def _test_plugin() -> types.ModuleType:
    module = types.ModuleType("test_design_plugin")

    @hookimpl
    def rockfall_design_measures():
        return [ProductWall]

    module.rockfall_design_measures = rockfall_design_measures
    return module


@pytest.fixture()
def registry():
    reg = load_registry(extra_plugins=[("test_design", _test_plugin())])
    assert "product_wall" in reg.measures and not reg.failures
    return reg


def write(tmp_path: Path, text: str = TEXT, products: str = PRODUCTS, costs: str = COSTS) -> Path:
    (tmp_path / "products.yaml").write_text(products)
    (tmp_path / "costs.yaml").write_text(costs)
    path = tmp_path / "p.yaml"
    path.write_text(text)
    return path


def resolve(tmp_path, registry, text=TEXT, products=PRODUCTS, costs=COSTS) -> DesignSpec:
    return resolve_design(load_project(write(tmp_path, text, products, costs)), registry)


def error(tmp_path, registry, text=TEXT, products=PRODUCTS, costs=COSTS) -> ProjectError:
    with pytest.raises(ProjectError) as info:
        resolve(tmp_path, registry, text, products, costs)
    assert "\n" not in str(info.value)
    return info.value


def edit(old: str, new: str, text: str = TEXT) -> str:
    assert text.count(old) == 1, f"{old!r} must occur once"
    return text.replace(old, new)


def test_resolve_design(tmp_path, registry):
    spec = resolve(tmp_path, registry)
    assert (spec.max_measures, spec.residual_count, spec.residual_fraction) == (2, None, 0.001)
    assert (spec.fresh_rocks, spec.fresh_seed, spec.length_m) == (None, None, 120.0)
    assert isinstance(spec.cost_model, UnitPrices)
    assert spec.cost_model.params.fixed_per_measure == 15000.0
    rx100 = Product("RX-100", "fence", 1000.0, (3.0, 4.0, 5.0), {})
    assert spec.products["fence"]["RX-100"] == rx100
    gabion = spec.products["product_wall"]["gabion"]
    assert gabion.extra == {"thickness": 2.0, "supplier": "example"}
    fence, ditch, wall, row = spec.candidates
    assert fence == CandidateSpec(
        index=0,
        kind="fence",
        x_range=(60.0, 110.0),
        products=(rx100, spec.products["fence"]["RX-250"]),
        fixed={},
        ranges={},
        options={},
    )
    assert ditch.products == ()
    assert ditch.fixed == {"upslope_side_deg": 45}
    assert ditch.ranges == {"width": (3.0, 12.0)}
    assert ditch.options == {"depth": (1.0, 1.5, 2.0)}
    # no product list: every product of the kind
    assert wall.products == (gabion,) and wall.fixed == {} and wall.ranges == {}
    # a required parameter not given: the plugin's design-variable bounds
    assert row.ranges == {"block_size": (0.5, 3.0)}
    assert row.fixed == {"gap_ratio": 0.2} and row.options == {"capacity_kj": (300, 600)}
    assert fence.product("RX-250").capacity_kj == 2500.0
    with pytest.raises(KeyError, match="not allowed"):
        fence.product("RX-050")


def test_resolve_with_inline_catalogues(registry):
    text = EXAMPLE + (
        "design:\n"
        "  site: {length_m: 10}\n"
        "  products: {fence: {A: {capacity_kj: 500, heights: [2]}}}\n"
        "  costs: {params: {fixed_per_measure: 0, excavation_per_m3: 1, boulder_per_m3: 1,\n"
        "                   barrier_per_m: {fence: {A: {2: 300}}}}}\n"
        "  candidates: [{type: fence, x: [60, 110]}]\n"
    )
    spec = resolve_design(load_project_text(text), registry)
    (fence,) = spec.candidates
    assert [p.name for p in fence.products] == ["A"]
    assert spec.cost_model.params.currency == "EUR"


def test_build_candidate_measure(tmp_path, registry):
    spec = resolve(tmp_path, registry)
    fence, ditch, wall, row = spec.candidates
    m = build_candidate_measure(fence, registry, {"x": 80, "product": "RX-250", "height": 5})
    assert m.kind == "fence"
    assert (m.params.x, m.params.height, m.params.capacity_kj, m.params.product) == (
        80.0,
        5.0,
        2500.0,
        "RX-250",
    )
    w = build_candidate_measure(wall, registry, {"x": 120, "product": "gabion", "height": 3})
    assert (w.params.thickness, w.params.capacity_kj, w.params.height) == (2.0, 2000.0, 3.0)
    d = build_candidate_measure(ditch, registry, {"x": 120, "width": 8, "depth": 1.5})
    assert (d.params.width, d.params.depth, d.params.upslope_side_deg) == (8.0, 1.5, 45.0)
    r = build_candidate_measure(row, registry, {"x": 155, "block_size": 1.0, "capacity_kj": 600})
    assert (r.params.gap_ratio, r.params.capacity_kj) == (0.2, 600.0)
    cost = spec.cost_model.cost(m, m.quantities(None), spec.length_m)
    assert cost == pytest.approx(15000 + 980 * 120)


@pytest.mark.parametrize(
    ("which", "params", "fragment"),
    [
        (0, {"x": 80, "height": 5}, "needs a product"),
        (0, {"x": 80, "product": "RX-050", "height": 5}, "not allowed"),
        (0, {"x": 80, "product": "RX-100"}, "needs a height"),
        (0, {"x": 80, "product": "RX-100", "height": 6}, "does not come in height 6"),
        (0, {"x": 50, "product": "RX-100", "height": 3}, "x = 50 is outside its range [60, 110]"),
        (1, {"x": 120, "width": 20, "depth": 1.5}, "width = 20 is outside its range [3, 12]"),
        (1, {"x": 120, "width": 8, "depth": 1.2}, "depth = 1.2 is not one of its options"),
        (1, {"x": 120, "width": 8}, "depth: required key is missing"),
        (1, {"x": 120, "width": 8, "depth": 1.5, "upslope_side_deg": 5}, "upslope_side_deg"),
        (1, {"x": 120, "width": 8, "depth": 1.5, "widht": 3}, "unknown key 'widht'"),
    ],
)
def test_build_candidate_measure_errors(tmp_path, registry, which, params, fragment):
    spec = resolve(tmp_path, registry)
    with pytest.raises(ValueError, match=r"^candidate \d \(\w+\): ") as info:
        build_candidate_measure(spec.candidates[which], registry, params)
    assert fragment in str(info.value)


@pytest.mark.parametrize(
    ("old", "new", "needle", "key", "fragment"),
    [
        (
            "    - type: ditch\n",
            "    - type: ditsch\n",
            "type: ditsch",
            "design.candidates[1].type",
            "unknown measure type 'ditsch'; did you mean 'ditch'?",
        ),
        (
            "      upslope_side_deg: 45\n",
            "      upslope_side: 45\n",
            "upslope_side:",
            "design.candidates[1].upslope_side",
            "did you mean 'upslope_side_deg'",
        ),
        (
            "      upslope_side_deg: 45\n",
            "      upslope_side_deg: 90\n",
            "upslope_side_deg",
            "design.candidates[1].upslope_side_deg",
            "<= 80",
        ),
        (
            "      upslope_side_deg: 45\n",
            "      upslope_side_deg: steep\n",
            "upslope_side_deg",
            "design.candidates[1].upslope_side_deg",
            "expected a number",
        ),
        (
            "      width: [3, 12]\n",
            "      width: [-1, 12]\n",
            "width:",
            "design.candidates[1].width[0]",
            "> 0",
        ),
        (
            "      depth: {options: [1.0, 1.5, 2.0]}\n",
            "      depth: {options: [1.0, 0]}\n",
            "depth:",
            "design.candidates[1].depth.options[1]",
            "> 0",
        ),
        (
            "      depth: {options: [1.0, 1.5, 2.0]}\n",
            "      depth: {options: [1.0, deep]}\n",
            "depth:",
            "design.candidates[1].depth.options[1]",
            "expected a number",
        ),
        (
            "      upslope_side_deg: 45\n",
            "      material: [1, 2]\n",
            "material:",
            "design.candidates[1].material",
            "not a number",
        ),
        (
            "      product: [RX-100, RX-250]\n",
            "      product: [RX-100, RX-205]\n",
            "product:",
            "design.candidates[0].product[1]",
            "unknown fence product 'RX-205'; did you mean 'RX-250'?",
        ),
        (
            "      product: [RX-100, RX-250]\n",
            "      product: RX-10\n",
            "product:",
            "design.candidates[0].product",
            "did you mean 'RX-100'?",
        ),
        (
            "      product: [RX-100, RX-250]\n",
            "      product: {options: [RX-100, X]}\n",
            "product:",
            "design.candidates[0].product.options[1]",
            "unknown fence product 'X'",
        ),
        (
            "      product: [RX-100, RX-250]\n",
            "      height: [3, 5]\n",
            "height: [3, 5]",
            "design.candidates[0].height",
            "chooses it among the heights",
        ),
        (
            "      product: [RX-100, RX-250]\n",
            "      capacity_kj: 1000\n",
            "capacity_kj:",
            "design.candidates[0].capacity_kj",
            "energy class of the catalogue product",
        ),
        (
            "      x: [100, 140]\n",
            "      x: [100, 140]\n      thickness: 3\n",
            "thickness:",
            "design.candidates[2].thickness",
            "the catalogue product sets it",
        ),
        (
            "      product: [RX-100, RX-250]\n",
            "      product: [RX-100]\n      mesh: 3\n",
            "mesh:",
            "design.candidates[0].mesh",
            "unknown fence parameter 'mesh'",
        ),
        (
            "    - type: ditch\n",
            "    - type: ditch\n      product: A\n",
            "product: A",
            "design.candidates[1].product",
            "unknown ditch parameter 'product'",
        ),
        (
            "      gap_ratio: 0.2\n",
            "",
            "type: boulder_row",
            "design.candidates[3]",
            "required boulder_row parameter 'gap_ratio' is missing",
        ),
        (
            "      gap_ratio: 0.2\n",
            "      gap_ratio: [0.1, 1.5]\n",
            "gap_ratio",
            "design.candidates[3].gap_ratio[1]",
            "< 1",
        ),
        (
            "    file: costs.yaml\n",
            "    file: costs.yaml\n    model: unit_price\n",
            "model: unit_price",
            "design.costs.model",
            "unknown cost model 'unit_price'; did you mean 'unit_prices'?",
        ),
    ],
)
def test_resolution_errors_in_the_project(tmp_path, registry, old, new, needle, key, fragment):
    text = edit(old, new)
    err = error(tmp_path, registry, text)
    assert (err.file, err.line, err.key) == (
        str(tmp_path / "p.yaml"),
        line_of(text, needle),
        key,
    ), str(err)
    assert fragment in err.message, err.message


def test_candidate_with_products_but_none_in_the_catalogue(tmp_path, registry):
    products = PRODUCTS.split("product_wall:")[0]
    err = error(tmp_path, registry, products=products)
    assert (err.line, err.key) == (line_of(TEXT, "- type: product_wall"), "design.candidates[2]")
    assert "needs catalogue products" in err.message and "no product_wall products" in err.message
    text = EXAMPLE + (
        "design:\n  site: {length_m: 10}\n  costs: {params: {}}\n"
        "  candidates: [{type: fence, x: [60, 110]}]\n"
    )
    with pytest.raises(ProjectError, match="design.products is not given"):
        resolve_design(load_project_text(text), registry)


def test_no_design_section(registry):
    with pytest.raises(ProjectError, match="no design: section"):
        resolve_design(load_project_text(EXAMPLE), registry)


def test_integer_parameter_cannot_be_a_range(tmp_path, registry):
    from pydantic import BaseModel, ConfigDict, Field

    from rockfall_design import Barrier, BarrierBehaviour, ProtectiveMeasure

    class NetParams(BaseModel):
        model_config = ConfigDict(extra="forbid")
        x: float
        rows: int = Field(ge=1)

    class Net(ProtectiveMeasure):
        kind = "net"
        Params = NetParams
        example = {"x": 1.0, "rows": 2}

        def footprint(self, section):
            return Barrier(
                x=self.params.x, height_m=1.0, capacity_kj=1.0, behaviour=BarrierBehaviour.NET
            )

        def design_properties(self):
            return {}

        def quantities(self, section):
            return {}

    module = types.ModuleType("net_plugin")

    @hookimpl
    def rockfall_design_measures():
        return [Net]

    module.rockfall_design_measures = rockfall_design_measures
    reg = load_registry(extra_plugins=[("net", module), ("test_design", _test_plugin())])
    assert "net" in reg.measures, reg.failures
    text = edit("    - type: boulder_row\n", "    - type: net\n      rows: [1, 3]\n")
    text = edit("      gap_ratio: 0.2\n      capacity_kj: {options: [300, 600]}\n", "", text)
    err = error(tmp_path, reg, text)
    assert (err.line, err.key) == (line_of(text, "rows:"), "design.candidates[3].rows")
    assert "integer parameter" in err.message
    ok = edit("rows: [1, 3]", "rows: {options: [1, 3]}", text)
    costs = COSTS + "other_per_m: {net: 10}\n"  # a running metre of net has a price
    assert resolve(tmp_path, reg, ok, costs=costs).candidates[3].options == {"rows": (1, 3)}
    err = error(tmp_path, reg, ok)  # it has none: found before any search
    assert (err.file, err.line, err.key) == (str(tmp_path / "p.yaml"),
                                             line_of(ok, "  costs:"), "design.costs")
    assert "candidate design.candidates[3] (net): no price for quantity 'net'" in err.message
    assert "catalogue costs.yaml" in err.message


@pytest.mark.parametrize(
    ("products", "line", "key", "fragment"),
    [
        # a wall product whose thickness the wall rejects: at the catalogue line
        (
            PRODUCTS.replace("thickness: 2.0", "thickness: -2"),
            8,
            "product_wall.gabion.thickness",
            "product_wall product 'gabion': expected a number > 0",
        ),
        (
            PRODUCTS.replace("thickness: 2.0", "thickness: thick"),
            8,
            "product_wall.gabion.thickness",
            "expected a number",
        ),
    ],
)
def test_product_errors_in_the_catalogue_file(tmp_path, registry, products, line, key, fragment):
    err = error(tmp_path, registry, products=products)
    assert (err.file, err.line, err.key) == (str(tmp_path / "products.yaml"), line, key), str(err)
    assert fragment in err.message


@pytest.mark.parametrize(
    ("costs", "line", "key", "fragment"),
    [
        (
            COSTS.replace("fixed_per_measure: 15000", "fixed_per_measure: -1"),
            2,
            "fixed_per_measure",
            ">= 0",
        ),
        (
            COSTS.replace("excavation_per_m3: 25", "excavaton_per_m3: 25"),
            9,
            "excavaton_per_m3",
            "did you mean 'excavation_per_m3'",
        ),
        (
            COSTS.replace("{3: 520, 4: 600", "{3: 520, 4: -600"),
            5,
            "barrier_per_m.fence.RX-100.4",
            ">= 0",
        ),
        (
            COSTS.replace("{3: 520, 4: 600", "{3: 520, x: 600"),
            5,
            "barrier_per_m.fence.RX-100.x",
            "invalid key: expected a number",
        ),
        (
            COSTS.replace("{3: 520, 4: 600", "{3: 520, -4: 600"),
            5,
            "barrier_per_m.fence.RX-100.-4",
            "invalid key: expected a number > 0",
        ),
        (COSTS.replace("boulder_per_m3: 110\n", ""), 1, "boulder_per_m3", "required key"),
        (COSTS.replace("currency: EUR", "currency: 3"), 1, "currency", "expected a string"),
    ],
)
def test_cost_errors_in_the_costs_file(tmp_path, registry, costs, line, key, fragment):
    err = error(tmp_path, registry, costs=costs)
    assert (err.file, err.line, err.key) == (str(tmp_path / "costs.yaml"), line, key), str(err)
    assert fragment in err.message


def test_cost_errors_inline(registry):
    text = EXAMPLE + (
        "design:\n"
        "  site: {length_m: 10}\n"
        "  costs:\n"
        "    params:\n"
        "      fixed_per_measure: 0\n"
        "      excavation_per_m3: cheap\n"
        "      boulder_per_m3: 1\n"
        "  candidates: [{type: ditch, x: [118, 130]}]\n"
    )
    with pytest.raises(ProjectError) as info:
        resolve_design(load_project_text(text, source="p.yaml"), registry)
    err = info.value
    assert (err.line, err.key) == (
        line_of(text, "excavation_per_m3"),
        "design.costs.params.excavation_per_m3",
    )


def test_bundled_catalogues_resolve(tmp_path, registry):
    products = (ROOT / "projects" / "catalogue_products.yaml").read_text()
    costs = (ROOT / "projects" / "catalogue_costs.yaml").read_text()
    assert "ILLUSTRATIVE" in products and "ILLUSTRATIVE" in costs
    text = edit("product: [RX-100, RX-250]", "product: [RX-050, RX-850]")
    text = edit("    - type: product_wall\n      x: [100, 140]\n", "", text)
    spec = resolve(tmp_path, registry, text, products, costs)
    model = spec.cost_model
    # every product at every height has a price
    for kind, table in spec.products.items():
        for name, product in table.items():
            for height in product.heights:
                assert model.params.barrier_per_m[kind][name][height] > 0, (kind, name, height)
    assert {p.capacity_kj for p in spec.products["fence"].values()} >= {500.0, 8500.0}

"""The example third-party plugin, examples/rockfall-embankment, works as documented.

It is installed as a distribution (``plugin_helpers.install_embankment_example``,
as pip would), runs its own tests, is listed by ``plugins --json``, and is
designed with by ``optimise`` on ``projects/design_embankment.yaml``, priced
by its own quantity: the project's catalogue price, else its default.
"""

from __future__ import annotations

import importlib.util
import inspect
import json
import sys
import tomllib
from pathlib import Path

import pytest

from rockfall_design import testing
from rockfall_design.cli.program import main
from rockfall_design.judge.candidates import build_candidate_measure
from rockfall_design.judge.costing import design_cost
from rockfall_design.judge.design_spec import resolve_design
from rockfall_design.plugins import load_registry
from rockfall_design.project import load_project
from rockfall_design.run.releases import section_from_project

from ..plugin_helpers import EMBANKMENT_EXAMPLE, install_embankment_example

ROOT = Path(__file__).resolve().parents[2]
PROJECT = ROOT / "projects" / "design_embankment.yaml"


@pytest.fixture()
def installed(tmp_path, monkeypatch):
    install_embankment_example(tmp_path, monkeypatch)
    yield
    sys.modules.pop("rockfall_embankment", None)


def test_it_is_a_pip_installable_distribution_with_an_entry_point():
    meta = tomllib.loads((EMBANKMENT_EXAMPLE / "pyproject.toml").read_text(encoding="utf-8"))
    assert meta["project"]["name"] == "rockfall-embankment"
    assert meta["project"]["entry-points"]["rockfall_design"] == {
        "embankment": "rockfall_embankment"}
    assert "rockfall-design" in meta["project"]["dependencies"]


def test_its_own_tests_pass(installed):
    path = EMBANKMENT_EXAMPLE / "tests" / "test_embankment.py"
    spec = importlib.util.spec_from_file_location("example_test_embankment", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    fixtures = {"tiny_slope": testing.tiny_slope, "rockfall_registry": testing.make_registry}
    ran = 0
    for name, fn in vars(module).items():
        if name.startswith("test_") and callable(fn):
            fn(**{p: fixtures[p] for p in inspect.signature(fn).parameters})
            ran += 1
    assert ran >= 5


def test_listed_with_units_defaults_and_design_declarations(installed, capsys):
    assert main(["plugins", "--json"]) == 0
    (m,) = [m for m in json.loads(capsys.readouterr().out)["measures"]
            if m["kind"] == "embankment"]
    assert m["provider"] == "rockfall-embankment"
    params = {p["name"]: p for p in m["parameters"]}
    assert (params["height"]["unit"], params["height"]["design"]) == (
        "m", {"role": "range", "bounds": [1.5, 6.0]})
    assert (params["uphill_face_deg"]["unit"], params["uphill_face_deg"]["default"]) == (
        "deg", 60.0)
    assert params["crest_width"]["design"] is None


def _fill_cost(spec, registry, section, params, price):
    (cand,) = [c for c in spec.candidates if c.kind == "embankment"]
    m = build_candidate_measure(cand, registry, params)
    fill = m.quantities(section)["fill_m3_per_m"]
    return design_cost(registry, spec, [m], section), 15000 + spec.length_m * fill * price


def test_priced_by_the_catalogue_else_by_its_default_price(installed, tmp_path):
    registry = load_registry()
    project = load_project(PROJECT)
    section = section_from_project(project)
    spec = resolve_design(project, registry)
    params = {"x": 100.0, "height": 2.0, "uphill_face_deg": 60.0}
    got, expected = _fill_cost(spec, registry, section, params, 38.0)  # the catalogue's
    assert got == pytest.approx(expected)
    costs = (ROOT / "projects" / "catalogue_costs.yaml").read_text(encoding="utf-8")
    (tmp_path / "catalogue_costs.yaml").write_text(
        costs.replace("  embankment_fill_m3: 38", "  other_quantity: 1"), encoding="utf-8")
    for name in ("design_embankment.yaml", "catalogue_products.yaml"):
        (tmp_path / name).write_text((ROOT / "projects" / name).read_text(encoding="utf-8"),
                                     encoding="utf-8")
    spec = resolve_design(load_project(tmp_path / "design_embankment.yaml"), registry)
    got, expected = _fill_cost(spec, registry, section, params, 45.0)  # the plugin's default
    assert got == pytest.approx(expected)


@pytest.mark.slow  # an end-to-end run of a few seconds: CI runs it with -m slow
def test_optimise_chooses_it_and_check_accepts_the_design(installed, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["optimise", str(PROJECT), "--out", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    alternatives = {a["name"]: a for a in summary["alternatives"]}
    assert summary["best"]["name"] == summary["best_name"] == "embankment"
    assert alternatives["embankment"]["cost"] < alternatives["fence"]["cost"]
    (m,) = alternatives["embankment"]["measures"]
    assert m["type"] == "embankment" and 1.5 <= m["height"] <= 6.0
    assert main(["check", str(out / "design.yaml"), "--json"]) == 0
    checked = json.loads(capsys.readouterr().out)
    assert [x["type"] for x in checked["measures"]] == ["embankment"]

"""The least-cost optimiser: against exhaustive grids, reproducible, honest about fresh rocks."""

from __future__ import annotations

import itertools
import json
import math
from pathlib import Path

import numpy as np
import pytest

from rockfall_design.cli import main
from rockfall_design.design import resolve_design
from rockfall_design.evaluate import build_concept
from rockfall_design.optimise import (
    EDIT_STEP_M,
    RANGE_STEPS,
    STATION_STEP_M,
    Screening,
    optimise,
)
from rockfall_design.plugins import load_registry
from rockfall_design.project import load_project, load_project_text

ROOT = Path(__file__).resolve().parents[1]
PROJECTS = ROOT / "projects"


@pytest.fixture(scope="module")
def registry():
    return load_registry()


def _small(path: Path, **replace: str):
    """A bundled project with its catalogue paths made absolute and text replaced."""
    text = path.read_text()
    text = text.replace("catalogue_products.yaml", str(PROJECTS / "catalogue_products.yaml"))
    text = text.replace("catalogue_costs.yaml", str(PROJECTS / "catalogue_costs.yaml"))
    for old, new in replace.items():
        assert old in text, old
        text = text.replace(old, new)
    return load_project_text(text, str(path))


def _lattice(lo: float, hi: float, step: float) -> np.ndarray:
    return lo + step * np.arange(math.floor((hi - lo) / step + 1e-9) + 1)


def _grid_best_fence(screen: Screening, ci: int) -> float:
    c = screen.spec.candidates[ci]
    best = math.inf
    for x in _lattice(*c.x_range, STATION_STEP_M):
        for prod in c.products:
            for h in prod.heights:
                ms = screen.measures([(ci, {"x": float(x), "product": prod.name, "height": h})])
                r = screen.screen(ms)
                if r.feasible:
                    best = min(best, r.cost)
    return best


def test_one_fence_is_within_one_percent_of_the_exhaustive_grid(registry):
    project = _small(PROJECTS / "design_two_zones.yaml", **{"count: 3000": "count: 400"})
    res = optimise(project, registry)
    alt = {a.name: a for a in res.alternatives}["fence 113-280 m"]
    spec = resolve_design(project, registry)
    screen = Screening(project, registry, spec, build_concept(project, registry), rocks=400,
                       seed=project.rocks.seed)
    grid = _grid_best_fence(screen, 1)
    assert math.isfinite(grid) and alt.screened_feasible
    assert grid <= alt.cost <= 1.01 * grid


def test_fence_or_ditch_each_within_one_percent_of_the_grid(registry):
    project = _small(PROJECTS / "design_ditch_or_fence.yaml", **{"count: 3000": "count: 300"})
    res = optimise(project, registry)
    alts = {a.name: a for a in res.alternatives}
    spec = resolve_design(project, registry)
    screen = Screening(project, registry, spec, build_concept(project, registry), rocks=300,
                       seed=project.rocks.seed)
    assert alts["fence"].cost <= 1.01 * _grid_best_fence(screen, 0)
    c = spec.candidates[1]
    wlo, whi = c.ranges["width"]
    wstep = max((whi - wlo) / RANGE_STEPS, EDIT_STEP_M)
    best = math.inf
    for x, w, d in itertools.product(_lattice(*c.x_range, STATION_STEP_M),
                                     _lattice(wlo, whi, wstep), c.options["depth"]):
        r = screen.screen(screen.measures([(1, {"x": float(x), "width": float(w), "depth": d})]))
        if r.feasible:
            best = min(best, r.cost)
    assert math.isfinite(best)
    assert best <= alts["ditch"].cost <= 1.01 * best
    # And the optimiser's choice is the cheaper of the two that hold on fresh
    # rocks. Since issue 14 (rolling resistance acts while a rock slips: the
    # physics changed) the ditch that 300 search rocks admit no longer holds
    # on fresh rocks, so here the fence is chosen; with 1,000 rocks the ditch
    # holds and wins (test_chosen_design_checked_with_another_seed).
    assert alts["ditch"].cost < alts["fence"].cost
    robust = [a for a in (alts["ditch"], alts["fence"]) if a.holds_on_fresh_rocks]
    assert robust and res.best is min(robust, key=lambda a: a.cost)


def test_same_seed_same_result(registry):
    project = _small(PROJECTS / "design_ditch_or_fence.yaml", **{"count: 3000": "count: 200"})
    a = optimise(project, registry).summary()
    b = optimise(project, registry).summary()
    for s in (a, b):
        s.pop("runtime_s")
    assert a == b


def test_two_smaller_fences_beat_one_heavy_fence_at_the_toe(registry):
    project = load_project(PROJECTS / "design_two_zones.yaml")
    res = optimise(project, registry)  # the project's own 3000 rocks
    alts = {a.name: a for a in res.alternatives}
    two = alts["fence 25-92 m + fence 113-280 m"]  # one fence below each release zone
    one = alts["fence 113-280 m"]
    assert two.feasible and one.feasible and two.holds_on_fresh_rocks
    assert two.cost < one.cost
    assert res.best is two
    heavy = one.measures[0]
    assert heavy.params.capacity_kj > max(m.params.capacity_kj for m in two.measures)
    assert heavy.x > 200  # toward the toe


def test_chosen_design_checked_with_another_seed(tmp_path, capsys):
    proj = PROJECTS / "design_ditch_or_fence.yaml"
    # 1,000 rocks, not 600, since issue 14 changed the physics: with 600 the
    # cheap ditch the search finds does not hold on fresh rocks.
    code = main(["optimise", str(proj), "--rocks", "1000", "--out", str(tmp_path), "--json"])
    s = json.loads(capsys.readouterr().out)
    assert code == 0 and s["best"] == "ditch"
    (best,) = [a for a in s["alternatives"] if a["name"] == s["best"]]
    assert {"name", "measures", "cost", "feasible", "holds_on_fresh_rocks", "checks"} <= set(best)
    design = tmp_path / "design.yaml"
    assert (tmp_path / "alternatives.csv").stat().st_size > 0
    code = main(["check", str(design), "--rocks", "1000", "--seed", str(s["fresh_seed"]), "--json"])
    chk = json.loads(capsys.readouterr().out)
    # check on the fresh rocks agrees with what the optimiser reported.
    assert chk["ok"] is best["holds_on_fresh_rocks"]
    assert (code == 0) is best["holds_on_fresh_rocks"]


def test_no_design_section_is_a_clear_error(capsys):
    assert main(["optimise", str(PROJECTS / "quarry_road.yaml")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "design" in err

"""A look's screening goes on from the last look's rocks: only the new rocks run.

The look of ``2n`` rocks is the look of ``n`` and ``n`` new ones, never a
fresh ``2n`` (issue 37, item 2): its table must be bit for bit the one of
all the rocks run at once, at the look's stations, whatever stations the
earlier screening recorded (the stations a run records at do not change
its paths).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rockfall_design.judge.design_spec import resolve_design
from rockfall_design.judge.placing import build_concept
from rockfall_design.judge.sequential import plan_looks
from rockfall_design.optimiser import Screening
from rockfall_design.optimiser.decide import Decider
from rockfall_design.plugins import load_registry
from rockfall_design.project import load_project_text

PROJECTS = Path(__file__).resolve().parents[2] / "projects"


def _setup(name: str = "design_two_zones.yaml"):
    text = (PROJECTS / name).read_text()
    for cat in ("catalogue_products.yaml", "catalogue_costs.yaml"):
        text = text.replace(cat, str(PROJECTS / cat))
    project = load_project_text(text, name, base_dir=PROJECTS)
    registry = load_registry()
    spec = resolve_design(project, registry)
    return project, registry, spec, build_concept(project, registry)


def _same_table(a: Screening, b: Screening) -> None:
    assert np.array_equal(a.grid, b.grid)
    for f in ("h", "e_kj", "v", "max_x", "x_end", "status"):
        assert np.array_equal(getattr(a.bare, f), getattr(b.bare, f), equal_nan=True), f
    assert np.array_equal(a.mass, b.mass)
    assert np.array_equal(a.radius, b.radius)
    assert np.array_equal(a.u_gap, b.u_gap)
    assert np.array_equal(a.releases.x, b.releases.x)


@pytest.mark.parametrize("seed", [3, 11])
def test_going_on_is_the_run_at_once(seed: int) -> None:
    project, registry, spec, concept = _setup()
    search = Screening(project, registry, spec, concept, rocks=150, seed=seed)
    xs = np.array([search.grid[7], search.grid[40]])
    once = Screening(project, registry, spec, concept, rocks=400, seed=seed, stations=xs)
    on = Screening(project, registry, spec, concept, rocks=400, seed=seed, stations=xs,
                   after=search)
    assert on.rocks_run == 250 and once.rocks_run == 400
    _same_table(on, once)
    again = Screening(project, registry, spec, concept, rocks=900, seed=seed, stations=xs,
                      after=on)
    _same_table(again, Screening(project, registry, spec, concept, rocks=900, seed=seed,
                                 stations=xs))


def test_going_on_refuses_another_run() -> None:
    project, registry, spec, concept = _setup()
    search = Screening(project, registry, spec, concept, rocks=100, seed=5)
    xs = np.array([search.grid[3]])
    with pytest.raises(ValueError):
        Screening(project, registry, spec, concept, rocks=200, seed=6, stations=xs,
                  after=search)
    with pytest.raises(ValueError):
        Screening(project, registry, spec, concept, rocks=200, seed=5,
                  stations=np.array([search.grid[3] + 0.25]), after=search)


def test_decider_runs_only_the_new_rocks() -> None:
    """Looks 1 and 2 run their new rocks only; a station new at look 2 adds its rocks to
    look 1 too, never a fresh run of a whole look."""
    project, registry, spec, concept = _setup()
    looks = plan_looks(100, 800, 0.95)
    search = Screening(project, registry, spec, concept, rocks=looks.sizes[0], seed=2)
    dec = Decider(search, looks)
    a, b = float(search.grid[5]), float(search.grid[30])
    s1 = dec._screening(1, [a])
    assert dec.simulated == looks.sizes[1] - looks.sizes[0]
    dec._screening(2, [a])
    assert dec.simulated == looks.sizes[2] - looks.sizes[0]
    s2 = dec._screening(2, [b])
    # b is added to looks 1 and 2: each of their new rocks once more.
    assert dec.simulated == 2 * (looks.sizes[2] - looks.sizes[0])
    assert b in s2.grid and a in s2.grid and dec._chains[None][1] is not s1
    _same_table(s2, Screening(project, registry, spec, concept, rocks=looks.sizes[2], seed=2,
                              stations=s2.grid))

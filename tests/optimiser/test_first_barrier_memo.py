"""The screening judges the first barrier of the search's placements once per option."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rockfall_design.judge.design_spec import resolve_design
from rockfall_design.judge.placing import PlacedMeasure, build_concept
from rockfall_design.optimiser import Screening
from rockfall_design.optimiser.search import BarrierSlots
from rockfall_design.project import load_project

PROJECTS = Path(__file__).resolve().parents[2] / "projects"


def _same(a, b) -> None:
    assert (a.feasible, a.near, a.approximate, a.point_ok, a.residual, a.labels) == (
        b.feasible, b.near, b.approximate, b.point_ok, b.residual, b.labels)
    assert a.violation == b.violation
    assert [[c.as_dict() for c in cs] for cs in a.checks] == [
        [c.as_dict() for c in cs] for cs in b.checks]
    for ra, rb in zip(a.results, b.results, strict=True):
        assert (ra.index, ra.met, ra.caught, ra.passed_over, ra.broken_through,
                ra.clearance_m) == (rb.index, rb.met, rb.caught, rb.passed_over,
                                    rb.broken_through, rb.clearance_m)
        for name in ("passing_height_m", "energy_kj", "velocity_ms", "mass_kg", "radius_m"):
            np.testing.assert_array_equal(getattr(ra, name), getattr(rb, name))


def test_placements_judged_with_the_first_barrier_remembered_are_judged_the_same(registry):
    project = load_project(PROJECTS / "design_two_zones.yaml")
    spec = resolve_design(project, registry)
    concept = build_concept(project, registry)
    project = project.model_copy(update={"protect": project.protect.model_copy(
        update={"allowed_fraction": spec.residual_fraction})})
    screen = Screening(project, registry, spec, concept, rocks=1500, seed=12)
    slots = BarrierSlots(screen)
    up, down = slots.of(0), slots.of(1)
    rng = np.random.default_rng(5)
    # Few upslope options, many downslope ones: each upslope fence is met first
    # in several placements, some judged before the memo holds it, most after.
    firsts = rng.choice(len(up), size=4, replace=False)
    judged = 0
    for _ in range(3):
        for a in firsts:
            for b in rng.choice(len(down), size=5, replace=False):
                chosen = [up[a], down[b]]
                placed = [PlacedMeasure(i, o.measure, o.footprint, o.label)
                          for i, o in enumerate(chosen)]
                cost = sum(o.cost for o in chosen)
                plain = screen.screen_placed(placed, screen.bare, cost)
                memo = screen.screen_placed(placed, screen.bare, cost,
                                            keys=[(0, int(a)), (1, int(b))])
                _same(plain, memo)
                judged += 1
    assert judged == 60 and len(screen._first) == 4

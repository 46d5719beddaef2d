"""The ground-edit search runs the lattice next to the design the decisions chose
(search.EditSearch.around): what differential evolution's samples missed at one seed."""

from __future__ import annotations

import math
from itertools import chain
from pathlib import Path

import numpy as np

from rockfall_design.judge.design_spec import resolve_design
from rockfall_design.judge.evaluation import check_slack
from rockfall_design.judge.placing import build_concept
from rockfall_design.optimiser import Screening
from rockfall_design.optimiser.search import (
    POLISH_SHIFTS,
    BarrierSlots,
    EditSearch,
    Tally,
)
from rockfall_design.optimiser.space import STATION_STEP_M, decode
from rockfall_design.project import load_project

PROJECTS = Path(__file__).resolve().parents[2] / "projects"


def _search(registry) -> EditSearch:
    project = load_project(PROJECTS / "design_ditch_or_fence.yaml")
    spec = resolve_design(project, registry)
    project = project.model_copy(update={"protect": project.protect.model_copy(
        update={"allowed_fraction": spec.residual_fraction})})
    screen = Screening(project, registry, spec, build_concept(project, registry), rocks=600,
                       seed=3)
    (ci,) = sorted(screen.edit_candidates)
    return EditSearch(screen, BarrierSlots(screen), (ci,), Tally())


def test_around_runs_the_cheaper_steps_of_the_chosen_geometry_near_its_station(registry):
    search = _search(registry)
    cands, slots, variables = search.cands, search.edit_slots, search.variables
    names = [v.name for v in variables]
    start = np.array([109.0 if n == "x" else 5.25 if n == "width" else 1.0
                      for n in names])  # depth: index 1 of its options, 1.5 m
    (ditch,) = search.screen.measures(decode(cands, slots, variables, start))
    assert (ditch.x, ditch.params.width, ditch.params.depth) == (109.0, 5.25, 1.5)
    assert np.array_equal(search._vector([ditch]), start)  # the vector of a design, back
    cost = search.screen.cost([ditch])
    near = search.around([ditch], cost)
    ran = {key for key in search.seen}
    # Every design returned is new, cheaper than the chosen one, and next to it.
    assert near and all(d.cost < cost for d in near)
    costs = [d.cost for d in near]
    assert costs == sorted(costs)
    for d in near:
        (m,) = d.measures
        assert abs(m.x - 109.0) <= POLISH_SHIFTS * STATION_STEP_M + 1e-9
        assert (m.params.width, m.params.depth) in {(5.0, 1.5), (5.25, 1.0)}
    # 2 cheaper steps (narrower, shallower) x 9 stations; nothing dearer was run.
    assert len(ran) == 2 * (2 * POLISH_SHIFTS + 1)
    # Run again: nothing new to return, nothing run again.
    assert search.around([ditch], cost) == []
    assert set(search.seen) == ran


def test_the_stations_of_one_geometry_share_a_level_and_the_likeliest_comes_first(registry):
    """A ditch geometry run at several stations is one level of decisions (three at most,
    as a barrier product's stations): a level per station let design_ditch_or_fence at
    seed 11 spend its family's 40 decisions on 4 to 7 stations of each of nine ditches.
    Of one cost, the placement with most slack on the search rocks comes first."""
    search = _search(registry)
    names = [v.name for v in search.variables]
    start = np.array([109.0 if n == "x" else 5.25 if n == "width" else 1.0 for n in names])
    (ditch,) = search.screen.measures(decode(search.cands, search.edit_slots, search.variables,
                                             start))
    near = search.around([ditch], search.screen.cost([ditch]))
    by_geometry: dict[tuple, set] = {}
    for d in near:
        (m,) = d.measures
        by_geometry.setdefault((m.params.width, m.params.depth), set()).add(d.level)
    assert by_geometry and all(len(levels) == 1 for levels in by_geometry.values())
    assert len({lv for levels in by_geometry.values() for lv in levels}) == len(by_geometry)
    for cost in {d.cost for d in near}:
        same = [d for d in near if d.cost == cost]
        keys = [(not d.result.feasible, d.result.violation,
                 -min(map(check_slack, chain(*d.result.checks)), default=math.inf))
                for d in same]
        assert keys == sorted(keys)

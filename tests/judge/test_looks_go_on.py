"""A look at more rocks goes on from the last look's rocks and gives the run of all of them.

The optimiser's sequential looks at a design (and its fresh-rock check) are
nested: look j + 1 has the rocks of look j and more, at the same seed. They
simulate only the new rocks (``run_in_memory``'s and ``evaluate_design``'s
``after``); the joined run must be bit for bit the run of all rocks at once,
or a decision would depend on the schedule of looks.
"""

from __future__ import annotations

from dataclasses import fields
from pathlib import Path

import numpy as np
import pytest

from rockfall_design.engine import EnsembleResult, Releases
from rockfall_design.judge.evaluation import evaluate_design
from rockfall_design.judge.plan import plan_for
from rockfall_design.plugins import load_registry
from rockfall_design.project import load_project
from rockfall_design.run.simulation import run_in_memory

PROJECTS = Path(__file__).resolve().parents[2] / "projects"


def _same(a, b) -> None:
    for f in fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, list):
            assert len(x) == len(y), f.name
            for u, v in zip(x, y, strict=True):
                np.testing.assert_array_equal(u, v, err_msg=f.name)
        else:
            np.testing.assert_array_equal(np.asarray(x), np.asarray(y), err_msg=f.name)


@pytest.mark.parametrize("name", ["design_two_zones.yaml", "quarry_fence_ditch.yaml"])
@pytest.mark.parametrize("seed", [3, 41])
def test_a_run_that_goes_on_is_the_run_of_all_its_rocks(name, seed):
    project = load_project(PROJECTS / name)
    registry = load_registry()
    plan = plan_for(project, registry)
    measures = [p.measure for p in plan.placed]
    whole = evaluate_design(project, registry, measures, plan.concept, rocks=260, seed=seed)
    first = evaluate_design(project, registry, measures, plan.concept, rocks=97, seed=seed)
    more = evaluate_design(project, registry, measures, plan.concept, rocks=180, seed=seed,
                           after=first)
    last = evaluate_design(project, registry, measures, plan.concept, rocks=260, seed=seed,
                           after=more)
    assert last.run.n == 260 and more.run.n == 180
    _same(whole.run.result, last.run.result)
    _same(whole.run.releases, last.run.releases)
    assert [c.as_dict() for cs in whole.checks for c in cs] == [
        c.as_dict() for cs in last.checks for c in cs]
    assert whole.protect == last.protect


def test_a_run_goes_on_only_from_its_own_first_rocks():
    project = load_project(PROJECTS / "design_two_zones.yaml")
    part = run_in_memory(project, rocks=50, seed=5)
    with pytest.raises(ValueError, match="first rocks of the same run"):
        run_in_memory(project, rocks=100, seed=6, after=part)
    with pytest.raises(ValueError, match="first rocks of the same run"):
        run_in_memory(project, rocks=40, seed=5, after=part)


def test_joined_results_keep_their_types():
    project = load_project(PROJECTS / "design_two_zones.yaml")
    a = run_in_memory(project, rocks=30, seed=2)
    b = run_in_memory(project, rocks=70, seed=2, after=a)
    assert isinstance(b.result, EnsembleResult) and isinstance(b.releases, Releases)
    assert b.result.grid_height.dtype == a.result.grid_height.dtype
    assert b.releases.zone.size == 70



def test_a_run_goes_on_twice_from_one_look_alike_and_without_its_stream():
    """The next rocks' releases come from the look's kept stream, a copy of it: going on
    from the same look twice, or from a look without its stream, gives the same rocks."""
    project = load_project(PROJECTS / "design_two_zones.yaml")
    whole = run_in_memory(project, rocks=90, seed=8)
    part = run_in_memory(project, rocks=40, seed=8)
    assert part.stream is not None and part.stream.drawn == 40
    once = run_in_memory(project, rocks=90, seed=8, after=part)
    twice = run_in_memory(project, rocks=90, seed=8, after=part)
    part.stream = None  # as a look made elsewhere: the releases are drawn again
    redrawn = run_in_memory(project, rocks=90, seed=8, after=part)
    for other in (once, twice, redrawn):
        _same(whole.releases, other.releases)
        _same(whole.result, other.result)
    assert once.stream.drawn == 90


@pytest.mark.parametrize("seed", [3, 41])
def test_a_look_without_the_envelope_grid_judges_alike_and_draws_it_again(seed):
    """The optimiser's looks leave the envelope grid out (a few hundred bytes a rock
    instead of kilobytes): the same rocks, records and checks as a look with it, and
    its envelopes (the chosen design's figures) those of the same rocks run with it."""
    project = load_project(PROJECTS / "quarry_fence_ditch.yaml")
    registry = load_registry()
    plan = plan_for(project, registry)
    measures = [p.measure for p in plan.placed]
    with_grid = evaluate_design(project, registry, measures, plan.concept, rocks=150, seed=seed)
    first = evaluate_design(project, registry, measures, plan.concept, rocks=60, seed=seed,
                            envelope=False)
    lean = evaluate_design(project, registry, measures, plan.concept, rocks=150, seed=seed,
                           after=first)
    assert not lean.run.envelope_recorded
    assert lean.run.result.grid.size < with_grid.run.result.grid.size
    for f in fields(lean.run.result):
        if not f.name.startswith("grid"):
            a, b = getattr(lean.run.result, f.name), getattr(with_grid.run.result, f.name)
            if not isinstance(a, list):
                np.testing.assert_array_equal(np.asarray(a), np.asarray(b), err_msg=f.name)
    assert [c.as_dict() for cs in lean.checks for c in cs] == [
        c.as_dict() for cs in with_grid.checks for c in cs]
    env, ref = lean.run.envelopes(), with_grid.run.envelopes()
    assert env.attrs["rocks"] == 150
    assert env.equals(ref)
    with pytest.raises(ValueError, match="grid"):  # a lean look goes on only leanly
        run_in_memory(project, rocks=200, seed=seed, after=run_in_memory(
            project, rocks=100, seed=seed, envelope=False), envelope=True)

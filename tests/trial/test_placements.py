"""Measures placed by hand, judged from the trial run's table (trial/placements.py).

The browser app reaches them through rockfall_design.api.trial_run; these
tests call it as the app does, on a bundled project with few rocks.
"""

from pathlib import Path

import numpy as np
import pytest

from rockfall_design import api
from rockfall_design.errors import InputError
from rockfall_design.judge.placing import place_measures

PROJECT = Path(__file__).resolve().parents[2] / "projects" / "design_two_zones.yaml"


@pytest.fixture(scope="module")
def run_and_project(registry):
    project = api.load_project(PROJECT, registry=registry)
    run = api.trial_run(project, registry, 300, 7, table_step_m=1.0, restart_step_m=10.0,
                        paths_drawn=5)
    return run, project


def _measure(registry, project, raw):
    cls = registry.measures[raw["type"]]
    return cls(cls.Params(**{k: v for k, v in raw.items() if k != "type"}))


def test_a_fence_is_judged_as_the_screening_judges_it(run_and_project, registry):
    run, project = run_and_project
    sc = run.screening
    fence = _measure(registry, project, {"type": "fence", "x": 150.4, "height": 4.0,
                                         "capacity_kj": 2000.0})
    trial = run.place(project, registry, [fence])
    ref = sc.screen_placed(place_measures(project, registry, [fence], sc.section), sc.bare, 0.0)
    assert trial.result.residual == ref.residual and not trial.reshapes_ground
    assert [c.value for c in trial.result.checks[0]] == [c.value for c in ref.checks[0]]
    assert trial.rerun_rocks == 0 and run.table_station(150.4) == 150.0
    assert trial.protect["reaching"] == ref.residual
    assert len(run.paths) == 5 and all(p.shape[1] == 2 for p in run.paths)


def test_the_p95_bounds_are_ordered(run_and_project):
    run, _ = run_and_project
    h = run.screening.bare.h
    for lo, hi in run.p95_bounds(h):
        if lo is not None and hi is not None:
            assert lo <= hi
    assert np.all(np.isfinite(run.stopped_x))


def test_a_ditch_with_no_restart_station_above_it_is_the_users_to_move(run_and_project,
                                                                         registry):
    run, project = run_and_project
    x0 = float(run.section.x[0])
    ditch = _measure(registry, project, {"type": "ditch", "x": x0 + 0.5, "width": 3.0,
                                         "depth": 1.0})
    with pytest.raises(InputError, match="ditch"):
        run.place(project, registry, [ditch])

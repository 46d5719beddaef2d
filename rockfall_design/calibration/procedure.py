"""Run a calibration (fit and bootstrap as tasks) or a comparison (no fit).

:func:`run_calibration` reads the observed stops of the project's
``calibrate:`` section, builds the fit (:func:`~.fit.problem_for`), and
runs replicate 0 (the fit) and the B bootstrap replicates as independent
tasks (:func:`~rockfall_design.studies.executors.run_tasks`, locally or on
Dask), then summarises them (:func:`~.uncertainty.summarise`).
:func:`run_comparison` runs the project as it is and measures how far its
stops are from a set of observations: the validation of a calibration on
a second profile or on held-out blocks.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from ..project import Project
from .calibrated import CalibrationResult, ComparisonResult
from .distances import fit_statistics, level_shares
from .observations import (
    Observations,
    observed_file,
    read_observations,
    size_distribution,
    size_limits,
)

__all__ = ["run_calibration", "run_comparison"]


def _observations(project: Project, path: str | os.PathLike[str] | None) -> Observations:
    if path is None:
        path = observed_file(project)
    return read_observations(path, project.slope.x_range, size_limits(project.rocks.density))


def _load_on_this_thread(problem: Any) -> None:
    """Import the search's scipy modules and load the engine here, before the pool starts.

    On a pool's threads the first replicates would do it (scipy.optimize and
    scipy.stats take 2 to 12 s to import on a loaded machine, numba's cached
    engine about 1 s to load), and a thread cannot be stopped in the middle:
    Ctrl-C then waited for them. On the caller's thread the interrupt stops
    it at once, and the replicates start evaluating, where they check it.
    """
    from dataclasses import replace

    import scipy.optimize  # noqa: F401 - loaded for the replicates
    import scipy.stats.qmc  # noqa: F401

    from .fit import simulated_stops

    simulated_stops(replace(problem, rocks=2), {}, 0)


def run_calibration(
    project: Project,
    *,
    observed: str | os.PathLike[str] | None = None,
    rocks: int | None = None,
    bootstrap: int | None = None,
    seed: int | None = None,
    workers: int | None = None,
    scheduler: Any = None,
    pool: str = "threads",
    on_done: Callable[[int, int], None] | None = None,
) -> CalibrationResult:
    """Calibrate ``project``'s ``calibrate.fit`` inputs to its observed stops.

    Parameters
    ----------
    project
        A validated project with a ``calibrate:`` section.
    observed
        Another file of observed stops than ``calibrate.observed``.
    rocks, bootstrap
        Override ``calibrate.rocks`` and ``calibrate.bootstrap``.
    seed
        The calibration's seed (default ``rocks.seed``).
    workers, scheduler, pool
        Where the replicates run (:func:`~rockfall_design.studies.executors.run_tasks`).
    on_done
        Called as ``on_done(done, total)`` as replicates finish.

    Raises
    ------
    ProjectError
        No ``calibrate:`` section, a bad observation file, a path that is
        not an input, or a range end that is not a valid value.
    """
    from ..studies.executors import run_tasks
    from .fit import problem_for
    from .uncertainty import ReplicateTask, run_replicate, summarise

    spec = project.calibrate
    if spec is None:
        raise project.error_at((), "the project has no calibrate: section (the observed stops "
                               "and the inputs to fit; see docs/calibration.md)")
    obs = _observations(project, observed)
    n_rocks = int(spec.rocks if rocks is None else rocks)
    n_boot = int(spec.bootstrap if bootstrap is None else bootstrap)
    run_seed = int(project.rocks.seed if seed is None else seed)
    sizes = size_distribution(obs)
    problem = problem_for(project, spec.fit, levels=spec.levels, rocks=n_rocks,
                          kind=spec.distance, sizes=sizes)
    _load_on_this_thread(problem)
    tasks = [ReplicateTask(problem, obs.x, b, run_seed) for b in range(n_boot + 1)]
    done = [0]

    def finished(_: int, __: Any) -> None:
        done[0] += 1
        if on_done is not None:
            on_done(done[0], len(tasks))

    t0 = time.perf_counter()
    replicates = run_tasks(run_replicate, tasks, workers=workers, scheduler=scheduler,
                           pool=pool, on_done=finished)
    runtime = time.perf_counter() - t0
    parameters, correlation = summarise(problem, replicates, spec.confidence, obs.n)
    stops = np.asarray(replicates[0]["stops"])
    return CalibrationResult(
        project=project, problem=problem, observations=obs, parameters=parameters,
        correlation=correlation, replicates=replicates,
        fit=fit_statistics(obs.x, stops, spec.distance, problem.x_range),
        levels=level_shares(obs.x, stops, spec.levels, spec.confidence),
        simulated=stops, seed=run_seed, confidence=spec.confidence, sizes=sizes,
        runtime_s=runtime,
    )


def run_comparison(
    project: Project,
    observed: str | os.PathLike[str],
    *,
    rocks: int | None = None,
    seed: int | None = None,
    levels: Mapping[str, tuple[float, float]] | None = None,
    confidence: float = 0.95,
    kind: str = "energy",
) -> ComparisonResult:
    """How well ``project`` as it is predicts the observed stops in ``observed``.

    The project's rocks take the observed blocks' sizes where the file gives
    them (as a calibration does); nothing is fitted.

    Parameters
    ----------
    project
        A validated project (e.g. a calibration's ``calibrated.yaml``).
    observed
        The file of observed stops.
    rocks, seed
        Simulated rocks and their seed (default ``rocks.count``, ``rocks.seed``).
    levels
        Name -> (from, to) (m) compared as shares (default: the project's
        ``calibrate.levels``, if any).
    confidence
        Of the observed shares' Wilson intervals.
    kind
        The distance reported.
    """
    from .fit import problem_for, simulated_stops

    obs = _observations(project, observed)
    if levels is None:
        levels = project.calibrate.levels if project.calibrate is not None else {}
    n = int(project.rocks.count if rocks is None else rocks)
    s = int(project.rocks.seed if seed is None else seed)
    sizes = size_distribution(obs)
    problem = problem_for(project, {}, levels=levels, rocks=n, kind=kind, sizes=sizes)
    stops = simulated_stops(problem, {}, s)
    return ComparisonResult(
        project=project, observations=obs,
        fit=fit_statistics(obs.x, stops, kind, problem.x_range),
        levels=level_shares(obs.x, stops, problem.levels, confidence),
        simulated=stops, seed=s, rocks=n, sizes=sizes,
    )

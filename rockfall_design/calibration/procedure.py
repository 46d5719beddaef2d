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
from dataclasses import replace
from typing import Any

import numpy as np

from ..project import Project
from ..project.calibrate import auto_fit_ranges
from ..studies.executors import run_tasks
from .calibration_result import CalibrationResult, ComparisonResult
from .distances import fit_statistics, level_shares
from .fit import FitProblem, problem_for, simulated_sets, simulated_stops
from .observations import (
    Observations,
    read_observations,
    size_distribution,
    size_limits,
)
from .screen import Screened
from .screen import screen as screen_inputs
from .sets import Site, profile_sizes, read_site
from .terms import SetStatistics, set_statistics
from .uncertainty import ReplicateTask, run_replicate, summarise

__all__ = ["run_calibration", "run_comparison"]


def _observations(project: Project, path: str | os.PathLike[str]) -> Observations:
    """The observed stops of ``path``, checked on the project's section."""
    return read_observations(path, project.slope.x_range, size_limits(project.rocks.density))


def fit_ranges(project: Project, site: Site) -> dict[str, tuple[float, float]]:
    """The inputs fitted: ``calibrate.fit``; with ``fit: auto`` and profiles, theirs too.

    ``fit: auto`` fits the calibrated parameters of every material on every
    section of the site (the project's material of a name where several
    define it, as the profiles run them).
    """
    spec = project.calibrate
    assert spec is not None
    if not (spec.auto and site.profiles):
        return dict(spec.fit)
    materials = dict(project.materials)
    names = list(project.slope.materials)
    for other in site.profiles.values():
        for name, m in other.materials.items():
            materials.setdefault(name, m)
        names += list(other.slope.materials)
    try:
        return auto_fit_ranges(materials, names)
    except ValueError as exc:
        raise project.error_at(("calibrate", "fit"), str(exc)) from None


def _load_on_this_thread(problem: Any) -> None:
    """Import the search's scipy modules and load the engine here, before the pool starts.

    On a pool's threads the first replicates would do it (scipy.optimize and
    scipy.stats take 2 to 12 s to import on a loaded machine, numba's cached
    engine about 1 s to load), and a thread cannot be stopped in the middle:
    Ctrl-C then waited for them. On the caller's thread the interrupt stops
    it at once, and the replicates start evaluating, where they check it.
    """
    import scipy.optimize  # noqa: F401 - loaded for the replicates
    import scipy.stats.qmc  # noqa: F401


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
    prior: bool | None = None,
    screen: bool | None = None,
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
    prior, screen
        A fit regularised by each input's value and range (:mod:`.prior`),
        and the inputs that move the criterion by less than its noise left
        out (:mod:`.screen`). None: with ``fit: auto``; False: neither (the
        criterion alone, as before); True: also for a listed ``fit:``.

    Raises
    ------
    ProjectError
        No ``calibrate:`` section, a bad observation file, a path that is
        not an input, or a range end that is not a valid value.
    """
    spec = project.calibrate
    if spec is None:
        raise project.error_at((), "the project has no calibrate: section (the observed stops "
                               "and the inputs to fit; see docs/calibration.md)")
    site = read_site(project, observed)
    obs = site.main_observations
    n_boot = int(spec.bootstrap if bootstrap is None else bootstrap)
    run_seed = int(project.rocks.seed if seed is None else seed)
    sizes = profile_sizes(site.sets, "")
    problem, data, screened = _prepared(project, site, int(spec.rocks if rocks is None
                                                           else rocks), run_seed, prior, screen)
    tasks = [ReplicateTask(problem, data, b, run_seed) for b in range(n_boot + 1)]
    done = [0]

    def finished(_: int, __: Any) -> None:
        done[0] += 1
        if on_done is not None:
            on_done(done[0], len(tasks))

    t0 = time.perf_counter()
    replicates = run_tasks(run_replicate, tasks, workers=workers, scheduler=scheduler,
                           pool=pool, on_done=finished)
    runtime = time.perf_counter() - t0
    # The expanded interval's n: the smallest set's (the widest correction).
    parameters, correlation = summarise(problem, replicates, spec.confidence,
                                        min(s.n for s in site.sets))
    stops = np.asarray(replicates[0].stops)
    simulated = replicates[0].simulated or [stops]
    return CalibrationResult(
        project=project, problem=problem, observations=obs, parameters=parameters,
        correlation=correlation, replicates=replicates,
        fit=fit_statistics(obs.x, stops, spec.distance, problem.x_range),
        levels=level_shares(obs.x, stops, site.main_stops.levels, spec.confidence),
        simulated=stops, seed=run_seed, confidence=spec.confidence, sizes=sizes,
        runtime_s=runtime,
        sets=_statistics(problem, site, simulated, spec.confidence), screened=screened,
    )


def _prepared(project: Project, site: Site, rocks: int, seed: int, prior: bool | None,
              screen: bool | None) -> tuple[FitProblem, Any, list[Screened]]:
    """The fit's problem (screened), the observed data the replicates resample, the screen.

    ``prior`` and ``screen`` as :func:`run_calibration`'s (None: with ``fit: auto``).
    """
    spec = project.calibrate
    assert spec is not None
    problem = problem_for(project, fit_ranges(project, site), levels=site.main_stops.levels,
                          rocks=rocks, kind=spec.distance, sizes=profile_sizes(site.sets, ""),
                          sets=site.sets, profiles=site.profiles,
                          prior=spec.auto if prior is None else prior)
    _load_on_this_thread(problem)
    data = site.main_observations.x if not problem.terms \
        else tuple(s.values for s in site.sets)
    problem, screened = _screened(problem, data, seed,
                                  bool(problem.prior) if screen is None else screen)
    return problem, data, screened


def _screened(problem: FitProblem, data: Any, seed: int, on: bool
              ) -> tuple[FitProblem, list[Screened]]:
    """The problem without the inputs the screen leaves out (:func:`~.screen.screen`).

    Off, or without a prior (whose modes the screen starts from): the problem
    as it is and no screen.
    """
    if not on or not problem.prior:
        return problem, []
    screened = screen_inputs(problem, data, seed)
    keep = [j for j, s in enumerate(screened) if s.kept]
    if len(keep) == problem.dimension:
        return problem, screened
    return replace(problem, paths=tuple(problem.paths[j] for j in keep),
                   low=tuple(problem.low[j] for j in keep),
                   high=tuple(problem.high[j] for j in keep),
                   prior=tuple(problem.prior[j] for j in keep)), screened


def _statistics(problem: Any, site: Site, simulated: list[Any], confidence: float
                ) -> list[SetStatistics]:
    """Each observation set's statistics (:func:`~.terms.set_statistics`); [] for one file."""
    if not problem.terms:
        return []
    ranges = {"": problem.x_range, **{o.name: o.x_range for o in problem.others}}
    return set_statistics(site.sets, [np.asarray(v) for v in simulated], problem.kind,
                          confidence, ranges, problem.rocks)


def run_comparison(
    project: Project,
    observed: str | os.PathLike[str] | None,
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
        The file of observed stops; None: every observation set of the
        project's ``calibrate:`` section (each kind, each profile), each
        reported on its own.
    rocks, seed
        Simulated rocks and their seed (default ``rocks.count``, ``rocks.seed``).
    levels
        Name -> (from, to) (m) compared as shares (default: the project's
        ``calibrate.levels``, if any).
    confidence
        Of the observed shares' Wilson intervals.
    kind
        The distance reported.

    Raises
    ------
    ProjectError
        No file given and no ``calibrate:`` section; a bad observation file.
    """
    n = int(project.rocks.count if rocks is None else rocks)
    s = int(project.rocks.seed if seed is None else seed)
    if observed is None:
        if project.calibrate is None:
            raise project.error_at((), "compare needs --observed, or a calibrate: section "
                                   "whose observed: sets it compares")
        site = read_site(project)
        main, obs = site.main_stops, site.main_observations
        sizes = profile_sizes(site.sets, "")
        problem = problem_for(project, {}, levels=main.levels, rocks=n, kind=kind,
                              sizes=sizes, sets=site.sets, profiles=site.profiles)
        simulated = simulated_sets(problem, {}, s)
        first = next(i for i, t in enumerate(problem.all_terms)
                     if t.kind == "stops" and t.run == 0)
        stops = simulated[first]
        sets = _statistics(problem, site, simulated, confidence)
    else:
        obs = _observations(project, observed)
        if levels is None:
            levels = project.calibrate.levels if project.calibrate is not None else {}
        sizes = size_distribution(obs)
        problem = problem_for(project, {}, levels=levels, rocks=n, kind=kind, sizes=sizes)
        stops = simulated_stops(problem, {}, s)
        sets = []
    return ComparisonResult(
        project=project, observations=obs,
        fit=fit_statistics(obs.x, stops, kind, problem.x_range),
        levels=level_shares(obs.x, stops, problem.levels, confidence),
        simulated=stops, seed=s, rocks=n, sizes=sizes, sets=sets,
    )

"""Fit: the parameter vector whose simulated stops are nearest the observed ones.

One evaluation sets the fitted inputs of the project by their paths
(:func:`~rockfall_design.studies.paths.with_values`, so every rule of the
project file applies to a tried value), runs the engine on the bare slope
and measures the distance of its stops from the observed ones
(:func:`~.distances.objective`).

Common random numbers: every evaluation of one fit runs the same rocks
(the same seed: the same sizes, releases and per-impact draws), so the
objective changes with the parameters alone and is a deterministic,
nearly smooth function of them, which a direct search can minimise. The
search is global first (a Latin hypercube over the ranges), then local
(Nelder-Mead from the best point of the hypercube), both in the unit cube
of the ranges.

References
----------
Kleijnen, J. P. C. (2015). Design and Analysis of Simulation Experiments,
2nd ed., Springer, ch. 3 (common random numbers).
Nelder, J. A., Mead, R. (1965). A simplex method for function minimization.
Comput. J. 7, 308-313.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..errors import ProjectError
from ..project import Project
from ..studies.executors import stop_if_cancelled
from ..studies.paths import with_values
from .distances import objective, spread, stop_positions

__all__ = ["FitOutcome", "FitProblem", "fit", "minimise", "problem_for", "simulated_stops"]

#: Points of the global stage per fitted input (at least MIN_DESIGN in all).
DESIGN_PER_INPUT = 16
MIN_DESIGN = 16
#: Local searches, from the best points of the global stage that lie apart.
STARTS = 2
#: The global stage runs this share of the rocks (at least COARSE_ROCKS).
COARSE_SHARE = 0.25
COARSE_ROCKS = 100
#: Evaluations of the local stage per fitted input (plus a fixed 20).
LOCAL_PER_INPUT = 25
#: The local stage stops when the simplex is this small (share of each range).
X_TOLERANCE = 2e-3


@dataclass(frozen=True)
class FitProblem:
    """What one fit needs (picklable: it is sent to a pool's or a cluster's workers).

    Attributes
    ----------
    project : Project
        The project the values are set in (no study or calibrate section,
        the observed sizes already set), to validate each tried vector.
    base : dict
        Its resolved data (:func:`~rockfall_design.studies.paths.with_values`'s base).
    paths : tuple of str
        The fitted inputs.
    low, high : tuple of float
        Their ranges.
    levels : dict
        Name -> (from, to) (m) of the levels compared as shares.
    rocks : int
        Simulated rocks per evaluation.
    kind : str
        ``"energy"`` or ``"wasserstein"``.
    x_range : tuple of float
        First and last station of the section (m).
    """

    project: Project
    base: dict[str, Any]
    paths: tuple[str, ...]
    low: tuple[float, ...]
    high: tuple[float, ...]
    levels: dict[str, tuple[float, float]] = field(default_factory=dict)
    rocks: int = 1000
    kind: str = "energy"
    x_range: tuple[float, float] = (0.0, 1.0)

    @property
    def dimension(self) -> int:
        return len(self.paths)

    def values(self, u: Sequence[float]) -> dict[str, float]:
        """Path -> value of the point ``u`` of the unit cube of the ranges."""
        lo, hi = np.asarray(self.low), np.asarray(self.high)
        theta = lo + np.clip(np.asarray(u, dtype=float), 0.0, 1.0) * (hi - lo)
        return {p: float(v) for p, v in zip(self.paths, theta, strict=True)}


def _base(project: Project, sizes: Mapping[str, Any] | None) -> dict[str, Any]:
    """The resolved data every evaluation starts from: no study, no calibration."""
    base = project.resolved_dict()
    base.pop("study", None)
    base.pop("calibrate", None)
    if isinstance(base.get("design"), dict):
        base["design"].pop("scenarios", None)
    if sizes:
        base["rocks"].update({"radius": None, "volume": None, "mass": None, **sizes})
    return base


def problem_for(project: Project, fit_ranges: Mapping[str, tuple[float, float]], *,
                levels: Mapping[str, tuple[float, float]] | None = None, rocks: int = 1000,
                kind: str = "energy", sizes: Mapping[str, Any] | None = None,
                at: tuple = ("calibrate", "fit")) -> FitProblem:
    """The fit of ``project``'s inputs at ``fit_ranges``, each range's ends checked.

    Parameters
    ----------
    project
        A validated project.
    fit_ranges
        Path -> (lo, hi).
    levels
        Name -> (from, to) (m).
    rocks
        Simulated rocks per evaluation.
    kind
        The distance (:func:`~.distances.distance`).
    sizes
        The rock size fitted to the observed blocks
        (:func:`~.observations.size_distribution`), or None to keep the project's.
    at
        Key path of the fitted ranges in the project file, for messages.

    Raises
    ------
    ProjectError
        A path names no input, or an end of its range is not a valid value
        there, located at ``calibrate.fit.<path>``; or a level outside the section.
    """
    base = _base(project, sizes)
    first, last = project.slope.x_range
    for name, (lo, hi) in (levels or {}).items():
        if hi <= first or lo >= last:
            raise project.error_at(("calibrate", "levels", name),
                                   f"level [{lo:g}, {hi:g}] lies outside the slope section "
                                   f"[{first:g}, {last:g}] m")
    try:
        plain = with_values(project, {}, base=base)
    except ProjectError as exc:  # the observed sizes do not fit the project
        raise project.error_at(("calibrate", "observed"), f"the observed sizes: {exc.message}"
                               ) from None
    for path, ends in fit_ranges.items():
        for value in ends:
            try:
                with_values(plain, {path: float(value)}, base=base)
            except ProjectError as exc:
                raise project.error_at((*at, path), exc.message) from None
    plain._plan = None  # a worker needs the data alone
    return FitProblem(
        project=plain, base=base, paths=tuple(fit_ranges),
        low=tuple(float(lo) for lo, _ in fit_ranges.values()),
        high=tuple(float(hi) for _, hi in fit_ranges.values()),
        levels={str(k): (float(a), float(b)) for k, (a, b) in (levels or {}).items()},
        rocks=int(rocks), kind=kind, x_range=(float(first), float(last)),
    )


def simulated_stops(problem: FitProblem, values: Mapping[str, float], seed: int
                    ) -> np.ndarray:
    """Stop stations (m) of ``problem.rocks`` rocks with the inputs set to ``values``."""
    from ..run.simulation import run_study

    # A replicate on a pool's thread stops here, or between batches, once its
    # calibration is given up (Ctrl-C): a thread cannot be stopped from outside.
    stop_if_cancelled()
    project = with_values(problem.project, values, base=problem.base)
    run = run_study(project, rocks=problem.rocks, seed=seed,
                    progress=lambda _done: stop_if_cancelled()).result
    return stop_positions(run.x_end, run.status, problem.x_range)


@dataclass(frozen=True)
class FitOutcome:
    """The best point of one fit.

    Attributes
    ----------
    values : dict
        Path -> fitted value.
    objective : float
        The objective there (-).
    evaluations : int
        Engine runs the fit took (those of the global stage with fewer rocks).
    stops : ndarray
        The simulated stops at the best point (m).
    """

    values: dict[str, float]
    objective: float
    evaluations: int
    stops: np.ndarray


def minimise(f: Callable[[np.ndarray, bool], float], dimension: int, seed: int
             ) -> tuple[np.ndarray, float]:
    """Minimise ``f`` over the unit cube: a Latin hypercube, then Nelder-Mead from its best.

    Parameters
    ----------
    f
        The objective of a point of [0, 1]**dimension; ``f(u, True)`` a
        cheaper, coarser estimate of it (fewer rocks) for the global stage.
    dimension
        Number of inputs.
    seed
        Seed of the hypercube.

    Returns
    -------
    (u, value)
        The best point found and its (full) objective.

    Notes
    -----
    The objective of stop positions over restitution and rolling resistance
    has long curved valleys (the two trade off) and may have a second basin
    (rocks held on a bench, or not), so the local search starts from the
    :data:`STARTS` best points of the hypercube that lie apart.
    """
    from scipy.optimize import minimize
    from scipy.stats.qmc import LatinHypercube

    n0 = max(MIN_DESIGN, DESIGN_PER_INPUT * dimension)
    design = LatinHypercube(d=dimension, seed=np.random.default_rng(seed)).random(n0)
    coarse = np.array([f(u, True) for u in design])
    starts: list[np.ndarray] = []
    for i in np.argsort(coarse, kind="stable"):
        if all(np.max(np.abs(design[i] - s)) > 0.2 for s in starts):
            starts.append(design[i])
        if len(starts) == STARTS:
            break
    best_u, best = starts[0], np.inf
    for start in starts:
        # The first simplex reaches a tenth of each range, towards the inside.
        step = np.where(start < 0.5, 0.1, -0.1)
        simplex = np.vstack([start] + [start + step * np.eye(dimension)[i]
                                       for i in range(dimension)])
        local = minimize(lambda u: f(u, False), start, method="Nelder-Mead",
                         bounds=[(0.0, 1.0)] * dimension,
                         options={"initial_simplex": simplex, "xatol": X_TOLERANCE,
                                  "fatol": 1e-6, "maxfev": LOCAL_PER_INPUT * dimension + 20})
        if local.fun < best:
            best_u, best = np.clip(local.x, 0.0, 1.0), float(local.fun)
    return best_u, best


def fit(problem: FitProblem, observed: np.ndarray, seed: int) -> FitOutcome:
    """Fit the problem's inputs to ``observed`` stops, every evaluation with rocks ``seed``.

    Parameters
    ----------
    problem
        From :func:`problem_for`.
    observed
        Observed stop stations (m).
    seed
        The rock seed of every evaluation (common random numbers) and of the
        global stage's hypercube.
    """
    scale = spread(observed)
    seen: dict[tuple[float, ...], tuple[float, np.ndarray]] = {}
    few = replace(problem, rocks=min(problem.rocks,
                                     max(COARSE_ROCKS, int(COARSE_SHARE * problem.rocks))))
    runs = [0]

    def evaluate(u: np.ndarray, coarse: bool = False) -> float:
        key = tuple(np.round(np.clip(u, 0.0, 1.0), 12))
        if coarse:
            runs[0] += 1
            stops = simulated_stops(few, problem.values(key), seed)
            return objective(observed, stops, problem.levels, problem.kind, scale)
        if key not in seen:
            runs[0] += 1
            stops = simulated_stops(problem, problem.values(key), seed)
            seen[key] = (objective(observed, stops, problem.levels, problem.kind, scale), stops)
        return seen[key][0]

    u, _ = minimise(evaluate, problem.dimension, seed)
    key = tuple(np.round(np.clip(u, 0.0, 1.0), 12))
    evaluate(u)
    return FitOutcome(problem.values(key), seen[key][0], runs[0], seen[key][1])

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
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import ProjectError
from ..project import Project
from ..run.simulation import run_in_memory
from ..studies.executors import stop_if_cancelled
from ..studies.paths import with_values
from ..studies.sampling import scenario_seed
from .distances import objective, stop_positions
from .prior import (
    criterion_noise,
    posterior_shares,
    prior_centres,
    prior_penalty,
    prior_sds,
)
from .sets import profile_sizes, site_materials
from .terms import ProfileRun, Term, scales_of, sets_objective, terms_for

if TYPE_CHECKING:  # pragma: no cover
    from .sets import ObservationSet

__all__ = ["FitOutcome", "FitProblem", "criterion_for", "fit", "minimise", "problem_for",
           "simulated_sets", "simulated_stops"]

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
#: The rock seed of profile k (k >= 1) of a run with seed s is
#: ``scenario_seed(s, PROFILE_SEED + k)``: its own stream, apart from the
#: bootstrap replicates' (``scenario_seed(s, b)`` with b <= 2,000).
PROFILE_SEED = 100_000


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
    terms : tuple of Term
        One per observation set (:mod:`.terms`); empty for the single-file form,
        whose one term is the stops on this section with ``levels`` (as before
        sets existed, to the bit).
    others : tuple of ProfileRun
        The other profiles of the site (runs 1, 2, ...).
    run_base : dict or None
        ``base`` with the observation stations this section records (None: ``base``).
    prior : tuple of float
        Each input's prior mode (its class's value, :mod:`.prior`): the fit is
        then regularised (maximum a posteriori); empty: the criterion alone,
        the ranges only as bounds.
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
    terms: tuple[Term, ...] = ()
    others: tuple[ProfileRun, ...] = ()
    run_base: dict[str, Any] | None = None
    prior: tuple[float, ...] = ()

    @property
    def dimension(self) -> int:
        return len(self.paths)

    @property
    def all_terms(self) -> tuple[Term, ...]:
        """The terms of the objective (the single-file form's one term of stops)."""
        return self.terms or (Term("stops", levels=dict(self.levels)),)

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


def _with_stations(base: dict[str, Any], stations: Sequence[float]) -> dict[str, Any]:
    """``base`` whose runs record the passages at ``stations`` (m), nothing else changed."""
    return {**base, "analysis": {**base["analysis"], "stations": [float(x) for x in stations]}}


def _check_ends(plain: Project, base: dict[str, Any], fit_ranges: Mapping[str, Any],
                located: Callable[[str, str], ProjectError], materials_only: bool = False
                ) -> None:
    """Each end of each fitted range is a valid value of ``plain`` (else ``located``'s error)."""
    for path, ends in fit_ranges.items():
        if materials_only and not path.startswith("materials."):
            continue
        for value in ends:
            try:
                with_values(plain, {path: float(value)}, base=base)
            except ProjectError as exc:
                raise located(path, exc.message) from None


def _profile_runs(project: Project, sets: Sequence[ObservationSet],
                  profiles: Mapping[str, Project], fit_ranges: Mapping[str, Any],
                  materials: dict[str, Any], stations: Sequence[Sequence[float]]
                  ) -> tuple[ProfileRun, ...]:
    """The other profiles as every evaluation runs them: the site's materials, their stations."""
    runs = []
    for k, (name, other) in enumerate(profiles.items(), start=1):
        sizes = profile_sizes(sets, name)
        base = _base(other, sizes)
        base["materials"] = {**base["materials"], **materials}
        try:
            plain = with_values(other, {}, base=base)
        except ProjectError as exc:
            raise project.error_at(("calibrate", "profiles", name), f"profile {name} with the "
                                   f"site's materials and observed sizes: {exc.message}"
                                   ) from None
        _check_ends(plain, base, fit_ranges, lambda path, m, name=name: project.error_at(
            ("calibrate", "fit", path), f"on profile {name}: {m}"), materials_only=True)
        plain._plan = None
        runs.append(ProfileRun(name, plain, _with_stations(base, stations[k]),
                               tuple(map(float, other.slope.x_range)), sizes))
    return tuple(runs)


def problem_for(project: Project, fit_ranges: Mapping[str, tuple[float, float]], *,
                levels: Mapping[str, tuple[float, float]] | None = None, rocks: int = 1000,
                kind: str = "energy", sizes: Mapping[str, Any] | None = None,
                at: tuple = ("calibrate", "fit"), sets: Sequence[ObservationSet] | None = None,
                profiles: Mapping[str, Project] | None = None, prior: bool = False
                ) -> FitProblem:
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
    sets, profiles
        The observation sets and the profiles they lie on (:func:`~.sets.read_site`):
        one term of the objective per set, the profiles run with the site's
        materials (:func:`~.sets.site_materials`). None (or the single-file
        form): the stops on this section alone, with ``levels``.
    prior
        Regularise the fit by each input's value in the project as the prior's
        mode and its range as the prior's ±2 sd (:mod:`.prior`).

    Raises
    ------
    ProjectError
        A path names no input, or an end of its range is not a valid value
        there, located at ``calibrate.fit.<path>``; or a level outside the section.
    """
    base = _base(project, sizes)
    profiles = dict(profiles or {})
    if profiles:  # one table of materials for the site, written to calibrated.yaml too
        base["materials"] = site_materials(project, profiles)
    first, last = project.slope.x_range
    _check_levels(project, levels, sets, profiles)
    try:
        plain = with_values(project, {}, base=base)
    except ProjectError as exc:  # the observed sizes do not fit the project
        raise project.error_at(("calibrate", "observed"), f"the observed sizes: {exc.message}"
                               ) from None
    _check_ends(plain, base, fit_ranges, lambda path, m: project.error_at((*at, path), m))
    plain._plan = None  # a worker needs the data alone
    terms: tuple[Term, ...] = ()
    others: tuple[ProfileRun, ...] = ()
    run_base = None
    if sets is not None and not (len(sets) == 1 and not profiles and sets[0].weight == 1.0):
        terms, stations = terms_for(sets, ["", *profiles])
        others = _profile_runs(project, sets, profiles, fit_ranges, base["materials"],
                               stations)
        run_base = _with_stations(base, stations[0]) if stations[0] else None
    return FitProblem(
        project=plain, base=base, paths=tuple(fit_ranges),
        low=tuple(float(lo) for lo, _ in fit_ranges.values()),
        high=tuple(float(hi) for _, hi in fit_ranges.values()),
        levels={str(k): (float(a), float(b)) for k, (a, b) in (levels or {}).items()},
        rocks=int(rocks), kind=kind, x_range=(float(first), float(last)),
        terms=terms, others=others, run_base=run_base,
        prior=_prior(project, base, fit_ranges, at) if prior else (),
    )


def _prior(project: Project, base: dict[str, Any],
           fit_ranges: Mapping[str, tuple[float, float]], at: tuple) -> tuple[float, ...]:
    """The prior's modes (:func:`~.prior.prior_centres`), or one line at ``at``."""
    try:
        return prior_centres(base, fit_ranges)
    except ValueError as exc:
        raise project.error_at(at, str(exc)) from None


def _check_levels(project: Project, levels: Mapping[str, tuple[float, float]] | None,
                  sets: Sequence[ObservationSet] | None, profiles: Mapping[str, Project]
                  ) -> None:
    """Every level lies (at least in part) on its section, else one line at its key.

    Without sets, ``levels`` at ``calibrate.levels``; with sets, each set of
    stops' levels, at its own ``levels:`` or, where it takes the section's,
    at ``calibrate.levels``.
    """
    todo = [] if sets else [(("calibrate", "levels"), levels or {}, project)]
    entries = project.calibrate.entries if sets and project.calibrate is not None else []
    for i, s in enumerate(sets or []):
        if s.kind == "stops":
            own = i < len(entries) and entries[i].levels is not None
            todo.append((("calibrate", "observed", i, "levels") if own else
                         ("calibrate", "levels"), s.levels,
                         profiles[s.profile] if s.profile else project))
    for at, spans, on in todo:
        first, last = on.slope.x_range
        for name, (lo, hi) in spans.items():
            if hi <= first or lo >= last:
                raise project.error_at((*at, name), f"level [{lo:g}, {hi:g}] lies outside "
                                       f"the slope section [{first:g}, {last:g}] m")


def simulated_stops(problem: FitProblem, values: Mapping[str, float], seed: int
                    ) -> np.ndarray:
    """Stop stations (m) of ``problem.rocks`` rocks with the inputs set to ``values``."""
    # A replicate on a pool's thread stops here, or between batches, once its
    # calibration is given up (Ctrl-C): a thread cannot be stopped from outside.
    stop_if_cancelled()
    project = with_values(problem.project, values, base=problem.base)
    run = run_in_memory(project, rocks=problem.rocks, seed=seed,
                        progress=lambda _done: stop_if_cancelled()).result
    return stop_positions(run.x_end, run.status, problem.x_range)


def _run(problem: FitProblem, k: int, values: Mapping[str, float], seed: int) -> Any:
    """Run ``k`` of the problem (0: the project's own section) with ``values`` set."""
    stop_if_cancelled()
    if k == 0:
        project = with_values(problem.project, values, base=problem.run_base or problem.base)
    else:
        other = problem.others[k - 1]
        # Only the ground is shared: another input (a release) is the project's own.
        mine = {p: v for p, v in values.items() if p.startswith("materials.")}
        project = with_values(other.project, mine, base=other.base)
        seed = scenario_seed(int(seed), PROFILE_SEED + k)
    return run_in_memory(project, rocks=problem.rocks, seed=seed,
                         progress=lambda _done: stop_if_cancelled())


def simulated_sets(problem: FitProblem, values: Mapping[str, float], seed: int
                   ) -> list[np.ndarray]:
    """The simulated values of each term of ``problem`` with the inputs at ``values``.

    Each profile that a term needs is run once (``problem.rocks`` rocks;
    the project's own section with ``seed``, profile k with its own seed,
    :data:`PROFILE_SEED`); a term of stops takes its stop stations (m), a
    term of passages the heights or speeds of the rocks that passed its
    station (:mod:`.terms`). The single-file form: its stops alone, as
    :func:`simulated_stops`.
    """
    if not problem.terms:
        return [simulated_stops(problem, values, seed)]
    runs = {k: _run(problem, k, values, seed) for k in sorted({t.run for t in problem.terms})}
    ranges = [problem.x_range, *(o.x_range for o in problem.others)]
    out = []
    for t in problem.terms:
        run = runs[t.run]
        if t.kind == "stops":
            out.append(stop_positions(run.result.x_end, run.result.status, ranges[t.run]))
        else:
            a = run.crossing_arrays()[t.quantity][:, t.station]
            out.append(np.asarray(a[np.isfinite(a)], dtype=float))
    return out


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
        The simulated stops at the best point (m): of the first term (the stops
        on the project's own section, where the single-file form has them).
    simulated : tuple of ndarray
        Each term's simulated values at the best point.
    penalty : float
        The prior's term at the best point, s_D * sum z**2 (-); 0 without a prior.
    noise : float or None
        s_D, the criterion's sampling noise that weighs the prior
        (:func:`~.prior.criterion_noise`); None without a prior.
    prior_shares : tuple of float or None
        Each input's posterior sd over its prior sd (``fit(..., diagnose=True)``
        with a prior), else None.
    """

    values: dict[str, float]
    objective: float
    evaluations: int
    stops: np.ndarray
    simulated: tuple[np.ndarray, ...] = ()
    penalty: float = 0.0
    noise: float | None = None
    prior_shares: tuple[float, ...] | None = None


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


def criterion_for(problem: FitProblem, observed: np.ndarray | Sequence[np.ndarray],
                  seed: int, with_noise: bool = False
                  ) -> tuple[Callable[[Sequence[np.ndarray]], float], float | None]:
    """The criterion D of simulated values against ``observed``, and its noise s_D.

    Parameters
    ----------
    problem
        From :func:`problem_for`.
    observed
        As :func:`fit`'s.
    seed
        Of the noise's draws (:func:`~.prior.criterion_noise`).
    with_noise
        Whether to measure s_D (else None).

    Returns
    -------
    (value, noise)
        ``value(simulated)``: D of :func:`simulated_sets`' output (-); s_D (-) or None.
    """
    sets = [np.asarray(observed, dtype=float)] if isinstance(observed, np.ndarray) \
        else [np.asarray(o, dtype=float) for o in observed]
    terms = problem.all_terms
    scales = scales_of(sets, terms)
    noise = None
    if with_noise:
        noise = criterion_noise(sets, terms, problem.kind, scales, problem.rocks, seed,
                                None if problem.terms else problem.levels)

    def value(sim: Sequence[np.ndarray]) -> float:
        if not problem.terms:  # the single-file form, to the bit as before sets existed
            return objective(sets[0], sim[0], problem.levels, problem.kind, scales[0])
        return sets_objective(sets, sim, terms, problem.kind, scales)

    return value, noise


def fit(problem: FitProblem, observed: np.ndarray | Sequence[np.ndarray], seed: int,
        diagnose: bool = False) -> FitOutcome:
    """Fit the problem's inputs to the observations, every evaluation with rocks ``seed``.

    Parameters
    ----------
    problem
        From :func:`problem_for`.
    observed
        Observed stop stations (m) of the single-file form, or one array per
        term of ``problem.terms`` (stops m, heights m, speeds m/s).
    seed
        The rock seed of every evaluation (common random numbers) and of the
        global stage's hypercube.
    diagnose
        With a prior: also each input's posterior sd over its prior sd
        (:func:`~.prior.posterior_shares`, 1 + 2 d**2 more evaluations).

    Notes
    -----
    With ``problem.prior`` the search minimises the criterion plus the
    prior's term, s_D * sum z**2 (:mod:`.prior`), s_D measured on these
    observations; ``objective`` is the criterion alone at the best point,
    ``penalty`` the prior's term.
    """
    value, noise = criterion_for(problem, observed, seed, with_noise=bool(problem.prior))
    terms = problem.all_terms
    seen: dict[tuple[float, ...], tuple[float, list[np.ndarray]]] = {}
    few = replace(problem, rocks=min(problem.rocks,
                                     max(COARSE_ROCKS, int(COARSE_SHARE * problem.rocks))))
    runs = [0]

    def penalty(key: tuple[float, ...]) -> float:
        if noise is None:
            return 0.0
        theta = [problem.values(key)[p] for p in problem.paths]
        return noise * prior_penalty(theta, problem.prior, problem.low, problem.high)

    def evaluate(u: np.ndarray, coarse: bool = False) -> float:
        key = tuple(np.round(np.clip(u, 0.0, 1.0), 12))
        if coarse:
            runs[0] += 1
            return value(simulated_sets(few, problem.values(key), seed)) + penalty(key)
        return criterion(key) + penalty(key)

    def criterion(key: tuple[float, ...]) -> float:
        if key not in seen:
            runs[0] += 1
            sim = simulated_sets(problem, problem.values(key), seed)
            seen[key] = (value(sim), sim)
        return seen[key][0]

    u, _ = minimise(evaluate, problem.dimension, seed)
    key = tuple(np.round(np.clip(u, 0.0, 1.0), 12))
    evaluate(u)
    best, sim = seen[key]
    shares = None
    if diagnose and noise is not None:
        sd = prior_sds(u, problem.prior, problem.low, problem.high)
        shares = tuple(float(v) for v in posterior_shares(
            lambda x: criterion(tuple(np.round(np.clip(x, 0.0, 1.0), 12))), u, sd, noise))
    main = next(i for i, t in enumerate(terms) if t.kind == "stops" and t.run == 0)
    return FitOutcome(problem.values(key), best, runs[0], sim[main], tuple(sim),
                      penalty=penalty(key), noise=noise, prior_shares=shares)

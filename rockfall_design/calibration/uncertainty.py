"""Uncertainty: how sure a calibration is, from a bootstrap of the observations.

Replicate 0 is the fit itself: the observed stops, every evaluation with
the run's seed. Replicate b = 1..B refits from scratch (global and local
search) to a resample of the observed stops (n drawn with replacement)
with its own simulation seed, so that its spread holds both sources of
error of the fitted value: which blocks happened to be observed, and which
rocks happened to be simulated. The interval of a parameter is the central
share of its B refitted values (the expanded percentile interval, which
widens the plain percentile one for a small number of observations, see
:func:`expanded_tail`); the correlation between parameters is that of the
refitted values.

A parameter the observations cannot pin down lands anywhere in its range
from one replicate to the next (each replicate's global search starts from
its own hypercube): its interval then fills most of the range, and it is
flagged ``identified: false`` rather than given as a value.

Every replicate is an independent task with its own seed, run by
:func:`~rockfall_design.studies.executors.run_tasks`: the numbers are the
same in this process, on a local pool, or on a Dask cluster.

References
----------
Efron, B., Tibshirani, R. J. (1993). An Introduction to the Bootstrap.
Chapman & Hall, ch. 13 (percentile intervals).
Davison, A. C., Hinkley, D. V. (1997). Bootstrap Methods and their
Application. Cambridge University Press, sec. 5.3.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..studies.sampling import scenario_seed
from .fit import FitProblem, fit
from .prior import HELD_BY_PRIOR_SHARE

__all__ = ["IDENTIFIED_SD_SHARE", "INTERVAL", "MIN_INTERVAL_REPLICATES", "FittedParameter",
           "Replicate", "ReplicateTask", "Rounded", "decimals", "expanded_tail", "intervals_flag",
           "replicate_seed", "rounded", "run_replicate", "summarise"]

#: A parameter whose refitted values spread with a standard deviation above
#: this share of its range is reported as not identified by the observations:
#: half the standard deviation of values spread evenly over the range
#: (1 / sqrt(12) of it), which does not depend on how many replicates there are.
IDENTIFIED_SD_SHARE = 0.5 / 12**0.5
#: A best value within this share of its range from an end is "at the bound".
AT_BOUND_SHARE = 0.02
#: Fewest bootstrap replicates whose intervals are given as intervals of the
#: stated confidence. With fewer, the 2.5 % and 97.5 % quantiles of B refits
#: are interpolated between the two most extreme ones (each holds 1/B > 5 %
#: of them), so the interval is about the range of the refits, whose coverage
#: depends on B, not on the confidence; and the standard deviation of the
#: refits, on which ``identified`` rests, is itself uncertain by more than
#: 1/sqrt(2 (B - 1)) = 16 %. Such intervals are flagged as rough
#: (:func:`intervals_flag`), not refused: a quick look with a few replicates
#: stays possible. Efron & Tibshirani (1993, sec. 19.3) ask for B of 1,000 or
#: more for percentile intervals; 20 is the floor below which they are not
#: even rough intervals of the stated confidence.
MIN_INTERVAL_REPLICATES = 20
#: Share of a fitted input's range to which the search pins its best value
#: (as :data:`~.fit.X_TOLERANCE`): the precision of a value without an interval.
SEARCH_PRECISION_SHARE = 2e-3
#: How the intervals are made (``method.interval`` of ``calibrate --json``).
INTERVAL = ("expanded percentile bootstrap (Hesterberg 2015), each replicate refitted with "
            "its own simulation seed")


@dataclass(frozen=True)
class ReplicateTask:
    """One replicate of the bootstrap (picklable).

    Attributes
    ----------
    problem : FitProblem
    observed : ndarray
        The observed stops (m), all of them: the replicate resamples them itself.
    index : int
        0 for the fit itself, 1..B for the bootstrap.
    seed : int
        The calibration's seed.
    """

    problem: FitProblem
    observed: np.ndarray | tuple[np.ndarray, ...]
    index: int
    seed: int


@dataclass(frozen=True)
class Replicate:
    """One fitted replicate of the bootstrap (:func:`run_replicate`).

    Attributes
    ----------
    index : int
        0 for the fit itself, 1..B for the bootstrap.
    seed : int
        The replicate's simulation seed (:func:`replicate_seed`).
    values : dict of str to float
        Fitted input path -> fitted value (the input's unit).
    objective : float
        The distance at the fitted values (m, or m/s for speeds).
    evaluations : int
        Evaluations of the distance the fit made.
    stops : ndarray or None
        Replicate 0 only: its simulated stops (m).
    simulated : list of ndarray or None
        Replicate 0 with observation sets only: each set's simulated values
        (m or m/s).
    penalty : float
        The prior's term at the fitted values (-; :mod:`.prior`); 0 without a prior.
    noise : float or None
        s_D, the criterion's sampling noise that weighed the prior (-); None
        without a prior.
    prior_shares : tuple of float or None
        Replicate 0 with a prior: each input's posterior sd over its prior sd
        (:func:`~.prior.posterior_shares`).
    """

    index: int
    seed: int
    values: dict[str, float]
    objective: float
    evaluations: int
    stops: np.ndarray | None = None
    simulated: list[Any] | None = None
    penalty: float = 0.0
    noise: float | None = None
    prior_shares: tuple[float, ...] | None = None


@dataclass(frozen=True)
class FittedParameter:
    """A fitted input: its best value, its bootstrap interval and its flags (:func:`summarise`).

    Attributes
    ----------
    path : str
        The input, as under ``fit:`` (``materials.scree.restitution``).
    value : float
        Replicate 0's fitted value (the input's unit).
    range : tuple of float
        (lowest, highest) value searched (the input's unit).
    low, high : float or None
        The expanded percentile interval (the input's unit); None without replicates.
    sd : float or None
        Standard deviation of the refitted values (the input's unit).
    width_share : float or None
        Interval width over range width (-).
    identified : bool or None
        False when the refits spread over the range (:data:`IDENTIFIED_SD_SHARE`);
        None without replicates.
    at_bound : str or None
        ``"low"`` or ``"high"``: the best value lies at that end of the range.
    prior_share : float or None
        A regularised fit: the input's posterior sd over its prior sd
        (:func:`~.prior.posterior_shares`); above
        :data:`~.prior.HELD_BY_PRIOR_SHARE` the prior, not the observations,
        holds it (``identified`` False). None without a prior.
    """

    path: str
    value: float
    range: tuple[float, float]
    low: float | None = None
    high: float | None = None
    sd: float | None = None
    width_share: float | None = None
    identified: bool | None = None
    at_bound: str | None = None
    prior_share: float | None = None

    @property
    def held_by_prior(self) -> bool:
        """Whether the prior, not the observations, holds the value (``prior_share``)."""
        return self.prior_share is not None and self.prior_share > HELD_BY_PRIOR_SHARE

    def to_json(self) -> dict[str, Any]:
        """The entry of ``parameters`` in ``calibrate --json`` (``range`` as a list)."""
        return {"path": self.path, "value": self.value, "low": self.low, "high": self.high,
                "sd": self.sd, "range": list(self.range), "width_share": self.width_share,
                "identified": self.identified, "at_bound": self.at_bound,
                "prior_share": self.prior_share}


@dataclass(frozen=True)
class Rounded:
    """A fitted input's value, interval and sd as shown and written (:func:`rounded`).

    Attributes
    ----------
    value : float
        The best value to :func:`decimals` places, kept in range (the input's unit).
    low, high : float or None
        The interval's ends to the same places (the input's unit).
    sd : float or None
        The refits' standard deviation to 2 significant digits (the input's unit).
    """

    value: float
    low: float | None
    high: float | None
    sd: float | None


def replicate_seed(seed: int, index: int) -> int:
    """The simulation seed of replicate ``index`` (the run's own seed for replicate 0)."""
    return int(seed) if index == 0 else scenario_seed(int(seed), int(index))


def run_replicate(task: ReplicateTask) -> Replicate:
    """Fit one replicate: its resample of the observations with its own seed.

    Every observation set is resampled, each on its own: its n values
    drawn with replacement, from a generator of the run's seed, the
    replicate and the set (the first set's draws those of the single-file
    form's).

    Returns
    -------
    Replicate
        Replicate 0 also with ``stops`` (its simulated stops, m) and, with
        observation sets, ``simulated`` (each set's simulated values).
    """
    single = isinstance(task.observed, np.ndarray)
    sets = [np.asarray(task.observed, dtype=float)] if single \
        else [np.asarray(o, dtype=float) for o in task.observed]
    seed = replicate_seed(task.seed, task.index)
    if task.index > 0:
        for j, observed in enumerate(sets):
            key = [int(task.seed), int(task.index)] + ([j] if j else [])
            rng = np.random.default_rng(key)
            sets[j] = rng.choice(observed, size=observed.size, replace=True)
    first = task.index == 0
    out = fit(task.problem, sets[0] if single else sets, seed, diagnose=first)
    return Replicate(index=task.index, seed=seed, values=out.values, objective=out.objective,
                     evaluations=out.evaluations, stops=out.stops if first else None,
                     simulated=list(out.simulated) if first and not single else None,
                     penalty=out.penalty, noise=out.noise, prior_shares=out.prior_shares)


def expanded_tail(confidence: float, n: int) -> float:
    """The tail share of the expanded percentile interval for ``n`` observations.

    The percentile bootstrap of a small sample is too narrow by about the
    factor that separates the plug-in from the unbiased variance and a
    normal from a Student quantile; the expanded percentile interval takes
    its bootstrap quantiles at ``Phi(-sqrt(n / (n - 1)) * t(1 - a/2, n - 1))``
    instead of ``a / 2`` (a = 1 - confidence). For n = 41 at 95 %: 0.0204
    instead of 0.025.

    References
    ----------
    Hesterberg, T. C. (2015). What teachers should know about the bootstrap:
    resampling in the undergraduate statistics curriculum. The American
    Statistician 69(4), 371-386, sec. 4.3.
    """
    from scipy import stats

    alpha = 1.0 - confidence
    if n < 2:
        return alpha / 2
    z = np.sqrt(n / (n - 1)) * stats.t.ppf(1 - alpha / 2, n - 1)
    return float(stats.norm.cdf(-z))


def summarise(problem: FitProblem, replicates: list[Replicate], confidence: float,
              observed: int = 0) -> tuple[list[FittedParameter], np.ndarray | None]:
    """Each parameter's best value, interval and flags; the correlation of the parameters.

    Parameters
    ----------
    problem
        The fit.
    replicates
        :func:`run_replicate`'s results, replicate 0 first.
    confidence
        Two-sided confidence of the intervals.
    observed
        Number of observed blocks (for :func:`expanded_tail`; 0: the plain
        percentile interval).

    Returns
    -------
    (parameters, correlation)
        One :class:`FittedParameter` per fitted input: ``path``, ``value`` (replicate 0's),
        ``low`` and ``high`` (the percentile interval; None without
        replicates), ``sd`` (of the refitted values), ``range``,
        ``width_share`` (interval width / range width), ``identified``
        (False when the refitted values spread over the range, their
        standard deviation above :data:`IDENTIFIED_SD_SHARE` of it: the data
        do not pin it down; None without replicates), ``at_bound`` ("low",
        "high" or None: the best value at an end of the range, which should
        then be widened). ``correlation``: the parameters' correlation
        matrix over the replicates (None with fewer than 3 replicates or
        one parameter).
    """
    best = replicates[0].values
    shares = replicates[0].prior_shares or (None,) * len(problem.paths)
    boot = np.array([[r.values[p] for p in problem.paths] for r in replicates[1:]])
    tail = expanded_tail(confidence, observed) if observed else (1.0 - confidence) / 2
    params = []
    for j, path in enumerate(problem.paths):
        lo, hi = problem.low[j], problem.high[j]
        width = hi - lo
        value = float(best[path])
        near = AT_BOUND_SHARE * width
        at_bound = "low" if value <= lo + near else "high" if value >= hi - near else None
        share = shares[j]
        held = share is not None and share > HELD_BY_PRIOR_SHARE
        entry = FittedParameter(path=path, value=value, range=(lo, hi), at_bound=at_bound,
                                identified=False if held else None, prior_share=share)
        if len(boot) >= 2:
            a, b = np.quantile(boot[:, j], [tail, 1 - tail])
            # The interval holds the best value itself (a percentile interval
            # of a skewed bootstrap may not, with few replicates).
            a, b = min(float(a), value), max(float(b), value)
            sd = float(boot[:, j].std(ddof=1))
            entry = FittedParameter(path=path, value=value, low=a, high=b, sd=sd,
                                    range=(lo, hi), width_share=(b - a) / width,
                                    identified=bool(sd <= IDENTIFIED_SD_SHARE * width
                                                    and not held),
                                    at_bound=at_bound, prior_share=share)
        params.append(entry)
    correlation = None
    if len(boot) >= 3 and len(problem.paths) > 1:
        with np.errstate(invalid="ignore", divide="ignore"):
            correlation = np.corrcoef(boot, rowvar=False)
        correlation = np.where(np.isfinite(correlation), correlation, 0.0)
    return params, correlation


def intervals_flag(replicates: int, confidence: float) -> str | None:
    """Why ``replicates`` bootstrap replicates give no ``confidence`` intervals, or None.

    None for no replicates (no intervals) and for
    :data:`MIN_INTERVAL_REPLICATES` or more.
    """
    if replicates == 0 or replicates >= MIN_INTERVAL_REPLICATES:
        return None
    return (f"rough intervals from only {replicates} bootstrap replicate"
            f"{'s' if replicates != 1 else ''} (fewer than {MIN_INTERVAL_REPLICATES}): about "
            f"the range of the refits, not {100 * confidence:g} % intervals; rerun with "
            f"--bootstrap {MIN_INTERVAL_REPLICATES * 2} or more before using them")


def decimals(parameter: FittedParameter) -> int:
    """The decimal places a fitted value is shown and written with: its interval's precision.

    Two significant digits of the interval's half-width (the last digit
    that the bootstrap still supports); without an interval, the search's
    own resolution (:data:`SEARCH_PRECISION_SHARE` of the range). Never
    fewer than 0.

    Parameters
    ----------
    parameter
        One of :func:`summarise`'s entries (``low``, ``high``, ``range``).

    Notes
    -----
    The usual rule of reporting a measured value to the precision of its
    uncertainty, given with two significant digits (JCGM 100:2008, GUM,
    sec. 7.2.6): more digits are noise, and a 17-digit value read from a
    calibrated project suggests a knowledge of the ground no one has.
    """
    lo, hi = parameter.range
    step = SEARCH_PRECISION_SHARE * (hi - lo)
    if parameter.low is not None and parameter.high is not None \
            and parameter.high > parameter.low:
        step = (parameter.high - parameter.low) / 2
    if not math.isfinite(step) or step <= 0:
        return 6
    return max(0, 1 - math.floor(math.log10(step)))


def rounded(parameter: FittedParameter) -> Rounded:
    """value, low, high to :func:`decimals` (the value kept in range); sd to 2 digits."""
    places = decimals(parameter)
    lo, hi = parameter.range

    def r(v: float | None) -> float | None:
        return None if v is None else round(float(v), places)

    value = min(max(round(float(parameter.value), places), lo), hi)
    sd = parameter.sd
    return Rounded(value=value, low=r(parameter.low), high=r(parameter.high),
                   sd=None if sd is None else float(f"{sd:.2g}"))

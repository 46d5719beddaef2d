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

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..studies.scenarios import scenario_seed
from .fit import FitProblem, fit

__all__ = ["IDENTIFIED_SD_SHARE", "ReplicateTask", "expanded_tail", "replicate_seed",
           "run_replicate", "summarise"]

#: A parameter whose refitted values spread with a standard deviation above
#: this share of its range is reported as not identified by the observations:
#: half the standard deviation of values spread evenly over the range
#: (1 / sqrt(12) of it), which does not depend on how many replicates there are.
IDENTIFIED_SD_SHARE = 0.5 / 12**0.5
#: A best value within this share of its range from an end is "at the bound".
AT_BOUND_SHARE = 0.02


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
    observed: np.ndarray
    index: int
    seed: int


def replicate_seed(seed: int, index: int) -> int:
    """The simulation seed of replicate ``index`` (the run's own seed for replicate 0)."""
    return int(seed) if index == 0 else scenario_seed(int(seed), int(index))


def run_replicate(task: ReplicateTask) -> dict[str, Any]:
    """Fit one replicate: its resample of the observations with its own seed.

    Returns
    -------
    dict
        ``index``, ``seed``, ``values`` (path -> fitted value), ``objective``,
        ``evaluations``; replicate 0 also ``stops`` (its simulated stops, m).
    """
    observed = np.asarray(task.observed, dtype=float)
    seed = replicate_seed(task.seed, task.index)
    if task.index > 0:
        rng = np.random.default_rng([int(task.seed), int(task.index)])
        observed = rng.choice(observed, size=observed.size, replace=True)
    out = fit(task.problem, observed, seed)
    result: dict[str, Any] = {"index": task.index, "seed": seed, "values": out.values,
                              "objective": out.objective, "evaluations": out.evaluations}
    if task.index == 0:
        result["stops"] = out.stops
    return result


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


def summarise(problem: FitProblem, replicates: list[dict[str, Any]], confidence: float,
              observed: int = 0) -> tuple[list[dict[str, Any]], np.ndarray | None]:
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
        One dict per fitted input: ``path``, ``value`` (replicate 0's),
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
    best = replicates[0]["values"]
    boot = np.array([[r["values"][p] for p in problem.paths] for r in replicates[1:]])
    tail = expanded_tail(confidence, observed) if observed else (1.0 - confidence) / 2
    params = []
    for j, path in enumerate(problem.paths):
        lo, hi = problem.low[j], problem.high[j]
        width = hi - lo
        value = float(best[path])
        entry: dict[str, Any] = {"path": path, "value": value, "low": None, "high": None,
                                 "sd": None, "range": [lo, hi], "width_share": None,
                                 "identified": None}
        if len(boot) >= 2:
            a, b = np.quantile(boot[:, j], [tail, 1 - tail])
            # The interval holds the best value itself (a percentile interval
            # of a skewed bootstrap may not, with few replicates).
            a, b = min(float(a), value), max(float(b), value)
            sd = float(boot[:, j].std(ddof=1))
            entry.update(low=a, high=b, sd=sd, width_share=(b - a) / width,
                         identified=bool(sd <= IDENTIFIED_SD_SHARE * width))
        near = AT_BOUND_SHARE * width
        entry["at_bound"] = "low" if value <= lo + near else "high" if value >= hi - near else None
        params.append(entry)
    correlation = None
    if len(boot) >= 3 and len(problem.paths) > 1:
        with np.errstate(invalid="ignore", divide="ignore"):
            correlation = np.corrcoef(boot, rowvar=False)
        correlation = np.where(np.isfinite(correlation), correlation, 0.0)
    return params, correlation

"""Distances: how far simulated stop positions are from observed ones.

Two distributions of stop stations x are compared: the observed blocks
(20 to 200 of them) and the simulated rocks of one parameter vector. The
objective a calibration minimises is dimensionless::

    D(obs, sim) = d(obs, sim)**2 / L  +  sum over levels (p_obs - p_sim)**2

with d the energy distance (or the Wasserstein-1 distance) between the two
samples of x (m), L the spread of the observed stops (m: their
interquartile range, at least 1 m), and p the share of the stops on each
named level (a stretch of x). The energy distance in one dimension is
``sqrt(2 * integral (F - G)**2 dx)``, so ``d**2 / L`` is about twice the mean
squared gap between the two cumulative distributions over the observed
spread: of the same order as a squared share, which the levels add.

A rock that leaves the section (downslope or upslope) counts as stopped at
that end of it: it went at least that far, and the observations, all on
the section, are then far from it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..engine.columns import STOPPED

__all__ = ["FitStatistics", "LevelShare", "SampleStatistics", "SPREAD_FLOOR", "TEST_LEVEL",
           "distance", "fit_statistics", "level_shares", "objective", "spread", "stop_positions",
           "verdict", "wilson_interval"]

#: Significance level of compare's verdict (the two-sample KS test).
TEST_LEVEL = 0.05


def stop_positions(x_end: np.ndarray, status: np.ndarray, x_range: tuple[float, float]
                   ) -> np.ndarray:
    """Stop stations (m) of simulated rocks, a rock that left the section at its end.

    Parameters
    ----------
    x_end, status
        The engine's end x (m) and end state of each rock.
    x_range
        (first, last) station of the section (m).
    """
    x = np.asarray(x_end, dtype=float).copy()
    gone = np.asarray(status) != STOPPED
    mid = 0.5 * (x_range[0] + x_range[1])
    # Leaving downslope: at the last station; upslope: at the first.
    x[gone] = np.where(x[gone] >= mid, x_range[1], x_range[0])
    return np.clip(x, x_range[0], x_range[1])


def distance(observed: np.ndarray, simulated: np.ndarray, kind: str = "energy") -> float:
    """The distance (m) between two samples of stop stations.

    Parameters
    ----------
    observed, simulated
        Stop stations (m).
    kind
        ``"energy"``: the energy distance ``sqrt(2 * integral (F - G)**2 dx)``
        (:func:`scipy.stats.energy_distance`); ``"wasserstein"``: the
        Wasserstein-1 distance ``integral |F - G| dx``
        (:func:`scipy.stats.wasserstein_distance`).

    References
    ----------
    Szekely, G. J., Rizzo, M. L. (2013). Energy statistics: a class of
    statistics based on distances. J. Stat. Plan. Inference 143, 1249-1272.
    """
    from scipy import stats

    if kind == "energy":
        return float(stats.energy_distance(observed, simulated))
    if kind == "wasserstein":
        return float(stats.wasserstein_distance(observed, simulated))
    raise ValueError(f"unknown distance {kind!r}")


#: The smallest scale L of each kind of observation (its unit): a guard against
#: observations that happen to coincide (an interquartile range of 0), of the
#: order of how precisely each is measured in the field: a stop to a metre, a
#: mark's height to 10 cm, a speed from video to 0.5 m/s. ILLUSTRATIVE.
SPREAD_FLOOR = {"stops": 1.0, "passing_heights": 0.1, "speeds": 0.5}


def spread(observed: np.ndarray, floor: float = 1.0) -> float:
    """The observed values' interquartile range, at least ``floor``: the objective's scale.

    For stops (m) the floor is 1 m; other kinds take theirs from :data:`SPREAD_FLOOR`.
    """
    q1, q3 = np.percentile(observed, [25, 75])
    return float(max(q3 - q1, floor))


def shares(x: np.ndarray, levels: Mapping[str, tuple[float, float]]) -> np.ndarray:
    """Share of ``x`` in each level ``[from, to)`` (half-open: a stop on a shared end counts once).

    A simulated rock that left the section is at its last station, so it is
    on no level that ends there.
    """
    n = max(len(x), 1)
    return np.array([np.count_nonzero((x >= lo) & (x < hi)) / n for lo, hi in levels.values()])


def objective(observed: np.ndarray, simulated: np.ndarray,
              levels: Mapping[str, tuple[float, float]], kind: str = "energy",
              scale: float | None = None) -> float:
    """The calibration's dimensionless objective (see the module's docstring).

    Parameters
    ----------
    observed, simulated
        Stop stations (m).
    levels
        Name -> (from, to) (m); may be empty.
    kind
        ``"energy"`` or ``"wasserstein"`` (:func:`distance`).
    scale
        L (m), default :func:`spread` of ``observed``.
    """
    L = spread(observed) if scale is None else scale
    d = distance(observed, simulated, kind)
    value = d * d / L
    if levels:
        value += float(np.sum((shares(observed, levels) - shares(simulated, levels)) ** 2))
    return value


def wilson_interval(k: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Wilson score interval of a share k / n.

    Used for the observed share of a level, where n is a few dozen blocks
    and the share may be near 0 or 1 (the Wald interval fails there).

    References
    ----------
    Wilson, E. B. (1927). Probable inference, the law of succession, and
    statistical inference. J. Am. Stat. Assoc. 22, 209-212.
    """
    from scipy.stats import binomtest

    ci = binomtest(int(k), int(n)).proportion_ci(confidence_level=confidence, method="wilson")
    return float(ci.low), float(ci.high)


@dataclass(frozen=True)
class LevelShare:
    """One level's observed share (with its Wilson interval) and simulated share."""

    name: str
    x: tuple[float, float]
    observed_count: int
    observed_share: float
    low: float
    high: float
    simulated_share: float

    @property
    def consistent(self) -> bool:
        """Whether the simulated share lies in the observed share's interval."""
        return self.low <= self.simulated_share <= self.high

    def as_dict(self) -> dict[str, Any]:
        return {"name": self.name, "x": list(self.x), "observed_count": self.observed_count,
                "observed_share": self.observed_share, "low": self.low, "high": self.high,
                "simulated_share": self.simulated_share, "consistent": self.consistent}


def level_shares(observed: np.ndarray, simulated: np.ndarray,
                 levels: Mapping[str, tuple[float, float]], confidence: float = 0.95
                 ) -> list[LevelShare]:
    """Each level's observed share, its Wilson interval, and the simulated share."""
    obs = shares(observed, levels)
    sim = shares(simulated, levels)
    out = []
    for (name, span), p, q in zip(levels.items(), obs, sim, strict=True):
        k = int(round(p * len(observed)))
        low, high = wilson_interval(k, len(observed), confidence)
        out.append(LevelShare(str(name), (float(span[0]), float(span[1])), k, float(p),
                              low, high, float(q)))
    return out


@dataclass(frozen=True)
class SampleStatistics:
    """Count, mean and percentiles of a sample of stop stations (m; m/s for speeds).

    The ``_m`` of the names is that of ``--json``'s keys, kept for a speed too.
    """

    count: int
    mean_m: float
    p5_m: float
    p25_m: float
    p50_m: float
    p75_m: float
    p95_m: float

    @classmethod
    def of(cls, x: np.ndarray) -> SampleStatistics:
        """The statistics of the values ``x``."""
        p = np.percentile(x, [5, 25, 50, 75, 95])
        return cls(int(x.size), float(x.mean()), *(float(v) for v in p))

    @property
    def row(self) -> tuple[float, ...]:
        """mean, p5, p25, p50, p75, p95: a table's row after the count."""
        return (self.mean_m, self.p5_m, self.p25_m, self.p50_m, self.p75_m, self.p95_m)

    def to_json(self) -> dict[str, Any]:
        """``count``, ``mean_m``, ``p5_m`` .. ``p95_m`` as in ``--json``."""
        return {"count": self.count, "mean_m": self.mean_m, "p5_m": self.p5_m,
                "p25_m": self.p25_m, "p50_m": self.p50_m, "p75_m": self.p75_m,
                "p95_m": self.p95_m}


@dataclass(frozen=True)
class FitStatistics:
    """How well simulated values match observed ones (:func:`fit_statistics`).

    Attributes
    ----------
    distance : float
        The distance of ``distance_kind`` (m; m/s for speeds).
    distance_kind : str
        ``energy`` or ``wasserstein`` (:func:`distance`).
    objective : float
        The objective without levels (:func:`objective`).
    ks_statistic, ks_pvalue : float
        Two-sample Kolmogorov-Smirnov D and p (-).
    observed, simulated : SampleStatistics
    beyond_section : float or None
        Share of the simulated rocks that left the section at its lower end
        (-); None where no section's end applies (a passage's values).
    """

    distance: float
    distance_kind: str
    objective: float
    ks_statistic: float
    ks_pvalue: float
    observed: SampleStatistics
    simulated: SampleStatistics
    beyond_section: float | None = None

    def to_json(self) -> dict[str, Any]:
        """The ``fit`` of ``--json`` (``beyond_section`` only where it applies)."""
        out: dict[str, Any] = {
            "distance": self.distance, "distance_kind": self.distance_kind,
            "objective": self.objective, "ks_statistic": self.ks_statistic,
            "ks_pvalue": self.ks_pvalue, "observed": self.observed.to_json(),
            "simulated": self.simulated.to_json()}
        if self.beyond_section is not None:
            out["beyond_section"] = self.beyond_section
        return out


def fit_statistics(observed: np.ndarray, simulated: np.ndarray, kind: str = "energy",
                   x_range: tuple[float, float] | None = None) -> FitStatistics:
    """How well simulated stops match observed ones, without fitting anything.

    Returns
    -------
    FitStatistics
        ``distance`` (m, of ``kind``), ``distance_kind``, ``objective`` (no
        levels), ``ks_statistic`` and ``ks_pvalue`` (two-sample
        Kolmogorov-Smirnov, :func:`scipy.stats.ks_2samp`), ``observed`` and
        ``simulated`` (:class:`SampleStatistics`), and ``beyond_section``: the share
        of simulated rocks that left the section at its lower end.

    Notes
    -----
    The KS p-value treats both samples as independent draws. After a fit
    it is optimistic (the parameters were chosen to match these data); on
    held-out observations (``compare``) it is a fair test.
    """
    from scipy.stats import ks_2samp

    ks = ks_2samp(observed, simulated)
    return FitStatistics(
        distance=distance(observed, simulated, kind), distance_kind=kind,
        objective=objective(observed, simulated, {}, kind),
        ks_statistic=float(ks.statistic), ks_pvalue=float(ks.pvalue),
        observed=SampleStatistics.of(observed), simulated=SampleStatistics.of(simulated),
        beyond_section=None if x_range is None else float(np.mean(simulated >= x_range[1])))


def verdict(fit: FitStatistics, levels: Sequence[LevelShare], confidence: float = 0.95,
            level: float = TEST_LEVEL) -> tuple[bool, str]:
    """Whether a prediction is consistent with the observed stops, and the line that says so.

    The test is the two-sample Kolmogorov-Smirnov test of the observed and
    simulated stop positions at ``level``: consistent when its p-value is at
    least ``level``. A level whose simulated share lies outside the observed
    share's Wilson interval (at ``confidence``) makes the prediction
    inconsistent too, and is named.

    Parameters
    ----------
    fit
        :func:`fit_statistics`' result (its ``ks_pvalue``).
    levels
        :func:`level_shares`' result.
    confidence, level
        Of the levels' intervals, and of the KS test.

    Returns
    -------
    (consistent, line)

    Notes
    -----
    Consistent means only that the observations cannot tell the prediction
    apart at this level: with few observed blocks the test has little
    power, so the distance and the percentiles say how close the two are.
    After a fit to the same observations the p-value is optimistic.

    References
    ----------
    Hollander, M., Wolfe, D. A., Chicken, E. (2014). Nonparametric
    Statistical Methods, 3rd ed., Wiley, sec. 5.4 (the two-sample
    Kolmogorov-Smirnov test).
    """
    p = float(fit.ks_pvalue)
    ks_ok = p >= level
    outside = [s.name for s in levels if not s.consistent]
    test = (f"two-sample Kolmogorov-Smirnov test at {100 * level:g} %: p = {p:.2g} "
            f"{'>=' if ks_ok else '<'} {level:g}")
    if ks_ok and not outside:
        return True, f"consistent with the observations ({test})"
    why = [test] if not ks_ok else [f"the {test} passes"]
    if outside:
        why.append(f"the simulated share of level{'s' if len(outside) > 1 else ''} "
                   f"{', '.join(outside)} lies outside the observed share's "
                   f"{100 * confidence:g} % interval")
    return False, f"NOT consistent with the observations ({'; '.join(why)})"

"""Sensitivity: which varied input moves each design value, and by how much.

Targets, per scenario (from its run, see :func:`targets`):

- at each analysis station x: the p95 and p99 of the passing height (m) and
  of the total kinetic energy (kJ), named ``x=100 passing_height_m p95``,
  ``x=100 energy_kj p99``, ...;
- at each barrier of the project (fence, wall, boulder row: its station on
  the bare slope) the same four, named ``measures[0] x=120 energy_kj p95``;
- at the protected zone, the fraction of rocks reaching it, ``x=150 residual``: with the
  project's measures in place where it has any (as ``check`` counts it), and then the
  bare slope's beside it, ``x=150 residual, bare slope``.

The effect of an input on a target is a main-effect range: the target's
mean over the scenarios at each level of the input (averaged over the other
inputs), and the effect is the highest of these means less the lowest. In a
grid, the levels are the input's values; in a sampled study a list of values
is categorical too, and a range is cut into equal-width bins (each holding
about the same number of Latin hypercube points). The effect is in the
target's unit; it says how far the design value moves over the input's
range, which is what the engineer designs against.

How sure the effect is: each scenario's design values are Monte Carlo
estimates, so part of an effect may be noise. Every entry carries
``effect_low`` and ``effect_high``, an interval that holds, with the safety
concept's confidence c (``confidence``, default 0.95) and for all inputs of a
target together, for the effect of the true design values (those of
infinitely many rocks) of the study's scenarios; see :func:`effect_interval`
and :func:`joint_bounds`. An entry whose ``effect_low`` is 0 is not resolved
from the Monte Carlo noise: more rocks (or ``seeds: common``) may resolve it.

A sampled study adds variance-based first-order indices from SALib's
RBD-FAST (``S1``, the share of the target's variance explained by the input
alone, with a bootstrap ``S1_conf``), which apply to any sample and are
computed on the study's own Latin hypercube. SALib is imported only then.
Its main-effect range (over the bins of a range) has the interval too; it
bounds the Monte Carlo noise of the sampled scenarios' design values, not
the sampling of the points themselves.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..project.messages import fmt
from ..project.study import Range, StudySpec
from .scenario_result import ScenarioResult

__all__ = ["targets", "sensitivity", "TARGET_STATISTICS", "salib_available", "LADDER",
           "ladder_confidences", "joint_bounds", "effect_interval", "SensitivityEntry",
           "relative_effect", "rank", "JointBounds"]

#: The statistics of passing height and energy that are design values.
TARGET_STATISTICS = ("p95", "p99")

#: Numbers of scenarios k at which a scenario's run bounds its design values for the
#: sensitivity (each side at 1 - (1 - c) / (2k)) when its task does not say how many
#: scenarios its study has (``ScenarioTask.scenarios`` 0; a study's tasks say it, and are
#: bounded at k itself): the study then takes the first k' >= its own (at most 1.5 times
#: it: a slightly wider interval, never a weaker one). The last is above the largest
#: study (``MAX_SCENARIOS``, 10,000).
LADDER = tuple(sorted({2 ** m for m in range(15)} | {3 * 2 ** m for m in range(13)}))
_QUANTITIES = (("passing_height_m", "m"), ("energy_kj", "kJ"))


@dataclass(frozen=True)
class SensitivityEntry:
    """The effect of one varied input on one design value (:func:`sensitivity`).

    Attributes
    ----------
    parameter : str
        The input, as under ``vary:``.
    target : str
        The design value (``x=100 energy_kj p95``, ``x=150 residual``; :func:`targets`).
    effect : float
        ``high - low``, in ``unit``.
    unit : str
        ``m``, ``kJ`` or ``fraction``.
    low, high : float
        The lowest and highest mean of the design value over the input's levels (``unit``).
    effect_low, effect_high : float or None
        The effect's interval at the study's confidence, for all inputs of the
        target together (:func:`effect_interval`); None where a scenario has
        no bound of the target.
    resolved : bool
        ``effect_low > 0``: more than Monte Carlo noise (False without an interval).
    s1, s1_conf : float or None
        RBD-FAST's first-order index and its bootstrap spread (-), for a
        sampled study with SALib; None otherwise (``S1``, ``S1_conf`` in JSON).
    relative_effect : float
        :func:`relative_effect` (-).
    """

    parameter: str
    target: str
    effect: float
    unit: str
    low: float
    high: float
    effect_low: float | None = None
    effect_high: float | None = None
    resolved: bool = False
    s1: float | None = None
    s1_conf: float | None = None
    relative_effect: float = 0.0

    def to_json(self) -> dict[str, Any]:
        """The entry of ``sensitivity`` in ``study --json`` (``S1``, ``S1_conf`` if any)."""
        out: dict[str, Any] = {
            "parameter": self.parameter, "target": self.target, "effect": self.effect,
            "unit": self.unit, "low": self.low, "high": self.high,
            "effect_low": self.effect_low, "effect_high": self.effect_high,
            "resolved": self.resolved}
        if self.s1 is not None:
            out["S1"], out["S1_conf"] = self.s1, self.s1_conf
        out["relative_effect"] = self.relative_effect
        return out


def _value(block: Mapping[str, Any] | None, stat: str) -> float:
    v = None if block is None else block.get(stat)
    return math.nan if v is None else float(v)


def place_names(stations: Sequence[float], barriers: Sequence[tuple[int, str, float]],
                project: Any = None) -> list[tuple[str, float]]:
    """(name, x) of the places of design values: ``x=100`` per station x of ``stations``
    (m: the stations of a summary, of which those of the project's analysis),
    ``measures[0] x=160`` per barrier."""
    own = [float(x) for x in project.analysis.stations] if project is not None else None
    out = [(f"x={fmt(x)}", float(x)) for x in stations if own is None or float(x) in own]
    out += [(f"measures[{i}] x={fmt(x)}", float(x)) for i, _, x in barriers]
    return out


def residual_names(protect: Mapping[str, Any], with_measures: Mapping[str, Any] | None
                   ) -> list[tuple[str, Mapping[str, Any]]]:
    """The residual targets of a scenario: (name, its ``protect``-like block) each.

    ``x=200 residual`` is the residual of the project as it stands: with its
    measures in place where it has any (``protect_with_measures``, as
    ``check`` counts it), else the bare slope's; with measures the bare
    slope's is beside it as ``x=200 residual, bare slope``, labelled so.
    """
    name = f"x={fmt(protect['x'])} residual"
    if with_measures is None:
        return [(name, protect)]
    return [(name, with_measures), (f"{name}, bare slope", protect)]


def targets(results: Sequence[ScenarioResult]) -> dict[str, tuple[str, np.ndarray]]:
    """Target name -> (unit, value per scenario; NaN where a scenario has none).

    Parameters
    ----------
    results
        The scenarios' results (:func:`~.runner.run_scenario`), in scenario order.
    """
    rows: list[dict[str, float]] = []
    units: dict[str, str] = {}
    for result in results:
        row: dict[str, float] = {}
        places = [(f"x={fmt(st['x'])}", st) for st in result.stations]
        places += [(f"measures[{m.index}] x={fmt(m.x)}", m.to_json())
                   for m in result.measures or ()]
        for where, block in places:
            for quantity, unit in _QUANTITIES:
                for stat in TARGET_STATISTICS:
                    name = f"{where} {quantity} {stat}"
                    row[name] = _value(block[quantity], stat)
                    units[name] = unit
        protect = result.protect
        if protect is not None:
            for name, block in residual_names(protect, result.protect_with_measures):
                row[name] = float(block["fraction"])
                units[name] = "fraction"
        rows.append(row)
    names = list(dict.fromkeys(name for row in rows for name in row))
    return {
        name: (units[name], np.array([row.get(name, math.nan) for row in rows], dtype=float))
        for name in names
    }


def ladder_confidences(confidence: float, rungs: Sequence[int] = LADDER) -> list[float]:
    """The one-sided confidence of each side of a scenario's bounds per k of ``rungs``:
    ``1 - (1 - c) / (2k)``, so that its two-sided interval holds at ``1 - (1 - c) / k``."""
    return [1.0 - (1.0 - confidence) / (2 * k) for k in rungs]


@dataclass(frozen=True)
class JointBounds:
    """Per scenario, the interval of each design value that holds for all scenarios at once.

    Attributes
    ----------
    confidence : float
        c, the smallest of the scenarios' (-).
    scenario_confidence : float
        ``1 - (1 - c) / k'``, the two-sided confidence of each scenario's interval (-).
    lower, upper : list of dict of str to float or None
        Per scenario, design value name -> bound (its unit; None where too
        few rocks passed).
    """

    confidence: float
    scenario_confidence: float
    lower: list[dict[str, float | None]]
    upper: list[dict[str, float | None]]


def joint_bounds(results: Sequence[ScenarioResult]) -> JointBounds | None:
    """Per scenario, the interval of each design value that holds for all scenarios at once.

    Parameters
    ----------
    results
        The study's k scenario results (:func:`~.runner.run_scenario`), each with
        its ``bounds`` (``confidence`` c and the ``ladder``).

    Returns
    -------
    JointBounds or None
        ``confidence``: c, the smallest of the scenarios' (all the same unless
        the safety concept's confidence is varied); ``scenario_confidence``:
        ``1 - (1 - c) / k'``, the two-sided confidence of each scenario's
        interval, with ``k'`` = k when the scenarios' bounds were computed
        for k (a study's scenarios are), else the first number of
        :data:`LADDER` not below k;
        ``lower`` and ``upper``: per scenario, name -> bound (None where too
        few rocks passed). None without scenarios or without bounds.

    Notes
    -----
    Bonferroni: each side of each scenario's interval fails with a
    probability of at most ``(1 - c) / (2k')`` (the distribution-free order
    statistic bound of a percentile, Clopper-Pearson for the residual); by
    the union bound over the 2k sides of the k scenarios, all the intervals
    of one design value hold together with a probability of at least
    ``1 - k (1 - c) / k' >= c``, whether the scenarios' rocks are
    independent or common. (Not over several design values together.)
    """
    k = len(results)
    if k == 0:
        return None
    # k itself if every scenario has it (a study's tasks know k), else the
    # first rung of the ladder not below it (a conservative rounding)
    exact = all(k in r.bounds.ladder.scenarios for r in results)
    rung = k if exact else next((n for n in LADDER if n >= k), None)
    if rung is None:
        return None
    confidence = min(float(r.bounds.confidence) for r in results)
    lower, upper = [], []
    for result in results:
        ladder = result.bounds.ladder
        if rung not in ladder.scenarios:
            return None
        at = list(ladder.scenarios).index(rung)
        lower.append({name: v[at] for name, v in ladder.lower.items()})
        upper.append({name: v[at] for name, v in ladder.upper.items()})
    return JointBounds(confidence, 1.0 - (1.0 - confidence) / rung, lower, upper)


def effect_interval(keys: Sequence[Any], lower: Sequence[float | None],
                    upper: Sequence[float | None]) -> tuple[float, float] | None:
    """The interval of a main-effect range from intervals of the scenarios' values.

    Parameters
    ----------
    keys
        Each scenario's level of the input (:func:`_level_keys`).
    lower, upper
        Each scenario's lower and upper bound of the target (its unit); None
        or NaN where it has none.

    Returns
    -------
    (float, float) or None
        ``(effect_low, effect_high)`` with, over the levels' means of the
        bounds ``L_i`` (of ``lower``) and ``U_i`` (of ``upper``),
        ``effect_high = max_i U_i - min_j L_j`` and ``effect_low =
        max(0, max over i != j of L_i - U_j)``. None if a scenario has no
        bound or there are fewer than two levels.

    Notes
    -----
    If every scenario's true value t lies in its interval [l, u], the true
    mean ``m_i`` of level i (the mean of its scenarios' t) lies in
    [L_i, U_i], the means of their bounds (a mean of values each within
    bounds lies within the mean of the bounds). The true effect
    ``max_i m_i - min_j m_j`` is then at most ``max_i U_i - min_j L_j``, and
    at least ``m_i - m_j >= L_i - U_j`` for every pair i != j, and at least
    0. So the interval holds whenever all the scenarios' intervals do: with
    those of :func:`joint_bounds`, at the confidence c.
    """
    lo = np.array([math.nan if v is None else float(v) for v in lower], dtype=float)
    hi = np.array([math.nan if v is None else float(v) for v in upper], dtype=float)
    if lo.size == 0 or not (np.isfinite(lo).all() and np.isfinite(hi).all()):
        return None
    levels = list(dict.fromkeys(keys))
    if len(levels) < 2:
        return None
    at = [np.array([k == key for k in keys]) for key in levels]
    low_means = np.array([lo[m].mean() for m in at])
    high_means = np.array([hi[m].mean() for m in at])
    gaps = low_means[:, None] - high_means[None, :]  # L_i - U_j
    np.fill_diagonal(gaps, -math.inf)
    return max(0.0, float(gaps.max())), float(high_means.max() - low_means.min())


def _level_keys(spec: StudySpec, path: str, values: Sequence[Any]) -> list[Any]:
    """The level of each scenario for input ``path``: its value, or its bin of a range."""
    levels = spec.vary[path]
    if isinstance(levels, Range) and spec.sampled:
        lo, hi = levels.range
        n_bins = max(2, min(5, len(values) // 5))
        return [min(int((v - lo) / (hi - lo) * n_bins), n_bins - 1) for v in values]
    return [json.dumps(v, sort_keys=True) if isinstance(v, dict | list) else v for v in values]


def _main_effect(keys: Sequence[Any], y: np.ndarray) -> tuple[float, float] | None:
    """(lowest, highest) mean of ``y`` over the scenarios at each level; None if < 2 levels."""
    means = []
    for key in dict.fromkeys(keys):
        at = np.array([k == key for k in keys]) & np.isfinite(y)
        if at.any():
            means.append(float(y[at].mean()))
    if len(means) < 2:
        return None
    return min(means), max(means)


def salib_available() -> bool:
    """True if SALib can be imported (the ``study`` extra)."""
    try:
        import SALib  # noqa: F401
    except ImportError:
        return False
    return True


def _indices(spec: StudySpec, points: Sequence[Mapping[str, Any]], y: np.ndarray,
             seed: int) -> dict[str, tuple[float, float]]:
    """Input path -> (S1, S1_conf) of RBD-FAST on the finite values of ``y``."""
    from SALib.analyze import rbd_fast

    paths = list(spec.vary)
    columns, bounds = [], []
    for path in paths:
        levels = spec.vary[path]
        if isinstance(levels, Range):
            columns.append([float(p[path]) for p in points])
            bounds.append(list(levels.range))
        else:  # a categorical input: the index of its value
            keys = [json.dumps(v, sort_keys=True) for v in levels]
            columns.append([float(keys.index(json.dumps(p[path], sort_keys=True)))
                            for p in points])
            bounds.append([0.0, float(max(len(levels) - 1, 1))])
    x = np.array(columns, dtype=float).T
    finite = np.isfinite(y)
    x, yy = x[finite], y[finite]
    if yy.size < 5 or np.ptp(yy) == 0:
        return {}
    problem = {"num_vars": len(paths), "names": paths, "bounds": bounds}
    harmonics = max(1, min(10, (yy.size - 1) // 2))
    with np.errstate(all="ignore"):
        si = rbd_fast.analyze(problem, x, yy, M=harmonics, num_resamples=100, seed=seed)
    return {
        path: (float(si["S1"][k]), float(si["S1_conf"][k]))
        for k, path in enumerate(paths)
        if math.isfinite(float(si["S1"][k]))
    }


def sensitivity(
    spec: StudySpec,
    points: Sequence[Mapping[str, Any]],
    results: Sequence[ScenarioResult],
    *,
    indices: bool | None = None,
) -> list[SensitivityEntry]:
    """The effect of every varied input on every target, largest first.

    Parameters
    ----------
    spec
        The study section.
    points
        Each scenario's values (path -> value), in scenario order.
    results
        Each scenario's result, in the same order.
    indices
        Add SALib's RBD-FAST indices (default: for a sampled study, if
        SALib is installed).

    Returns
    -------
    list of SensitivityEntry
        ``parameter, target, effect, unit, low, high, effect_low,
        effect_high, resolved`` (and ``s1``, ``s1_conf`` with indices),
        ranked by :func:`rank`: grouped by target, the targets by their
        largest ``relative_effect``, each target's inputs by ``effect``,
        largest first (ties: in study order). ``low`` and ``high`` are the lowest and
        highest level means; ``effect`` is ``high - low``, in ``unit``;
        ``relative_effect`` is it relative to the design value's size
        (:func:`relative_effect`, unit-free), by which the design values are
        ranked (:func:`rank`).
        ``effect_low`` and ``effect_high`` bound the effect of the true
        design values at the safety concept's confidence c, for all the
        inputs of a target together (:func:`effect_interval` of the
        scenarios' :func:`joint_bounds`); both None where a scenario has no
        bound of the target (too few rocks passed). ``resolved``:
        ``effect_low > 0``, the effect is more than Monte Carlo noise (False
        where there is no interval).
    """
    if indices is None:
        indices = spec.sampled and salib_available()
    seed = spec.scenarios.seed if spec.sampled else 0  # type: ignore[union-attr]
    joint = joint_bounds(results)
    out = []
    order = {}
    for t, (name, (unit, y)) in enumerate(targets(results).items()):
        s1 = _indices(spec, points, y, seed) if indices else {}
        if joint is None:
            lower: list[float | None] = [None] * len(results)
            upper: list[float | None] = [None] * len(results)
        else:
            lower = [b.get(name) for b in joint.lower]
            upper = [b.get(name) for b in joint.upper]
        for p, path in enumerate(spec.vary):
            order[(name, path)] = (t, p)
            keys = _level_keys(spec, path, [pt[path] for pt in points])
            found = _main_effect(keys, y)
            if found is None:
                continue
            low, high = found
            interval = effect_interval(keys, lower, upper)
            index, spread = s1.get(path, (None, None))
            entry = SensitivityEntry(
                parameter=path, target=name, effect=high - low, unit=unit, low=low, high=high,
                effect_low=None if interval is None else interval[0],
                effect_high=None if interval is None else interval[1],
                resolved=interval is not None and interval[0] > 0, s1=index, s1_conf=spread)
            out.append(dataclasses.replace(entry, relative_effect=relative_effect(entry)))
    return rank(out, order)


def relative_effect(entry: SensitivityEntry) -> float:
    """An effect relative to its design value's size, unit-free (-).

    ``effect / max(|low|, |high|)``: an energy that moves from 400 to 800 kJ
    and a height from 2 to 4 m are both 0.5, whatever their units; 0 where
    the design value is 0 at every level.
    """
    size = max(abs(entry.low), abs(entry.high))
    return float(entry.effect / size) if size > 0 else 0.0


def rank(entries: Sequence[SensitivityEntry],
         order: Mapping[tuple[str, str], tuple[int, int]] | None = None
         ) -> list[SensitivityEntry]:
    """The sensitivity's one order, for ``--json`` and the terminal alike.

    Grouped by design value (target), the groups by their largest
    :func:`relative_effect` (unit-free, so that metres, kilojoules and
    fractions compare), each group by its raw ``effect`` (one unit within a
    group), largest first; ties in the study's order of targets and inputs.
    """
    order = order or {(e.target, e.parameter): (i, i) for i, e in enumerate(entries)}
    groups: dict[str, list[SensitivityEntry]] = {}
    for e in entries:
        groups.setdefault(e.target, []).append(e)
    targets_ranked = sorted(groups, key=lambda t: (-max(relative_effect(e) for e in groups[t]),
                                                   min(order[(e.target, e.parameter)]
                                                       for e in groups[t])))
    return [e for t in targets_ranked
            for e in sorted(groups[t], key=lambda e: (-e.effect, order[(e.target, e.parameter)]))]

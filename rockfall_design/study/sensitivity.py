"""Sensitivity: which varied input moves each design value, and by how much.

Targets, per scenario (from its run, see :func:`targets`):

- at each analysis station x: the p95 and p99 of the passing height (m) and
  of the total kinetic energy (kJ), named ``x=100 passing_height_m p95``,
  ``x=100 energy_kj p99``, ...;
- at each barrier of the project (fence, wall, boulder row: its station on
  the bare slope) the same four, named ``measures[0] x=120 energy_kj p95``;
- at the protected zone, the fraction of rocks reaching it, ``x=150 residual``.

The effect of an input on a target is a main-effect range: the target's
mean over the scenarios at each level of the input (averaged over the other
inputs), and the effect is the highest of these means less the lowest. In a
grid, the levels are the input's values; in a sampled study a list of values
is categorical too, and a range is cut into equal-width bins (each holding
about the same number of Latin hypercube points). The effect is in the
target's unit; it says how far the design value moves over the input's
range, which is what the engineer designs against.

A sampled study adds variance-based first-order indices from SALib's
RBD-FAST (``S1``, the share of the target's variance explained by the input
alone, with a bootstrap ``S1_conf``), which apply to any sample and are
computed on the study's own Latin hypercube. SALib is imported only then.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..project.messages import _fmt
from ..project.study import Range, StudySpec

__all__ = ["targets", "sensitivity", "TARGET_STATISTICS", "salib_available"]

#: The statistics of passing height and energy that are design values.
TARGET_STATISTICS = ("p95", "p99")
_QUANTITIES = (("passing_height_m", "m"), ("energy_kj", "kJ"))


def _value(block: Mapping[str, Any] | None, stat: str) -> float:
    v = None if block is None else block.get(stat)
    return math.nan if v is None else float(v)


def place_names(stations: Sequence[Mapping[str, Any]], barriers: Sequence[tuple[int, str, float]],
                project: Any = None) -> list[tuple[str, float]]:
    """(name, x) of the places of design values: ``x=100`` per station of ``stations``
    (the analysis stations of a summary), ``measures[0] x=160`` per barrier."""
    own = [float(x) for x in project.analysis.stations] if project is not None else None
    out = [(f"x={_fmt(st['x'])}", float(st["x"])) for st in stations
           if own is None or float(st["x"]) in own]
    out += [(f"measures[{i}] x={_fmt(x)}", float(x)) for i, _, x in barriers]
    return out


def targets(results: Sequence[Mapping[str, Any]]) -> dict[str, tuple[str, np.ndarray]]:
    """Target name -> (unit, value per scenario; NaN where a scenario has none).

    Parameters
    ----------
    results
        The scenarios' results (:func:`~.run.run_scenario`), in scenario order.
    """
    rows: list[dict[str, float]] = []
    units: dict[str, str] = {}
    for result in results:
        row: dict[str, float] = {}
        places = [(f"x={_fmt(st['x'])}", st) for st in result["stations"]]
        places += [(f"measures[{m['index']}] x={_fmt(m['x'])}", m)
                   for m in result.get("measures", ())]
        for where, block in places:
            for quantity, unit in _QUANTITIES:
                for stat in TARGET_STATISTICS:
                    name = f"{where} {quantity} {stat}"
                    row[name] = _value(block[quantity], stat)
                    units[name] = unit
        protect = result.get("protect")
        if protect is not None:
            name = f"x={_fmt(protect['x'])} residual"
            row[name] = float(protect["fraction"])
            units[name] = "fraction"
        rows.append(row)
    names = list(dict.fromkeys(name for row in rows for name in row))
    return {
        name: (units[name], np.array([row.get(name, math.nan) for row in rows], dtype=float))
        for name in names
    }


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
    results: Sequence[Mapping[str, Any]],
    *,
    indices: bool | None = None,
) -> list[dict[str, Any]]:
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
    list of dict
        ``{parameter, target, effect, unit, low, high}`` (and ``S1``,
        ``S1_conf`` with indices), sorted by ``effect``, largest first
        (ties: by target, then parameter, in study order). ``low`` and
        ``high`` are the lowest and highest level means; ``effect`` is
        ``high - low``, in ``unit``.
    """
    if indices is None:
        indices = spec.sampled and salib_available()
    seed = spec.scenarios.seed if spec.sampled else 0  # type: ignore[union-attr]
    out = []
    order = {}
    for t, (name, (unit, y)) in enumerate(targets(results).items()):
        s1 = _indices(spec, points, y, seed) if indices else {}
        for p, path in enumerate(spec.vary):
            order[(name, path)] = (t, p)
            keys = _level_keys(spec, path, [pt[path] for pt in points])
            found = _main_effect(keys, y)
            if found is None:
                continue
            low, high = found
            entry: dict[str, Any] = {
                "parameter": path, "target": name, "effect": high - low,
                "unit": unit, "low": low, "high": high,
            }
            if path in s1:
                entry["S1"], entry["S1_conf"] = s1[path]
            out.append(entry)
    out.sort(key=lambda e: (-e["effect"], order[(e["target"], e["parameter"])]))
    return out

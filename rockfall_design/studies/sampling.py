"""Scenarios: the runs of a parametric study, each with its values and its own seed.

A study's ``vary:`` section names inputs and their values; ``scenarios:``
says which combinations are run:

- ``grid``: every combination, in the order of nested loops over the inputs
  as written under ``vary:``, the last input varying fastest (the first
  scenarios hold every input but the last at its first value). A range is
  tried at its ``levels`` evenly spaced values.
- ``{sample: latin_hypercube, n: N, seed: S}``: ``N`` points of a Latin
  hypercube (:class:`scipy.stats.qmc.LatinHypercube`, drawn from a generator
  seeded with ``S``), one dimension per input in the order of ``vary:``. A
  range ``[lo, hi]`` is sampled uniformly, ``lo + u (hi - lo)``; a list of
  values is a categorical input, value ``floor(u k)`` of its ``k`` values,
  so every value is drawn about ``N / k`` times.

Every scenario has its own rock seed, drawn from the run's seed (``--seed``
or ``rocks.seed``) and the scenario's index by
:class:`numpy.random.SeedSequence`: the child ``index`` of the run seed's
sequence, as ``SeedSequence(seed).spawn(n)[index]`` gives it. The scenarios
are therefore independent samples; the same run seed gives the same seeds,
and a scenario's seed depends on its index only, never on who runs it.

With ``seeds: common`` every scenario runs with the run's seed itself:
the same release draws and per-rock random streams in every scenario
(common random numbers), so that the differences between scenarios, and
the sensitivity, come from the inputs alone and not from Monte Carlo noise.
(A varied input that changes what is drawn, such as the size distribution,
still changes the rocks' sizes, from the same random numbers.)
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..project.study import Range, Sample, StudySpec
from .paths import with_values

if TYPE_CHECKING:  # pragma: no cover
    from ..project import Project

__all__ = ["Scenario", "ScenarioRun", "required_scenarios", "scenario_runs", "scenario_seed",
           "scenarios"]

#: Scenario seeds are kept below 2**53, so that they read back exactly from
#: JSON in any language (a JavaScript number holds integers up to 2**53).
_SEED_BITS = 53


@dataclass(frozen=True)
class Scenario:
    """One run of a study.

    Attributes
    ----------
    index : int
        Position in the study (0-based), as in ``--json`` and scenarios.csv.
    values : dict
        Path -> value, keys exactly as written under ``vary:``, in that order.
    seed : int
        The rock seed of this scenario's Monte Carlo run (0 <= seed < 2**53).
    """

    index: int
    values: dict[str, Any] = field(default_factory=dict)
    seed: int = 0


def scenario_seed(run_seed: int, index: int) -> int:
    """The rock seed of scenario ``index`` of a run with seed ``run_seed``.

    Parameters
    ----------
    run_seed
        The study's seed (``--seed`` or ``rocks.seed``), >= 0.
    index
        The scenario's index, >= 0.

    Returns
    -------
    int
        ``SeedSequence(run_seed, spawn_key=(index,))`` (the ``index``-th child of
        ``SeedSequence(run_seed)``), its first 64-bit word shifted to 53 bits.
    """
    child = np.random.SeedSequence(int(run_seed), spawn_key=(int(index),))
    word = int(child.generate_state(1, np.uint64)[0])
    return word >> (64 - _SEED_BITS)


def _unit_sample(n: int, d: int, seed: int) -> np.ndarray:
    """An ``(n, d)`` Latin hypercube sample in [0, 1), from a generator seeded with ``seed``."""
    from scipy.stats import qmc

    rng = np.random.default_rng(int(seed))
    try:
        sampler = qmc.LatinHypercube(d=d, rng=rng)
    except TypeError:  # scipy < 1.15 names the generator ``seed``
        sampler = qmc.LatinHypercube(d=d, seed=rng)
    return sampler.random(n)


def _plain(value: Any) -> Any:
    """numpy scalars as Python numbers (for YAML, JSON and validation)."""
    return value.item() if isinstance(value, np.generic) else value


def design_points(spec: StudySpec) -> list[dict[str, Any]]:
    """The values of each scenario of ``spec``, in scenario order (see the module doc)."""
    paths = list(spec.vary)
    if isinstance(spec.scenarios, Sample):
        unit = _unit_sample(spec.scenarios.n, len(paths), spec.scenarios.seed)
        points = []
        for row in unit:
            point = {}
            for path, u in zip(paths, row, strict=True):
                levels = spec.vary[path]
                if isinstance(levels, Range):
                    lo, hi = levels.range
                    point[path] = float(lo + u * (hi - lo))
                else:
                    k = len(levels)
                    point[path] = _plain(levels[min(int(u * k), k - 1)])
            points.append(point)
        return points
    columns = [
        levels.grid_values() if isinstance(levels, Range) else list(levels)
        for levels in spec.vary.values()
    ]
    return [dict(zip(paths, combo, strict=True)) for combo in itertools.product(*columns)]


def scenarios(spec: StudySpec | Mapping[str, Any], run_seed: int) -> list[Scenario]:
    """The scenarios of a study.

    Parameters
    ----------
    spec
        The project's ``study:`` section (:class:`StudySpec`, or its raw
        mapping, validated here).
    run_seed
        The run's seed (``--seed`` or ``rocks.seed``), >= 0.

    Returns
    -------
    list of Scenario
        In the documented order (grid: nested loops, last input fastest;
        sample: the order of the Latin hypercube's points), each with its
        values and seed (:func:`scenario_seed`; the run's seed with
        ``seeds: common``).
    """
    if not isinstance(spec, StudySpec):
        spec = StudySpec.model_validate(spec)
    if int(run_seed) < 0:
        raise ValueError(f"the run seed must be >= 0, got {run_seed}")
    common = spec.seeds == "common"
    return [
        Scenario(index=i, values=values,
                 seed=int(run_seed) if common else scenario_seed(run_seed, i))
        for i, values in enumerate(design_points(spec))
    ]


@dataclass(frozen=True)
class ScenarioRun:
    """One scenario of a study, ready to run: its index, values, seed and project.

    ``project`` is the study's project with the scenario's values set
    (:func:`~rockfall_design.studies.with_values`) and ``rocks.seed`` set to
    the scenario's seed.
    """

    index: int
    values: dict[str, Any]
    seed: int
    project: Any  # Project

    def head(self) -> dict[str, Any]:
        """``{index, values, seed}``, the scenario's keys in every JSON object about it."""
        return {"index": self.index, "values": dict(self.values), "seed": self.seed}


def required_scenarios(share: float, k: int) -> int:
    """Scenarios of ``k`` a design must hold in for ``share`` (``ceil(share k)``, at least 1)."""
    # The tolerance keeps an exact share (0.25 of 4) from rounding up on float noise.
    return max(1, min(k, math.ceil(share * k - 1e-9)))


def scenario_runs(project: Project, seed: int | None = None) -> list[ScenarioRun]:
    """The study's scenarios of ``project`` as runnable projects, each with its own seed.

    Parameters
    ----------
    project
        With a ``study:`` section.
    seed
        The run seed (default ``rocks.seed``); scenario ``i`` runs with
        :func:`scenario_seed` ``(seed, i)``, as ``rockfall-design study``
        runs it.

    Raises
    ------
    ProjectError
        No ``study:`` section, or values that do not fit together.
    """
    if project.study is None:
        raise project.error_at(("design", "scenarios"), "the design's scenarios are those "
                               "of a study: give a study: section")
    run_seed = int(project.rocks.seed if seed is None else seed)
    out = []
    for sc in scenarios(project.study, run_seed):
        p = with_values(project, sc.values)
        p = p.model_copy(update={"rocks": p.rocks.model_copy(update={"seed": sc.seed})})
        out.append(ScenarioRun(sc.index, dict(sc.values), int(sc.seed), p))
    return out

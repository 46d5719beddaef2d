"""Run a study: one full Monte Carlo run per scenario, as independent tasks.

:func:`prepare` turns the project's ``study:`` section into tasks, in this
process: the scenarios (values and seeds), each scenario's project
(:func:`~.paths.with_values`, then the plugin sections checked as every
command checks them) and the stations of its barriers. Every task is made
before any runs, except on a pool of threads, which starts each as it is
made (:func:`prepare_lazily`): a bad scenario then stops the study a few
milliseconds in, with nothing written.
:func:`run_scenario` is the task: the run of ``simulate`` on the scenario's
project with the scenario's seed, reduced to the blocks of
``simulate --json`` (``stations``, ``stops``, ``protect``), the passing height
and energy at each barrier, and the scenario's envelopes for the figure.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..engine.columns import STOPPED
from ..errors import ProjectError
from ..judge.bounds import (
    fraction_bounds,
    fraction_lower_bound,
    fraction_upper_bound,
    quantile_index_table,
)
from ..judge.evaluation import evaluate
from ..judge.placing import build_measures, place_measures
from ..judge.plan import validate_plugin_sections
from ..plugins import load_registry
from ..plugins.measure import Barrier
from ..project import Project
from ..project.messages import describe
from ..run.reach import protected_zone_counts
from ..run.releases import section_from_project
from ..run.simulation import SimulationRun, simulate
from ..run.summary import STATION_QUANTITIES, STATISTICS, RunSummary, run_record, stat_block
from .executors import run_tasks
from .paths import ALIASES, parse_path, scenario_base, shown, with_values
from .sampling import Scenario, scenarios
from .scenario_result import BarrierBlock, BoundsLadder, ScenarioBounds, ScenarioResult
from .sensitivity import (
    LADDER,
    TARGET_STATISTICS,
    ladder_confidences,
    place_names,
    residual_names,
    sensitivity,
)
from .study_result import StudyResult, envelope_percentile

__all__ = ["ScenarioTask", "prepare", "prepare_lazily", "run_parametric", "run_scenario",
           "run_tasks_of"]

#: The station quantities a study keeps per scenario (design values and envelopes).
QUANTITIES = ("passing_height_m", "energy_kj")


@dataclass(frozen=True)
class ScenarioTask:
    """Everything one scenario's run needs (picklable, sent to a worker).

    Attributes
    ----------
    index : int
        The scenario's index.
    seed : int
        Its rock seed.
    rocks : int
        Rocks of its Monte Carlo run.
    project : Project
        Its project: the study's project with the scenario's values.
    barriers : tuple of (int, str, float)
        (index in ``measures``, label, station x in m) of each barrier
        (fence, wall, boulder row, ...) of the project, whose passing height
        and energy on the bare slope are design values of the study.
    scenarios : int
        How many scenarios the study has (k): the bounds the sensitivity
        needs are computed for this k alone (0: for every k of
        :data:`~.sensitivity.LADDER`).
    envelope : bool
        Whether to compute the scenario's envelopes along x (for the figure
        of every scenario's envelopes; nothing else reads them). They cost
        two sorts of the run's whole (rocks, points) tables, about a tenth
        of a 10,000-rock scenario: a run that draws no figure skips them.
    """

    index: int
    seed: int
    rocks: int
    project: Project
    barriers: tuple[tuple[int, str, float], ...] = ()
    envelope: bool = True
    scenarios: int = 0


def _relocated(project: Project, scenario: Scenario, exc: ProjectError) -> ProjectError:
    """A complaint about a scenario's project, at the ``study.vary`` line to blame.

    The path to blame is the first varied path that the complaint's key lies
    on (``measures[0].height`` for a complaint at ``measures[0]``), else the
    first one; the message names the scenario and all its values.
    """
    def key_text(path: str) -> str:
        keys = parse_path(path)
        if isinstance(keys[0], str) and keys[0] in ALIASES:
            keys = (*ALIASES[keys[0]], *keys[1:])
        return shown(keys)

    paths = list(scenario.values)
    blamed = next((p for p in paths if exc.key and (key_text(p).startswith(exc.key)
                                                    or exc.key.startswith(key_text(p)))),
                  paths[0])
    given = ", ".join(f"{p} = {describe(v)}" for p, v in scenario.values.items())
    where = f"{exc.key}: " if exc.key else ""
    return project.error_at(("study", "vary", blamed),
                            f"scenario {scenario.index} ({given}): {where}{exc.message}")


def _barriers(project: Project, registry: Any) -> tuple[tuple[int, str, float], ...]:
    """The barriers of a project, checked and placed as every command does."""
    validate_plugin_sections(project, registry)
    measures = build_measures(project, registry)
    placed = place_measures(project, registry, measures, section_from_project(project))
    return tuple(
        (p.index, p.label, float(p.footprint.x))
        for p in placed
        if isinstance(p.footprint, Barrier)
    )


def prepare(
    project: Project, registry: Any, *, rocks: int | None = None, seed: int | None = None,
    envelopes: bool = True,
) -> tuple[list[Scenario], list[ScenarioTask]]:
    """The scenarios of the project's study and their tasks, every input checked.

    Parameters
    ----------
    project
        A project with a ``study:`` section (validated, plugins included).
    registry
        The plugins, to check each scenario's plugin sections.
    rocks
        Rocks per scenario (default: ``rocks.count``).
    seed
        The run's seed (default: ``rocks.seed``); each scenario's seed is
        derived from it (:func:`~.sampling.scenario_seed`).
    envelopes
        Whether each scenario computes its envelopes (:attr:`ScenarioTask.envelope`).

    Raises
    ------
    ProjectError
        No ``study:`` section, or a scenario's values are not valid together
        (located at the ``study.vary`` line to blame).
    """
    chosen, tasks = prepare_lazily(project, registry, rocks=rocks, seed=seed,
                                   envelopes=envelopes)
    return chosen, list(tasks)


def prepare_lazily(
    project: Project, registry: Any, *, rocks: int | None = None, seed: int | None = None,
    envelopes: bool = True,
) -> tuple[list[Scenario], Iterator[ScenarioTask]]:
    """As :func:`prepare`, but each scenario's task is made (and checked) when asked for.

    The scenarios are known at once; a scenario's project is checked as the
    iterator reaches it, and a bad one raises there. A pool of threads
    (:func:`~.executors.run_tasks`) starts each task as it is made, so the
    checks overlap the first runs instead of keeping the cores waiting.
    """
    if project.study is None:
        raise project.error_at(
            (), "the project has no study: section (inputs to vary and the scenarios to run; "
            "see 'Parametric studies' in the README)"
        )
    n = int(project.rocks.count if rocks is None else rocks)
    run_seed = int(project.rocks.seed if seed is None else seed)
    chosen = scenarios(project.study, run_seed)
    base = scenario_base(project)

    def tasks() -> Iterator[ScenarioTask]:
        for scenario in chosen:
            try:
                checked = with_values(project, scenario.values, base=base)
                barriers = _barriers(checked, registry)
            except ProjectError as exc:
                raise _relocated(project, scenario, exc) from None
            # The check keeps what the plugins built for it on the project (its
            # plan: the plugins' objects, the registry), which a worker neither
            # needs nor may be able to unpickle: the task's project is the data alone.
            checked._plan = None
            yield ScenarioTask(scenario.index, scenario.seed, n, checked, barriers, envelopes,
                               len(chosen))

    return chosen, tasks()


def _with_stations(project: Project, extra: Sequence[float]) -> Project:
    """``project`` with more analysis stations (they only observe: no rock changes path)."""
    if not extra:
        return project
    analysis = project.analysis.model_copy(
        update={"stations": [*project.analysis.stations, *extra]})
    copy = project.model_copy(update={"analysis": analysis})
    return copy


def run_scenario(task: ScenarioTask) -> ScenarioResult:
    """Run one scenario: ``simulate`` of its project with its seed.

    Returns
    -------
    ScenarioResult
        ``index``, ``seed``, ``rocks``, ``events``, ``project_hash``, and the
        blocks ``stations``, ``stops`` and ``protect`` (if the project has a
        protected zone) exactly as ``simulate --json`` of the scenario's
        project gives them; ``measures``: per barrier its ``index``,
        ``label``, ``x`` and the ``passing_height_m`` and ``energy_kj``
        blocks on the bare slope at its station; ``envelope``: x (m),
        crossings and the percentile envelopes of height (m) and energy
        (kJ), if the task asks for them (:attr:`ScenarioTask.envelope`);
        ``runtime_s`` (not part of the study's JSON: it differs between
        runs).
    """
    project = task.project
    own = [float(x) for x in project.analysis.stations]
    extra = sorted({x for _, _, x in task.barriers if x not in own})
    t0 = time.perf_counter()
    run = simulate(_with_stations(project, extra), rocks=task.rocks, seed=task.seed)
    record = _summary_of(run, own, project.resolved_hash())
    runtime = time.perf_counter() - t0
    by_x = {st.x: st for st in record.stations}
    protect = None if record.protect is None else record.protect.to_json()
    with_measures = _residual_with_measures(task) if protect and project.measures else None
    barriers = [BarrierBlock(i, label, x, by_x[x].crossings, by_x[x].passing_height_m.to_json(),
                             by_x[x].energy_kj.to_json()) for i, label, x in task.barriers]
    return ScenarioResult(
        index=task.index, seed=task.seed, rocks=record.rocks, events=record.events,
        project_hash=record.project_hash,
        stations=[st.to_json() for st in record.stations if st.x in own],
        stops=record.stops.to_json(),
        bounds=_bounds(run, record, task, _confidence(project), with_measures),
        runtime_s=runtime, protect=protect, protect_with_measures=with_measures,
        measures=barriers or None,
        envelope=_envelope(run, envelope_percentile(project)) if task.envelope else None)


def _residual_with_measures(task: ScenarioTask) -> dict[str, Any]:
    """The rocks reaching the protected zone with the project's measures in place.

    The scenario's rocks (its seed and count) run as ``check`` runs them:
    with the barriers in place and the ground edited, judged by the judge
    (:mod:`rockfall_design.judge.outcomes`). What the study calls the
    residual, as ``check`` does; the bare slope's stays in ``protect``.
    The plugins are loaded in the worker (the task carries data alone); the
    study checked the project with the command's plugins already.

    Returns
    -------
    dict
        ``x`` (m), ``reaching``, ``fraction``, ``unresolved`` as ``check``'s
        ``protect``, and ``measures``: the labels of the measures in place.
    """
    ev = evaluate(task.project, _registry(), rocks=task.rocks, seed=task.seed)
    p = ev.protect or {}
    return {"x": p.get("x"), "reaching": int(p.get("reaching", 0)),
            "fraction": float(p.get("fraction", 0.0)), "unresolved": int(p.get("unresolved", 0)),
            "measures": [pl.label for pl in ev.placed]}


_REGISTRY: list[Any] = []


def _registry() -> Any:
    """The installed plugins, loaded once per process (a worker's first scenario)."""
    if not _REGISTRY:
        _REGISTRY.append(load_registry())
    return _REGISTRY[0]


def _summary_of(run: Any, own: Sequence[float], project_hash: str) -> RunSummary:
    """The run's record (``run.run_summary()``), less what the study drops: a fifth of a
    scenario's statistics.

    At a station of the project (``own``) every block, as ``simulate
    --json`` gives it; at a station added for a barrier only the blocks the
    study keeps (:data:`QUANTITIES`), the others left empty (None). Each
    block is computed as :meth:`~rockfall_design.run.simulation.SimulationRun.summary`
    computes it, so the numbers are the same to the bit (a test holds the
    scenario to ``simulate``). A streamed run: its own summary, whole.
    ``project_hash``: the hash the summary gives, the scenario's project's
    (not that of its copy with the barriers' stations).
    """
    if not isinstance(run, SimulationRun):
        return replace(run.run_summary(), project_hash=project_hash)
    r = run.result
    a = run.crossing_arrays()
    kept = {float(x) for x in own}
    empty = dict.fromkeys(STATISTICS)
    blocks = {
        key: [stat_block(a[arr][:, j] / scale)
              if key in QUANTITIES or float(x) in kept else dict(empty)
              for j, x in enumerate(r.stations)]
        for key, (arr, scale) in STATION_QUANTITIES.items()
    }
    crossings = np.isfinite(a["passing_height_m"]).sum(axis=0)
    stop_block = stat_block(r.x_end[r.status == STOPPED])
    protect = run.project.protect
    reaching = None if protect is None else protected_zone_counts(r.max_x, r.status, protect.x)
    return run_record(run, r.events_total, crossings, blocks, stop_block, reaching,
                      project_hash)


#: Confidence of the design values' upper bounds when the safety concept gives none.
DEFAULT_CONFIDENCE = 0.95


def _confidence(project: Project) -> float:
    """The safety concept's ``confidence`` (the bounds of ``check``), else 0.95."""
    value = project.safety.get("confidence", DEFAULT_CONFIDENCE)
    ok = isinstance(value, int | float) and not isinstance(value, bool) and 0 < value < 1
    return float(value) if ok else DEFAULT_CONFIDENCE


def _bounds(run: Any, summary: RunSummary, task: ScenarioTask,
            confidence: float, with_measures: dict[str, Any] | None = None
            ) -> ScenarioBounds:
    """Confidence bounds of the scenario's design values, by name.

    Each p95 and p99 of passing height and energy at the stations and
    barriers: the distribution-free order-statistic bounds over the rocks
    that passed (None where too few did); the fraction reaching the
    protected zone: Clopper-Pearson. A streamed run (more than
    ``EXACT_ROCKS`` rocks) keeps no per-rock values: only the fraction's
    bounds are given then.

    Returns
    -------
    ScenarioBounds
        ``confidence`` (c); ``upper`` and ``lower``, the one-sided upper and
        lower bound of each design value at c (together a two-sided
        interval at 2c - 1); ``ladder``, the bounds the sensitivity needs
        (:func:`~.sensitivity.joint_bounds`): for the study's number of
        scenarios k (:attr:`ScenarioTask.scenarios`; a task that does not
        know it: for every k of :data:`~.sensitivity.LADDER`), ``lower`` and
        ``upper`` at the one-sided confidence 1 - (1 - c) / (2k) each. It is
        left out of the study's JSON.
    """
    rungs = [task.scenarios] if task.scenarios > 0 else list(LADDER)
    sides = ladder_confidences(confidence, rungs)
    out = ScenarioBounds(confidence, upper={}, lower={},
                         ladder=BoundsLadder(scenarios=rungs, lower={}, upper={}))
    ladder = out.ladder
    if isinstance(run, SimulationRun):
        arrays = run.crossing_arrays()
        columns = {float(x): j for j, x in enumerate(run.stations)}
        names, samples, qs = [], [], []
        for where, x in place_names([st.x for st in summary.stations], task.barriers,
                                    task.project):
            j = columns[x]
            for quantity, array, scale in (("passing_height_m", "passing_height_m", 1.0),
                                           ("energy_kj", "energy_j", 1e3)):
                column = arrays[array][:, j]
                # one sort per column: every bound of its design values is an index into it
                ordered = np.sort(column[np.isfinite(column)] / scale)
                for stat in TARGET_STATISTICS:
                    names.append(f"{where} {quantity} {stat}")
                    samples.append(ordered)
                    qs.append(float(stat[1:]) / 100)
        found = _order_bounds(samples, qs, confidence, sides)
        for name, (lower, upper, low_ladder, high_ladder) in zip(names, found, strict=True):
            out.lower[name], out.upper[name] = lower, upper
            ladder.lower[name], ladder.upper[name] = low_ladder, high_ladder
    if summary.protect is not None:
        n = int(summary.rocks)
        for name, block in residual_names(summary.protect.to_json(), with_measures):
            x = int(block["reaching"])
            out.upper[name] = fraction_upper_bound(x, n, confidence)
            out.lower[name] = fraction_lower_bound(x, n, confidence)
            low, high = fraction_bounds(x, n, sides)
            ladder.lower[name], ladder.upper[name] = low.tolist(), high.tolist()
    return out


def _order_bounds(samples: Sequence[np.ndarray], qs: Sequence[float], confidence: float,
                  sides: Sequence[float]) -> list[tuple[Any, Any, list[Any], list[Any]]]:
    """Per sorted sample and its quantile q: the lower and upper bound of the q-quantile
    at ``confidence``, then the lists of both at each one-sided confidence of
    ``sides``; None where the sample is too small.

    All from two vectorised searches, one a side
    (:func:`~rockfall_design.judge.bounds.quantile_index_table`: the upper
    bound at ``confidence`` is the one of ``check``,
    :func:`~rockfall_design.judge.bounds.quantile_upper_bound`).
    """
    ns = [int(v.size) for v in samples]
    levels = [confidence, *sides]
    lows = quantile_index_table(ns, qs, levels, "lower")
    highs = quantile_index_table(ns, qs, levels, "upper")
    out = []
    for v, n, low, high in zip(samples, ns, lows, highs, strict=True):
        if n == 0:
            out.append((None, None, [None] * len(sides), [None] * len(sides)))
            continue
        picked_low = [None if i < 0 else x for i, x in zip(low.tolist(), v[low].tolist(),
                                                             strict=True)]
        picked_high = [None if i < 0 else x for i, x in zip(high.tolist(), v[high].tolist(),
                                                              strict=True)]
        out.append((picked_low[0], picked_high[0], picked_low[1:], picked_high[1:]))
    return out


def _finite_counts(values: np.ndarray) -> np.ndarray:
    """Finite values (rocks that passed) in each column of a (rocks, stations) table."""
    return np.isfinite(values).sum(axis=0)


def column_percentile(values: np.ndarray, q: float,
                       count: np.ndarray | None = None) -> np.ndarray:
    """The ``q``-th percentile (0..100) of each column's finite values; NaN if none.

    Linear interpolation between order statistics, as numpy's default
    method, from one sort of the whole table: ``np.nanpercentile`` per
    column took as long as the scenario's run. The table is sorted as
    (stations, rocks), each station's rocks contiguous (numpy sorts
    contiguous rows with its vectorised sort, a quarter faster than down the
    columns; the same order statistics, so the same numbers). ``count``: the
    columns' finite counts if already known (:func:`_finite_counts`).
    """
    ordered = np.ascontiguousarray(np.asarray(values).T)
    if np.shares_memory(ordered, values):  # one row or column: a view, not a copy
        ordered = ordered.copy()  # sorted in place below
    ordered.sort(axis=1)  # NaN sort last
    if count is None:
        count = _finite_counts(values)
    out = np.full(ordered.shape[0], np.nan)
    cols = np.nonzero(count > 0)[0]
    pos = (count[cols] - 1) * (q / 100.0)
    lo = np.floor(pos).astype(np.int64)
    hi = np.minimum(lo + 1, count[cols] - 1)
    low = ordered[cols, lo].astype(float)
    out[cols] = low + (ordered[cols, hi].astype(float) - low) * (pos - lo)
    return out


def _envelope(run: Any, q: float) -> dict[str, list[float]]:
    """x (m), crossings and the ``q`` envelopes of height (m) and energy (kJ) of a run."""
    label = f"{q:g}".replace(".", "_")
    if isinstance(run, SimulationRun):
        r = run.result
        crossings = _finite_counts(r.grid_height)
        return {
            "x_m": np.asarray(r.grid, dtype=float).tolist(),
            "crossings": crossings.tolist(),
            f"height_p{label}_m": column_percentile(r.grid_height, q, crossings).tolist(),
            f"energy_p{label}_kj": (column_percentile(r.grid_energy, q) / 1e3).tolist(),
        }
    env = run.envelopes()  # a streamed run: from its histograms
    keep = ["x_m", "crossings", f"height_p{label}_m", f"energy_p{label}_kj"]
    return {c: env[c].tolist() for c in keep if c in env.columns}


def run_tasks_of(
    tasks: Iterable[ScenarioTask],
    *,
    workers: int | None = None,
    scheduler: Any = None,
    on_done: Callable[[int, ScenarioResult], None] | None = None,
    pool: str = "threads",
    total: int | None = None,
) -> list[ScenarioResult]:
    """Run the tasks with :func:`~.executors.run_tasks`; results in scenario order.

    A scenario spends its time in the compiled engine, which releases the
    GIL: locally, by default, the scenarios run on threads of this process
    (``pool="threads"``), which start at once; ``pool="processes"`` runs them
    on a process pool instead. The results are the same either way.
    """
    return run_tasks(run_scenario, tasks, workers=workers, scheduler=scheduler, on_done=on_done,
                     pool=pool, total=total)


def run_parametric(
    project: Project,
    registry: Any,
    *,
    rocks: int | None = None,
    seed: int | None = None,
    workers: int | None = None,
    scheduler: Any = None,
    progress: Callable[[int, int, int], None] | None = None,
    indices: bool | None = None,
    pool: str = "threads",
    envelopes: bool = True,
) -> Any:
    """Prepare, run and analyse the project's study; a :class:`~.study_result.StudyResult`.

    Parameters are those of :func:`prepare` and :func:`run_tasks_of`;
    ``indices`` those of :func:`~.sensitivity.sensitivity`; ``envelopes``
    False skips each scenario's envelopes (then the result cannot draw them). ``progress`` is
    called as ``progress(done, total, rocks_done)`` once the scenarios are
    known (``done`` 0) and as each finishes.
    """
    t0 = time.perf_counter()
    chosen, tasks = prepare_lazily(project, registry, rocks=rocks, seed=seed,
                                   envelopes=envelopes)
    on_done = None
    if progress is not None:
        done = [0, 0]  # scenarios, rocks

        def on_done(i: int, result: ScenarioResult) -> None:
            done[0] += 1
            done[1] += int(result.rocks)
            progress(done[0], len(chosen), done[1])

        progress(0, len(chosen), 0)
    results = run_tasks_of(tasks, workers=workers, scheduler=scheduler, on_done=on_done,
                           pool=pool, total=len(chosen))
    assert project.study is not None  # prepare checked it
    effects = sensitivity(project.study, [s.values for s in chosen], results, indices=indices)
    run_seed = int(project.rocks.seed if seed is None else seed)
    return StudyResult(project, chosen, results, run_seed, time.perf_counter() - t0, effects)

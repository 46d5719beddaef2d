"""The public Python API: load a project, simulate, check, optimise; tables and figures.

>>> import rockfall_design as rd
>>> p = rd.load_project("projects/design_two_zones.yaml")   # doctest: +SKIP
>>> r = rd.optimise(p, rocks=2000, seed=1)                  # doctest: +SKIP
>>> r.best["name"], r.alternatives, r.plot()                # doctest: +SKIP

The functions do what the commands of the same name do, and the CLI is a
layer over them: ``.summary`` of a result is the dict that ``--json``
prints. Tables are pandas DataFrames; figures are
:class:`matplotlib.figure.Figure` objects built without pyplot, so nothing
here chooses or switches matplotlib's backend (a notebook's inline figures
stay as they were).
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

from .errors import InputError
from .judge.evaluation import evaluate
from .judge.plan import Plan, plan_for, planned_section, validate_plugin_sections
from .judge.verdict import requirement_warnings
from .limits import MAX_BOOTSTRAP, MAX_ROCKS, whole_number
from .plugins import load_registry, plugins_json  # noqa: F401
from .project import Corridor
from .project import load_corridor as _load_corridor
from .project import load_project as _load
from .report.progress import fits_progress, rocks_progress, scenarios_progress
from .results import DEFAULT_TRAJECTORIES, CheckResult, OptimiseResult, SimulationResult
from .run import simulation
from .run.simulation import simulate as _simulate
from .studies.corridor import (
    COMMANDS,
    SectionOutcome,
    run_sections,
    section_seeds,  # noqa: F401
)
from .studies.executors import EXTRA_HINT, usable_cores  # noqa: F401
from .studies.executors import run_tasks as run_elsewhere  # noqa: F401
from .studies.paths import check_study
from .studies.sampling import design_points, scenario_runs  # noqa: F401
from .studies.scenario_checks import check_across  # noqa: F401
from .studies.sensitivity import salib_available  # noqa: F401
from .terrain.cut import cut_section  # noqa: F401
from .terrain.dem import read_dem  # noqa: F401
from .terrain.fall_line import trace_fall_line  # noqa: F401
from .terrain.map_figure import corridor_map  # noqa: F401
from .terrain.mapping import chosen_measures, write_measures  # noqa: F401

# The names marked noqa (F401) are the front ends' way in: the command line
# imports only the API, the results, the report, the errors and the project,
# and calls these besides the commands (each documented where it is defined).
#
# optimise, study, calibrate, compare and trial_run import their room where they
# run: the optimiser imports scipy.optimize at its top, a study's and a
# calibration's results matplotlib (their figures subclass its Figure) and a
# calibration pandas, and simulate and check must not pay for them.

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

    from .plugins import Registry
    from .project import CorridorSection, Project
    from .run.simulation import SimulationRun
    from .run.streamed import StreamedRun
    from .studies.corridor import CorridorSummary, SectionOutcome
    from .trial.placements import TrialRun

__all__ = [
    "load_project",
    "simulate",
    "check",
    "optimise",
    "study",
    "calibrate",
    "compare",
    "run_corridor",
    "SimulationResult",
    "CheckResult",
    "OptimiseResult",
    "DEFAULT_TRAJECTORIES",
]


_REGISTRIES: dict[tuple[str, ...], Registry] = {}


def default_registry(block: tuple[str, ...] = ()) -> Registry:
    """The installed plugins, loaded once per process (per set of blocked names).

    A plugin that fails to load is named in a :class:`UserWarning`; the
    others are used.
    """

    key = tuple(sorted(block))
    if key not in _REGISTRIES:
        registry = load_registry(blocked=key)
        for f in registry.failures:
            warnings.warn(f"plugin {f.plugin!r} was not loaded: {f.reason}", stacklevel=3)
        _REGISTRIES[key] = registry
    return _REGISTRIES[key]


def load_project(path: str | os.PathLike[str], *, registry: Registry | None = None) -> Project:
    """Read a project file and validate all of it, the plugins' sections included.

    Parameters
    ----------
    path : str or path-like
        The YAML project file.
    registry : Registry, optional
        The plugins to validate ``measures:``, ``safety:`` and ``design:``
        with (default: the installed ones).

    Returns
    -------
    Project
        The validated, normalised project (pydantic model; ``p.rocks.count``,
        ``p.analysis.stations``, ``p.resolved_dict()``, ...).

    Raises
    ------
    ProjectError
        The file is not a valid project: one line ``file:line: key.path: message``.
    """


    project = _load(path)
    validate_project(project, registry or default_registry())
    return project


def _project(project: Any, registry: Registry | None = None) -> Project:
    """A Project from a Project or a path (validated with ``registry``)."""
    if isinstance(project, str | os.PathLike):
        return load_project(project, registry=registry)
    if isinstance(project, Corridor):
        raise InputError("a corridor runs section by section: pass one section's project "
                         "(corridor.sections[i].project), or run_corridor(), which runs "
                         "every section")
    return project


def run_corridor(
    corridor: Corridor | str | os.PathLike[str],
    command: str = "check",
    *,
    rocks: int | None = None,
    seed: int | None = None,
    registry: Registry | None = None,
) -> tuple[CorridorSummary, list[Any]]:
    """Run a command over every section of a corridor (``rockfall-design COMMAND CORRIDOR``).

    Each section is an ordinary project, run as :func:`simulate`,
    :func:`check`, :func:`optimise` or :func:`study` runs a project, in
    order, each with its own seed derived from the run seed; then the
    sections are added up
    (:func:`~rockfall_design.studies.corridor.run_sections`).

    Parameters
    ----------
    corridor : Corridor or path
        From :func:`~rockfall_design.project.load_corridor`, or the path of a
        corridor file (``sections:``).
    command : str
        ``simulate``, ``check`` (default), ``optimise`` or ``study``.
    rocks : int, optional
        Rocks of every section (default: each section's ``rocks.count``).
    seed : int, optional
        The run seed (default: the corridor's ``rocks.seed``).
    registry : Registry, optional
        The plugins (default: the installed ones).

    Returns
    -------
    (CorridorSummary, list)
        The corridor's result (``.to_json()`` is what ``--json`` prints,
        ``.ok``, ``.totals``, ``.sections``) and each section's own result
        (:class:`SimulationResult`, :class:`CheckResult`,
        :class:`OptimiseResult` or :class:`~rockfall_design.StudyResult`).
        The command line adds its file records to a section's JSON
        (``optimise``: the design file's name); the numbers are the same.

    Raises
    ------
    InputError
        ``command`` is not one of the four, or the file is a single project.
    """
    # Imported here: the corridor's run loads the judge and the engine (numba), which
    # `import rockfall_design.api` does not.

    if command not in COMMANDS:
        raise InputError(f"a corridor runs {', '.join(COMMANDS)}, not {command!r}")
    _checked(seed=seed)
    c = _load_corridor(corridor) if isinstance(corridor, str | os.PathLike) else corridor
    if not isinstance(c, Corridor):
        raise InputError(f"{c.source}: not a corridor (no sections:): use {command}()")
    reg = registry or default_registry()
    for section in c.sections:
        validate_project(section.project, reg)

    def one(i: int, section: CorridorSection, section_seed: int) -> SectionOutcome:
        return _section_outcome(command, section.project, rocks, section_seed, reg)

    summary, done = run_sections(c, command, one, seed=seed)
    return summary, [d.result for d in done]


def _section_outcome(command: str, project: Project, rocks: int | None, seed: int,
                     registry: Registry) -> SectionOutcome:
    """One section's run of ``command`` through this API: its JSON, cost and result."""

    if command == "simulate":
        result: Any = simulate(project, rocks=rocks, seed=seed, trajectories=0)
    elif command == "check":
        result = check(project, rocks=rocks, seed=seed, trajectories=0, registry=registry)
    elif command == "optimise":
        result = optimise(project, rocks=rocks, seed=seed, registry=registry)
        best = result.result.best
        return SectionOutcome(result.summary, None if best is None else float(best.cost),
                              result)
    else:
        result = study(project, rocks=rocks, seed=seed, registry=registry)
    return SectionOutcome(result.summary, None, result)


def _call(progress: bool | Callable[..., None], total: int, fn: Callable[..., Any],
          stages: bool = False, **kw: Any) -> Any:
    bar, callback = rocks_progress(progress, total, stages)
    if callback is not None:
        kw["progress"] = callback
    if bar is None:
        return fn(**kw)
    with bar:
        return fn(**kw)


# ---- results --------------------------------------------------------------------


# ---- the functions --------------------------------------------------------------


def simulate(
    project: Project | str | os.PathLike[str],
    *,
    rocks: int | None = None,
    seed: int | None = None,
    progress: bool | Callable[[int], None] = False,
    trajectories: int = DEFAULT_TRAJECTORIES,
) -> SimulationResult:
    """Simulate the rocks of a project on the bare slope (``rockfall-design simulate``).

    Parameters
    ----------
    project : Project or path
        From :func:`load_project`, or the path of a project file.
    rocks : int, optional
        Number of rocks (default: ``rocks.count`` of the project).
    seed : int, optional
        Random seed (default: ``rocks.seed`` of the project). The same seed
        and count give the same rocks.
    progress : bool or callable
        True: a progress bar on stderr; a callable is called with the number
        of rocks done.
    trajectories : int
        Paths of the first rocks kept for :meth:`SimulationResult.plot_profile`.

    Returns
    -------
    SimulationResult
        ``.summary`` (as ``--json``), ``.rocks`` (one row per rock),
        ``.stations``, ``.crossings``, ``.envelopes``, ``.plot()``.
    """

    _checked(seed=seed, trajectories=trajectories)
    p = _project(project)
    n = _count(p, rocks)
    tables: list[pd.DataFrame] | None = None
    on_chunk = None
    if n > simulation.EXACT_ROCKS:
        # A streamed run keeps statistics only; the per-rock rows are small
        # enough to keep for a DataFrame (not the crossings: rows x stations).
        tables = []

        def on_chunk(part: Any) -> None:
            tables.append(part.rocks_table())

    run = run_simulation(p, rocks=n, seed=seed, progress=progress,
                         trajectories=trajectories, on_chunk=on_chunk)
    return SimulationResult(p, run, tables)


def run_simulation(project: Project, *, rocks: int | None, seed: int | None,
                   progress: bool | Callable[[int], None], trajectories: int,
                   on_chunk: Callable[[SimulationRun], None] | None = None,
                   ) -> SimulationRun | StreamedRun:
    """The run behind :func:`simulate` (and the CLI, which streams its tables to files)."""

    n = _count(project, rocks)
    return _call(progress, n, _simulate, project=project, rocks=n, seed=seed,
                 n_trajectories=trajectories, on_chunk=on_chunk,
                 section=planned_section(project))


def _count(project: Project, rocks: int | None) -> int:
    """``rocks``, checked as ``--rocks`` is, or the project's ``rocks.count``."""
    if rocks is None:
        return int(project.rocks.count)
    return whole_number(rocks, "rocks", 1, MAX_ROCKS)


def _checked(*, seed: Any = None, workers: Any = None, bootstrap: Any = None,
             trajectories: Any = None) -> None:
    """Check the numbers a run takes as the command line checks its options.

    Raises
    ------
    ArgumentError
        An :class:`InputError` naming the keyword, in the command line's words.
    """
    if seed is not None:
        whole_number(seed, "seed", 0, what="seed")
    if workers is not None:
        whole_number(workers, "workers", 1, what="number of workers")
    if bootstrap is not None:
        whole_number(bootstrap, "bootstrap", 0, MAX_BOOTSTRAP, "number of replicates")
    if trajectories is not None:
        whole_number(trajectories, "trajectories", 0, what="number")


def check(
    project: Project | str | os.PathLike[str],
    *,
    rocks: int | None = None,
    seed: int | None = None,
    progress: bool | Callable[[int], None] = False,
    trajectories: int = DEFAULT_TRAJECTORIES,
    registry: Registry | None = None,
) -> CheckResult:
    """Check the project's measures against its safety concept (``rockfall-design check``).

    Parameters
    ----------
    project : Project or path
    rocks, seed, progress, trajectories
        As :func:`simulate`.
    registry : Registry, optional
        The plugins (default: the installed ones).

    Returns
    -------
    CheckResult
        ``.ok``, ``.summary`` (as ``--json``), ``.measures`` and ``.checks``
        (DataFrames), ``.rocks`` (with ``caught_by_measure``), ``.crossings``,
        ``.plot()``.
    """

    _checked(seed=seed, trajectories=trajectories)
    p = _project(project, registry)
    n = _count(p, rocks)
    reg = registry or default_registry()
    ev = _call(progress, n, evaluate, project=p, registry=reg,
               rocks=n, seed=seed, n_trajectories=trajectories)
    return CheckResult(p, ev, reg)


def optimise(
    project: Project | str | os.PathLike[str],
    *,
    rocks: int | None = None,
    seed: int | None = None,
    progress: bool | Callable[[str, int, int], None] = False,
    registry: Registry | None = None,
) -> OptimiseResult:
    """Find the least-cost design of every family (``rockfall-design optimise``).

    Parameters
    ----------
    project : Project or path
        With a ``design:`` section.
    rocks, seed : int, optional
        Search rocks and seed (default: the project's).
    progress : bool or callable
        True: progress bars on stderr; a callable is called as
        ``progress(stage, done, total)``.
    registry : Registry, optional
        The plugins (default: the installed ones).

    Returns
    -------
    OptimiseResult
        ``.best`` (dict, None without an admissible design),
        ``.alternatives`` (DataFrame), ``.summary`` (as ``--json``),
        ``.design`` (the chosen design as a :class:`CheckResult`),
        ``.plot()`` (the alternatives compared).

    Raises
    ------
    ProjectError
        The project has no ``design:`` section.
    """
    # design.scenarios: the cheapest design that holds across the study's scenarios
    from .optimiser.driver import optimise as _optimise

    _checked(seed=seed)
    p = _project(project, registry)
    if p.design is None:
        raise p.error_at((), "the project has no design: section to optimise "
                             "(see the README, 'Designing protection')")
    reg = registry or default_registry()
    n = _count(p, rocks)
    if "max_rocks" in p.design.model_fields_set and p.design.max_rocks < n:
        # The last look of a decision with fewer rocks than the search: no look at all.
        raise p.error_at(("design", "max_rocks"), f"expected at least the {n:,} rocks of the "
                         f"search, got {p.design.max_rocks:,}: a decision looks at more rocks "
                         "than the search, never fewer")
    result = _call(progress, n, _optimise, stages=True, project=p, registry=reg, rocks=n,
                   seed=seed)
    return OptimiseResult(p, result, reg)


def study(
    project: Project | str | os.PathLike[str],
    *,
    rocks: int | None = None,
    seed: int | None = None,
    workers: int | None = None,
    scheduler: Any = None,
    progress: bool | Callable[[int, int, int], None] = False,
    registry: Registry | None = None,
    pool: str = "threads",
    envelopes: bool = True,
) -> Any:
    """Run the parametric study of a project's ``study:`` section (``rockfall-design study``).

    Every scenario is a full Monte Carlo run of ``simulate`` with the
    scenario's values and its own seed; the scenarios run as independent
    tasks (see :mod:`rockfall_design.studies.executors`), with the same results
    wherever they run.

    Parameters
    ----------
    project : Project or path
        A project with a ``study:`` section, or the path of its file.
    rocks : int, optional
        Rocks per scenario (default: ``rocks.count``).
    seed : int, optional
        The study's seed (default: ``rocks.seed``); scenario ``i`` runs with
        the seed :func:`~rockfall_design.studies.scenario_seed` derives from it.
    workers : int, optional
        Scenarios run at once locally (default: every usable core); 1 runs
        them in this process, one after the other, each on every core.
    scheduler : str or dask.distributed.Client, optional
        Run on a Dask cluster instead (``"tcp://127.0.0.1:8786"``); needs the
        ``study`` extra.
    progress : bool or callable
        True: a progress bar on stderr (scenarios done, rocks per second); a
        callable is called as ``progress(done, total, rocks_done)``.
    registry : Registry, optional
        The plugins (default: the installed ones).
    pool : {"threads", "processes"}
        The local pool of ``workers`` > 1: threads of this process, each
        scenario with one engine thread (the default: nothing to start), or
        a process pool. The results are the same.
    envelopes : bool
        Compute every scenario's envelopes along x, for
        ``.plot_envelopes()`` (default). False skips them, which saves about
        a tenth of each scenario's time; every number of ``.summary`` is the
        same either way.

    Returns
    -------
    StudyResult
        ``.summary`` (as ``--json``), ``.scenarios`` and ``.sensitivity``
        (DataFrames), ``.plot_envelopes()``, ``.plot_tornado()``, ``.print()``.
    """
    from .studies.runner import run_parametric

    _checked(seed=seed, workers=workers)
    registry = registry or default_registry()
    p = _project(project, registry)
    n = _count(p, rocks)
    bar, callback = scenarios_progress(progress)
    kw = dict(rocks=n, seed=seed, workers=workers, scheduler=scheduler, progress=callback,
              pool=pool, envelopes=envelopes)
    if bar is None:
        return run_parametric(p, registry, **kw)
    with bar:
        return run_parametric(p, registry, **kw)


def calibrate(
    project: Project | str | os.PathLike[str],
    *,
    observed: str | os.PathLike[str] | None = None,
    rocks: int | None = None,
    bootstrap: int | None = None,
    seed: int | None = None,
    workers: int | None = None,
    scheduler: Any = None,
    progress: bool | Callable[[int, int], None] = False,
    registry: Registry | None = None,
    pool: str = "threads",
    prior: bool | None = None,
    screen: bool | None = None,
) -> Any:
    """Back-analyse the inputs of a project's ``calibrate:`` section (``calibrate`` command).

    The fitted inputs are set by their paths (as in ``study.vary``); each
    evaluation runs the engine with the same rocks (common random numbers)
    and measures the distance of their stop positions from the observed
    ones; the intervals come from a bootstrap of the observations, each
    replicate refitted with its own seed (see :mod:`rockfall_design.calibration`).

    Parameters
    ----------
    project : Project or path
        A project with a ``calibrate:`` section, or the path of its file.
    observed : path, optional
        Another file of observed stops than ``calibrate.observed``.
    rocks : int, optional
        Simulated rocks per evaluation (default ``calibrate.rocks``).
    bootstrap : int, optional
        Bootstrap replicates (default ``calibrate.bootstrap``; 0: the fit only).
    seed : int, optional
        The calibration's seed (default ``rocks.seed``).
    workers, scheduler, pool
        Where the replicates run, as for :func:`study`; the numbers are the
        same wherever they run.
    progress : bool or callable
        True: a progress bar on stderr; a callable is called as
        ``progress(done, total)`` with replicates done.
    registry : Registry, optional
        The plugins (default: the installed ones).
    prior : bool, optional
        A fit regularised by the literature (each input's value as the
        prior's mode, its range as ±2 sd; docs/calibration.md, "The
        method"). None: with ``fit: auto``; False: the criterion alone
        (``--no-prior``); True: also for the inputs listed under ``fit:``.
    screen : bool, optional
        Leave out of a regularised fit the inputs that move the criterion by
        less than its sampling noise over their range (they keep their
        class's value; the warnings name them). None: with a prior; False:
        fit every input (``--no-screen``).

    Returns
    -------
    CalibrationResult
        ``.summary`` (as ``--json``), ``.parameters``, ``.values``,
        ``.calibrated_project()``, ``.figures()``, ``.print()``.
    """
    from .calibration.procedure import run_calibration

    _checked(seed=seed, workers=workers, bootstrap=bootstrap)
    if rocks is not None:
        whole_number(rocks, "rocks", 1, MAX_ROCKS)
    p = _project(project, registry or default_registry())
    kw = dict(observed=observed, rocks=rocks, bootstrap=bootstrap, seed=seed, workers=workers,
              scheduler=scheduler, pool=pool, prior=prior, screen=screen)
    bar, callback = fits_progress(progress)
    if bar is None:
        return run_calibration(p, on_done=callback, **kw)
    with bar:
        return run_calibration(p, on_done=callback, **kw)


def compare(
    project: Project | str | os.PathLike[str],
    observed: str | os.PathLike[str] | None = None,
    *,
    rocks: int | None = None,
    seed: int | None = None,
    registry: Registry | None = None,
) -> Any:
    """How well a project predicts observed stops, nothing fitted (``rockfall-design compare``).

    Parameters
    ----------
    project : Project or path
        E.g. the ``calibrated.yaml`` of a calibration on another profile.
    observed : path, optional
        CSV of the observed stops (as ``calibrate.observed``); None: every
        observation set of the project's ``calibrate:`` section (each kind,
        each profile), each reported (``.summary["sets"]``).
    rocks, seed : int, optional
        Simulated rocks and their seed (default ``rocks.count``, ``rocks.seed``).
    registry : Registry, optional
        The plugins (default: the installed ones).

    Returns
    -------
    ComparisonResult
        ``.summary`` (``fit``, ``levels``, and ``sets``), ``.figures()``, ``.print()``.
    """
    from .calibration.procedure import run_comparison

    _checked(seed=seed)
    if rocks is not None:
        whole_number(rocks, "rocks", 1, MAX_ROCKS)
    p = _project(project, registry or default_registry())
    kind = p.calibrate.distance if p.calibrate is not None else "energy"
    confidence = p.calibrate.confidence if p.calibrate is not None else 0.95
    return run_comparison(p, observed, rocks=rocks, seed=seed, kind=kind,
                          confidence=confidence)


def validate_project(project: Project, registry: Registry) -> None:
    """Check the sections of a project that its plugins own, whatever the command.

    Loading a project validates the core sections; ``measures:``, ``safety:``
    and ``design:`` belong to plugins and are checked here: every measure's
    parameters and its place on the section (fit, overlaps), the safety
    concept's parameters, and the design's candidates, catalogues and cost
    model. Every command calls it, so a bad project file is reported by
    ``simulate`` too, although ``simulate`` runs the bare slope.

    Raises
    ------
    ProjectError
        Exit code 2, located at the offending key.
    PluginError
        Exit code 3, if a plugin misbehaves.
    """

    validate_plugin_sections(project, registry)
    if project.study is not None:
        # the study's paths and values, against this project (after the sections above it)
        check_study(project, registry)


def plan(project: Project, registry: Registry) -> Plan:
    """The project resolved against its plugins, as every command builds it before a rock.

    Its bare section, its measures placed on it (labels, footprints, fit and
    overlaps checked), the edited section, the safety concept and the
    resolved ``design:`` section (:class:`~rockfall_design.judge.plan.Plan`);
    built once and kept with the project. The browser app draws the section
    and labels the measures from it.

    Raises
    ------
    ProjectError
        Exit code 2, located at the offending key (a measure that does not
        fit or overlaps another, a parameter its plugin rejects).
    PluginError
        Exit code 3, if a plugin misbehaves.
    """
    return plan_for(project, registry)


def trial_run(project: Project, registry: Registry, rocks: int, seed: int, *,
              table_step_m: float, restart_step_m: float, paths_drawn: int,
              progress: Callable[[int], None] | None = None) -> TrialRun:
    """The bare slope's rocks kept at dense stations, to judge measures placed by hand.

    The run behind the browser app's section page: its
    :meth:`~rockfall_design.trial.placements.TrialRun.place` judges measures
    placed anywhere from the kept table, in milliseconds for barriers (see
    :func:`rockfall_design.trial.placements.trial_run` for the parameters).

    Raises
    ------
    ProjectError
        Exit code 2, a project whose plugin sections do not resolve.
    PluginError
        Exit code 3, if a plugin misbehaves.
    """
    # Imported on first use, as every command's machinery here: `rockfall-design
    # --help` does not load the engine.
    from .trial.placements import trial_run as _trial_run

    return _trial_run(project, registry, int(rocks), int(seed),
                      table_step_m=table_step_m, restart_step_m=restart_step_m,
                      paths_drawn=paths_drawn, progress=progress)


# ---- what the command line needs besides the commands -------------------------------


def load_plugins(block: Sequence[str] = ()) -> Registry:
    """The installed plugins, loaded afresh (the command line's load: one per command).

    Unlike :func:`default_registry`, nothing is cached and no warning is
    issued: a plugin that failed to load is listed in ``registry.failures``
    for the caller to report.

    Parameters
    ----------
    block
        Entry-point or distribution names not to load (``--block``).

    Returns
    -------
    Registry
    """
    return load_registry(blocked=tuple(block))


def simulation_memory(project: Project, rocks: int) -> int:
    """Estimated peak memory (bytes) of simulating ``rocks`` rocks of ``project``.

    What the command line compares with the machine's memory before a run
    (see :func:`rockfall_design.run.simulation.simulation_memory`).

    Parameters
    ----------
    project
        The project (its analysis grid sets the memory per rock).
    rocks
        Rocks of the run.

    Returns
    -------
    int
        Bytes.
    """
    return simulation.simulation_memory(project, rocks)


def never_holding(project: Project, command: str) -> list[str]:
    """Requirements of ``project`` that can never hold with confidence, one line each.

    An allowed fraction of 0 is shown by no finite number of rocks (see
    :func:`rockfall_design.judge.verdict.requirement_warnings`).

    Parameters
    ----------
    project
        The project.
    command : {"check", "optimise"}
        Which requirement is judged: the protected zone's allowed fraction
        (``check``) or the design's residual (``optimise``).

    Returns
    -------
    list of str
        One line per requirement, located in the project file.
    """
    return requirement_warnings(project, command)


def exact_rocks() -> int:
    """Most rocks of a run kept whole; a larger run is streamed (statistics from histograms).

    Read from :data:`rockfall_design.run.simulation.EXACT_ROCKS` at each
    call, so that a changed limit holds everywhere.

    Returns
    -------
    int
    """
    return simulation.EXACT_ROCKS

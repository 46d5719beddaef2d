"""Corridors run: every section an ordinary project, reported per section and in total.

A corridor file (``sections:``, see :mod:`rockfall_design.project.corridor`)
loads as one complete :class:`~rockfall_design.project.Project` per section,
so each section runs through the same ``simulate``, ``check`` and
``optimise`` as a single project; this module runs them as independent tasks
(see :func:`each_section`) and adds them up:

- ``--json`` prints ``{name, seed, command, sections: [...], totals: {...}}``,
  each item of ``sections`` the section's usual JSON object with its
  ``name`` and ``index`` in front (its ``seed`` is the section's own);
- ``totals``: ``sections``, ``rocks`` (the sum), ``ok`` (every section holds:
  ``check``, every check; ``optimise``, a design found for every section),
  ``reaching`` (``simulate``/``check``: rocks reaching the protected zones),
  ``cost`` and ``currency`` (``optimise``: the corridor design's total cost,
  null unless every section has a design) and ``failures`` (one line each,
  naming the section);
- ``check --scenarios``: every section checked over its study's scenarios
  (:mod:`rockfall_design.cli.scenario_commands`); ``"scenarios": true``, each section's
  block the JSON of ``check --scenarios``, and ``totals`` with ``sections``,
  ``scenarios``, ``rocks`` (of every scenario), ``ok``, ``binding`` (the
  corridor's binding scenario: of the sections' binding ones, the least margin, with its
  ``section``) and ``failures``.

Files: ``--out DIR`` writes each section's usual files into ``DIR/<section>/``
(the section name with other characters than letters, digits, ``.``, ``-``
and ``_`` made ``_``) and the corridor's ``DIR/summary.json``; ``--plot``
and ``--report`` likewise. A section's ``design.yaml`` is an ordinary
project file that ``check`` reads.

Sections are independent tasks: ``simulate`` and ``check`` run them on a
local pool of processes by default (``--workers N``, ``--scheduler
ADDRESS`` for a Dask cluster), ``optimise`` in this process.

A single-section project (no ``sections:``) never comes here: its commands,
files and JSON are exactly those of a project file.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..api import (
    check,
    default_registry,
    exact_rocks,
    load_plugins,
    run_elsewhere,
    run_sections,
    run_simulation,
    section_seeds,
    simulation_memory,
    validate_project,
)
from ..errors import ExitCode, InputError
from ..report.outputs import OutputSet
from ..report.terminal import print_check, print_simulation
from ..results import (
    DEFAULT_TRAJECTORIES,
    CheckResult,
    CorridorSummary,
    SectionOutcome,
    SimulationResult,
)
from .common import (
    FIGURES,
    REPORT_FILES,
    figure_files,
    figures_and_report,
    in_memory_guard,
    memory_guard,
    reserve,
    run_record,
    run_with_progress,
    table_writers,
    warn_failures,
)
from .corridor_map import map_files, write_map
from .corridor_report import print_section_rule, print_totals
from .optimise_outputs import optimise_with_files, print_optimised
from .scenario_commands import SCENARIO_FIGURES, check_scenarios_with_files, print_check_across

if TYPE_CHECKING:  # pragma: no cover
    from ..plugins import Registry
    from ..project import Corridor, CorridorSection
    from ..report.outputs import OutputSet

__all__ = ["each_section", "SectionRun", "SectionDone",
           "cli_simulate", "cli_check", "cli_optimise"]


# ---- summaries -------------------------------------------------------------------


# ---- sections as tasks elsewhere ---------------------------------------------------


def _pooled(args: argparse.Namespace) -> bool:
    """Whether the sections run on the study's executors (a pool or a cluster)."""
    return getattr(args, "scheduler", None) is not None or getattr(args, "workers", None) != 1


def _trajectories(args: argparse.Namespace) -> int:

    return DEFAULT_TRAJECTORIES if (args.plot or args.report) else 0


def _simulate_task(task: tuple[Any, int, int, int]) -> Any:
    """One section's run of ``simulate`` (a task for a pool or a cluster): its SimulationRun."""

    project, rocks, seed, trajectories = task
    return run_simulation(project, rocks=rocks, seed=seed, progress=False,
                          trajectories=trajectories)


def _check_task(task: tuple[Any, int, int, int, tuple[str, ...]]) -> Any:
    """One section's ``check`` (a task for a pool or a cluster): its Evaluation.

    The plugins are loaded where the task runs, as the command loads them.
    """

    project, rocks, seed, trajectories, block = task
    return check(project, rocks=rocks, seed=seed, trajectories=trajectories,
                 registry=default_registry(block)).evaluation


def _on_executors(fn: Callable[[Any], Any], corridor: Corridor,
                  subs: Sequence[argparse.Namespace], args: argparse.Namespace) -> list[Any]:
    """Every section's run of ``fn`` on a pool (``--workers``) or a cluster (``--scheduler``).

    Each section carries its project, rocks and seed, so the numbers are
    those of the run in this process, wherever it runs.
    """

    tasks = []
    for section, sub in zip(corridor.sections, subs, strict=True):
        task: tuple = (section.project, int(args.rocks or section.project.rocks.count),
                       int(sub.seed), _trajectories(args))
        if fn is _check_task:
            task += (tuple(args.block),)
        tasks.append(task)
    return run_elsewhere(fn, tasks, workers=args.workers, scheduler=args.scheduler)


# ---- the commands ----------------------------------------------------------------


def _registry(corridor: Corridor, args: argparse.Namespace) -> Registry:
    """The plugins, loaded once, with every section's plugin sections checked."""

    registry = load_plugins(args.block)
    warn_failures(registry)
    for section in corridor.sections:
        validate_project(section.project, registry)
    return registry


def _section_args(args: argparse.Namespace, section: CorridorSection,
                  seed: int) -> argparse.Namespace:
    """The command's options for one section: its own seed and its own subdirectories."""
    sub = argparse.Namespace(**vars(args))
    sub.seed = seed
    for name in ("out", "plot", "report"):
        base: Path | None = getattr(args, name, None)
        setattr(sub, name, None if base is None else base / section.slug)
    return sub


@dataclass
class SectionRun:
    """What a command's per-section body gets from :func:`each_section`.

    Attributes
    ----------
    section
        The section (its name, index and ordinary project).
    args
        The command's options for this section: ``seed`` is the section's
        own, ``out``, ``plot`` and ``report`` its subdirectories (or None).
    files
        The command's output set (every section's files and the corridor's
        summary land together, or none).
    registry
        The plugins, loaded once for every section.
    ran
        What the command ran for this section elsewhere (a pool or a
        cluster) before the bodies run, or None.
    """

    section: CorridorSection
    args: argparse.Namespace
    files: OutputSet
    registry: Registry
    ran: Any = None


@dataclass
class SectionDone:
    """What a per-section body returns to :func:`each_section`.

    Attributes
    ----------
    summary
        The section's JSON object, as the command prints it for one project.
    show
        Prints the section's terminal report (called unless ``--json``).
    cost
        ``optimise``: the chosen design's cost (None: no design).
    """

    summary: dict[str, Any]
    show: Callable[[], None]
    cost: float | None = None


def _reserve(files: OutputSet, args: argparse.Namespace, subs: Sequence[argparse.Namespace],
             out_files: Sequence[str], figures: Sequence[str], report: bool,
             extra: Sequence[Path] = ()) -> None:
    """Reserve every section's files, the corridor's ``summary.json`` and ``extra``."""

    for sub in subs:
        reserve(files, sub.out, out_files)
        if report:
            reserve(files, sub.report, REPORT_FILES)
        reserve(files, sub.plot, figure_files(figures, sub))
    reserve(files, args.out, ("summary.json",))
    if extra:
        files.reserve(*extra)


def _write_summary(files: OutputSet, args: argparse.Namespace, summary: CorridorSummary,
                   write_extra: Callable[[OutputSet, dict[str, Any]], None] | None
                   ) -> dict[str, Any]:
    """Put the corridor's ``summary.json`` and its extra files in the set; its JSON."""
    data = summary.to_json()
    if args.out:
        files.write_json(args.out / "summary.json", data)
    if write_extra is not None:
        write_extra(files, data)
    return data


def each_section(
    args: argparse.Namespace,
    corridor: Corridor,
    command: str,
    body: Callable[[SectionRun], SectionDone],
    *,
    out_files: Sequence[str],
    figures: Sequence[str],
    report: bool = True,
    guard: Callable[[CorridorSection], None] | None = None,
    elsewhere: Callable[[Sequence[argparse.Namespace]], Sequence[Any] | None] | None = None,
    scenarios: bool = False,
    extra: tuple[Sequence[Path], Callable[[OutputSet, dict[str, Any]], None]] | None = None,
) -> CorridorSummary:
    """Run a command over every section of a corridor: the command line's side of it.

    Loads the plugins once (checking every section's plugin sections),
    reserves every file, runs ``body`` on each section in order
    (:func:`~rockfall_design.studies.corridor.run_sections`), printing its
    rule and report unless ``--json``; then writes, prints and returns the totals.

    Parameters
    ----------
    args, corridor
        The command's options, and the corridor.
    command
        ``simulate``, ``check``, ``optimise`` or ``study`` (the JSON's ``command``).
    body
        One section's run, files and report.
    out_files, figures, report
        The files each section writes: ``out_files`` under ``--out``,
        ``figures`` in every ``--plot-format`` under ``--plot``, the
        report's under ``--report`` when ``report``.
    guard
        Refuses a section before anything runs (e.g. too many rocks for the memory).
    elsewhere
        Given every section's options, runs the sections elsewhere and
        returns one result per section (``SectionRun.ran``), or None.
    scenarios
        ``check --scenarios`` (see
        :func:`~rockfall_design.studies.corridor.corridor_summary`).
    extra
        More files of the corridor (reserved first) and their writer, called
        with the set and the corridor's JSON (the map of a corridor on a DEM).

    Returns
    -------
    CorridorSummary
        The corridor's result (its ``to_json()`` the corridor's JSON object).
    """

    registry = _registry(corridor, args)
    _, seeds = section_seeds(corridor, args.seed)
    if guard is not None:
        for section in corridor.sections:
            guard(section)
    with OutputSet() as files:
        subs = [_section_args(args, s, seed) for s, seed in
                zip(corridor.sections, seeds, strict=True)]
        _reserve(files, args, subs, out_files, figures, report, extra[0] if extra else ())
        ran = elsewhere(subs) if elsewhere is not None else None

        def one(i: int, section: CorridorSection, seed: int) -> SectionOutcome:
            done = body(SectionRun(section, subs[i], files, registry,
                                   None if ran is None else ran[i]))
            if not args.json:
                print_section_rule(section, len(subs), seed)
                done.show()
            return SectionOutcome(done.summary, done.cost)

        # In this process, in order: the bodies write and print; where the runs went
        # elsewhere (_on_executors), the numbers are the same wherever a section ran.
        summary, _ = run_sections(corridor, command, one, seed=args.seed, scenarios=scenarios)
        data = _write_summary(files, args, summary, extra[1] if extra else None)
    if args.json:
        sys.stdout.write(json.dumps(data, allow_nan=False) + "\n")
    else:
        print_totals(summary)
    return summary


def cli_simulate(args: argparse.Namespace, corridor: Corridor) -> int:
    """``simulate`` of a corridor: every section's run, files and report, then the totals."""

    def guard(section: CorridorSection) -> None:
        project = section.project
        n = args.rocks or project.rocks.count
        memory_guard(simulation_memory(project, n), f"section {section.name!r}: {n:,} rocks "
                      f"with {project.analysis.envelope_points} envelope points",
                      "Use fewer analysis.envelope_points or analysis.stations.")

    def elsewhere(subs: Sequence[argparse.Namespace]) -> list[Any] | None:
        pooled = _pooled(args) and all(
            (args.rocks or s.project.rocks.count) <= exact_rocks() for s in corridor.sections)
        return _on_executors(_simulate_task, corridor, subs, args) if pooled else None

    def body(run: SectionRun) -> SectionDone:
        section, sub, files = run.section, run.args, run.files
        if run.ran is not None:  # run elsewhere, kept whole: its tables written here
            sim_run = run.ran
            if sub.out:
                files.write_csv(sub.out / "rocks.csv", sim_run.rocks_table())
                files.write_csv(sub.out / "crossings.csv", sim_run.crossings_table())
        else:
            on_chunk = table_writers(files, sub.out) if sub.out else None
            sim_run = run_with_progress(run_simulation, section.project, sub, on_chunk=on_chunk)
        result = SimulationResult(section.project, sim_run)
        summary = result.summary
        if sub.out:
            files.write_json(sub.out / "summary.json",
                             {**summary, "run": run_record(sim_run, sub)})
        figures_and_report(result, sub, files)
        return SectionDone(summary, lambda: print_simulation(summary))

    each_section(args, corridor, "simulate", body, guard=guard, elsewhere=elsewhere,
                 out_files=("rocks.csv", "crossings.csv", "summary.json"), figures=FIGURES)
    return int(ExitCode.OK)


def cli_check(args: argparse.Namespace, corridor: Corridor) -> int:
    """``check`` of a corridor: every section checked; exit 0 only if every section holds."""

    def guard(section: CorridorSection) -> None:
        a = section.project.analysis
        in_memory_guard(args.rocks or section.project.rocks.count,
                         a.envelope_points + len(a.stations), len(a.stations))

    if getattr(args, "scenarios", False):
        return _check_scenarios(args, corridor, guard)

    def elsewhere(subs: Sequence[argparse.Namespace]) -> list[Any] | None:
        return _on_executors(_check_task, corridor, subs, args) if _pooled(args) else None

    def body(run: SectionRun) -> SectionDone:
        section, sub, files = run.section, run.args, run.files
        if run.ran is not None:  # run elsewhere
            result = CheckResult(section.project, run.ran)
        else:
            result = run_with_progress(check, section.project, sub, registry=run.registry)
        evaluation = result.evaluation
        summary = result.summary
        if sub.out:
            out: Path = sub.out
            files.write_csv(out / "rocks.csv", result.rocks)
            files.write_csv(out / "crossings.csv", evaluation.run.crossings_table())
            files.write_csv(out / "measures.csv", evaluation.outcomes_table())
            record = run_record(evaluation.run, sub)
            record["project"] = evaluation.resolved_project().resolved_dict()
            record["project_hash"] = evaluation.resolved_project().resolved_hash()
            files.write_json(out / "summary.json", {**summary, "run": record})
        figures_and_report(result, sub, files)
        return SectionDone(summary, lambda: print_check(summary))

    summary = each_section(args, corridor, "check", body, guard=guard, elsewhere=elsewhere,
                           out_files=("rocks.csv", "crossings.csv", "measures.csv",
                                      "summary.json"), figures=FIGURES)
    return int(ExitCode.OK if summary.ok else ExitCode.CHECK_FAILED)


def cli_optimise(args: argparse.Namespace, corridor: Corridor) -> int:
    """``optimise`` of a corridor: the cheapest design of each section, and their total.

    Sections share no measure, so the corridor's cheapest design is the
    cheapest design of every section; exit 0 only if every section has one.
    """

    for section in corridor.sections:
        if section.project.design is None:
            raise section.project.error_at(
                ("design",), "the section has no design: section to optimise (give design: "
                "at the top level, or in every section)")

    def guard(section: CorridorSection) -> None:
        a = section.project.analysis
        in_memory_guard(args.rocks or section.project.rocks.count,
                         a.envelope_points + 400, len(a.stations))

    def body(run: SectionRun) -> SectionDone:
        project = run.section.project
        report = optimise_with_files(project, run.args, run.registry, run.files,
                                     f"{args.project}, section {run.section.name!r}",
                                     {"section": run.section.name})
        result = report.result
        cost = None if result.best is None else float(result.best.cost)
        return SectionDone(report.summary,
                           lambda: print_optimised(result, project, report.summary), cost)

    extra = None
    if corridor.map is not None:  # a corridor along a road on a DEM: the design on the map
        extra = (map_files(args),
                 lambda files, summary: write_map(args, corridor, files, summary["sections"]))
    summary = each_section(args, corridor, "optimise", body, guard=guard,
                           out_files=("design.yaml", "alternatives.csv", "summary.json"),
                           figures=FIGURES, extra=extra)
    return int(ExitCode.OK if summary.ok else ExitCode.CHECK_FAILED)


def _check_scenarios(args: argparse.Namespace, corridor: Corridor,
                     guard: Callable[[CorridorSection], None]) -> int:
    """``check --scenarios`` of a corridor: every section over its study's scenarios.

    Each section is checked as ``check --scenarios`` checks its project
    alone (its study: the shared one or its own; its own seed, from which its
    scenarios' seeds derive); the scenarios of a section run on the study's
    executors (``--workers``, ``--scheduler``), one section after the other.
    The corridor holds when every section holds in its required scenarios:
    exit 0, else 1. A corridor without a study is refused before anything
    runs (exit 2), as is a section without one: checking it plainly would
    hide that nothing varies there.
    """

    missing = [s for s in corridor.sections if s.project.study is None]
    if len(missing) == len(corridor.sections):
        raise InputError(f"{corridor.source}: check --scenarios needs a study: section (at "
                         "the top level of a corridor: every section's study), or check "
                         "without --scenarios")
    if missing:  # should a section ever have a study of its own
        raise missing[0].project.error_at(
            (), "check --scenarios: the section has no study: section; check without "
            "--scenarios")

    def body(run: SectionRun) -> SectionDone:
        found = check_scenarios_with_files(run.section.project, run.args, run.registry,
                                           run.files)
        return SectionDone(found.to_json(), lambda: print_check_across(found))

    summary = each_section(args, corridor, "check", body, guard=guard, scenarios=True,
                           out_files=("summary.json",), figures=SCENARIO_FIGURES)
    return int(ExitCode.OK if summary.ok else ExitCode.CHECK_FAILED)

"""The commands on one project: simulate, check, optimise, plugins and serve."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from ..api import check, load_plugins, plugins_json, run_simulation, simulation_memory
from ..errors import ExitCode, InputError
from ..project import Project
from ..report.interrupts import forget_interrupts
from ..report.outputs import OutputSet
from ..report.terminal import fitted_console, plugins_table, print_check, print_simulation
from ..results import SimulationResult
from ..serve import serve
from .common import (
    FIGURES,
    REPORT_FILES,
    comparable,
    decision_memory_guard,
    figure_files,
    figures_and_report,
    in_memory_guard,
    load,
    load_repeat,
    memory_guard,
    plugins_for,
    requirement_warnings,
    reserve,
    run_record,
    run_with_progress,
    table_writers,
)
from .corridor_commands import cli_check, cli_optimise, cli_simulate
from .optimise_outputs import optimise_with_files, print_optimised
from .options import (
    PROG,
)
from .scenario_commands import cli_check_scenarios

if TYPE_CHECKING:  # pragma: no cover
    pass


def cmd_simulate(args: argparse.Namespace) -> int:

    recorded = None
    if getattr(args, "repeat", None):
        if args.project is not None:
            raise InputError("give either a project file or --repeat SUMMARY, not both")
        project, recorded = load_repeat(args)
    elif args.project is None:
        raise InputError("a project file (or --repeat SUMMARY) is needed")
    else:
        project = load(args.project)
        if not isinstance(project, Project):  # a corridor: every section

            return cli_simulate(args, project)
    if args.workers or args.scheduler:
        raise InputError("--workers and --scheduler run the sections of a corridor (a project "
                         "file with sections:); this file has none")
    plugins_for(project, args)
    n = args.rocks or project.rocks.count
    memory_guard(simulation_memory(project, n), f"{n:,} rocks with "
                  f"{project.analysis.envelope_points} envelope points",
                  "Use fewer analysis.envelope_points or analysis.stations.")
    with OutputSet() as files:
        reserve(files, args.out, ("rocks.csv", "crossings.csv", "barriers.csv",
                                  "summary.json"))
        reserve(files, args.report, REPORT_FILES)
        reserve(files, args.plot, figure_files(FIGURES, args))
        on_chunk = table_writers(files, args.out) if args.out else None
        run = run_with_progress(run_simulation, project, args, on_chunk=on_chunk)
        result = SimulationResult(project, run)
        summary = result.summary
        if args.out:
            files.write_csv(args.out / "barriers.csv", result.barriers)
            files.write_json(args.out / "summary.json",
                             {**summary, "run": run_record(run, args)})
        figures_and_report(result, args, files)
    if recorded is not None:
        same = comparable(summary) == comparable(recorded)
        sys.stderr.write(
            f"{PROG}: repeated {args.repeat}: "
            + ("the results are identical\n" if same else
               "the results DIFFER from the recorded ones (another version or machine?)\n")
        )
    if args.json:
        sys.stdout.write(json.dumps(summary, allow_nan=False) + "\n")
    else:

        print_simulation(summary)
    if recorded is not None and not same:
        # A repeat is a check of reproducibility: results that differ fail it.
        return int(ExitCode.CHECK_FAILED)
    return int(ExitCode.OK)


def cmd_check(args: argparse.Namespace) -> int:
    """Evaluate the project's measures; exit 0 if every check holds, else 1."""

    project = load(args.project)
    if not isinstance(project, Project):  # a corridor: every section

        return cli_check(args, project)
    if not args.scenarios and (args.workers or args.scheduler):
        raise InputError("--workers and --scheduler run the scenarios of check --scenarios "
                         "(give --scenarios too), or the sections of a corridor")
    registry = plugins_for(project, args)
    if args.scenarios:  # every scenario of the study

        return cli_check_scenarios(args, project, registry)
    warnings = requirement_warnings(project, args)
    n = args.rocks or project.rocks.count
    in_memory_guard(n, project.analysis.envelope_points + len(project.analysis.stations),
                     len(project.analysis.stations))
    with OutputSet() as files:
        reserve(files, args.out, ("rocks.csv", "crossings.csv", "measures.csv", "barriers.csv",
                                  "summary.json"))
        reserve(files, args.report, REPORT_FILES)
        reserve(files, args.plot, figure_files(FIGURES, args))
        result = run_with_progress(check, project, args, registry=registry)
        evaluation = result.evaluation
        summary = result.summary
        run = evaluation.run
        if args.out:
            out: Path = args.out
            files.write_csv(out / "rocks.csv", result.rocks)
            files.write_csv(out / "crossings.csv", run.crossings_table())
            files.write_csv(out / "measures.csv", evaluation.outcomes_table())
            files.write_csv(out / "barriers.csv", result.barriers)
            record = run_record(run, args)
            record["project"] = evaluation.resolved_project().resolved_dict()
            record["project_hash"] = evaluation.resolved_project().resolved_hash()
            files.write_json(out / "summary.json", {**summary, "run": record})
        figures_and_report(result, args, files)
    sys.stderr.writelines(warnings)
    if args.json:
        sys.stdout.write(json.dumps(summary, allow_nan=False) + "\n")
    else:

        print_check(summary)
    # result.ok: the checks hold on their point values, and something was tested
    return int(ExitCode.OK if result.ok else ExitCode.CHECK_FAILED)


def cmd_optimise(args: argparse.Namespace) -> int:
    """Least-cost design; exit 0 with a design, 1 if no family meets the targets."""

    project = load(args.project)
    if not isinstance(project, Project):  # a corridor: every section

        return cli_optimise(args, project)
    if project.design is None:
        raise project.error_at((), "the project has no design: section to optimise "
                                   "(see the README, 'Designing protection')")
    registry = plugins_for(project, args)
    warnings = requirement_warnings(project, args)
    if getattr(args, "max_rocks", None):
        if args.max_rocks < (args.rocks or project.rocks.count):
            raise InputError(f"--max-rocks {args.max_rocks:,}: expected at least the "
                             f"{args.rocks or project.rocks.count:,} rocks of the search; a "
                             "decision looks at more rocks than the search, never fewer")
        project = project.model_copy(update={"design": project.design.model_copy(
            update={"max_rocks": args.max_rocks})})
    n = args.rocks or project.rocks.count
    grid = project.analysis.envelope_points + 400
    in_memory_guard(n, grid, len(project.analysis.stations))
    decision_memory_guard(max(n, project.design.max_rocks), len(project.analysis.stations))
    with OutputSet() as files:
        reserve(files, args.out, ("design.yaml", "alternatives.csv", "barriers.csv",
                                  "summary.json"))
        reserve(files, args.report, REPORT_FILES)
        reserve(files, args.plot, figure_files(FIGURES, args))
        report = optimise_with_files(project, args, registry, files, args.project)
    sys.stderr.writelines(warnings)
    if args.json:
        sys.stdout.write(json.dumps(report.summary, allow_nan=False) + "\n")
    else:
        print_optimised(report.result, project, report.summary,
                        None if report.design is None else report.design.summary)
    return int(ExitCode.OK if report.result.best is not None else ExitCode.CHECK_FAILED)


def cmd_plugins(args: argparse.Namespace) -> int:
    """List the plugins; exit 0 even if some failed (they are listed), 3 on duplicates."""

    registry = load_plugins(args.block)  # PluginError -> exit 3 in main()
    if args.json:
        sys.stdout.write(json.dumps(plugins_json(registry), allow_nan=False) + "\n")
    else:

        table = plugins_table(registry)
        fitted_console(table).print(table)
    return int(ExitCode.OK)


def cmd_serve(args: argparse.Namespace) -> int:
    """Serve the browser app until Ctrl-C (the web extra, imported only here)."""

    code = serve(args.project, host=args.host, port=args.port, block=args.block)
    # Ctrl-C is how the server is stopped (uvicorn raises it again once it has
    # shut down): its normal end, not an interrupted command.
    forget_interrupts()
    return code


# ---- the commands' parsers ---------------------------------------------------------



"""The commands on one project: simulate, check, optimise, plugins and serve."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import ExitCode, InputError
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
from .optimised import optimise_with_files, print_optimised
from .options import (
    PROG,
    add_block_option,
    add_run_options,
    add_tasks_options,
    int_at_least,
)

if TYPE_CHECKING:  # pragma: no cover
    pass


def cmd_simulate(args: argparse.Namespace) -> int:
    from ..api import run_simulation
    from ..project import Project
    from ..report.outputs import OutputSet
    from ..results import SimulationResult
    from ..run.simulation import study_memory

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
            from .corridor_commands import cli_simulate

            return cli_simulate(args, project)
    if args.workers or args.scheduler:
        raise InputError("--workers and --scheduler run the sections of a corridor (a project "
                         "file with sections:); this file has none")
    plugins_for(project, args)
    n = args.rocks or project.rocks.count
    memory_guard(study_memory(project, n), f"{n:,} rocks with "
                  f"{project.analysis.envelope_points} envelope points",
                  "Use fewer analysis.envelope_points or analysis.stations.")
    with OutputSet() as files:
        reserve(files, args.out, ("rocks.csv", "crossings.csv", "barriers.csv",
                                  "summary.json"))
        reserve(files, args.report, REPORT_FILES)
        reserve(files, args.plot, figure_files(FIGURES, args))
        on_chunk = table_writers(files, args.out) if args.out else None
        study = run_with_progress(run_simulation, project, args, on_chunk=on_chunk)
        result = SimulationResult(project, study)
        summary = result.summary
        if args.out:
            files.write_csv(args.out / "barriers.csv", result.barriers)
            files.write_json(args.out / "summary.json",
                             {**summary, "run": run_record(study, args)})
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
        from ..report.terminal import print_simulation

        print_simulation(summary)
    if recorded is not None and not same:
        # A repeat is a check of reproducibility: results that differ fail it.
        return int(ExitCode.CHECK_FAILED)
    return int(ExitCode.OK)


def cmd_check(args: argparse.Namespace) -> int:
    """Evaluate the project's measures; exit 0 if every check holds, else 1."""
    from ..api import check
    from ..project import Project
    from ..report.outputs import OutputSet

    project = load(args.project)
    if not isinstance(project, Project):  # a corridor: every section
        from .corridor_commands import cli_check

        return cli_check(args, project)
    if not args.scenarios and (args.workers or args.scheduler):
        raise InputError("--workers and --scheduler run the scenarios of check --scenarios "
                         "(give --scenarios too), or the sections of a corridor")
    registry = plugins_for(project, args)
    if args.scenarios:  # every scenario of the study
        from .scenario_commands import cli_check_scenarios

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
        study = evaluation.study
        if args.out:
            out: Path = args.out
            files.write_csv(out / "rocks.csv", result.rocks)
            files.write_csv(out / "crossings.csv", study.crossings_table())
            files.write_csv(out / "measures.csv", evaluation.outcomes_table())
            files.write_csv(out / "barriers.csv", result.barriers)
            record = run_record(study, args)
            record["project"] = evaluation.resolved_project().resolved_dict()
            record["project_hash"] = evaluation.resolved_project().resolved_hash()
            files.write_json(out / "summary.json", {**summary, "run": record})
        figures_and_report(result, args, files)
    sys.stderr.writelines(warnings)
    if args.json:
        sys.stdout.write(json.dumps(summary, allow_nan=False) + "\n")
    else:
        from ..report.terminal import print_check

        print_check(summary)
    # result.ok: the checks hold on their point values, and something was tested
    return int(ExitCode.OK if result.ok else ExitCode.CHECK_FAILED)


def cmd_optimise(args: argparse.Namespace) -> int:
    """Least-cost design; exit 0 with a design, 1 if no family meets the targets."""
    from ..project import Project
    from ..report.outputs import OutputSet

    project = load(args.project)
    if not isinstance(project, Project):  # a corridor: every section
        from .corridor_commands import cli_optimise

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
    decision_memory_guard(max(n, project.design.max_rocks), grid, len(project.analysis.stations))
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
    from ..plugins import load_registry, plugins_json
    from ..report.terminal import plugins_table

    registry = load_registry(blocked=args.block)  # PluginError -> exit 3 in main()
    if args.json:
        sys.stdout.write(json.dumps(plugins_json(registry), allow_nan=False) + "\n")
    else:
        from ..report.terminal import fitted_console

        table = plugins_table(registry)
        fitted_console(table).print(table)
    return int(ExitCode.OK)


def cmd_serve(args: argparse.Namespace) -> int:
    """Serve the browser app until Ctrl-C (the web extra, imported only here)."""
    from ..report.interrupts import forget_interrupts
    from ..serve import serve

    code = serve(args.project, host=args.host, port=args.port, block=args.block)
    # Ctrl-C is how the server is stopped (uvicorn raises it again once it has
    # shut down): its normal end, not an interrupted command.
    forget_interrupts()
    return code


# ---- the commands' parsers ---------------------------------------------------------


def add_simulate_parser(sub: Any) -> None:
    """The ``simulate`` command and its options."""
    sim = sub.add_parser(
        "simulate",
        help="run the rockfall study of a project",
        description="Simulate the rocks of a project: where they go, how high and how fast "
        "they pass the analysis stations, and where they stop.",
    )
    add_run_options(
        sim,
        project="project file (YAML)",
        rocks="number of rocks (default: rocks.count of the project, or the count that "
        "--repeat reads)",
        seed="random seed (default: rocks.seed of the project, or the seed that --repeat "
        "reads)",
        out="write rocks.csv (one row per rock), crossings.csv (one row per rock and "
        "station), barriers.csv (one row per station and quantity: its statistics) and "
        "summary.json (the summary and the run record that --repeat reads) into DIR",
        plot="draw profile.png (the section, rock paths and rest positions), envelopes.png "
        "(passing height, energy and speed along x), stops.png (where the rocks ended) and "
        "passing_station_N.png (histograms and cumulative distributions at analysis station "
        "N) into DIR",
        json_="print the summary as one JSON object on stdout instead of the report",
        repeatable=True,
    )
    add_tasks_options(sim, "a corridor's sections (a file with sections:)")
    add_block_option(sim)
    sim.set_defaults(func=cmd_simulate)


def add_check_parser(sub: Any) -> None:
    """The ``check`` command and its options."""
    chk = sub.add_parser(
        "check",
        help="check the protective measures of a project against its safety concept",
        description="Run the project's rocks against its measures: per measure how many "
        "rocks it met, caught, let over or through, its safety factors against their "
        "targets, and how many rocks still reach the protected zone. Exit code 0 when "
        "every check holds, 1 when one fails.",
    )
    add_run_options(
        chk,
        project="project file (YAML) with the measures: to check",
        rocks="number of rocks (default: rocks.count of the project)",
        seed="random seed (default: rocks.seed of the project)",
        out="write rocks.csv (one row per rock, with the measure that caught it), "
        "crossings.csv (one row per rock and station), measures.csv (one row per rock and "
        "measure), barriers.csv (one row per station or barrier and quantity: its "
        "statistics and the barrier's figures) and summary.json (the summary and the run "
        "record) into DIR",
        plot="draw profile.png (the section with the measures, rock paths and rest "
        "positions), envelopes.png, stops.png, passing_station_N.png and "
        "passing_measure_N.png (the distributions at analysis station N and at barrier N of "
        "measures:) into DIR; with --scenarios, those of the binding scenario and the "
        "margins figure (the margin in every scenario)",
        json_="print the summary with measures, protect, ok and failures as one JSON object "
        "on stdout instead of the report",
    )
    chk.add_argument("--scenarios", action="store_true",
                     help="check the measures in every scenario of the project's study: "
                     "section, each with its own rocks; holds when it holds in the share "
                     "design.scenarios asks (default: all); names the binding scenario")
    add_tasks_options(chk, "the scenarios of --scenarios, or a corridor's sections")
    add_block_option(chk)
    chk.set_defaults(func=cmd_check)


def add_optimise_parser(sub: Any) -> None:
    """The ``optimise`` command (alias ``optimize``) and its options."""
    opt = sub.add_parser(
        "optimise",
        aliases=["optimize"],
        help="find the least-cost protection that meets the safety targets",
        description="Search the candidate measures of the project's design section for the "
        "cheapest design of every family (each type alone, pairs, the same type twice, ...) "
        "that meets every safety check and the residual target, check each family's best "
        "exactly and on fresh rocks, and compare them.",
    )
    add_run_options(
        opt,
        project="project file (YAML) with a design: section",
        rocks="number of rocks every design is searched with (default: rocks.count of the "
        "project; at least the rocks that can show the residual target); a design near a "
        "limit is decided with more, up to design.max_rocks, and checked on fresh rocks, at "
        "least twice those that decided it",
        seed="random seed of the search and of the decision (default: rocks.seed of the "
        "project; the fresh rocks use another seed)",
        out="write design.yaml (the project with the chosen measures, for check; removed "
        "when no design is admissible), alternatives.csv (one row per family of measures), "
        "barriers.csv (the chosen design's stations and barriers, one row per place and "
        "quantity) and summary.json (the summary and the run record) into DIR",
        plot="draw alternatives.png (every family's cost or reason) and profile.png, "
        "envelopes.png, stops.png, passing_station_N.png and passing_measure_N.png of the "
        "chosen design into DIR (only alternatives.png when no design is admissible)",
        json_="print the alternatives and the best design as one JSON object on stdout "
        "instead of the report",
    )
    opt.add_argument("--max-rocks", type=int_at_least(1, "number", 2_000_000),
                     metavar="N", help="rocks of the last look of every decision (default: "
                     "design.max_rocks of the project, 400,000): a design still undecided "
                     "there is marginal, and the report says how many rocks would decide it")
    add_block_option(opt)
    opt.set_defaults(func=cmd_optimise)


def add_plugins_parser(sub: Any) -> None:
    """The ``plugins`` command and its options."""
    plg = sub.add_parser(
        "plugins",
        help="list the measures, safety concepts and cost models of the installed plugins",
        description="List what the installed plugins provide, which distribution provides "
        "each name, and every plugin that failed to load (with the reason).",
    )
    plg.add_argument("--json", action="store_true",
                     help="print the measures, safety concepts, cost models and failed "
                     "plugins as one JSON object on stdout instead of tables")
    add_block_option(plg)
    plg.set_defaults(func=cmd_plugins)


def add_serve_parser(sub: Any) -> None:
    """The ``serve`` command and its options."""
    srv = sub.add_parser(
        "serve",
        help="design in the browser: the section, the rocks, and measures dragged along it",
        description="Start the browser app on the projects (needs the web extra: "
        'pip install "rockfall-design[web]") and print its address, with a per-run token '
        "that keeps other local users and other sites out. Ctrl-C stops it.",
    )
    srv.add_argument("project", type=Path, nargs="*",
                     help="project files (YAML), one or more; default: those of the current "
                     "directory")
    srv.add_argument("--port", type=int_at_least(0, "port", 65535), metavar="N",
                     help="port to listen on (default: the first free one from 8765; "
                     "0: any free port)")
    srv.add_argument("--host", default="127.0.0.1", metavar="H",
                     help="address to listen on (default: 127.0.0.1, this machine only)")
    add_block_option(srv)
    srv.set_defaults(func=cmd_serve)

"""The ``rockfall-design`` command. The only place that turns errors into exit codes."""

from __future__ import annotations

import argparse
import json
import os
import signal
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

# The project's limit (rockfall_design.project.MAX_ROCKS), from a module
# light enough for every --help (no pydantic).
from .arguments import MAX_ROCKS as _MAX_ROCKS
from .errors import ExitCode, InputError, Interrupted, RockfallError
from .version import __version__

if TYPE_CHECKING:  # pragma: no cover
    from .outputs import OutputSet

__all__ = ["main"]

PROG = "rockfall-design"


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line and exit code 2 (BAD_INPUT)."""

    def error(self, message: str) -> NoReturn:
        self.exit(int(ExitCode.BAD_INPUT), f"{self.prog}: error: {message} (see --help)\n")


def _int_at_least(low: int, what: str, high: int | None = None):
    """An argparse type: a whole number >= ``low`` ("expected a {what} >= {low}"), <= ``high``."""

    def parse(text: str) -> int:
        from .arguments import bounds_problem

        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        # The API's checks and words (rockfall_design.arguments).
        problem = bounds_problem(v, low, high, what)
        if problem is not None:
            raise argparse.ArgumentTypeError(problem)
        return v

    return parse


_positive_int = _int_at_least(1, "number", _MAX_ROCKS)


def _formats(text: str) -> tuple[str, ...]:
    """An argparse type: 'png,svg' -> ('png', 'svg'), each a known figure format."""
    from .report.figures import FIGURE_FORMATS

    out = tuple(dict.fromkeys(f.strip().lower() for f in text.split(",") if f.strip()))
    bad = [f for f in out if f not in FIGURE_FORMATS]
    if bad or not out:
        raise argparse.ArgumentTypeError(
            f"expected formats among {', '.join(FIGURE_FORMATS)}, got {text!r}")
    return out
_seed = _int_at_least(0, "seed")


def _add_run_options(
    p: argparse.ArgumentParser,
    *,
    project: str,
    rocks: str,
    seed: str,
    out: str,
    plot: str,
    json_: str,
    repeatable: bool = False,
) -> None:
    """The options every run command has; each command says what they do for it.

    The help texts differ because the commands write different files and
    JSON (tests/cli/test_cli_help.py runs each command to hold them to it).
    """
    if repeatable:
        p.add_argument("project", type=Path, nargs="?", help=project)
        p.add_argument("--repeat", type=Path, metavar="SUMMARY",
                       help="repeat the run recorded in a summary.json (its resolved project, "
                       "seed and rock count) instead of reading a project file")
    else:
        p.add_argument("project", type=Path, help=project)
    p.add_argument("--rocks", type=_positive_int, metavar="N", help=rocks)
    p.add_argument("--seed", type=_seed, metavar="S", help=seed)
    p.add_argument("--out", type=Path, metavar="DIR", help=out)
    p.add_argument("--plot", type=Path, metavar="DIR", help=plot)
    p.add_argument("--plot-format", type=_formats, default=("png",), metavar="FMT[,FMT]",
                   help="file formats of the --plot figures: png, svg, pdf, comma-separated "
                   "(default: png)")
    p.add_argument("--report", type=Path, metavar="DIR",
                   help="write DIR/report.html (self-contained: figures inline as SVG) and "
                   "DIR/report.md (its Markdown twin, figures beside it as SVG)")
    p.add_argument("--json", action="store_true", help=json_)


def _add_tasks_options(p: argparse.ArgumentParser, what: str) -> None:
    """--workers and --scheduler: where independent runs (scenarios, sections) run."""
    p.add_argument("--workers", type=_int_at_least(1, "number of workers"), metavar="N",
                   help=f"run {what} on a local pool of N processes (default: one per core; "
                   "1 runs them in this process)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help=f"run {what} on the Dask cluster of this scheduler (e.g. "
                   "tcp://127.0.0.1:8786); needs the study extra")


def _add_block_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--block", action="append", default=[], metavar="NAME",
                   help="do not load the plugin with this entry-point or distribution "
                   "name (repeatable)")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog=PROG, description="Rockfall trajectories and protection design.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    sim = sub.add_parser(
        "simulate",
        help="run the rockfall study of a project",
        description="Simulate the rocks of a project: where they go, how high and how fast "
        "they pass the analysis stations, and where they stop.",
    )
    _add_run_options(
        sim,
        project="project file (YAML)",
        rocks="number of rocks (default: rocks.count of the project, or the count that "
        "--repeat reads)",
        seed="random seed (default: rocks.seed of the project, or the seed that --repeat "
        "reads)",
        out="write rocks.csv (one row per rock), crossings.csv (one row per rock and "
        "station) and summary.json (the summary and the run record that --repeat reads) "
        "into DIR",
        plot="draw profile.png (the section, rock paths and rest positions), envelopes.png "
        "(passing height and energy along x) and stops.png (rest positions) into DIR",
        json_="print the summary as one JSON object on stdout instead of the report",
        repeatable=True,
    )
    _add_tasks_options(sim, "a corridor's sections (a file with sections:)")
    _add_block_option(sim)
    sim.set_defaults(func=cmd_simulate)
    chk = sub.add_parser(
        "check",
        help="check the protective measures of a project against its safety concept",
        description="Run the project's rocks against its measures: per measure how many "
        "rocks it met, caught, let over or through, its safety factors against their "
        "targets, and how many rocks still reach the protected zone. Exit code 0 when "
        "every check holds, 1 when one fails.",
    )
    _add_run_options(
        chk,
        project="project file (YAML) with the measures: to check",
        rocks="number of rocks (default: rocks.count of the project)",
        seed="random seed (default: rocks.seed of the project)",
        out="write rocks.csv (one row per rock, with the measure that caught it), "
        "crossings.csv (one row per rock and station), measures.csv (one row per rock and "
        "measure) and summary.json (the summary and the run record) into DIR",
        plot="draw profile.png (the section with the measures, rock paths and rest "
        "positions), envelopes.png and stops.png into DIR; with --scenarios, those of the "
        "binding scenario and the margins figure (the margin in every scenario)",
        json_="print the summary with measures, protect, ok and failures as one JSON object "
        "on stdout instead of the report",
    )
    chk.add_argument("--scenarios", action="store_true",
                     help="check the measures in every scenario of the project's study: "
                     "section, each with its own rocks; holds when it holds in the share "
                     "design.scenarios asks (default: all); names the binding scenario")
    _add_tasks_options(chk, "the scenarios of --scenarios, or a corridor's sections")
    _add_block_option(chk)
    chk.set_defaults(func=cmd_check)
    opt = sub.add_parser(
        "optimise",
        aliases=["optimize"],
        help="find the least-cost protection that meets the safety targets",
        description="Search the candidate measures of the project's design section for the "
        "cheapest design of every family (each type alone, pairs, the same type twice, ...) "
        "that meets every safety check and the residual target, check each family's best "
        "exactly and on fresh rocks, and compare them.",
    )
    _add_run_options(
        opt,
        project="project file (YAML) with a design: section",
        rocks="number of rocks every design is searched with (default: rocks.count of the "
        "project; at least the rocks that can show the residual target); a design near a "
        "limit is decided with more, up to design.max_rocks, and checked on fresh rocks, at "
        "least twice those that decided it",
        seed="random seed of the search and of the decision (default: rocks.seed of the "
        "project; the fresh rocks use another seed)",
        out="write design.yaml (the project with the chosen measures, for check; removed "
        "when no design is admissible), alternatives.csv (one row per family of measures) "
        "and summary.json (the summary and the run record) into DIR",
        plot="draw alternatives.png (every family's cost or reason) and profile.png, "
        "envelopes.png and stops.png of the chosen design into DIR (only alternatives.png "
        "when no design is admissible)",
        json_="print the alternatives and the best design as one JSON object on stdout "
        "instead of the report",
    )
    opt.add_argument("--max-rocks", type=_int_at_least(1, "number", 2_000_000),
                     metavar="N", help="rocks of the last look of every decision (default: "
                     "design.max_rocks of the project, 50,000): a design still undecided "
                     "there is marginal, and the report says how many rocks would decide it")
    _add_block_option(opt)
    opt.set_defaults(func=cmd_optimise)
    from .study.command import add_study_parser

    add_study_parser(sub)
    from .calibration.command import add_calibrate_parser

    add_calibrate_parser(sub)
    plg = sub.add_parser(
        "plugins",
        help="list the measures, safety concepts and cost models of the installed plugins",
        description="List what the installed plugins provide, which distribution provides "
        "each name, and every plugin that failed to load (with the reason).",
    )
    plg.add_argument("--json", action="store_true",
                     help="print the measures, safety concepts, cost models and failed "
                     "plugins as one JSON object on stdout instead of tables")
    _add_block_option(plg)
    plg.set_defaults(func=cmd_plugins)
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
    srv.add_argument("--port", type=_int_at_least(0, "port", 65535), metavar="N",
                     help="port to listen on (default: the first free one from 8765; "
                     "0: any free port)")
    srv.add_argument("--host", default="127.0.0.1", metavar="H",
                     help="address to listen on (default: 127.0.0.1, this machine only)")
    _add_block_option(srv)
    srv.set_defaults(func=cmd_serve)
    return parser


def _memory_guard(need: int, what: str, advice: str) -> None:
    """Refuse a run that would need more memory than the machine has, before it starts.

    ``need`` (bytes) is the run's estimated peak; the limit is 60 % of the
    physical memory, leaving room for Python, the libraries and the rest of
    the machine.
    """
    try:
        total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):  # pragma: no cover - non-POSIX
        return
    if need > 0.6 * total:
        raise InputError(
            f"{what} would need about {need / 2**30:.1f} GiB of memory; this machine has "
            f"{total / 2**30:.1f} GiB. {advice}"
        )


def _in_memory_guard(n_rocks: int, n_grid: int, n_stations: int) -> None:
    """The guard for ``check`` and ``optimise``, which keep every rock's results.

    Per rock and envelope point: float32 height and energy, and float64
    copies of them while the percentiles are taken.
    """
    need = n_rocks * (32 * n_grid + 40 * n_stations + 200)
    _memory_guard(need, f"{n_rocks:,} rocks with {n_grid} envelope points",
                  "Use fewer rocks or fewer analysis.envelope_points.")


def _rich_progress(elapsed: bool) -> Any:
    """A transient rich progress display on stderr (time remaining, or elapsed)."""
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    return Progress(
        "[progress.description]{task.description}",
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn() if elapsed else TimeRemainingColumn(),
        console=Console(stderr=True),
        transient=True,
    )


def _progress(console_needed: bool, total: int):
    """A rich progress bar on stderr for long interactive runs (or None), and its callback.

    The callback is also a safe point: between batches of rocks it stops the
    run if an interrupt was noted whose exception got lost.
    """
    from .outputs import check_interrupt

    if not console_needed:
        return None, (lambda done: check_interrupt())
    prog = _rich_progress(elapsed=False)
    task = prog.add_task("rocks", total=total)

    def update(done: int) -> None:
        check_interrupt()
        prog.update(task, completed=done)

    return prog, update


def _run(run: Any, project: Any, args: argparse.Namespace, **kw: Any) -> Any:
    """Call the API's ``run(project, rocks=..., seed=..., ...)``, with a progress bar if
    interactive, keeping the paths of the first rocks when a figure will need them."""
    from .api import DEFAULT_TRAJECTORIES

    n = args.rocks or project.rocks.count
    drawn = args.plot or args.report
    kw.update(rocks=n, seed=args.seed, trajectories=DEFAULT_TRAJECTORIES if drawn else 0)
    prog, callback = _progress(sys.stderr.isatty() and n >= 20_000, n)
    if prog is None:
        return run(project, progress=callback, **kw)
    with prog:
        return run(project, progress=callback, **kw)


#: The files of --report DIR.
REPORT_FILES = ("report.html", "report.md")


def _figures_and_report(result: Any, args: argparse.Namespace, files: OutputSet) -> None:
    """The --plot figures and the --report documents of an API result, in the output set."""
    if not (args.plot or args.report):
        return
    figures = result.figures()  # drawn once for both
    if args.report:
        from .report.documents import write_report

        write_report(result, args.report, outputs=files, figures=figures)
    if args.plot:
        from .report.figures import save_figures

        # --plot and --report into one directory with --plot-format svg: the
        # report has written those figures already, from the same drawings.
        for fmt in args.plot_format:
            todo = {name: fig for name, fig in figures.items()
                    if args.plot / f"{name}.{fmt}" not in files}
            save_figures(todo, args.plot, (fmt,), files)


def _warn_failures(registry: Any) -> None:
    for f in registry.failures:
        sys.stderr.write(f"{PROG}: warning: plugin {f.plugin!r} was not loaded: {f.reason}\n")


def _requirement_warnings(project: Any, args: argparse.Namespace) -> list[str]:
    """One line per requirement that can never hold with confidence (an allowed fraction 0).

    Found when the project is loaded and written once the run has ended, so
    that a run that fails on bad input or a plugin fault still says one line.
    """
    from .judge.verdict import requirement_warnings

    command = "check" if args.command == "check" else "optimise"
    return [f"{PROG}: warning: {line}\n" for line in requirement_warnings(project, command)]


def _plugins_for(project: Any, args: argparse.Namespace) -> Any:
    """Load the plugins and check the project's plugin sections with them.

    Every command checks the whole project file, ``measures:``, ``safety:``
    and ``design:`` included, so that a bad file is reported whichever
    command reads it (``simulate`` runs the bare slope but still says so).
    """
    from .api import validate_project
    from .plugins import load_registry

    registry = load_registry(blocked=args.block)
    _warn_failures(registry)
    validate_project(project, registry)
    return registry


def cmd_simulate(args: argparse.Namespace) -> int:
    from .api import SimulationResult, run_simulation
    from .outputs import OutputSet
    from .project import Project
    from .run.simulation import study_memory

    recorded = None
    if getattr(args, "repeat", None):
        if args.project is not None:
            raise InputError("give either a project file or --repeat SUMMARY, not both")
        project, recorded = _load_repeat(args)
    elif args.project is None:
        raise InputError("a project file (or --repeat SUMMARY) is needed")
    else:
        project = _load(args.project)
        if not isinstance(project, Project):  # a corridor: every section
            from .corridor import cli_simulate

            return cli_simulate(args, project)
    if args.workers or args.scheduler:
        raise InputError("--workers and --scheduler run the sections of a corridor (a project "
                         "file with sections:); this file has none")
    _plugins_for(project, args)
    n = args.rocks or project.rocks.count
    _memory_guard(study_memory(project, n), f"{n:,} rocks with "
                  f"{project.analysis.envelope_points} envelope points",
                  "Use fewer analysis.envelope_points or analysis.stations.")
    with OutputSet() as files:
        _reserve(files, args.out, ("rocks.csv", "crossings.csv", "summary.json"))
        _reserve(files, args.report, REPORT_FILES)
        _reserve(files, args.plot, _figure_files(_FIGURES, args))
        on_chunk = _table_writers(files, args.out) if args.out else None
        study = _run(run_simulation, project, args, on_chunk=on_chunk)
        result = SimulationResult(project, study)
        summary = result.summary
        if args.out:
            files.write_json(args.out / "summary.json",
                             {**summary, "run": run_record(study, args)})
        _figures_and_report(result, args, files)
    if recorded is not None:
        same = _comparable(summary) == _comparable(recorded)
        sys.stderr.write(
            f"{PROG}: repeated {args.repeat}: "
            + ("the results are identical\n" if same else
               "the results DIFFER from the recorded ones (another version or machine?)\n")
        )
    if args.json:
        sys.stdout.write(json.dumps(summary, allow_nan=False) + "\n")
    else:
        from .report.terminal import print_simulation

        print_simulation(summary)
    if recorded is not None and not same:
        # A repeat is a check of reproducibility: results that differ fail it.
        return int(ExitCode.CHECK_FAILED)
    return int(ExitCode.OK)


#: The figures of --plot (report.plot_study writes all three).
#: The figures of a run (``--plot``), one file per --plot-format each.
_FIGURES = ("profile", "envelopes", "stops")


def _figure_files(stems: Sequence[str], args: argparse.Namespace) -> list[str]:
    """File names of the figures ``stems`` in every format of ``--plot-format``."""
    return [f"{stem}.{fmt}" for stem in stems for fmt in args.plot_format]


def _reserve(files: OutputSet, out: Path | None, names: Sequence[str]) -> None:
    """Reserve the files ``names`` in the --out directory ``out`` (if given) of a run.

    Done before the run, so that a directory that cannot be written is
    reported at once instead of after minutes of computing.
    """
    if out is not None:
        files.reserve(*(out / name for name in names))


def _table_writers(files: OutputSet, out: Path) -> Any:
    """A chunk callback that appends rocks.csv and crossings.csv as the run goes.

    Both files belong to the command's output set ``files``: they stay
    temporary until it commits, so an interrupted run leaves the previous
    tables as they were.
    """
    rocks = files.open(out / "rocks.csv")
    crossings = files.open(out / "crossings.csv")
    first = [True]

    def write(part: Any) -> None:
        for fh, table in ((rocks, part.rocks_table()), (crossings, part.crossings_table())):
            table.to_csv(fh, index=False, header=first[0], lineterminator="\n")
        first[0] = False

    return write


def _load_repeat(args: argparse.Namespace) -> tuple[Any, dict[str, Any]]:
    """The project, seed and rock count recorded in a summary.json, for --repeat."""
    from .project import dump_yaml, load_project_text

    path: Path = args.repeat
    try:
        from .project.inputs import read_text

        recorded = json.loads(read_text(path, "summary to repeat"))
        run = recorded["run"]
        text = dump_yaml(run["project"])
        seed, rocks = run["seed"], run["rocks"]
        # Whole JSON numbers only: a message never quotes what an edited
        # (or any other) file holds.
        if not all(isinstance(v, int) and not isinstance(v, bool) for v in (seed, rocks)):
            raise ValueError("run.seed and run.rocks must be whole numbers")
        if not (seed >= 0 and 1 <= rocks <= _MAX_ROCKS):
            raise ValueError("seed or rock count out of range")
    except json.JSONDecodeError as exc:
        raise InputError(f"{path}:{exc.lineno}: not a summary.json with a run record "
                         f"(invalid JSON at column {exc.colno})") from None
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a summary.json with a run record (not UTF-8 "
                         "text)") from None
    except KeyError as exc:
        raise InputError(f"{path}: not a summary.json with a run record (no key "
                         f"{exc.args[0]!r})") from None
    except (OSError, ValueError, TypeError, AttributeError) as exc:
        reason = (exc.strerror or type(exc).__name__) if isinstance(exc, OSError) else (
            str(exc) if isinstance(exc, ValueError) else "not a mapping")
        raise InputError(f"{path}: not a summary.json with a run record ({reason})") from None
    if run.get("version") != __version__:
        sys.stderr.write(f"{PROG}: warning: {path} was written by version "
                         f"{run.get('version')}, this is {__version__}\n")
    from .project.messages import _unquoted

    with _unquoted():  # a value of the recorded project is not quoted back either
        project = load_project_text(text, f"{path} (run.project)")
    args.seed = seed if args.seed is None else args.seed
    args.rocks = rocks if args.rocks is None else args.rocks
    args.project = path
    return project, recorded


def _load(path: Path) -> Any:
    """The project file: a Project, or a Corridor when it lists ``sections:``."""
    from .project import load_corridor

    return load_corridor(path)


def _comparable(summary: dict[str, Any]) -> dict[str, Any]:
    """A summary without what legitimately changes between runs (timing, the run record)."""
    return {k: v for k, v in summary.items() if k not in ("runtime_s", "run")}


def cmd_check(args: argparse.Namespace) -> int:
    """Evaluate the project's measures; exit 0 if every check holds, else 1."""
    from .api import check
    from .outputs import OutputSet
    from .project import Project

    project = _load(args.project)
    if not isinstance(project, Project):  # a corridor: every section
        from .corridor import cli_check

        return cli_check(args, project)
    if not args.scenarios and (args.workers or args.scheduler):
        raise InputError("--workers and --scheduler run the scenarios of check --scenarios "
                         "(give --scenarios too), or the sections of a corridor")
    registry = _plugins_for(project, args)
    if args.scenarios:  # every scenario of the study
        from .across import cli_check_scenarios

        return cli_check_scenarios(args, project, registry)
    warnings = _requirement_warnings(project, args)
    n = args.rocks or project.rocks.count
    _in_memory_guard(n, project.analysis.envelope_points + len(project.analysis.stations),
                     len(project.analysis.stations))
    with OutputSet() as files:
        _reserve(files, args.out, ("rocks.csv", "crossings.csv", "measures.csv", "summary.json"))
        _reserve(files, args.report, REPORT_FILES)
        _reserve(files, args.plot, _figure_files(_FIGURES, args))
        result = _run(check, project, args, registry=registry)
        evaluation = result.evaluation
        summary = result.summary
        study = evaluation.study
        if args.out:
            out: Path = args.out
            files.write_csv(out / "rocks.csv", result.rocks)
            files.write_csv(out / "crossings.csv", study.crossings_table())
            files.write_csv(out / "measures.csv", evaluation.outcomes_table())
            record = run_record(study, args)
            record["project"] = evaluation.resolved_project().resolved_dict()
            record["project_hash"] = evaluation.resolved_project().resolved_hash()
            files.write_json(out / "summary.json", {**summary, "run": record})
        _figures_and_report(result, args, files)
    sys.stderr.writelines(warnings)
    if args.json:
        sys.stdout.write(json.dumps(summary, allow_nan=False) + "\n")
    else:
        from .report.terminal import print_check

        print_check(summary)
    # result.ok: the checks hold on their point values, and something was tested
    return int(ExitCode.OK if result.ok else ExitCode.CHECK_FAILED)


def cmd_optimise(args: argparse.Namespace) -> int:
    """Least-cost design; exit 0 with a design, 1 if no family meets the targets."""
    from .outputs import OutputSet
    from .project import Project

    project = _load(args.project)
    if not isinstance(project, Project):  # a corridor: every section
        from .corridor import cli_optimise

        return cli_optimise(args, project)
    if project.design is None:
        raise project.error_at((), "the project has no design: section to optimise "
                                   "(see the README, 'Designing protection')")
    registry = _plugins_for(project, args)
    warnings = _requirement_warnings(project, args)
    if getattr(args, "max_rocks", None):
        if args.max_rocks < (args.rocks or project.rocks.count):
            raise InputError(f"--max-rocks {args.max_rocks:,}: expected at least the "
                             f"{args.rocks or project.rocks.count:,} rocks of the search; a "
                             "decision looks at more rocks than the search, never fewer")
        project = project.model_copy(update={"design": project.design.model_copy(
            update={"max_rocks": args.max_rocks})})
    n = args.rocks or project.rocks.count
    _in_memory_guard(max(n, project.design.max_rocks), project.analysis.envelope_points + 400,
                     len(project.analysis.stations))
    with OutputSet() as files:
        _reserve(files, args.out, ("design.yaml", "alternatives.csv", "summary.json"))
        _reserve(files, args.report, REPORT_FILES)
        _reserve(files, args.plot, _figure_files(_FIGURES, args))
        report = optimise_with_files(project, args, registry, files, args.project)
    sys.stderr.writelines(warnings)
    if args.json:
        sys.stdout.write(json.dumps(report.summary, allow_nan=False) + "\n")
    else:
        print_optimised(report.result, project, report.summary)
    return int(ExitCode.OK if report.result.best is not None else ExitCode.CHECK_FAILED)


def optimise_with_files(project: Any, args: argparse.Namespace, registry: Any,
                        files: OutputSet, source: Any,
                        record: dict[str, Any] | None = None) -> Any:
    """Optimise one project and put its files (--out, --plot, --report) in the output set.

    Parameters
    ----------
    project
        The project (with ``design:``).
    args
        Its options: ``rocks``, ``seed``, ``out``, ``plot``, ``report``, ``plot_format``.
    registry
        The plugins.
    files
        The command's output set.
    source
        What design.yaml says the design was chosen from (the project file,
        or the corridor file and the section).
    record
        Keys added to the run record of summary.json after ``project_file``.

    Returns
    -------
    OptimiseResult
    """
    from .api import optimise
    from .report.terminal import design_yaml

    n = args.rocks or project.rocks.count
    prog, callback = _stage_progress(sys.stderr.isatty())
    if prog is None:
        report = optimise(project, rocks=n, seed=args.seed, registry=registry,
                          progress=callback)
    else:
        with prog:
            report = optimise(project, rocks=n, seed=args.seed, registry=registry,
                              progress=callback)
    result = report.result
    summary = report.summary
    if args.out:
        out: Path = args.out
        if result.best is not None and project.design.scenarios is not None:
            # a design across a study's scenarios
            from .across import across_design_yaml

            files.write_text(out / "design.yaml", across_design_yaml(result, source, project))
        elif result.best is not None:
            files.write_text(out / "design.yaml", design_yaml(result.best, source,
                                                              result.search_rocks,
                                                              result.looks))
        else:
            # A design.yaml of an earlier run must not sit beside a
            # summary that says there is no design.
            files.remove(out / "design.yaml")
        files.write_csv(out / "alternatives.csv", report.alternatives)
        run = {"command": "optimise", "version": __version__, "seed": result.seed,
               "rocks": result.rocks, "project_file": str(args.project), **(record or {}),
               "project_hash": project.resolved_hash(), "project": project.resolved_dict()}
        files.write_json(out / "summary.json", {**summary, "run": run})
    if args.plot and result.best is None:
        # Figures of an earlier run's design must not stay beside a
        # result that has none.
        for name in _figure_files(_FIGURES, args):
            files.remove(args.plot / name)
    # The chosen design's figures run its rocks again, keeping a sample of paths.
    _figures_and_report(report, args, files)
    return report


def print_optimised(result: Any, project: Any, summary: dict[str, Any] | None = None) -> None:
    """The terminal report of ``optimise``: the verdict, the alternatives, the chosen
    design's bill (from ``summary``), and the scenarios if any."""
    from .report.terminal import print_optimise

    print_optimise(result, project, summary=summary)
    if project.design.scenarios is not None:
        from .across import print_across

        print_across(result)


def _stage_progress(interactive: bool):
    """A rich progress display of the optimiser's stages on stderr (or None), and its callback.

    The callback is also a safe point, between families: it stops the run if
    an interrupt was noted whose exception got lost.
    """
    from .outputs import check_interrupt

    if not interactive:
        return None, (lambda stage, done, total: check_interrupt())
    prog = _rich_progress(elapsed=True)
    tasks: dict[str, Any] = {}

    def callback(stage: str, done: int, total: int) -> None:
        check_interrupt()
        label = {"search": "searching families", "check": "exact and fresh checks"}.get(
            stage, stage)
        if stage not in tasks:
            tasks[stage] = prog.add_task(label, total=total)
        prog.update(tasks[stage], completed=done, total=total)

    return prog, callback


def cmd_plugins(args: argparse.Namespace) -> int:
    """List the plugins; exit 0 even if some failed (they are listed), 3 on duplicates."""
    from .plugins import load_registry, plugins_json
    from .report.terminal import plugins_table

    registry = load_registry(blocked=args.block)  # PluginError -> exit 3 in main()
    if args.json:
        sys.stdout.write(json.dumps(plugins_json(registry), allow_nan=False) + "\n")
    else:
        from .report.terminal import fitted_console

        table = plugins_table(registry)
        fitted_console(table).print(table)
    return int(ExitCode.OK)


def cmd_serve(args: argparse.Namespace) -> int:
    """Serve the browser app until Ctrl-C (the web extra, imported only here)."""
    from .outputs import forget_interrupts
    from .serve import serve

    code = serve(args.project, host=args.host, port=args.port, block=args.block)
    # Ctrl-C is how the server is stopped (uvicorn raises it again once it has
    # shut down): its normal end, not an interrupted command.
    forget_interrupts()
    return code


def run_record(study: Any, args: argparse.Namespace) -> dict[str, Any]:
    """What is needed to repeat a run exactly: version, seed, rocks, project."""
    return {
        "command": args.command,
        "version": __version__,
        "seed": int(study.seed),
        "rocks": int(study.n),
        "project_file": str(args.project),
        "project_hash": study.project.resolved_hash(),
        "project": study.project.resolved_dict(),
    }


class _Interrupted(Interrupted):
    """The ``KeyboardInterrupt`` that SIGINT and SIGTERM raise while a command runs.

    An :class:`~rockfall_design.errors.Interrupted`, so that plugin code
    cannot pass for a real Ctrl-C by raising ``KeyboardInterrupt``. A subclass
    of ``KeyboardInterrupt`` on purpose: CPython records an exact ``KeyboardInterrupt``
    that passes through an ``exec()`` of a string (numba compiles that way)
    as unhandled, and ``python -m rockfall_design`` then ends by SIGINT at
    exit, even though :func:`main` handled it, instead of with exit code 130.
    """


#: True once the command has ended and the process is on its way out.
_exiting = [False]


def _on_signal(signum: int, frame: Any) -> None:
    # SIGTERM is treated like Ctrl-C, so that the command's output set is
    # discarded and the previous results stay as they were.
    if _exiting[0]:
        return  # the command is over, its output complete: nothing to stop
    from .outputs import note_interrupt

    # Noted first: the exception may be swallowed where it lands (numpy does,
    # in its __array_ufunc__ lookup); the note stops the next safe point and
    # every commit all the same.
    note_interrupt(signum)
    raise _Interrupted(signum)


class _StdoutFailed(InputError):
    """Standard output could not be written (a full disk, a closed pipe): exit code 2."""


class _GuardedStdout:
    """``sys.stdout`` while a command runs: a failing write is one line, not a traceback.

    The report or the JSON may go to a file on a full disk (``> /dev/full``)
    or a pipe whose reader has gone; the error is raised as
    :class:`_StdoutFailed` naming the OS error.
    """

    def __init__(self, stream: Any) -> None:
        self._stream = stream

    def _guard(self, method: str, *args: Any) -> Any:
        try:
            return getattr(self._stream, method)(*args)
        except OSError as exc:
            raise _StdoutFailed(
                f"cannot write to standard output: {exc.strerror or type(exc).__name__}"
            ) from None

    def write(self, text: str) -> int:
        return self._guard("write", text)

    def writelines(self, lines: Any) -> None:
        self._guard("writelines", lines)

    def flush(self) -> None:
        self._guard("flush")

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


def _silence_stdout() -> None:
    """After stdout failed: send what is left in its buffer to /dev/null at exit.

    Otherwise the interpreter's final flush fails again and prints a second
    message ("Exception ignored ...") and exits with code 120.
    """
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):  # not a real file (a test's capture)
        pass


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``rockfall-design`` console script."""
    from .outputs import check_interrupt, committed_sets, forget_interrupts

    parser = build_parser()
    args = parser.parse_args(argv)
    committed_before = committed_sets()
    from .project.inputs import forget_inputs

    forget_inputs()  # the files this command reads are noted anew
    forget_interrupts()
    handled = [signal.SIGTERM]
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        # An ignored SIGINT (a background job of a non-interactive shell) stays so.
        handled.append(signal.SIGINT)
    previous = {s: signal.signal(s, _on_signal) for s in handled}
    stdout = sys.stdout
    sys.stdout = _GuardedStdout(stdout)
    try:
        if getattr(args, "block", None):
            from .plugins import check_blocked_names

            check_blocked_names(args.block)
        code = int(args.func(args))
        sys.stdout.flush()  # here, where a failure can still be reported
        # An interrupt whose exception was swallowed: the command still ends as interrupted.
        check_interrupt()
        return code
    except RockfallError as exc:
        if isinstance(exc, _StdoutFailed):
            sys.stdout = stdout
            _silence_stdout()
        from .project.inputs import strip_controls

        # One line, and nothing in it that steers the terminal (a name from a file).
        msg = strip_controls(" ".join(str(exc).split("\n")))
        sys.stderr.write(f"{PROG}: error: {msg}\n")
        return int(exc.exit_code)
    except KeyboardInterrupt:
        # A command commits its output files as one set, and an interrupt that
        # arrives during the commit is held until it is complete: either all
        # of the new files are in place, or none was changed.
        if committed_sets() > committed_before:
            what = "the results had been written completely before the interrupt"
        else:
            what = "no files were changed"
        sys.stderr.write(f"{PROG}: interrupted; {what}\n")
        return int(ExitCode.INTERRUPTED)
    finally:
        # Set first, without a call: a signal from here on cannot raise.
        _exiting[0] = True
        forget_interrupts()  # this command's: they must not stop what the process does next
        sys.stdout = stdout
        for s, handler in previous.items():
            # Run as the program (no argv), the process exits next: a Ctrl-C
            # now would only print a traceback from the interpreter's exit.
            signal.signal(s, signal.SIG_IGN if argv is None else handler)
        _exiting[0] = False


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

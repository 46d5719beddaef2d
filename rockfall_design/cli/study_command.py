"""The ``rockfall-design study`` command: its options and what it runs, writes and prints.

Kept beside the study rather than in ``cli.py``, which only registers it;
errors and exit codes are still ``cli.main``'s.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import ExitCode
from .corridor_commands import SectionDone, SectionRun, each_section

if TYPE_CHECKING:  # pragma: no cover
    from ..project import Corridor

__all__ = ["add_study_parser", "cmd_study"]

#: The files of --out DIR.
OUT_FILES = ("scenarios.csv", "sensitivity.csv", "summary.json")


def add_study_parser(sub: Any) -> argparse.ArgumentParser:
    """Add the ``study`` command to the subparsers ``sub`` of the main parser."""
    from .options import add_block_option, formats, int_at_least, positive_int, seed_number

    p = sub.add_parser(
        "study",
        help="run the parametric study of a project's study: section",
        description="Run one full Monte Carlo simulation per scenario of the project's "
        "study: section (every combination of the varied inputs, or a Latin hypercube "
        "sample), each with its own seed, on a local process pool or a Dask cluster; report "
        "each scenario's design values and which input moves each of them most.",
    )
    p.add_argument("project", type=Path, help="project file (YAML) with a study: section")
    p.add_argument("--rocks", type=positive_int, metavar="N",
                   help="number of rocks of each scenario (default: rocks.count of the "
                   "project)")
    p.add_argument("--seed", type=seed_number, metavar="S",
                   help="random seed of the study (default: rocks.seed of the project); each "
                   "scenario's seed is derived from it and its index, and recorded")
    p.add_argument("--out", type=Path, metavar="DIR",
                   help="write scenarios.csv (one row per scenario: its values and design "
                   "values), sensitivity.csv (one row per input and design value) and "
                   "summary.json (the summary and the run record) into DIR")
    p.add_argument("--plot", type=Path, metavar="DIR",
                   help="draw study_envelopes.png (the envelopes of every scenario on one "
                   "plot) and tornado.png (which input moves each design value) into DIR")
    p.add_argument("--plot-format", type=formats, default=("png",), metavar="FMT[,FMT]",
                   help="file formats of the --plot figures: png, svg, pdf, comma-separated "
                   "(default: png)")
    p.add_argument("--json", action="store_true",
                   help="print the summary with vary, scenarios (each with its values, "
                   "stations, stops and protect) and sensitivity as one JSON object on "
                   "stdout instead of the report")
    p.add_argument("--workers", type=int_at_least(1, "number of workers"), metavar="N",
                   help="run N scenarios at once on the local pool (threads, or processes "
                   "with --pool processes; default: one per core; 1 runs them in this process, "
                   "one after the other)")
    p.add_argument("--pool", choices=("threads", "processes"), default="threads",
                   help="the local pool: threads of this process, each scenario with one "
                   "engine thread (the default; nothing to start), or processes (same "
                   "results)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="run the scenarios on the Dask cluster of this scheduler (e.g. "
                   "tcp://127.0.0.1:8786) instead of the local pool; needs the study extra")
    add_block_option(p)
    p.set_defaults(func=cmd_study)
    return p


def run_record(result: Any, args: argparse.Namespace) -> dict[str, Any]:
    """What is needed to repeat a study exactly: version, seed, rocks, project."""
    from ..version import __version__

    return {
        "command": "study",
        "version": __version__,
        "seed": result.seed,
        "rocks": result.n_rocks,
        "project_file": str(args.project),
        "project_hash": result.project.resolved_hash(),
        "project": result.project.resolved_dict(),
    }


def cmd_study(args: argparse.Namespace) -> int:
    """Run the study; exit 0 (a study has no pass or fail)."""
    from ..api import study
    from ..project import Project
    from ..report.outputs import OutputSet
    from ..run.simulation import study_memory
    from ..studies.executors import EXTRA_HINT, usable_cores
    from ..studies.sensitivity import salib_available
    from ..studies.study_result import FIGURES
    from .common import figure_files, load, memory_guard, plugins_for, reserve
    from .options import PROG

    project = load(args.project)
    if not isinstance(project, Project):  # a corridor: every section's study
        return cli_study(args, project)
    registry = plugins_for(project, args)
    if project.study is None:
        raise project.error_at(
            (), "the project has no study: section (inputs to vary and the scenarios to "
            "run; see 'Parametric studies' in the README)")
    n = args.rocks or project.rocks.count
    if args.scheduler is None:
        from ..studies.scenarios import design_points

        # No more at once than there are scenarios, whatever --workers says.
        at_once = min(args.workers or usable_cores(), len(design_points(project.study)))
        memory_guard(at_once * study_memory(project, n),
                      f"{at_once} scenarios of {n:,} rocks at once",
                      "Use fewer --workers, fewer rocks or fewer analysis.envelope_points.")
    if project.study.sampled and not salib_available():
        sys.stderr.write(f"{PROG}: warning: the variance-based indices of a sampled study "
                         f"need SALib: {EXTRA_HINT}; reporting main effects only\n")
    with OutputSet() as files:
        reserve(files, args.out, OUT_FILES)
        reserve(files, args.plot, figure_files(FIGURES, args))
        result = study(project, rocks=n, seed=args.seed, workers=args.workers,
                       scheduler=args.scheduler, progress=sys.stderr.isatty(),
                       registry=registry, pool=args.pool,
                       envelopes=args.plot is not None)  # only the figure reads them
        summary = result.summary
        if args.out:
            out: Path = args.out
            files.write_csv(out / "scenarios.csv", result.scenarios)
            files.write_csv(out / "sensitivity.csv", result.sensitivity)
            files.write_json(out / "summary.json", {**summary, "run": run_record(result, args)})
        if args.plot:
            from ..report.figures import save_figures

            save_figures(result.figures(), args.plot, args.plot_format, files)
    if args.json:
        sys.stdout.write(json.dumps(summary, allow_nan=False) + "\n")
    else:
        result.print()
    return int(ExitCode.OK)


def cli_study(args: argparse.Namespace, corridor: Corridor) -> int:
    """``study`` of a corridor: every section's parametric study, then the totals.

    Each section runs the study of its merged project (the shared
    ``study:`` or its own) with its own seed; its scenarios run on the
    study's executors (a local pool, ``--workers``, ``--scheduler``), one
    section after the other. A study has no pass or fail: exit 0.
    """
    from ..api import study
    from ..studies.study_result import FIGURES
    from .study_command import OUT_FILES, run_record

    for section in corridor.sections:
        if section.project.study is None:
            raise section.project.error_at(
                (), "the section has no study: section (give study: at the top level, or "
                "in every section)")

    def body(run: SectionRun) -> SectionDone:
        section, sub, files = run.section, run.args, run.files
        project = section.project
        result = study(project, rocks=sub.rocks or project.rocks.count, seed=sub.seed,
                       workers=args.workers, scheduler=args.scheduler,
                       progress=sys.stderr.isatty(), registry=run.registry,
                       pool=args.pool, envelopes=sub.plot is not None)
        summary = result.summary
        if sub.out:
            files.write_csv(sub.out / "scenarios.csv", result.scenarios)
            files.write_csv(sub.out / "sensitivity.csv", result.sensitivity)
            record = {**run_record(result, sub), "section": section.name}
            files.write_json(sub.out / "summary.json", {**summary, "run": record})
        if sub.plot:
            from ..report.figures import save_figures

            save_figures(result.figures(), sub.plot, args.plot_format, files)
        return SectionDone(summary, result.print)

    each_section(args, corridor, "study", body, out_files=OUT_FILES, figures=FIGURES,
                 report=False)
    return int(ExitCode.OK)

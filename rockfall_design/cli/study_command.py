"""The ``rockfall-design study`` command: its options and what it runs, writes and prints.

Kept beside the study rather than in ``cli.py``, which only registers it;
errors and exit codes are still ``cli.main``'s.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from ..api import (
    EXTRA_HINT,
    design_points,
    salib_available,
    simulation_memory,
    study,
    usable_cores,
)
from ..errors import ExitCode
from ..project import Project
from ..report.formats import save_figures
from ..report.outputs import OutputSet
from ..studies.study_result import FIGURES
from .common import figure_files, load, memory_guard, plugins_for, repeat_record, reserve
from .corridor_commands import SectionDone, SectionRun, each_section
from .options import PROG

if TYPE_CHECKING:  # pragma: no cover
    from ..project import Corridor

__all__ = ["cmd_study", "cli_study"]

#: The files of --out DIR.
OUT_FILES = ("scenarios.csv", "sensitivity.csv", "summary.json")


def cmd_study(args: argparse.Namespace) -> int:
    """Run the study; exit 0 (a study has no pass or fail)."""

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

        # No more at once than there are scenarios, whatever --workers says.
        at_once = min(args.workers or usable_cores(), len(design_points(project.study)))
        memory_guard(at_once * simulation_memory(project, n),
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
            record = repeat_record(args, result.project, result.seed, result.n_rocks)
            files.write_json(out / "summary.json", {**summary, "run": record})
        if args.plot:

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
            record = {**repeat_record(sub, result.project, result.seed, result.n_rocks),
                      "section": section.name}
            files.write_json(sub.out / "summary.json", {**summary, "run": record})
        if sub.plot:

            save_figures(result.figures(), sub.plot, args.plot_format, files)
        return SectionDone(summary, result.print)

    each_section(args, corridor, "study", body, out_files=OUT_FILES, figures=FIGURES,
                 report=False)
    return int(ExitCode.OK)

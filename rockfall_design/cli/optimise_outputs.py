"""What ``optimise`` writes and prints for one project or one section of a corridor."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .. import api
from ..report.progress import interruptible_stages
from ..report.terminal import design_yaml, print_optimise
from ..version import __version__
from .common import (
    FIGURES,
    figure_files,
    figures_and_report,
)
from .scenario_commands import across_design_yaml, print_across

if TYPE_CHECKING:  # pragma: no cover
    from ..report.outputs import OutputSet


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

    n = args.rocks or project.rocks.count
    prog, callback = interruptible_stages(sys.stderr.isatty())
    if prog is None:
        report = api.optimise(project, rocks=n, seed=args.seed, registry=registry,
                          progress=callback)
    else:
        with prog:
            report = api.optimise(project, rocks=n, seed=args.seed, registry=registry,
                              progress=callback)
    result = report.result
    summary = report.summary
    if args.out:
        out: Path = args.out
        if result.best is not None and project.design.scenarios is not None:
            # a design across a study's scenarios

            files.write_text(out / "design.yaml", across_design_yaml(result, source, project))
        elif result.best is not None:
            files.write_text(out / "design.yaml", design_yaml(result.best, source,
                                                              result.search_rocks,
                                                              result.looks, result.marginal))
        else:
            # A design.yaml of an earlier run must not sit beside a
            # summary that says there is no design.
            files.remove(out / "design.yaml")
        files.write_csv(out / "alternatives.csv", report.alternatives)
        if report.design is not None:  # the chosen design's stations and barriers
            files.write_csv(out / "barriers.csv", report.design.barriers)
        else:
            files.remove(out / "barriers.csv")
        run = {"command": "optimise", "version": __version__, "seed": result.seed,
               "rocks": result.rocks, "project_file": str(args.project), **(record or {}),
               "project_hash": project.resolved_hash(), "project": project.resolved_dict()}
        files.write_json(out / "summary.json", {**summary, "run": run})
    if args.plot and result.best is None:
        # Figures of an earlier run's design must not stay beside a
        # result that has none.
        for name in figure_files(FIGURES, args):
            files.remove(args.plot / name)
    # The chosen design's figures run its rocks again, keeping a sample of paths.
    figures_and_report(report, args, files)
    return report


def print_optimised(result: Any, project: Any, summary: dict[str, Any] | None = None,
                    design: dict[str, Any] | None = None) -> None:
    """The terminal report of ``optimise``: the verdict, the chosen design's design values
    (from ``design``, its check summary) and bill (from ``summary``), the alternatives,
    how sure, and the scenarios if any."""

    print_optimise(result, project, summary=summary, design=design)
    if project.design.scenarios is not None:

        print_across(result)

"""The ``rockfall-design calibrate`` and ``compare`` commands: options, files, printing.

Kept beside the calibration rather than in ``cli.py``, which only registers
them; errors and exit codes are still ``cli.main``'s.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from .. import api
from ..calibration.calibration_result import FIGURES
from ..errors import ExitCode, InputError
from ..project import Project, dump_yaml
from ..report.outputs import OutputSet
from .common import (
    REPORT_FILES,
    figure_files,
    figures_and_report,
    load,
    plugins_for,
    repeat_record,
    reserve,
)

__all__ = ["cmd_calibrate", "cmd_compare"]

#: The files of calibrate --out DIR.
OUT_FILES = ("calibrated.yaml", "materials.yaml", "parameters.csv", "replicates.csv",
             "summary.json")


def _header(result: Any, spread: bool) -> str:
    scatter = ("the scatter of a fitted material parameter\n# includes the spread of its fit"
               if spread else "the materials' scatter\n# is the project's, without the spread "
               "of the fit")
    lines = "".join(f"# {line}\n" for line in result.uncertainty_lines(spread))
    return (f"# Calibrated by rockfall-design calibrate from {result.observations.source} "
            f"({result.observations.n} blocks), seed {result.seed}.\n"
            f"# Fitted values and their intervals: parameters.csv; {scatter} "
            f"(see docs/calibration.md).\n{lines}")


def _one_section(args: argparse.Namespace) -> tuple[Any, Any]:
    """The project of ``args.project`` and its plugins; a corridor is refused."""

    project = load(args.project)
    if not isinstance(project, Project):
        raise InputError(f"{args.project}: a corridor of sections: {args.command} one "
                         "section's project at a time")
    return project, plugins_for(project, args)


def _save_plots(args: argparse.Namespace, result: Any, files: Any) -> None:
    """The --plot figures and the --report documents, written through the command's output
    set (the figures drawn once for both, as the other commands do)."""

    figures_and_report(result, args, files)


def _show(args: argparse.Namespace, summary: dict[str, Any], result: Any) -> int:
    """The JSON (--json) or the report; exit 0 (the statistics say how good the fit is)."""
    if args.json:
        sys.stdout.write(json.dumps(summary, allow_nan=False) + "\n")
    else:
        result.print()
    return int(ExitCode.OK)


def _library_file(args: argparse.Namespace, files: Any) -> Path | None:
    """--save-materials' file, reserved; None if none, or if it is --out's materials.yaml.

    --out's own materials.yaml has the same content, so naming it again is
    one file written once; any other file of the command named twice is
    refused in one line.
    """
    import os


    path = args.save_materials
    if path is None:
        return None
    if args.out is not None and (os.path.abspath(path)
                                 == os.path.abspath(args.out / "materials.yaml")):
        return None
    if files.holds(path):
        raise InputError(f"--save-materials {path}: another option of this command writes "
                         "that file already; name another file")
    files.reserve(path)
    return path


def cmd_calibrate(args: argparse.Namespace) -> int:
    """Calibrate; exit 0 (a calibration has no pass or fail: its warnings say what to doubt)."""

    project, registry = _one_section(args)
    # Every file of the command is one output set, which replaces only files
    # this program wrote (a shared materials library stays), checked now.
    with OutputSet(keep_others=True) as files:
        reserve(files, args.out, OUT_FILES)
        reserve(files, args.plot, figure_files(FIGURES, args))
        reserve(files, args.report, REPORT_FILES)
        library = _library_file(args, files)
        result = api.calibrate(project, observed=args.observed, rocks=args.rocks,
                           bootstrap=args.bootstrap, seed=args.seed, workers=args.workers,
                           scheduler=args.scheduler, pool=args.pool,
                           progress=sys.stderr.isatty(), registry=registry,
                           prior=args.prior, screen=args.screen)
        summary = result.summary
        spread = bool(args.widen_scatter)
        if args.out:
            out: Path = args.out
            files.write_text(out / "calibrated.yaml", _header(result, spread)
                             + dump_yaml(result.calibrated_data(str(out), spread=spread)))
            files.write_text(out / "materials.yaml", _header(result, spread)
                             + result.materials_library_text(spread=spread))
            files.write_csv(out / "parameters.csv", result.parameters_table())
            files.write_csv(out / "replicates.csv", result.replicates_table())
            record = repeat_record(args, project, result.seed, result.problem.rocks)
            files.write_json(out / "summary.json", {**summary, "run": record})
        if library is not None:
            files.write_text(library, _header(result, spread)
                             + result.materials_library_text(spread=spread))
        _save_plots(args, result, files)
    return _show(args, summary, result)


def cmd_compare(args: argparse.Namespace) -> int:
    """Compare; exit 0 (the statistics say how good the prediction is)."""

    project, registry = _one_section(args)
    with OutputSet(keep_others=True) as files:
        reserve(files, args.out, ("summary.json",))
        reserve(files, args.plot, figure_files(FIGURES[:1], args))
        reserve(files, args.report, REPORT_FILES)
        result = api.compare(project, args.observed, rocks=args.rocks, seed=args.seed,
                         registry=registry)
        summary = result.summary
        if args.out:
            record = repeat_record(args, project, result.seed, result.rocks)
            files.write_json(args.out / "summary.json", {**summary, "run": record})
        _save_plots(args, result, files)
    return _show(args, summary, result)

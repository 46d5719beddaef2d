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

from ..errors import ExitCode

__all__ = ["add_calibrate_parser", "cmd_calibrate", "cmd_compare"]

#: The files of calibrate --out DIR.
OUT_FILES = ("calibrated.yaml", "materials.yaml", "parameters.csv", "replicates.csv",
             "summary.json")


def _common(p: argparse.ArgumentParser, what: str, report: str) -> None:
    """--rocks, --seed, --json, --plot, --plot-format, --report of both commands."""
    from .options import formats, positive_int, seed_number

    p.add_argument("--rocks", type=positive_int, metavar="N",
                   help=f"simulated rocks {what}")
    p.add_argument("--seed", type=seed_number, metavar="S",
                   help="random seed (default: rocks.seed of the project); recorded")
    p.add_argument("--json", action="store_true",
                   help="print the result as one JSON object on stdout instead of the report")
    p.add_argument("--plot", type=Path, metavar="DIR",
                   help="draw calibration_stops (ECDF and histogram of the observed and "
                   "simulated stops) into DIR; calibrate also calibration_cloud (the bootstrap "
                   "cloud of the fitted inputs)")
    p.add_argument("--plot-format", type=formats, default=("png",), metavar="FMT[,FMT]",
                   help="file formats of the --plot figures: png, svg, pdf (default: png)")
    p.add_argument("--report", type=Path, metavar="DIR",
                   help="write DIR/report.html (self-contained: figures inline as SVG), "
                   "DIR/report.md (its Markdown twin, figures beside it as SVG) and "
                   f"DIR/report.pdf (the HTML printed at A4, with the pdf extra): {report}")


def add_calibrate_parser(sub: Any) -> None:
    """Add the ``calibrate`` and ``compare`` commands to the subparsers ``sub``."""
    from ..arguments import MAX_BOOTSTRAP
    from .options import add_block_option, int_at_least

    p = sub.add_parser(
        "calibrate",
        help="fit ground parameters to observed stop positions (the calibrate: section)",
        description="Back-analysis: fit the inputs named in the project's calibrate: section "
        "to the observed stop positions (common random numbers, a global then a local "
        "search), with intervals from a bootstrap of the observations (each replicate refitted "
        "with its own seed), the correlation of the inputs, and a flag for inputs the "
        "observations do not pin down.",
    )
    p.add_argument("project", type=Path, help="project file (YAML) with a calibrate: section")
    _common(p, "per evaluation (default: calibrate.rocks)",
            "the observed set, the fitted inputs with their intervals and correlation, the "
            "fit statistics, the levels, the figures and how to repeat the run")
    p.add_argument("--observed", type=Path, metavar="CSV",
                   help="observed stops to fit (default: calibrate.observed)")
    p.add_argument("--bootstrap", type=int_at_least(0, "number of replicates", MAX_BOOTSTRAP),
                   metavar="B", help="bootstrap replicates (default: calibrate.bootstrap; 0: "
                   "the best fit only, no intervals)")
    p.add_argument("--out", type=Path, metavar="DIR",
                   help="write calibrated.yaml (the project with the fitted values, the "
                   "materials' own scatter, the values' uncertainty as comments), "
                   "materials.yaml (its materials as a library, each entry's source the "
                   "observations, date and seed), "
                   "parameters.csv, replicates.csv and summary.json (with the run record) "
                   "into DIR")
    p.add_argument("--save-materials", type=Path, metavar="FILE",
                   help="write the calibrated project's materials as a materials library "
                   "(materials: {library: FILE}), as --out's materials.yaml")
    _fit_options(p)
    p.add_argument("--workers", type=int_at_least(1, "number of workers"), metavar="N",
                   help="fit N replicates at once on the local pool (default: one per core)")
    p.add_argument("--pool", choices=("threads", "processes"), default="threads",
                   help="the local pool: threads (default) or processes (same results)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="fit the replicates on the Dask cluster of this scheduler instead "
                   "(same results); needs the study extra")
    add_block_option(p)
    p.set_defaults(func=cmd_calibrate)

    c = sub.add_parser(
        "compare",
        help="how well a project predicts observed stop positions (nothing fitted)",
        description="Run the project as it is and compare its stop positions with observed "
        "ones: distance, Kolmogorov-Smirnov statistic and p-value, and the share of each "
        "level of the project's calibrate: section. This validates a calibration on a "
        "second profile or on held-out blocks.",
    )
    c.add_argument("project", type=Path, help="project file (YAML), e.g. a calibrated.yaml")
    c.add_argument("--observed", type=Path, metavar="CSV",
                   help="the observed stops (x, optionally volume_m3 or mass_kg); default: "
                   "every observation set of the project's calibrate: section (stops, "
                   "passing heights, speeds, on each profile), each reported")
    _common(c, "(default: rocks.count of the project)",
            "the observed set, the fit statistics, the levels, the figure and how to repeat "
            "the run")
    c.add_argument("--out", type=Path, metavar="DIR", help="write summary.json into DIR")
    add_block_option(c)
    c.set_defaults(func=cmd_compare)


def _fit_options(p: argparse.ArgumentParser) -> None:
    """calibrate's options on what is written and how the fit is regularised."""
    scatter = p.add_mutually_exclusive_group()
    scatter.add_argument("--keep-scatter", action="store_true",
                         help="write calibrated.yaml and --save-materials with the "
                         "materials' scatter as it was, without the spread of the fit "
                         "(the default)")
    scatter.add_argument("--widen-scatter", action="store_true",
                         help="add each fitted material parameter's bootstrap standard "
                         "deviation to its per-impact scatter in calibrated.yaml and "
                         "--save-materials (the former default)")
    p.add_argument("--prior", action=argparse.BooleanOptionalAction, default=None,
                   help="regularise the fit by the literature: each input's project value "
                   "as the prior's mode, its range as +-2 sd, weighed by the criterion's "
                   "sampling noise (default: on with fit: auto, off for inputs listed "
                   "under fit:); --no-prior fits the criterion alone, the ranges as bounds")
    p.add_argument("--screen", action=argparse.BooleanOptionalAction, default=None,
                   help="before a regularised fit, leave out each input that moves the "
                   "criterion by less than its sampling noise over its range (it keeps its "
                   "class's value; a warning names it); default: with the prior; "
                   "--no-screen fits every input")


def run_record(args: argparse.Namespace, project: Any, seed: int, rocks: int
               ) -> dict[str, Any]:
    """What is needed to repeat the command exactly: version, seed, rocks, project."""
    from ..version import __version__

    return {"command": args.command, "version": __version__, "seed": seed, "rocks": rocks,
            "project_file": str(args.project), "project_hash": project.resolved_hash(),
            "project": project.resolved_dict()}


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
    from ..errors import InputError
    from ..project import Project
    from .common import load, plugins_for

    project = load(args.project)
    if not isinstance(project, Project):
        raise InputError(f"{args.project}: a corridor of sections: {args.command} one "
                         "section's project at a time")
    return project, plugins_for(project, args)


def _save_plots(args: argparse.Namespace, result: Any, files: Any) -> None:
    """The --plot figures and the --report documents, written through the command's output
    set (the figures drawn once for both, as the other commands do)."""
    from .common import figures_and_report

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

    from ..errors import InputError

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
    from ..api import calibrate
    from ..calibration.calibrated import FIGURES
    from ..project import dump_yaml
    from ..report.outputs import OutputSet
    from .common import REPORT_FILES, figure_files, reserve

    project, registry = _one_section(args)
    # Every file of the command is one output set, which replaces only files
    # this program wrote (a shared materials library stays), checked now.
    with OutputSet(keep_others=True) as files:
        reserve(files, args.out, OUT_FILES)
        reserve(files, args.plot, figure_files(FIGURES, args))
        reserve(files, args.report, REPORT_FILES)
        library = _library_file(args, files)
        result = calibrate(project, observed=args.observed, rocks=args.rocks,
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
            record = run_record(args, project, result.seed, result.problem.rocks)
            files.write_json(out / "summary.json", {**summary, "run": record})
        if library is not None:
            files.write_text(library, _header(result, spread)
                             + result.materials_library_text(spread=spread))
        _save_plots(args, result, files)
    return _show(args, summary, result)


def cmd_compare(args: argparse.Namespace) -> int:
    """Compare; exit 0 (the statistics say how good the prediction is)."""
    from ..api import compare
    from ..calibration.calibrated import FIGURES
    from ..report.outputs import OutputSet
    from .common import REPORT_FILES, figure_files, reserve

    project, registry = _one_section(args)
    with OutputSet(keep_others=True) as files:
        reserve(files, args.out, ("summary.json",))
        reserve(files, args.plot, figure_files(FIGURES[:1], args))
        reserve(files, args.report, REPORT_FILES)
        result = compare(project, args.observed, rocks=args.rocks, seed=args.seed,
                         registry=registry)
        summary = result.summary
        if args.out:
            record = run_record(args, project, result.seed, result.rocks)
            files.write_json(args.out / "summary.json", {**summary, "run": record})
        _save_plots(args, result, files)
    return _show(args, summary, result)

"""Every command's parser, and nothing that runs a command.

Light on purpose: ``rockfall-design --help`` (and a usage error) builds
every parser, so this module imports only argparse, the shared options and
the numbers they check (:mod:`rockfall_design.limits`), never the engine,
numba, scipy, pandas or matplotlib. Which function runs a command is said
in one table, :data:`rockfall_design.cli.program.COMMANDS`; the module of
that function is imported only when its command is chosen.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from ..limits import DEFAULT_FLAT_DEG, DEFAULT_TOLERANCE_M, MAX_BOOTSTRAP
from .options import (
    add_block_option,
    add_run_options,
    add_tasks_options,
    formats,
    int_at_least,
    positive_int,
    seed_number,
)

__all__ = [
    "add_calibrate_parser",
    "add_check_parser",
    "add_optimise_parser",
    "add_plugins_parser",
    "add_section_parser",
    "add_serve_parser",
    "add_simulate_parser",
    "add_study_parser",
]


def add_simulate_parser(sub: Any) -> None:
    """The ``simulate`` command and its options."""
    sim = sub.add_parser(
        "simulate",
        help="simulate the rocks of a project (one Monte Carlo run)",
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


def add_study_parser(sub: Any) -> argparse.ArgumentParser:
    """Add the ``study`` command to the subparsers ``sub`` of the main parser."""

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
    return p


def _common(p: argparse.ArgumentParser, what: str, report: str) -> None:
    """--rocks, --seed, --json, --plot, --plot-format, --report of both commands."""

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


def add_calibrate_parser(sub: Any) -> None:
    """Add the ``calibrate`` and ``compare`` commands to the subparsers ``sub``."""

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


def _point(text: str) -> tuple[float, float]:
    parts = text.split(",")
    try:
        e, n = (float(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a map point E,N (m), got {text!r}") from None
    if not (math.isfinite(e) and math.isfinite(n)):
        raise argparse.ArgumentTypeError(f"expected finite coordinates, got {text!r}")
    return e, n


def _positive(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}")
    return value


def add_section_parser(sub: Any) -> None:
    """The ``section`` command and its options."""
    p = sub.add_parser(
        "section", help="cut a slope section from a DEM (along a line or a fall line)",
        description="Cut a slope section from a DEM (projected CRS in metres), along a map "
        "line or down the fall line from a point, and write it as a survey CSV (x along the "
        "line from its top, y the height). Needs the terrain extra: "
        "pip install 'rockfall-design[terrain]'.")
    p.add_argument("dem", type=Path, help="the DEM (GeoTIFF)")
    how = p.add_mutually_exclusive_group(required=True)
    how.add_argument("--fall-line", type=_point, metavar="E,N",
                     help="follow the steepest descent from this map point")
    how.add_argument("--line", type=_point, nargs="+", metavar="E,N",
                     help="the section's map line: two or more points")
    p.add_argument("--stop", type=_point, nargs="+", metavar="E,N",
                   help="a map line (a road) where the fall line ends")
    p.add_argument("--flat-deg", type=_positive, default=DEFAULT_FLAT_DEG,
                   help=f"the fall line ends where the ground is flatter (deg; default "
                   f"{DEFAULT_FLAT_DEG:g})")
    p.add_argument("--spacing", type=_positive, default=None,
                   help="sampling step along the line (m; default the DEM's resolution)")
    p.add_argument("--tolerance", type=_positive, default=DEFAULT_TOLERANCE_M,
                   help=f"vertical tolerance of the simplified section (m; default "
                   f"{DEFAULT_TOLERANCE_M:g})")
    p.add_argument("--out", type=Path, required=True, help="the section's CSV (x, y)")
    p.add_argument("--plot", type=Path, help="a figure of the section (.png, .svg, .pdf)")

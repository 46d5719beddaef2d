"""Options that commands share.

Number types with the API's bounds and words, output formats, the run and
task options, ``--block``.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import NoReturn

from ..errors import ExitCode
from ..limits import MAX_ROCKS as _MAX_ROCKS
from ..limits import bounds_problem
from ..report.formats import FIGURE_FORMATS

PROG = "rockfall-design"


class CommandParser(argparse.ArgumentParser):
    """argparse, but a usage error is one line and exit code 2 (BAD_INPUT)."""

    def error(self, message: str) -> NoReturn:
        self.exit(int(ExitCode.BAD_INPUT), f"{self.prog}: error: {message} (see --help)\n")


def int_at_least(low: int, what: str, high: int | None = None):
    """An argparse type: a whole number >= ``low`` ("expected a {what} >= {low}"), <= ``high``."""

    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        # The API's checks and words (rockfall_design.limits).
        problem = bounds_problem(v, low, high, what)
        if problem is not None:
            raise argparse.ArgumentTypeError(problem)
        return v

    return parse


positive_int = int_at_least(1, "number", _MAX_ROCKS)


def formats(text: str) -> tuple[str, ...]:
    """An argparse type: 'png,svg' -> ('png', 'svg'), each a known figure format."""
    out = tuple(dict.fromkeys(f.strip().lower() for f in text.split(",") if f.strip()))
    bad = [f for f in out if f not in FIGURE_FORMATS]
    if bad or not out:
        raise argparse.ArgumentTypeError(
            f"expected formats among {', '.join(FIGURE_FORMATS)}, got {text!r}")
    return out


seed_number = int_at_least(0, "seed")


def add_run_options(
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
    p.add_argument("--rocks", type=positive_int, metavar="N", help=rocks)
    p.add_argument("--seed", type=seed_number, metavar="S", help=seed)
    p.add_argument("--out", type=Path, metavar="DIR", help=out)
    p.add_argument("--plot", type=Path, metavar="DIR", help=plot)
    p.add_argument("--plot-format", type=formats, default=("png",), metavar="FMT[,FMT]",
                   help="file formats of the --plot figures: png, svg, pdf, comma-separated "
                   "(default: png)")
    p.add_argument("--report", type=Path, metavar="DIR",
                   help="write DIR/report.html (self-contained: figures inline as SVG), "
                   "DIR/report.md (its Markdown twin, figures beside it as SVG) and "
                   "DIR/report.pdf (the HTML printed at A4; needs the pdf extra and a "
                   "Chromium, else one line says how to get it)")
    p.add_argument("--json", action="store_true", help=json_)


def add_tasks_options(p: argparse.ArgumentParser, what: str) -> None:
    """--workers and --scheduler: where independent runs (scenarios, sections) run."""
    p.add_argument("--workers", type=int_at_least(1, "number of workers"), metavar="N",
                   help=f"run {what} on a local pool of N processes (default: one per core; "
                   "1 runs them in this process)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help=f"run {what} on the Dask cluster of this scheduler (e.g. "
                   "tcp://127.0.0.1:8786); needs the study extra")


def add_block_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--block", action="append", default=[], metavar="NAME",
                   help="do not load the plugin with this entry-point or distribution "
                   "name (repeatable)")

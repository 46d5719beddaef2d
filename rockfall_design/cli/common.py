"""What every command does around its run.

Plugins and their warnings, progress, the memory guard, files reserved,
figures and report, the run record.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..api import load_plugins, never_holding, validate_project
from ..errors import InputError
from ..limits import MAX_ROCKS as _MAX_ROCKS
from ..project import dump_yaml, load_corridor, load_project_text
from ..project.inputs import read_text
from ..project.messages import unquoted
from ..report.documents import write_report
from ..report.formats import save_figures
from ..report.progress import interruptible_rocks
from ..results import DEFAULT_TRAJECTORIES
from ..version import __version__
from .options import (
    PROG,
)

if TYPE_CHECKING:  # pragma: no cover
    from ..report.outputs import OutputSet


def memory_guard(need: int, what: str, advice: str) -> None:
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


def in_memory_guard(n_rocks: int, n_grid: int, n_stations: int) -> None:
    """The guard for ``check`` and ``optimise``, which keep every rock's results.

    Per rock and envelope point: float32 height, energy and speed, and
    float64 copies of them while the percentiles are taken.
    """
    need = n_rocks * (44 * n_grid + 40 * n_stations + 200)
    memory_guard(need, f"{n_rocks:,} rocks with {n_grid} envelope points",
                  "Use fewer rocks or fewer analysis.envelope_points.")


def decision_memory_guard(n_rocks: int, n_stations: int) -> None:
    """The guard for the last look of ``optimise``'s decisions (``design.max_rocks``).

    A look keeps each rock's records at the user's stations and the
    barriers, its release and its end, not the envelope grid
    (``run_in_memory``'s ``envelope``); the optimiser holds a few looks and
    the search's tables at once. Counted: 40 bytes per rock and station and
    2,000 for the rest. Measured, the peak resident memory of ``optimise
    --max-rocks 1600000``: design_quarry 1.3 to 2.4 GiB at seeds 11-15 (this
    estimate: 3.1 GiB), design_ditch_or_fence 2.8 GiB at seed 11 (3.2 GiB;
    docs/speed.md, "Looks without the envelope grid").
    """
    need = n_rocks * (40 * n_stations + 2_000)
    memory_guard(need, f"decisions of up to {n_rocks:,} rocks (design.max_rocks)",
                 "Give a smaller --max-rocks (design.max_rocks).")


def run_with_progress(run: Any, project: Any, args: argparse.Namespace, **kw: Any) -> Any:
    """Call the API's ``run(project, rocks=..., seed=..., ...)``, with a progress bar if
    interactive, keeping the paths of the first rocks when a figure will need them."""

    n = args.rocks or project.rocks.count
    drawn = args.plot or args.report
    kw.update(rocks=n, seed=args.seed, trajectories=DEFAULT_TRAJECTORIES if drawn else 0)
    prog, callback = interruptible_rocks(sys.stderr.isatty() and n >= 20_000, n)
    if prog is None:
        return run(project, progress=callback, **kw)
    with prog:
        return run(project, progress=callback, **kw)


#: The files of --report DIR (report.pdf where the pdf extra and a Chromium are there).
REPORT_FILES = ("report.html", "report.md", "report.pdf")


def figures_and_report(result: Any, args: argparse.Namespace, files: OutputSet) -> None:
    """The --plot figures and the --report documents of an API result, in the output set."""
    if not (args.plot or args.report):
        return
    figures = result.figures()  # drawn once for both
    if args.report:

        write_report(result, args.report, outputs=files, figures=figures,
                     note=lambda line: sys.stderr.write(f"{PROG}: {line}\n"))
    if args.plot:

        # --plot and --report into one directory with --plot-format svg: the
        # report has written those figures already, from the same drawings.
        for fmt in args.plot_format:
            todo = {name: fig for name, fig in figures.items()
                    if args.plot / f"{name}.{fmt}" not in files}
            save_figures(todo, args.plot, (fmt,), files)


def warn_failures(registry: Any) -> None:
    for f in registry.failures:
        sys.stderr.write(f"{PROG}: warning: plugin {f.plugin!r} was not loaded: {f.reason}\n")


def requirement_warnings(project: Any, args: argparse.Namespace) -> list[str]:
    """One line per requirement that can never hold with confidence (an allowed fraction 0).

    Found when the project is loaded and written once the run has ended, so
    that a run that fails on bad input or a plugin fault still says one line.
    """

    command = "check" if args.command == "check" else "optimise"
    return [f"{PROG}: warning: {line}\n" for line in never_holding(project, command)]


def plugins_for(project: Any, args: argparse.Namespace) -> Any:
    """Load the plugins and check the project's plugin sections with them.

    Every command checks the whole project file, ``measures:``, ``safety:``
    and ``design:`` included, so that a bad file is reported whichever
    command reads it (``simulate`` runs the bare slope but still says so).
    """

    registry = load_plugins(args.block)
    warn_failures(registry)
    validate_project(project, registry)
    return registry


#: The figures of --plot (report.plot_run writes all three).
#: The figures of a run (``--plot``), one file per --plot-format each.
FIGURES = ("profile", "envelopes", "stops")


def figure_files(stems: Sequence[str], args: argparse.Namespace) -> list[str]:
    """File names of the figures ``stems`` in every format of ``--plot-format``."""
    return [f"{stem}.{fmt}" for stem in stems for fmt in args.plot_format]


def reserve(files: OutputSet, out: Path | None, names: Sequence[str]) -> None:
    """Reserve the files ``names`` in the --out directory ``out`` (if given) of a run.

    Done before the run, so that a directory that cannot be written is
    reported at once instead of after minutes of computing.
    """
    if out is not None:
        files.reserve(*(out / name for name in names))


def table_writers(files: OutputSet, out: Path) -> Any:
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


def load_repeat(args: argparse.Namespace) -> tuple[Any, dict[str, Any]]:
    """The project, seed and rock count recorded in a summary.json, for --repeat."""

    path: Path = args.repeat
    try:

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

    with unquoted():  # a value of the recorded project is not quoted back either
        project = load_project_text(text, f"{path} (run.project)")
    args.seed = seed if args.seed is None else args.seed
    args.rocks = rocks if args.rocks is None else args.rocks
    args.project = path
    return project, recorded


def load(path: Path) -> Any:
    """The project file: a Project, or a Corridor when it lists ``sections:``."""

    return load_corridor(path)


def comparable(summary: dict[str, Any]) -> dict[str, Any]:
    """A summary without what legitimately changes between runs (timing, the run record)."""
    return {k: v for k, v in summary.items() if k not in ("runtime_s", "run")}


def repeat_record(args: argparse.Namespace, project: Any, seed: int, rocks: int
                  ) -> dict[str, Any]:
    """What is needed to repeat a command exactly: command, version, seed, rocks, project.

    The ``run`` of every command's summary.json (simulate, check, optimise,
    study, calibrate): the project as resolved (every default filled in) and
    its hash, so that the run repeats with another version's defaults too.
    """
    return {
        "command": args.command,
        "version": __version__,
        "seed": int(seed),
        "rocks": int(rocks),
        "project_file": str(args.project),
        "project_hash": project.resolved_hash(),
        "project": project.resolved_dict(),
    }


def run_record(run: Any, args: argparse.Namespace) -> dict[str, Any]:
    """:func:`repeat_record` of a run (its project, seed and rocks)."""
    return repeat_record(args, run.project, run.seed, run.n)

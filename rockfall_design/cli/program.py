"""The ``rockfall-design`` command. The only place that turns errors into exit codes."""

from __future__ import annotations

import argparse
import os
import signal
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

# The project's limit (rockfall_design.project.MAX_ROCKS), from a module
# light enough for every --help (no pydantic).
from ..errors import ExitCode, InputError, Interrupted, RockfallError
from ..version import __version__
from .options import (
    PROG,
    CommandParser,
    add_block_option,
    add_run_options,
    add_tasks_options,
    int_at_least,
)
from .section_commands import cmd_check, cmd_optimise, cmd_plugins, cmd_serve, cmd_simulate

if TYPE_CHECKING:  # pragma: no cover
    pass

__all__ = ["main"]


def build_parser() -> argparse.ArgumentParser:
    parser = CommandParser(prog=PROG, description="Rockfall trajectories and protection design.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=CommandParser)
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
        "station) and summary.json (the summary and the run record that --repeat reads) "
        "into DIR",
        plot="draw profile.png (the section, rock paths and rest positions), envelopes.png "
        "(passing height and energy along x) and stops.png (rest positions) into DIR",
        json_="print the summary as one JSON object on stdout instead of the report",
        repeatable=True,
    )
    add_tasks_options(sim, "a corridor's sections (a file with sections:)")
    add_block_option(sim)
    sim.set_defaults(func=cmd_simulate)
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
    add_tasks_options(chk, "the scenarios of --scenarios, or a corridor's sections")
    add_block_option(chk)
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
        "when no design is admissible), alternatives.csv (one row per family of measures) "
        "and summary.json (the summary and the run record) into DIR",
        plot="draw alternatives.png (every family's cost or reason) and profile.png, "
        "envelopes.png and stops.png of the chosen design into DIR (only alternatives.png "
        "when no design is admissible)",
        json_="print the alternatives and the best design as one JSON object on stdout "
        "instead of the report",
    )
    opt.add_argument("--max-rocks", type=int_at_least(1, "number", 2_000_000),
                     metavar="N", help="rocks of the last look of every decision (default: "
                     "design.max_rocks of the project, 50,000): a design still undecided "
                     "there is marginal, and the report says how many rocks would decide it")
    add_block_option(opt)
    opt.set_defaults(func=cmd_optimise)
    from .study_command import add_study_parser

    add_study_parser(sub)
    from .calibrate_command import add_calibrate_parser

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
    add_block_option(plg)
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
    srv.add_argument("--port", type=int_at_least(0, "port", 65535), metavar="N",
                     help="port to listen on (default: the first free one from 8765; "
                     "0: any free port)")
    srv.add_argument("--host", default="127.0.0.1", metavar="H",
                     help="address to listen on (default: 127.0.0.1, this machine only)")
    add_block_option(srv)
    srv.set_defaults(func=cmd_serve)
    return parser


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
    from ..report.interrupts import note_interrupt

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
    from ..report.interrupts import check_interrupt, committed_sets, forget_interrupts

    parser = build_parser()
    args = parser.parse_args(argv)
    committed_before = committed_sets()
    from ..project.inputs import forget_inputs

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
            from ..plugins import check_blocked_names

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
        from ..project.inputs import strip_controls

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

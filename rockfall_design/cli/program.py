"""The ``rockfall-design`` command. The only place that turns errors into exit codes."""

from __future__ import annotations

import argparse
import gc
import os
import signal
import sys
from collections.abc import Sequence
from importlib import import_module
from typing import Any

from ..errors import ExitCode, InputError, Interrupted, RockfallError
from ..plugins import check_blocked_names
from ..project.inputs import forget_inputs, strip_controls
from ..report.interrupts import check_interrupt, committed_sets, forget_interrupts, note_interrupt
from ..version import __version__
from .options import PROG, CommandParser
from .parsers import (
    add_calibrate_parser,
    add_check_parser,
    add_optimise_parser,
    add_plugins_parser,
    add_section_parser,
    add_serve_parser,
    add_simulate_parser,
    add_study_parser,
)

__all__ = ["COMMANDS", "build_parser", "main"]

#: Every command (aliases too) and the function that runs it, as (module of
#: rockfall_design.cli, function). The ONE place where the command line
#: imports a module by name: a runner's module imports what its command runs
#: (the engine, numba, the optimiser...) at its top, so it is imported only
#: when its command is chosen, never for ``--help``, a usage error or another
#: command (each parser lives in the light :mod:`.parsers`).
COMMANDS: dict[str, tuple[str, str]] = {
    "simulate": ("section_commands", "cmd_simulate"),
    "check": ("section_commands", "cmd_check"),
    "optimise": ("section_commands", "cmd_optimise"),
    "optimize": ("section_commands", "cmd_optimise"),
    "study": ("study_command", "cmd_study"),
    "calibrate": ("calibrate_command", "cmd_calibrate"),
    "compare": ("calibrate_command", "cmd_compare"),
    "plugins": ("section_commands", "cmd_plugins"),
    "serve": ("section_commands", "cmd_serve"),
    "section": ("terrain_command", "cmd_section"),
}


class Runner:
    """A command's runner, imported when its command runs (see :data:`COMMANDS`)."""

    def __init__(self, module: str, function: str) -> None:
        self.module = module
        self.function = function

    def __call__(self, args: argparse.Namespace) -> int:
        run = getattr(import_module(f".{self.module}", __package__), self.function)
        return int(run(args))


def build_parser() -> argparse.ArgumentParser:
    """The command line: every command's parser, and the runner of each command."""
    parser = CommandParser(prog=PROG, description="Rockfall trajectories and protection design.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=CommandParser)
    add_simulate_parser(sub)
    add_check_parser(sub)
    add_optimise_parser(sub)
    add_study_parser(sub)
    add_calibrate_parser(sub)
    add_plugins_parser(sub)
    add_serve_parser(sub)
    add_section_parser(sub)
    for name, command in sub.choices.items():
        command.set_defaults(func=Runner(*COMMANDS[name]))
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
    # Noted first: the exception may be swallowed where it lands (numpy does,
    # in its __array_ufunc__ lookup); the note stops the next safe point and
    # every commit all the same.
    note_interrupt(signum)
    raise _Interrupted(signum)


def _quiet_swallowed_interrupt(unraisable: Any) -> None:
    """``sys.unraisablehook`` while a command runs: a swallowed interrupt says nothing.

    The handler's exception can land where Python cannot raise it (a weakref
    callback of the import machinery, a ``__del__``): Python then prints
    "Exception ignored in ..." with a traceback. The interrupt was noted
    before it was raised, so the next safe point stops the run all the same
    and the command ends with its one line; anything else goes to the hook
    that was in place before the command.
    """
    if isinstance(unraisable.exc_value, _Interrupted):
        return
    _unraisable_before[0](unraisable)


#: ``sys.unraisablehook`` as it was when the command began.
_unraisable_before: list[Any] = [sys.__unraisablehook__]


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
    parser = build_parser()
    args = parser.parse_args(argv)
    committed_before = committed_sets()
    forget_inputs()  # the files this command reads are noted anew
    forget_interrupts()
    handled = [signal.SIGTERM]
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        # An ignored SIGINT (a background job of a non-interactive shell) stays so.
        handled.append(signal.SIGINT)
    previous = {s: signal.signal(s, _on_signal) for s in handled}
    hook = _unraisable_before[0] = sys.unraisablehook
    sys.unraisablehook = _quiet_swallowed_interrupt
    stdout = sys.stdout
    sys.stdout = _GuardedStdout(stdout)
    try:
        if getattr(args, "block", None):
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
        sys.unraisablehook = hook
        for s, handler in previous.items():
            # Run as the program (no argv), the process exits next: a Ctrl-C
            # now would only print a traceback from the interpreter's exit.
            signal.signal(s, signal.SIG_IGN if argv is None else handler)
        if argv is None:
            # Run as the program, the process exits next, and the interpreter's
            # last garbage collection walks every object the command made: about
            # 2 s after a calibration, after its results were written or its
            # interrupt reported. Freezing them leaves that walk nothing to do
            # (memory goes back to the system with the process all the same).
            gc.freeze()
        _exiting[0] = False


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

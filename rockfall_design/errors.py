"""User-facing errors and the exit codes of the command line.

Every error a user can cause (a bad project file, a broken plugin, ...) is a
:class:`RockfallError`: the command line prints ``str(error)`` -- always one
line, never a traceback -- and exits with ``error.exit_code``. Any other
exception is a bug and keeps its traceback. ``cli.py`` is the only place that
turns errors into exit codes; the codes themselves live in :class:`ExitCode`.
"""

import enum
import re

__all__ = [
    "ExitCode",
    "InputError",
    "Interrupted",
    "PluginError",
    "ProjectError",
    "RockfallError",
    "strip_controls",
]


class ExitCode(enum.IntEnum):
    """Process exit codes of ``rockfall-design``."""

    #: The command ran and every check passed.
    OK = 0
    #: The command ran, but a design check failed (e.g. a safety factor < 1).
    CHECK_FAILED = 1
    #: The input (project file, command-line arguments, catalogue) is invalid.
    BAD_INPUT = 2
    #: A plugin could not be loaded or misbehaved.
    PLUGIN_FAULT = 3
    #: Interrupted by the user (Ctrl-C), as shells report SIGINT.
    INTERRUPTED = 130


#: Characters that steer a terminal or reorder text rather than show: the C0
#: and C1 controls (ESC starts the sequences that set a window title or clear
#: the screen), DEL, and the bidirectional overrides and isolates.
_CONTROLS = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u202a-\u202e\u2066-\u2069]")


def strip_controls(text: str, *, lines: bool = False) -> str:
    """``text`` without control characters, as it may be shown on a terminal.

    Parameters
    ----------
    text : str
        Text from a file (a project's name, description).
    lines : bool
        Keep line breaks and tabs (a description of several lines); else
        they become spaces.
    """
    if not lines:
        text = text.replace("\n", " ").replace("\t", " ").replace("\r", " ")
    return _CONTROLS.sub("", text)


def _one_line(text: object) -> str:
    """``text`` as a single line: runs of whitespace, newlines included, become one space.

    Control characters go too (a key of a project file may hold them): the
    message is then the same on the terminal, which shows none, as in
    ``str(error)``.
    """
    return strip_controls(" ".join(str(text).split()))


class RockfallError(Exception):
    """Base class of every error that is the user's to fix, not a bug.

    Parameters
    ----------
    message
        What went wrong and, where possible, how to fix it. Newlines are
        collapsed: ``str(error)`` is always exactly one line.
    exit_code
        Overrides the class's :attr:`exit_code` for this instance.
    """

    #: Exit code the command line uses for this error.
    exit_code: ExitCode = ExitCode.BAD_INPUT

    def __init__(self, message: str, *, exit_code: ExitCode | None = None) -> None:
        self.message = _one_line(message)
        if exit_code is not None:
            self.exit_code = ExitCode(exit_code)
        super().__init__(self.message)

    def __str__(self) -> str:
        return self.message

    def __reduce__(self):  # keep instances picklable (e.g. across worker processes)
        return (_rebuild, (type(self), dict(self.__dict__)))


def _rebuild(cls: type, state: dict) -> "RockfallError":
    err = cls.__new__(cls)
    Exception.__init__(err, state.get("message", ""))
    err.__dict__.update(state)
    return err


class Interrupted(KeyboardInterrupt):
    """The ``KeyboardInterrupt`` of a real signal: raised by the program's signal handlers.

    The command line's SIGINT and SIGTERM handlers raise it, and so does the
    SIGINT handler that :func:`~rockfall_design.plugins.call_plugin` puts in
    place of Python's default one while plugin code runs. A plain
    ``KeyboardInterrupt`` (or ``SystemExit``) that plugin code raises itself
    is a plugin fault; this one stops the run (exit code 130).
    """


class InputError(RockfallError):
    """Invalid user input: project file, command-line arguments, catalogues."""

    exit_code = ExitCode.BAD_INPUT


class PluginError(RockfallError):
    """A plugin failed to load, registered something invalid or misbehaved."""

    exit_code = ExitCode.PLUGIN_FAULT


class ProjectError(InputError):
    """A problem in a project file, located by file, line and key path.

    ``str(error)`` is one line: ``"{file}:{line}: {key}: {message}"``; the
    ``:{line}`` part is left out when the line is unknown and the ``{key}: ``
    part when the problem concerns the whole file.

    Attributes
    ----------
    file : str
        The project file as the user named it (``"<string>"`` for text).
    line : int or None
        1-based line of the offending YAML node (or of its nearest existing
        ancestor when the key is missing), None when unknown.
    key : str
        Dotted key path such as ``rocks.release[1].x``; ``""`` for the whole file.
    message : str
        What is wrong and what was expected.
    """

    def __init__(self, file: str, line: int | None, key: str, message: str) -> None:
        self.file = _one_line(file)
        self.line = line
        self.key = _one_line(key)
        super().__init__(message)  # sets ``self.message`` (one line, without the location)

    def __str__(self) -> str:
        where = self.file if self.line is None else f"{self.file}:{self.line}"
        if self.key:
            return f"{where}: {self.key}: {self.message}"
        return f"{where}: {self.message}"

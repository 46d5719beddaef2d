"""Reading the files a command is given, within a size limit.

Every file the program reads on a user's behalf (the project file, the
catalogues and price files it names, a ``summary.json`` to repeat) goes
through :func:`read_text`. A path may point anywhere: at ``/dev/zero``, a
FIFO nobody writes to, a directory, or a log file of many gigabytes. So the
file is opened without blocking, checked to be a regular file, its size
compared with the limit before anything is read, and then at most one byte
more than the limit is read, so that a file that grows while it is read is
refused all the same.

The limit is ``RF_MAX_FILE_MB`` megabytes (10**6 bytes) from the environment,
:data:`DEFAULT_MAX_FILE_MB` by default: far beyond any project or catalogue,
small enough that a wrong path cannot exhaust the memory.

Every file read is also noted (:func:`note_input`), by its device and inode,
so that an output set can refuse to overwrite or remove a file the run reads
(the project, its survey, library, catalogues, a summary to repeat): a
command's results never replace what the user gave it. The command line
forgets them (:func:`forget_inputs`) at the start of every command.
"""

from __future__ import annotations

import os
import stat

from ..errors import InputError, strip_controls

__all__ = [
    "DEFAULT_MAX_FILE_MB",
    "MAX_FILE_ENV",
    "UnreadableFile",
    "forget_inputs",
    "input_at",
    "max_file_bytes",
    "note_input",
    "read_named_text",
    "read_text",
    "strip_controls",
]

#: Environment variable with the largest file (in MB, 10**6 bytes) the program reads.
MAX_FILE_ENV = "RF_MAX_FILE_MB"
#: The limit when the variable is not set.
DEFAULT_MAX_FILE_MB = 50.0


#: The files read so far: (device, inode) -> (what it is, the path as named).
_inputs: dict[tuple[int, int], tuple[str, str]] = {}


def note_input(path: str | os.PathLike[str], what: str, info: os.stat_result | None = None) -> None:
    """Note that ``path`` (a ``what``: "project file", "survey section", ...) is read.

    Parameters
    ----------
    path : path
        The file, as the user named it.
    what : str
        What it is, for the message of an output that would overwrite it.
    info : os.stat_result, optional
        Its status, if already taken (from the open file, say).
    """
    try:
        info = os.stat(path) if info is None else info
    except OSError:
        return  # nothing there: nothing an output could overwrite
    _inputs.setdefault((info.st_dev, info.st_ino), (what, os.fspath(path)))


def input_at(path: str | os.PathLike[str]) -> tuple[str, str] | None:
    """``(what, path as named)`` if ``path`` is (a link to) a file noted as read, else None.

    Compared by device and inode, so that another spelling of the path, a
    symbolic or a hard link is found too.
    """
    if not _inputs:
        return None
    try:
        info = os.stat(path)
    except OSError:
        return None
    return _inputs.get((info.st_dev, info.st_ino))


def forget_inputs() -> None:
    """Forget every file noted as read (a new command starts)."""
    _inputs.clear()


class UnreadableFile(OSError):
    """A file that is refused: not a regular file, or larger than the limit.

    An :class:`OSError` whose ``strerror`` is the reason, so that callers
    report it as they report "No such file or directory".
    """

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.strerror = reason


def max_file_bytes() -> int:
    """The largest file (bytes) :func:`read_text` reads, from ``RF_MAX_FILE_MB``.

    Raises
    ------
    InputError
        If the variable is set but not a number > 0.
    """
    text = os.environ.get(MAX_FILE_ENV, "").strip()
    if not text:
        return int(DEFAULT_MAX_FILE_MB * 1e6)
    try:
        mb = float(text)
    except ValueError:
        mb = float("nan")
    if not (mb > 0 and mb <= 1e9):  # NaN fails both
        raise InputError(
            f"{MAX_FILE_ENV}={text!r}: expected the largest file to read in MB, "
            "a number > 0 (and at most 1e9)"
        )
    return max(int(mb * 1e6), 1)


def _kind(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a directory"
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "a special file"


def read_text(path: str | os.PathLike[str], what: str = "input file") -> str:
    """The UTF-8 text of the regular file ``path``, if it is within the size limit.

    The file is noted as an input (:func:`note_input`) as ``what``.

    Raises
    ------
    UnreadableFile
        An OSError: ``path`` is a directory, FIFO, device or socket, or
        larger than :func:`max_file_bytes` (the reason says which and names
        ``RF_MAX_FILE_MB``).
    OSError
        As :func:`open` raises it (no such file, permission denied, ...).
    UnicodeDecodeError
        If the content is not UTF-8.
    InputError
        If ``RF_MAX_FILE_MB`` is not a valid number.
    """
    limit = max_file_bytes()
    # O_NONBLOCK: opening a FIFO for reading would otherwise wait for a writer.
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    try:
        info = os.fstat(fd)
        mode = info.st_mode
        if not stat.S_ISREG(mode):
            raise UnreadableFile(f"{_kind(mode)}, not a regular file")
        note_input(path, what, info)
        too_large = UnreadableFile(
            f"larger than {limit / 1e6:g} MB, the largest file read "
            f"(set {MAX_FILE_ENV} to change it)"
        )
        if os.fstat(fd).st_size > limit:
            raise too_large
        chunks: list[bytes] = []
        remaining = limit + 1  # one byte more: a file that grew meanwhile is refused
        while remaining > 0:
            chunk = os.read(fd, min(remaining, 1 << 20))
            if not chunk:
                break
            chunks.append(chunk)
            remaining -= len(chunk)
        if remaining <= 0:
            raise too_large
    finally:
        os.close(fd)
    return b"".join(chunks).decode("utf-8")


def read_named_text(path: str | os.PathLike[str], what: str) -> str:
    """:func:`read_text` of a file a project refers to, a failure said in one line.

    Parameters
    ----------
    path : path
        The file.
    what : str
        What it is, for the message ("product catalogue", "survey section").

    Raises
    ------
    ValueError
        "cannot read the WHAT PATH: REASON" (not UTF-8, not a regular file,
        over the size limit, no such file, ...); the caller places it at the
        key that names the file.
    """
    shown = os.fspath(path)
    try:
        return read_text(path, what)
    except UnicodeDecodeError as exc:
        raise ValueError(f"cannot read the {what} {shown}: not UTF-8 text ({exc.reason})") from None
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise ValueError(f"cannot read the {what} {shown}: {reason}") from None

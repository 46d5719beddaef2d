"""Temporary files of output sets: named by their owner, and removed once their owner is gone.

Every temporary file an output set makes beside a target is named
``.NAME.PID-HOST.RANDOM.tmp`` (``.rocks.csv.4711-1a2b3c4d.k2j8x_0q.tmp``):
``NAME`` the target's name, ``PID`` the process that writes it and ``HOST``
a short hash of its machine's name. A run that is killed outright
(``kill -9``, a power cut, an out-of-memory kill) cannot remove them; the
next run that writes a target of the same name into that directory does
(:func:`remove_stale`: every stale temporary file of this program in the
directory, whatever its target), and says so in one line.

A temporary file is stale only if it was made on this machine and its
process is gone: no process has its number, or the one that has it started
after the file was last written (the number was reused). The temporary
files of a live run, another one writing into the same directory at the
same time say, are never touched, however old; nor are those of another
machine (a shared folder), nor temporary files named without an owner.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import re
import socket
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

from ..errors import strip_controls

__all__ = ["make", "remove_stale", "set_notice", "stale"]

#: Seconds by which a process must have started after a file's last write
#: for its number to count as reused: /proc gives the boot time in whole
#: seconds, so a start time read from it may be off by up to one.
_START_SLACK_S = 2.0


def _host() -> str:
    """A short, stable tag of this machine (8 hex digits of its name's SHA-256)."""
    return hashlib.sha256(socket.gethostname().encode()).hexdigest()[:8]


_HOST = _host()


def make(directory: Path, name: str, suffix: str = ".tmp") -> tuple[int, str]:
    """A new temporary file for the target ``name`` in ``directory``: (fd, path), as mkstemp.

    Named ``.NAME.PID-HOST.RANDOM{suffix}``, so that a later run can tell
    whose it is (:func:`stale`).
    """
    return tempfile.mkstemp(prefix=f".{name}.{os.getpid()}-{_HOST}.", suffix=suffix,
                            dir=directory)


def _started_at(pid: int) -> float | None:
    """When process ``pid`` started (s since the epoch), if this system says (Linux); else None."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as fh:
            stat = fh.read().decode("ascii", "replace")
        with open("/proc/stat", "rb") as fh:
            boot = next(float(line.split()[1]) for line in fh.read().decode().splitlines()
                        if line.startswith("btime "))
        # After the command's name in parentheses (which may hold anything):
        # field 22, the start time in clock ticks after boot.
        ticks = float(stat.rsplit(")", 1)[1].split()[19])
        return boot + ticks / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError, StopIteration):
        return None


def _alive(pid: int, written_at: float) -> bool:
    """Whether process ``pid`` may still be the one that wrote a file last at ``written_at``."""
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # PermissionError: another user's live process
        return True
    started = _started_at(pid)
    # The number was reused if its process started after the file's last write.
    return started is None or started <= written_at + _START_SLACK_S


def stale(directory: Path) -> list[Path]:
    """The temporary files in ``directory`` whose owner is gone.

    Only files named by :func:`make` on this machine count; a file whose
    owner may be alive, or that cannot be examined, is left out.
    """
    pattern = re.compile(rf"\..+\.(\d+)-{_HOST}\.[a-z0-9_]+\.tmp\Z")
    found = []
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return []
    for entry in entries:
        match = pattern.match(entry.name)
        if match is None:
            continue
        try:
            info = entry.stat(follow_symlinks=False)
        except OSError:
            continue
        if not entry.is_file(follow_symlinks=False):
            continue
        if not _alive(int(match.group(1)), info.st_mtime):
            found.append(Path(entry.path))
    return found


def _stderr(line: str) -> None:
    sys.stderr.write(f"rockfall-design: {line}\n")


_notice: list[Callable[[str], None]] = [_stderr]


def set_notice(notice: Callable[[str], None]) -> Callable[[str], None]:
    """Send the line that :func:`remove_stale` reports to ``notice``; return the previous one."""
    previous = _notice[0]
    _notice[0] = notice
    return previous


def remove_stale(directory: Path) -> list[Path]:
    """Remove the stale temporary files in ``directory`` (:func:`stale`); say so.

    One line (to standard error, or to :func:`set_notice`'s function) names
    how many were removed, their size and the directory. A file that cannot
    be removed stays, silently: it is no part of any result.

    Returns
    -------
    list of Path
        The files removed.
    """
    removed: list[Path] = []
    size = 0
    for path in stale(directory):
        with contextlib.suppress(OSError):
            bytes_ = path.stat().st_size
            path.unlink()
            removed.append(path)
            size += bytes_
    if removed:
        where = strip_controls(os.fspath(directory))
        _notice[0](f"removed {len(removed)} temporary file(s) ({size / 1e6:.1f} MB) of earlier "
                   f"runs that were killed before they finished, in {where}")
    return removed

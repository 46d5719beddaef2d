"""Files staged beside their targets and swapped in together: the mechanics under OutputSet.

Each file of an output set is written to a temporary file in its target's
directory (:class:`_TargetFile`), synced, and renamed into place with the
others while Ctrl-C and SIGTERM are held (:func:`swap_in`); the manifest of
every directory says which files this program wrote, so that only those are
ever replaced or removed, and no input of the run is overwritten.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import json
import os
import signal
import threading
from collections.abc import Iterator
from pathlib import Path
from types import FrameType
from typing import IO, Any, Literal

from ..errors import InputError
from ..project.inputs import input_at
from .interrupts import HELD_SIGNALS
from .temporaries import make

#: The manifest in every directory an output set writes to: which of its
#: files this program wrote (and so may remove), as JSON.
MANIFEST = ".rockfall-design-outputs.json"


class OutputError(InputError):
    """A result file could not be written: ``cannot write FILE: REASON``.

    Exit code 2 (:attr:`~rockfall_design.errors.ExitCode.BAD_INPUT`): the
    place the results go to is the user's to fix (free space, a size limit,
    permissions, a directory where a file should go).
    """

    def __init__(self, target: Path, exc: OSError | str, done: str = "no file was changed") -> None:
        reason = exc if isinstance(exc, str) else (exc.strerror or type(exc).__name__)
        super().__init__(f"cannot write {target}: {reason}; {done}")
        self.target = target


class _TargetFile(io.FileIO):
    """The raw temporary file of a target: a failing write names the target.

    Writes go through :func:`os.write`, so that a test can make the disk
    "full" by patching it, and an :class:`OSError` (ENOSPC, EFBIG, EIO, ...)
    becomes an :class:`OutputError` naming the file the user asked for, not
    the temporary one, wherever the write happens (in pandas, matplotlib,
    at a flush).
    """

    def __init__(self, path: Path, target: Path) -> None:
        super().__init__(path, "w")
        self.target = target

    def write(self, data: Any) -> int:
        try:
            return os.write(self.fileno(), data)
        except OSError as exc:
            raise OutputError(self.target, exc) from None


def open_target(path: Path, target: Path, mode: str) -> IO[Any]:
    """``path`` opened for writing in ``mode`` ("w" or "wb"), its writes guarded."""
    buffered = io.BufferedWriter(_TargetFile(path, target))
    if "b" in mode:
        return buffered
    # newline="": lines are written as given (the CSV writers give "\n").
    return io.TextIOWrapper(buffered, encoding="utf-8", newline="")


@contextlib.contextmanager
def signals_held() -> Iterator[None]:
    """Hold SIGINT and SIGTERM while the block runs; deliver them after it.

    Their handlers are swapped for one that only notes the signal; after the
    block the handlers are put back and each noted signal is raised again,
    so that its own handler (``KeyboardInterrupt``, the default action, ...)
    takes effect then. A signal mask would not do: the kernel hands a
    signal that the main thread blocks to another thread (numpy's BLAS
    threads, say), and Python then runs the handler on the main thread all
    the same. Python runs signal handlers on the main thread only, so on any
    other thread an interrupt cannot raise inside the block and nothing is
    held; nor is a signal whose handler was installed from outside Python
    (it reads as None and could not be put back).
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    holding = True
    noted: list[int] = []
    originals: dict[int, Any] = {}

    def defer(signum: int, frame: FrameType | None) -> None:
        if holding:
            noted.append(signum)
        else:  # the block is over, this handler not yet replaced: pass the signal on
            signal.signal(signum, originals[signum])
            signal.raise_signal(signum)

    try:
        for s in HELD_SIGNALS:
            if signal.getsignal(s) is not None:
                originals[s] = signal.signal(s, defer)
        yield
    finally:
        holding = False
        for s, handler in originals.items():
            signal.signal(s, handler)
        for s in dict.fromkeys(noted):
            signal.raise_signal(s)


@dataclasses.dataclass
class StagedEntry:
    """One target of an output set and what is to replace it."""

    target: Path
    #: The temporary file beside the target; None if the target is to be removed.
    tmp: Path | None
    #: reserved: created, not written yet; open: being written; ready: closed
    #: and synced to disk; remove: the target is to be deleted; keep: it was
    #: to be deleted, but this program did not write it (see the manifest).
    state: Literal["reserved", "open", "ready", "remove", "keep"]
    fh: IO[Any] | None = None


def discard_entries(entries: dict[Path, StagedEntry], created: list[Path]) -> None:
    """Remove every temporary file of ``entries`` and the empty directories in ``created``.

    A module function rather than a method so that the set's finalizer can
    call it without keeping the set alive.
    """
    for entry in entries.values():
        if entry.fh is not None:
            # Closing flushes, which fails again on a full disk: the file goes anyway.
            with contextlib.suppress(Exception):
                entry.fh.close()
        if entry.tmp is not None:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(entry.tmp)
    entries.clear()
    # Newest first, so that a directory is emptied of the ones made inside it;
    # one that holds anything else stays.
    for directory in reversed(created):
        with contextlib.suppress(OSError):
            directory.rmdir()
    created.clear()


def refuse_input(target: Path) -> None:
    """Raise :class:`OutputError` if ``target`` is a file the run reads."""

    found = input_at(target)
    if found is not None:
        what, shown = found
        raise OutputError(
            target, f"it is the {what} {shown} that this run reads; write the results "
            "into another directory", "nothing was written")


def refuse_foreign(target: Path) -> None:
    """Raise :class:`OutputError` if ``target`` is a file this program did not write.

    A file is this program's if the manifest of its directory lists it,
    unchanged since it was written (:data:`MANIFEST`); any other file there
    (a materials library the user keeps beside their projects, a file they
    edited since) is the user's.
    """
    stamp = _stamp(target)
    if not os.path.lexists(target) or (
            stamp is not None and _read_manifest(target.parent).get(target.name) == stamp):
        return
    raise OutputError(
        target, f"a file this program did not write is there (the folder's {MANIFEST} does "
        "not list it, or it changed since); it is kept: write into another folder or file, "
        "or move it away first", "nothing was written")


#: The largest manifest read (bytes); a larger one is not ours and counts as empty.
_MANIFEST_LIMIT = 1 << 20


def _read_manifest(directory: Path) -> dict[str, dict[str, int]]:
    """The files of ``directory`` that its manifest lists: name -> {size, mtime_ns}.

    A missing, unreadable or malformed manifest lists nothing: then no
    file of the directory counts as written by this program.
    """
    try:
        with open(directory / MANIFEST, "rb") as fh:
            data = json.loads(fh.read(_MANIFEST_LIMIT + 1)[:_MANIFEST_LIMIT])
        files = data["files"]
        return {str(name): {"size": int(v["size"]), "mtime_ns": int(v["mtime_ns"])}
                for name, v in files.items()}
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return {}


def _stamp(path: Path) -> dict[str, int] | None:
    """Size (bytes) and modification time (ns) of the regular file ``path``, else None."""
    try:
        info = os.lstat(path)
    except OSError:
        return None
    if not os.path.isfile(path) or os.path.islink(path):
        return None
    return {"size": info.st_size, "mtime_ns": info.st_mtime_ns}


def manifests(entries: list[StagedEntry]) -> list[StagedEntry]:
    """The new manifest of every directory that ``entries`` write to or remove from.

    Each lists the files written now (stamped from their temporary files:
    a rename keeps size and time) and those of the old manifest that are
    still there unchanged. A removal of a file the old manifest does not
    list, or that changed since, becomes ``keep``: the file is the user's.
    """
    by_dir: dict[Path, list[StagedEntry]] = {}
    for entry in entries:
        if entry.target.name != MANIFEST:
            by_dir.setdefault(entry.target.parent, []).append(entry)
    made: list[StagedEntry] = []
    for directory, group in by_dir.items():
        old = _read_manifest(directory)
        # Only what is still there, as it was written.
        listed = {name: v for name, v in old.items() if _stamp(directory / name) == v}
        for entry in group:
            name = entry.target.name
            if entry.state == "remove":
                if name not in listed:
                    entry.state = "keep"
                listed.pop(name, None)
            elif entry.tmp is not None:
                stamp = _stamp(entry.tmp)
                if stamp is not None:
                    listed[name] = stamp
        target = directory / MANIFEST
        if target.is_dir():
            continue
        try:
            fd, name = make(directory, MANIFEST)
        except OSError as exc:
            raise OutputError(target, exc) from None
        entry = StagedEntry(target, Path(name), "reserved")
        made.append(entry)
        os.close(fd)
        os.chmod(name, 0o666 & ~current_umask())
        text = json.dumps({"written_by": "rockfall-design", "files": dict(sorted(listed.items()))},
                          indent=1)
        try:
            entry.fh = open_target(entry.tmp, target, "w")  # type: ignore[arg-type]
        except OSError as exc:
            raise OutputError(target, exc) from None
        entry.state = "open"
        entry.fh.write(text + "\n")
        finish_entry(entry)
    return made


def finish_entry(entry: StagedEntry) -> None:
    """Flush, sync to disk and close an open entry's file."""
    if entry.fh is None:
        return
    try:
        entry.fh.flush()
        os.fsync(entry.fh.fileno())
        entry.fh.close()
    except OSError as exc:  # e.g. EIO, or ENOSPC reported only at the sync
        raise OutputError(entry.target, exc) from None
    entry.fh, entry.state = None, "ready"


def swap_in(entries: list[StagedEntry]) -> list[Path]:
    """Rename every entry into place, keeping the old targets aside; all or none.

    Returns the old targets' new names (to be deleted once the commit is
    complete). If a rename fails, the ones done are undone in reverse order
    and :class:`OutputError` names the file that failed.
    """
    undo: list[tuple[str, Path, Path]] = []  # (what, moved from, moved to)
    backups: list[Path] = []
    current: Path | None = None
    try:
        for entry in entries:
            if entry.state == "keep":
                continue
            current = entry.target
            if os.path.lexists(entry.target):
                if entry.target.is_dir() and not entry.target.is_symlink():
                    raise IsADirectoryError(21, "it is a directory")
                # A unique name beside the target, then the old file onto it.
                fd, name = make(entry.target.parent, entry.target.name, ".old")
                os.close(fd)
                backup = Path(name)
                try:
                    os.replace(entry.target, backup)
                except OSError:
                    os.unlink(backup)
                    raise
                undo.append(("old", entry.target, backup))
                backups.append(backup)
            if entry.tmp is not None:
                os.replace(entry.tmp, entry.target)
                undo.append(("new", entry.tmp, entry.target))
    except OSError as exc:
        problems = []
        for _what, source, moved_to in reversed(undo):
            try:
                os.replace(moved_to, source)
            except OSError as again:  # pragma: no cover - a file system failing twice
                problems.append(f"{source}: {again.strerror or again}")
        done = "no file was changed"
        if problems:  # pragma: no cover
            done = "could not restore " + ", ".join(problems)
        raise OutputError(current if current is not None else Path("?"), exc, done) from None
    return backups


def target_key(path: str | os.PathLike[str]) -> Path:
    """The absolute path a target is known by, so one file cannot enter a set twice."""
    return Path(os.path.abspath(path))


def current_umask() -> int:
    """The process's file-creation mask (read by setting it and setting it back)."""
    mask = os.umask(0)
    os.umask(mask)
    return mask

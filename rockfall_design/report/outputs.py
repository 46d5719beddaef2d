"""Writing a command's results all together or not at all.

The files a command writes (tables, summary, design, figures) form one
:class:`OutputSet`. Each file goes to a temporary file beside its target, in
the same directory so that the final rename is atomic (``os.replace`` is, on
POSIX and Windows); only when the whole command has succeeded are all of
them renamed into place, one after another, with SIGINT and SIGTERM held so
that an interrupt cannot fall between two renames. An error or an interrupt
before that removes every temporary file and touches no target, so a reader
finds either the complete previous results or the complete new ones, never a
torn file nor a mix of old and new files.

A file system that fails is reported the same way, whatever the stage: a
full disk (ENOSPC), a file-size limit (EFBIG), a target that is a directory
or any other refusal raises :class:`OutputError` (exit code 2), one line
naming the file and the operating system's reason. If the failure comes in
the middle of the commit, the files already renamed are put back: the old
targets were moved aside, not overwritten, until the last rename succeeded.

Two guards keep a command from destroying what it did not make. A target
that is a file the run reads (the project, its survey, library or
catalogues, a summary to repeat; see :func:`rockfall_design.project.inputs.note_input`)
is refused when it is reserved or opened, before the command's work, with
:class:`OutputError`. And every commit records what it wrote in a manifest
per directory, :data:`MANIFEST` (name, size and modification time of each
file); :meth:`OutputSet.remove` deletes a stale result only if that manifest
lists it, unchanged since it was written, so that a file the user made
under the same name (a figure of their own) stays.

The single-file helpers (:func:`write_text`, :func:`write_json`,
:func:`write_csv`, :func:`write_with`, :func:`atomic_writer`) are output sets
of one file.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import json
import os
import signal
import tempfile
import threading
import weakref
from collections.abc import Callable, Iterator
from pathlib import Path
from types import FrameType, TracebackType
from typing import IO, Any, Literal

from ..errors import InputError
from .interrupts import HELD_SIGNALS, check_interrupt, note_commit

__all__ = [
    "MANIFEST",
    "OutputError",
    "OutputSet",
    "atomic_writer",
    "write_text",
    "write_json",
    "write_csv",
    "write_with",
]


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


def _open_target(path: Path, target: Path, mode: str) -> IO[Any]:
    """``path`` opened for writing in ``mode`` ("w" or "wb"), its writes guarded."""
    buffered = io.BufferedWriter(_TargetFile(path, target))
    if "b" in mode:
        return buffered
    # newline="": lines are written as given (the CSV writers give "\n").
    return io.TextIOWrapper(buffered, encoding="utf-8", newline="")


@contextlib.contextmanager
def _signals_held() -> Iterator[None]:
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
class _Entry:
    """One target of an output set and what is to replace it."""

    target: Path
    #: The temporary file beside the target; None if the target is to be removed.
    tmp: Path | None
    #: reserved: created, not written yet; open: being written; ready: closed
    #: and synced to disk; remove: the target is to be deleted; keep: it was
    #: to be deleted, but this program did not write it (see the manifest).
    state: Literal["reserved", "open", "ready", "remove", "keep"]
    fh: IO[Any] | None = None


def _discard(entries: dict[Path, _Entry], created: list[Path]) -> None:
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


class OutputSet:
    """The output files of one command, renamed into place together or not at all.

    Use it as a context manager: leaving the block normally commits the set
    (:meth:`commit`), leaving it by an exception, ``KeyboardInterrupt``
    included, discards it (:meth:`discard`). Files are written as temporary
    files beside their targets, synced to disk, and renamed into place only
    at the commit, with SIGINT and SIGTERM held during the renames; an
    interrupt that arrives then is delivered right after the last rename.

    A directory that a target needs is created when the file is reserved or
    opened, and removed again on discard if it is still empty; a target that
    is a directory is refused then, before the command's work. At the commit
    each old target is first moved aside, beside itself; if the operating
    system refuses a rename half-way, every file renamed so far is put back
    (the new ones return to their temporary names and are removed, the old
    ones to their places), and :class:`OutputError` says which file failed.
    Only once every rename has succeeded are the old files deleted.

    Examples
    --------
    >>> from pathlib import Path
    >>> import tempfile
    >>> out = Path(tempfile.mkdtemp())
    >>> with OutputSet() as files:
    ...     files.reserve(out / "summary.json")      # fail now if out cannot be written
    ...     rows = files.open(out / "rows.csv")      # streamed; the set closes it
    ...     _ = rows.write("a,b\\n1,2\\n")
    ...     files.write_json(out / "summary.json", {"rows": 1})
    >>> sorted(p.name for p in out.iterdir())
    ['.rockfall-design-outputs.json', 'rows.csv', 'summary.json']
    """

    def __init__(self) -> None:
        self._entries: dict[Path, _Entry] = {}
        self._created: list[Path] = []
        #: True once every file of the set is in place.
        self.committed = False
        # A backstop for an interrupt that lands where neither commit() nor
        # discard() can react (say, on the first instruction of __exit__):
        # the temporary files are still removed when the set is dropped or
        # the interpreter exits. Both methods retire it.
        self._finalizer = weakref.finalize(self, _discard, self._entries, self._created)

    def __enter__(self) -> OutputSet:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if exc_type is None:
            self.commit()
        else:
            self.discard()

    def __contains__(self, path: object) -> bool:
        """True if ``path`` is written (or being written) in this set."""
        if not isinstance(path, str | os.PathLike):
            return False
        entry = self._entries.get(_key(path))
        return entry is not None and entry.state in ("open", "ready")

    # ---- adding files ----------------------------------------------------
    def reserve(self, *paths: str | os.PathLike[str]) -> None:
        """Create the temporary files of ``paths`` now, to be written later.

        A command reserves its files before a long run so that an output
        directory that cannot be written is reported at once, not after the
        run. Every reserved file must be written, or removed with
        :meth:`remove`, before the commit.

        Raises
        ------
        InputError
            If the directory cannot be created or written.
        """
        for path in paths:
            self._reserve(path)

    def open(self, path: str | os.PathLike[str], mode: str = "w") -> IO[Any]:
        """A file to write ``path``'s new content into, e.g. chunk by chunk.

        Text modes write UTF-8 with newlines as given. The set flushes,
        syncs and closes the file at the commit (or discards it): do not
        close it yourself.
        """
        return self._open(path, mode).fh  # type: ignore[return-value]

    def write_text(self, path: str | os.PathLike[str], text: str) -> None:
        """Write ``text`` (UTF-8) as the new content of ``path``."""
        self._write(path, "w", lambda fh: fh.write(text))

    def write_json(self, path: str | os.PathLike[str], data: Any) -> None:
        """Write ``data`` as indented JSON (NaN refused) as the new content of ``path``."""
        self.write_text(path, json.dumps(data, indent=2, allow_nan=False) + "\n")

    def write_csv(self, path: str | os.PathLike[str], frame: Any) -> None:
        """Write a pandas DataFrame as CSV (no index) as the new content of ``path``."""
        self._write(path, "w", lambda fh: frame.to_csv(fh, index=False, lineterminator="\n"))

    def write_with(self, path: str | os.PathLike[str], writer: Callable[[IO[Any]], None]) -> None:
        """Write binary content produced by ``writer(fh)`` (e.g. a figure) for ``path``."""
        self._write(path, "wb", writer)

    def remove(self, path: str | os.PathLike[str]) -> None:
        """Delete ``path``, if it exists, at the commit: a stale result of an earlier run.

        ``path`` may have been reserved, but not written. It is deleted only
        if the manifest of its directory (:data:`MANIFEST`) lists it as
        written by this program and it has not changed since; a file of the
        user's with the same name stays.

        Raises
        ------
        OutputError
            If ``path`` is a file the run reads.
        """
        key = _key(path)
        _refuse_input(key)
        entry = self._entries.get(key)
        if entry is None:
            self._entries[key] = _Entry(key, None, "remove")
            return
        if entry.state != "reserved":
            raise ValueError(f"{key} is written in this output set; it cannot also be removed")
        os.unlink(entry.tmp)  # type: ignore[arg-type]
        entry.tmp, entry.state = None, "remove"

    # ---- commit and discard ----------------------------------------------
    def commit(self) -> None:
        """Rename every file into place (and delete the removed ones), as one step.

        Every file is synced to disk first; then the renames run with SIGINT
        and SIGTERM held, and a signal that arrived meanwhile is delivered
        (as ``KeyboardInterrupt``, say) only after the last one, with
        :attr:`committed` already True. Any exception before the renames
        discards the set.

        Raises
        ------
        RuntimeError
            If a reserved file was never written: committing the rest would
            leave the old file beside new ones.
        OutputError
            If a file cannot be synced or renamed into place; every target
            is then as it was before the commit.
        """
        try:
            # An interrupt whose exception was swallowed still stops the set.
            check_interrupt()
            unwritten = [str(e.target) for e in self._entries.values() if e.state == "reserved"]
            if unwritten:
                raise RuntimeError(f"reserved but never written: {', '.join(unwritten)}")
            for entry in self._entries.values():
                _finish(entry)
            # Recorded in the set, so that a failure from here on discards them too.
            for manifest in _manifests(list(self._entries.values())):
                self._entries[manifest.target] = manifest
            with _signals_held():
                check_interrupt()  # one that came while the files were synced
                backups = _swap_in(list(self._entries.values()))
                if self._entries:
                    note_commit()
                # Nothing is left to clean up: the entries are in place and
                # the directories made for them are theirs.
                self._finalizer.detach()
                self.committed = True
                # The old files, no longer needed; still with the signals
                # held, or an interrupt noted meanwhile would leave them.
                for backup in backups:
                    with contextlib.suppress(OSError):
                        os.unlink(backup)
        except BaseException:
            self.discard()
            raise

    def discard(self) -> None:
        """Remove every temporary file and the directories made for them; touch no target.

        Does nothing once the set is committed or discarded.
        """
        # Held so that a second Ctrl-C cannot cut the clean-up short.
        with _signals_held():
            self._finalizer()

    # ---- internals -------------------------------------------------------
    def _reserve(self, path: str | os.PathLike[str]) -> _Entry:
        key = _key(path)
        if key in self._entries:
            raise ValueError(f"{key} is already in this output set")
        # Held so that no interrupt can fall between creating the temporary
        # file (or a directory) and recording it, which would leave it behind.
        if key.is_dir():
            raise OutputError(key, "it is a directory", "nothing was written")
        _refuse_input(key)
        with _signals_held():
            try:
                missing = [d for d in (key.parent, *key.parent.parents) if not d.exists()]
                # Recorded first: mkdir may fail half-way, having made some.
                self._created.extend(reversed(missing))
                key.parent.mkdir(parents=True, exist_ok=True)
                fd, name = tempfile.mkstemp(prefix=f".{key.name}.", suffix=".tmp", dir=key.parent)
                entry = self._entries[key] = _Entry(key, Path(name), "reserved")
                os.close(fd)
                # mkstemp makes the file 0600; give it the mode open() would.
                os.chmod(name, 0o666 & ~_umask())
            except OSError as exc:
                raise OutputError(key, exc, "nothing was written") from None
        return entry

    def _open(self, path: str | os.PathLike[str], mode: str) -> _Entry:
        entry = self._entries.get(_key(path))
        if entry is None:
            entry = self._reserve(path)
        elif entry.state != "reserved":
            raise ValueError(f"{entry.target} is already written in this output set")
        try:
            entry.fh = _open_target(entry.tmp, entry.target, mode)  # type: ignore[arg-type]
        except OSError as exc:
            raise OutputError(entry.target, exc) from None
        entry.state = "open"
        return entry

    def _write(
        self, path: str | os.PathLike[str], mode: str, writer: Callable[[IO[Any]], Any]
    ) -> None:
        entry = self._open(path, mode)
        writer(entry.fh)  # type: ignore[arg-type]
        # Closed at once: a command may write many files; only streamed ones
        # stay open until the commit.
        _finish(entry)


def _refuse_input(target: Path) -> None:
    """Raise :class:`OutputError` if ``target`` is a file the run reads."""
    from ..project.inputs import input_at

    found = input_at(target)
    if found is not None:
        what, shown = found
        raise OutputError(
            target, f"it is the {what} {shown} that this run reads; write the results "
            "into another directory", "nothing was written")


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


def _manifests(entries: list[_Entry]) -> list[_Entry]:
    """The new manifest of every directory that ``entries`` write to or remove from.

    Each lists the files written now (stamped from their temporary files:
    a rename keeps size and time) and those of the old manifest that are
    still there unchanged. A removal of a file the old manifest does not
    list, or that changed since, becomes ``keep``: the file is the user's.
    """
    by_dir: dict[Path, list[_Entry]] = {}
    for entry in entries:
        if entry.target.name != MANIFEST:
            by_dir.setdefault(entry.target.parent, []).append(entry)
    made: list[_Entry] = []
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
            fd, name = tempfile.mkstemp(prefix=f".{MANIFEST}.", suffix=".tmp", dir=directory)
        except OSError as exc:
            raise OutputError(target, exc) from None
        entry = _Entry(target, Path(name), "reserved")
        made.append(entry)
        os.close(fd)
        os.chmod(name, 0o666 & ~_umask())
        text = json.dumps({"written_by": "rockfall-design", "files": dict(sorted(listed.items()))},
                          indent=1)
        try:
            entry.fh = _open_target(entry.tmp, target, "w")  # type: ignore[arg-type]
        except OSError as exc:
            raise OutputError(target, exc) from None
        entry.state = "open"
        entry.fh.write(text + "\n")
        _finish(entry)
    return made


def _finish(entry: _Entry) -> None:
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


def _swap_in(entries: list[_Entry]) -> list[Path]:
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
                fd, name = tempfile.mkstemp(prefix=f".{entry.target.name}.", suffix=".old",
                                            dir=entry.target.parent)
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


def _key(path: str | os.PathLike[str]) -> Path:
    """The absolute path a target is known by, so one file cannot enter a set twice."""
    return Path(os.path.abspath(path))


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_writer(path: str | os.PathLike[str], mode: str = "w") -> Iterator[IO[Any]]:
    """Open a temporary file beside ``path``; rename it onto ``path`` on success.

    An output set of one file: on any exception (KeyboardInterrupt included)
    the temporary file is removed and ``path`` is left untouched.
    """
    with OutputSet() as files:
        yield files.open(path, mode)


def write_text(path: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` to ``path`` atomically (see :meth:`OutputSet.write_text`)."""
    with OutputSet() as files:
        files.write_text(path, text)


def write_json(path: str | os.PathLike[str], data: Any) -> None:
    """Write ``data`` as JSON to ``path`` atomically (see :meth:`OutputSet.write_json`)."""
    with OutputSet() as files:
        files.write_json(path, data)


def write_csv(path: str | os.PathLike[str], frame: Any) -> None:
    """Write a pandas DataFrame as CSV (no index) to ``path`` atomically."""
    with OutputSet() as files:
        files.write_csv(path, frame)


def write_with(path: str | os.PathLike[str], writer: Callable[[IO[Any]], None]) -> None:
    """Write binary content produced by ``writer(fh)`` atomically (e.g. a figure)."""
    with OutputSet() as files:
        files.write_with(path, writer)

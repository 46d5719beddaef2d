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

A set made with ``keep_others=True`` (``calibrate``'s) goes further: it
refuses, before the command's work, any target that is there and that the
manifest does not list as this program's, unchanged: a materials library
kept beside the projects is never replaced by a calibration's
``materials.yaml``.

Temporary files are named after the process that writes them
(:mod:`.temporaries`): the first file a set reserves in a directory removes
the temporary files that runs killed outright (``kill -9``) left there, and
only those, with one line on standard error.

The single-file helpers (:func:`write_text`, :func:`write_json`,
:func:`write_csv`, :func:`write_with`, :func:`atomic_writer`) are output sets
of one file.
"""

from __future__ import annotations

import contextlib
import json
import os
import weakref
from collections.abc import Callable, Iterator
from pathlib import Path
from types import TracebackType
from typing import IO, Any

from .interrupts import check_interrupt, note_commit
from .staging import (
    MANIFEST,
    OutputError,
    StagedEntry,
    current_umask,
    discard_entries,
    finish_entry,
    manifests,
    open_target,
    refuse_foreign,
    refuse_input,
    signals_held,
    swap_in,
    target_key,
)
from .temporaries import make, remove_stale

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

    def __init__(self, *, keep_others: bool = False) -> None:
        #: Refuse a target that is a file this program did not write (see
        #: :func:`~.staging.refuse_foreign`), when it is reserved and again at the commit.
        self.keep_others = keep_others
        self._entries: dict[Path, StagedEntry] = {}
        self._created: list[Path] = []
        # The directories whose stale temporary files this set has looked for.
        self._swept: set[Path] = set()
        # A backstop for an interrupt that lands where neither commit() nor
        # discard() can react (say, on the first instruction of __exit__):
        # the temporary files are still removed when the set is dropped or
        # the interpreter exits. Both methods retire it.
        self._finalizer = weakref.finalize(self, discard_entries, self._entries, self._created)

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
        entry = self._entries.get(target_key(path))
        return entry is not None and entry.state in ("open", "ready")

    def holds(self, path: str | os.PathLike[str]) -> bool:
        """True if ``path`` is in this set in any state: reserved, written or to be removed."""
        return target_key(path) in self._entries

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
        key = target_key(path)
        refuse_input(key)
        entry = self._entries.get(key)
        if entry is None:
            self._entries[key] = StagedEntry(key, None, "remove")
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
        (as ``KeyboardInterrupt``, say) only after the last one, once every
        file is in place. Any exception before the renames
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
                finish_entry(entry)
                if self.keep_others and entry.tmp is not None:
                    refuse_foreign(entry.target)  # one the user put there during the run
            # Recorded in the set, so that a failure from here on discards them too.
            for manifest in manifests(list(self._entries.values())):
                self._entries[manifest.target] = manifest
            with signals_held():
                check_interrupt()  # one that came while the files were synced
                backups = swap_in(list(self._entries.values()))
                if self._entries:
                    note_commit()
                # Nothing is left to clean up: the entries are in place and
                # the directories made for them are theirs.
                self._finalizer.detach()
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
        with signals_held():
            self._finalizer()

    # ---- internals -------------------------------------------------------
    def _reserve(self, path: str | os.PathLike[str]) -> StagedEntry:
        key = target_key(path)
        if key in self._entries:
            raise ValueError(f"{key} is already in this output set")
        # Held so that no interrupt can fall between creating the temporary
        # file (or a directory) and recording it, which would leave it behind.
        if key.is_dir():
            raise OutputError(key, "it is a directory", "nothing was written")
        refuse_input(key)
        if self.keep_others:
            refuse_foreign(key)
        with signals_held():
            try:
                missing = [d for d in (key.parent, *key.parent.parents) if not d.exists()]
                # Recorded first: mkdir may fail half-way, having made some.
                self._created.extend(reversed(missing))
                key.parent.mkdir(parents=True, exist_ok=True)
                if key.parent not in self._swept:
                    # What runs killed outright left behind (see .temporaries).
                    self._swept.add(key.parent)
                    remove_stale(key.parent)
                fd, name = make(key.parent, key.name)
                entry = self._entries[key] = StagedEntry(key, Path(name), "reserved")
                os.close(fd)
                # mkstemp makes the file 0600; give it the mode open() would.
                os.chmod(name, 0o666 & ~current_umask())
            except OSError as exc:
                raise OutputError(key, exc, "nothing was written") from None
        return entry

    def _open(self, path: str | os.PathLike[str], mode: str) -> StagedEntry:
        entry = self._entries.get(target_key(path))
        if entry is None:
            entry = self._reserve(path)
        elif entry.state != "reserved":
            raise ValueError(f"{entry.target} is already written in this output set")
        try:
            entry.fh = open_target(entry.tmp, entry.target, mode)  # type: ignore[arg-type]
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
        finish_entry(entry)


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

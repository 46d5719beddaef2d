"""Interrupts that are never lost: the signal handler notes them, the run checks at safe points.

A handler that raises inside numpy can be swallowed (numpy looks up
``__array_ufunc__`` and ignores an exception raised meanwhile), so the
command's handler only notes the signal here; the run checks the note
between batches, families and decisions, and the output set holds the
signals while it swaps its files in.
"""

from __future__ import annotations

import signal

from ..errors import Interrupted

#: The signals held while an output set is renamed into place: Ctrl-C and
#: the polite kill, the two a user or a batch system sends to stop a run.
HELD_SIGNALS = (signal.SIGINT, signal.SIGTERM)

# The signals (SIGINT, SIGTERM) the command line's handler has received during
# the current command, in order; see note_interrupt().
_interrupts: list[int] = []

# How many non-empty output sets this process has committed (see
# committed_sets()); only ever incremented, with the signals held.
_committed = 0


def note_interrupt(signum: int) -> None:
    """Note that the command was interrupted by ``signum``; no output set commits after it.

    The command line's signal handler notes the signal before it raises
    ``KeyboardInterrupt``. The exception may be swallowed where it lands
    (numpy swallows one raised while it looks up ``__array_ufunc__``, say,
    and a library's ``except BaseException`` would too); the note is not:
    :meth:`~.outputs.OutputSet.commit` and :func:`check_interrupt` raise it again, so
    the command still ends as interrupted (exit code 130) and replaces
    nothing.
    """
    _interrupts.append(signum)


def check_interrupt() -> None:
    """Raise :class:`~rockfall_design.errors.Interrupted` if the command was interrupted.

    Called at safe points of a run (between batches of rocks, families and
    decisions of the optimiser, scenarios) and before every commit.
    """
    if _interrupts:
        raise Interrupted(_interrupts[0])


def forget_interrupts() -> None:
    """Forget the noted signals (a new command starts)."""
    _interrupts.clear()


def committed_sets() -> int:
    """How many output sets with at least one file this process has committed.

    The command line reads it before and after a command: if it grew, an
    interrupt came after the command's results were completely in place,
    otherwise no file was changed.
    """
    return _committed


def note_commit() -> None:
    """Count one committed, non-empty output set (called with the signals held)."""
    global _committed
    _committed += 1

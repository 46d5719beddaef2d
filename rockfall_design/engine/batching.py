"""How the rocks of a run are cut into batches and spread over threads.

Batches follow the measured cost of a rock (about :data:`BATCH_SECONDS`
each), so that progress is regular and an interrupt takes effect within a
second whatever the survey; the threads run them at once (the compiled
kernel releases the GIL). The results do not depend on either.
"""

from __future__ import annotations

import os
import threading
from contextvars import ContextVar

import numpy as np

THREADS_ENV = "ROCKFALL_DESIGN_THREADS"
"""Environment variable that sets the number of engine threads (default: every core)."""

#: Engine threads for runs started in this context (a thread of a study's
#: scenario pool sets 1); None: :data:`THREADS_ENV` or the usable cores.
#: A context variable, not the environment: several scenarios run at once in
#: one process, and the caller's other runs keep every core.
ENGINE_THREADS: ContextVar[int | None] = ContextVar("rockfall_design_engine_threads",
                                                    default=None)


def default_threads() -> int:
    """Threads the engine runs on.

    :data:`ENGINE_THREADS` if set in this context, else
    ``ROCKFALL_DESIGN_THREADS``, else the usable cores.
    """
    own = ENGINE_THREADS.get()
    if own is not None:
        return max(1, int(own))
    env = os.environ.get(THREADS_ENV, "").strip()
    if env:
        try:
            return max(1, int(env))
        except ValueError:
            pass
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


BATCH_SECONDS = 0.1
"""Work per batch that the batch sizes aim at (s of one thread).

A batch runs to its end once started (compiled code does not look at
signals), so an interrupt takes effect within about this time after the
running batches end, whatever the cost of a rock. The
size adapts to the measured cost per rock: 4096 rocks of the standard slope
take about 0.02 s, one rock of a size of its own on a survey of 100,000
points about a second (its centre path).
"""


FIRST_BATCH = 1
"""Rocks in the first batch, before the cost of a rock is known (a rock of a survey of
100,000 points and a size of its own costs seconds; batches grow 8-fold from there)."""

FIRST_BATCH_FEW_POINTS = 512
"""Rocks in the first batch on a section of few points (``ensemble.SHARED_PATH_VERTICES``
or fewer), where a rock costs microseconds to a few milliseconds. The optimiser makes
hundreds of runs of a few thousand rocks there (its ground edits), for which batches
of 1, 8 and 64 rocks cost more than they are worth."""


class Batches:
    """Cuts rocks 0..n-1 into consecutive batches sized to :data:`BATCH_SECONDS`.

    Thread-safe. The results do not depend on where the cuts fall (each rock
    draws from its own stream), so sizing them by measured time is harmless.

    Parameters
    ----------
    n : int
        Rocks.
    most : int
        Most rocks in a batch.
    radius : ndarray of float, shape (n,), optional
        The rocks' radii (m), with ``r0`` and ``path_seconds``: a batch makes
        the centre path of each rock whose radius is not ``r0`` and differs
        from the rock before it in the batch (``ensemble._run_batch``), and
        each costs about ``path_seconds`` (s). Batches then hold at most as
        many of those as fit in :data:`BATCH_SECONDS` (at least one rock), so
        that an interrupt waits for about that long on a survey of many
        points too, however cheap the rocks of ``r0`` that came first; the
        measured cost per rock leaves the paths out.
    r0 : float
        Radius (m) whose centre path every batch is given.
    path_seconds : float
        Cost of making one centre path (s); 0 to leave them out.
    first : int
        Rocks in the first batch (:data:`FIRST_BATCH`, or
        :data:`FIRST_BATCH_FEW_POINTS` on a section of few points).
    """

    def __init__(self, n: int, most: int, radius: np.ndarray | None = None,
                 r0: float = -1.0, path_seconds: float = 0.0, first: int = FIRST_BATCH) -> None:
        self.n = n
        self.most = max(1, int(most))
        self.next = 0
        self.size = min(self.most, max(1, int(first)))
        self.rocks = 0
        self.seconds = 0.0
        self.lock = threading.Lock()
        self.path_seconds = float(path_seconds) if radius is not None else 0.0
        if self.path_seconds > 0.0:
            rad = np.asarray(radius, dtype=float)
            own = rad != r0
            new = own.copy()
            new[1:] &= rad[1:] != rad[:-1]
            self._own = own
            # _new_before[j]: paths that rocks 0..j-1 make after the first of a batch.
            self._new_before = np.concatenate([[0], np.cumsum(new)])

    def _paths(self, a: int, b: int) -> int:
        """Centre paths a batch of rocks a..b-1 makes."""
        if self.path_seconds <= 0.0 or b <= a:
            return 0
        return int(self._own[a]) + int(self._new_before[b] - self._new_before[a + 1])

    def take(self) -> tuple[int, int] | None:
        """The next batch (first rock, end), or None when every rock is given out."""
        with self.lock:
            if self.next >= self.n:
                return None
            a = self.next
            b = min(self.n, a + self.size)
            if self.path_seconds > 0.0:
                fit = max(1, int(BATCH_SECONDS / self.path_seconds))
                # The largest end whose batch makes at most ``fit`` paths.
                limit = fit - int(self._own[a]) + self._new_before[a + 1]
                b_fit = int(np.searchsorted(self._new_before, limit, side="right")) - 1
                b = max(a + 1, min(b, b_fit))
            self.next = b
            return a, b

    def done(self, a: int, b: int, seconds: float) -> None:
        """Record that rocks a..b-1 took ``seconds`` (one thread); size the next batches."""
        with self.lock:
            paths = self._paths(a, b)
            if paths:
                # The first path may have been timed with numba's loading of the
                # code: a batch that made ``paths`` paths bounds their cost.
                self.path_seconds = min(self.path_seconds, seconds / paths)
            self.rocks += b - a
            self.seconds += max(seconds - paths * self.path_seconds, 0.0)
            per_rock = self.seconds / max(self.rocks, 1)
            fit = int(BATCH_SECONDS / per_rock) if per_rock > 0.0 else self.most
            # Grow at most 8-fold per batch: the first batches may be cheap ones.
            self.size = max(1, min(self.most, fit, 8 * self.size))

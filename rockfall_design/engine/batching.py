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
running batches end, whatever the cost of a rock (issue 27, item 2). The
size adapts to the measured cost per rock: 4096 rocks of the standard slope
take about 0.02 s, one rock of a size of its own on a survey of 100,000
points about a second (its centre path).
"""


FIRST_BATCH = 1
"""Rocks in the first batch, before the cost of a rock is known (a rock of a survey of
100,000 points and a size of its own costs seconds; batches grow 8-fold from there)."""


class _Batches:
    """Cuts rocks 0..n-1 into consecutive batches sized to :data:`BATCH_SECONDS`.

    Thread-safe. The results do not depend on where the cuts fall (each rock
    draws from its own stream), so sizing them by measured time is harmless.
    """

    def __init__(self, n: int, most: int) -> None:
        self.n = n
        self.most = max(1, int(most))
        self.next = 0
        self.size = min(self.most, FIRST_BATCH)
        self.rocks = 0
        self.seconds = 0.0
        self.lock = threading.Lock()

    def take(self) -> tuple[int, int] | None:
        """The next batch (first rock, end), or None when every rock is given out."""
        with self.lock:
            if self.next >= self.n:
                return None
            a = self.next
            self.next = min(self.n, a + self.size)
            return a, self.next

    def done(self, rocks: int, seconds: float) -> None:
        """Record that ``rocks`` rocks took ``seconds`` (one thread); size the next batches."""
        with self.lock:
            self.rocks += rocks
            self.seconds += seconds
            per_rock = self.seconds / max(self.rocks, 1)
            fit = int(BATCH_SECONDS / per_rock) if per_rock > 0.0 else self.most
            # Grow at most 8-fold per batch: the first batches may be cheap ones.
            self.size = max(1, min(self.most, fit, 8 * self.size))



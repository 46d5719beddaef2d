"""Executors: run independent tasks in-process, on a local process pool, or on Dask.

The scenarios of a study are independent tasks: a function applied to a
picklable task, returning a picklable result. Where they run changes nothing
in the results: every task carries its own seed, so a task gives the same
numbers in-process, on any worker of a pool, or on any worker of a cluster.

- ``workers=1``: in this process, one after the other (the engine uses its
  threads, every core).
- ``workers=N`` with ``pool="threads"`` (what a study does by default): N
  threads of this process, each running one task at a time with the engine
  on one thread (:data:`~rockfall_design.engine.batching.ENGINE_THREADS`).
  The compiled engine releases the GIL, so N threads keep N cores busy, with
  nothing to start: no process, no import, no loading of numba's cache.
  Only a task's pure-Python steps take turns on the GIL (numpy's sorts and
  partitions of a scenario's statistics release it too); measured in
  benchmarks/study.py. On an error or Ctrl-C no further task starts, and
  the tasks under way stop at their next call of :func:`stop_if_cancelled`
  (a calibration's replicates call it before every engine run and between
  its batches of rocks); a task that never calls it finishes (its result
  unused).
- ``workers=N`` with ``pool="processes"`` (the default of :func:`run_tasks`,
  for tasks that run plugins' Python code: sections, designs): a local
  :class:`~concurrent.futures.ProcessPoolExecutor` of N processes, started
  with the ``forkserver`` method where the platform has it (``spawn``
  elsewhere), never ``fork``: a forked copy of a process that runs threads
  (numba's, rich's) can deadlock. Each worker runs the engine on one thread
  (``ROCKFALL_DESIGN_THREADS=1``), so N workers keep N cores busy, not N x N
  threads.
- ``scheduler=ADDRESS``: a :class:`dask.distributed.Client` to a running
  scheduler (``tcp://host:8786``); the workers need only rockfall-design
  installed. Each task runs the engine on one thread there too. Needs the
  ``study`` extra.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import threading
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import (
    FIRST_COMPLETED,
    Future,
    ProcessPoolExecutor,
    ThreadPoolExecutor,
    wait,
)
from contextvars import ContextVar
from typing import Any

from ..engine.batching import ENGINE_THREADS, THREADS_ENV
from ..errors import InputError

__all__ = ["run_tasks", "stop_if_cancelled", "usable_cores", "Cancelled", "EXTRA_HINT",
           "POOLS", "SCHEDULER_TIMEOUT_S"]

#: How to install what a Dask cluster or SALib's indices need.
EXTRA_HINT = "pip install 'rockfall-design[study]'"

#: Seconds a Dask scheduler has to accept the connection, complete the
#: handshake and answer (s): far more than a scheduler across a network needs,
#: little enough that a wrong address (a web server, a silent port) is said
#: at once instead of waiting for ever.
SCHEDULER_TIMEOUT_S = 15.0

#: Longest wait (s) for a task to finish before the caller looks at its signals again.
WAKE_S = 0.25

#: The kinds of local pool :func:`run_tasks` runs tasks on.
POOLS = ("threads", "processes")


class Cancelled(Exception):
    """Raised in a task on a pool's thread when the run it belongs to was given up."""


#: The event that says the run of the task on this thread was given up (an
#: error or Ctrl-C in the caller): set by :func:`run_tasks`' pool of threads.
_CANCEL: ContextVar[threading.Event | None] = ContextVar("rockfall_design_cancel",
                                                         default=None)


def stop_if_cancelled() -> None:
    """Raise :class:`Cancelled` if the run of the task on this thread was given up.

    A task on :func:`run_tasks`' pool of threads cannot be stopped from
    outside (Python has no way to stop a thread), so a long task calls this
    at safe points (before each engine run, between batches of rocks): on
    Ctrl-C it then stops within one batch instead of running to its end.
    Elsewhere (in this process, on a process pool or on Dask) it does nothing.
    """
    event = _CANCEL.get()
    if event is not None and event.is_set():
        raise Cancelled("the run was given up")


def usable_cores() -> int:
    """Cores this process may run on (its CPU affinity), at least 1."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


def single_thread() -> None:
    """Run the engine of this process on one thread (a worker of a pool or a cluster)."""
    os.environ[THREADS_ENV] = "1"


def _pool_worker() -> None:
    """A pool's worker: one engine thread, and Ctrl-C left to the parent.

    The terminal sends SIGINT to the whole process group; the parent stops
    the pool (see :func:`_on_pool`), so a worker ignores it rather than print
    a traceback of its own.
    """
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    single_thread()


def _pool_context() -> multiprocessing.context.BaseContext:
    """forkserver (its server loads the engine once, see :mod:`._warm`), else spawn."""
    if "forkserver" in multiprocessing.get_all_start_methods():
        context = multiprocessing.get_context("forkserver")
        # Only heeded when the forkserver starts (the first pool of the process).
        context.set_forkserver_preload(["rockfall_design.studies._warm"])
        return context
    return multiprocessing.get_context("spawn")


def run_tasks(
    fn: Callable[[Any], Any],
    tasks: Iterable[Any],
    *,
    workers: int | None = None,
    scheduler: Any = None,
    on_done: Callable[[int, Any], None] | None = None,
    pool: str = "processes",
    total: int | None = None,
) -> list[Any]:
    """Apply ``fn`` to every task; the results in the order of ``tasks``.

    Parameters
    ----------
    fn
        A module-level function (picklable by reference).
    tasks
        Picklable arguments, one per call; or an iterator of them, with
        ``total`` their number. A pool of threads starts each task as the
        iterator gives it, so that making the tasks (a study checks each
        scenario's project) overlaps the first runs; an error the iterator
        raises stops the pool as a task's error does. Every other way of
        running takes them all first (one after the other in this process,
        each task would otherwise wait for the runs before it).
    workers
        Processes of the local pool; 1 runs in this process. Default: every
        usable core (but no more than there are tasks).
    scheduler
        Address of a Dask scheduler (``"tcp://127.0.0.1:8786"``), or a
        ``dask.distributed.Client``; overrides ``workers``.
    on_done
        Called in this process as each task finishes, with its position in
        ``tasks`` and its result (in the order they finish).
    pool
        The local pool of ``workers`` > 1: ``"processes"`` or ``"threads"``
        (of this process, each task with one engine thread; for tasks that
        spend their time in the compiled engine). The results are the same.
    total
        The number of ``tasks`` if they are an iterator.

    Raises
    ------
    InputError
        The scheduler cannot be reached, or dask.distributed is not installed.
    Exception
        Whatever a task raised (the first one to fail), as raised; or what
        the iterator of ``tasks`` raised.
    """
    if pool not in POOLS:
        raise ValueError(f"pool must be one of {POOLS}, not {pool!r}")
    count = len(tasks) if isinstance(tasks, Sequence) else total
    if count is None:
        tasks = list(tasks)
        count = len(tasks)
    if count == 0:
        return []
    n = min(int(workers) if workers else usable_cores(), count)
    if scheduler is None and n > 1 and pool == "threads":
        return _on_threads(fn, tasks, count, n, on_done)
    tasks = list(tasks)  # every task made before any runs
    if scheduler is not None:
        return _on_dask(fn, tasks, scheduler, on_done)
    if n <= 1:
        results = []
        for i, task in enumerate(tasks):
            results.append(fn(task))
            if on_done is not None:
                on_done(i, results[-1])
        return results
    return _on_pool(fn, tasks, n, on_done)


def _one_engine_thread(fn: Callable[[Any], Any], task: Any, cancel: threading.Event) -> Any:
    """A task on a thread of the pool: the engine on this one thread, ``cancel`` its stop."""
    if cancel.is_set():  # given up before it started
        raise Cancelled("the run was given up")
    token = ENGINE_THREADS.set(1)
    stop = _CANCEL.set(cancel)
    try:
        return fn(task)
    finally:
        _CANCEL.reset(stop)
        ENGINE_THREADS.reset(token)


def _collect(pending: dict[Future, int], results: list[Any],
             on_done: Callable[[int, Any], None] | None) -> None:
    """Put each finished task's result at its place, as they finish; ``on_done`` for each."""
    while pending:
        # A short timeout, so that a signal handled on another thread (the
        # kernel may hand SIGINT to any thread; Python then only notes it)
        # raises here within it, not when the next task happens to finish.
        done, _ = wait(pending, timeout=WAKE_S, return_when=FIRST_COMPLETED)
        for future in done:
            i = pending.pop(future)
            results[i] = future.result()  # a task's error is raised here, as it was
            if on_done is not None:
                on_done(i, results[i])


def _on_threads(fn: Callable[[Any], Any], tasks: Iterable[Any], count: int, n: int,
                on_done: Callable[[int, Any], None] | None) -> list[Any]:
    results: list[Any] = [None] * count
    pool = ThreadPoolExecutor(max_workers=n, thread_name_prefix="rockfall-task")
    cancel = threading.Event()
    try:
        pending: dict[Future, int] = {}
        # Each task starts as it is made: its run overlaps the making of the next.
        for i, t in enumerate(tasks):
            pending[pool.submit(_one_engine_thread, fn, t, cancel)] = i
        if len(pending) != count:
            raise ValueError(f"{len(pending)} tasks given, {count} announced")
        _collect(pending, results, on_done)
    except BaseException:
        # An error or Ctrl-C: nothing more starts, and a thread cannot be
        # stopped from outside: the tasks under way stop at their next
        # stop_if_cancelled() (results unused), or finish on their own.
        cancel.set()
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown(wait=True)
    return results


def _on_pool(fn: Callable[[Any], Any], tasks: Sequence[Any], n: int,
             on_done: Callable[[int, Any], None] | None) -> list[Any]:
    results: list[Any] = [None] * len(tasks)
    pool = ProcessPoolExecutor(max_workers=n, mp_context=_pool_context(),
                               initializer=_pool_worker)
    try:
        pending: dict[Future, int] = {pool.submit(fn, t): i for i, t in enumerate(tasks)}
        _collect(pending, results, on_done)
    except BaseException:
        # An error or Ctrl-C: nothing more is started, and the scenarios under
        # way are stopped rather than waited for (their results are not used).
        workers = list(getattr(pool, "_processes", {}).values())
        pool.shutdown(wait=False, cancel_futures=True)
        for process in workers:
            process.terminate()
        raise
    pool.shutdown(wait=True)
    return results


def _dask_task(fn: Callable[[Any], Any], task: Any) -> Any:
    """A task on a Dask worker: the engine on one thread, as on a pool's worker."""
    single_thread()
    return fn(task)


def _connect(client_class: Any, address: str) -> Any:
    """A Dask client connected to ``address`` within :data:`SCHEDULER_TIMEOUT_S`, or one line.

    Dask's own timeout covers the connection, not a peer that accepts and
    never answers (a silent port) nor one that answers something else (an
    HTTP or SSH server: Dask reads its first bytes as a frame length and
    tries to allocate exabytes). So the client is made on a thread of its
    own, waited for at most the timeout, and any failure is one line naming
    the address.

    Raises
    ------
    InputError
        The scheduler cannot be reached, does not answer in time, or is
        not a Dask scheduler.
    """
    box: dict[str, Any] = {}
    done = threading.Event()

    def connect() -> None:
        try:
            client = client_class(address, timeout=f"{SCHEDULER_TIMEOUT_S:g}s")
        except BaseException as exc:  # noqa: BLE001 - reported below, on the caller's thread
            box["error"] = exc
        else:
            if done.is_set():  # answered after we gave up: not ours any more
                with contextlib.suppress(Exception):  # nobody is left to tell
                    client.close()
            box["client"] = client
        finally:
            done.set()

    thread = threading.Thread(target=connect, name="rockfall-design dask connect", daemon=True)
    thread.start()
    answered = done.wait(SCHEDULER_TIMEOUT_S + 1.0)
    if not answered:
        done.set()
        raise InputError(
            f"the Dask scheduler at {address} did not answer within "
            f"{SCHEDULER_TIMEOUT_S:g} s (is a Dask scheduler listening there, not another "
            "service?)")
    error = box.get("error")
    if error is None:
        return box["client"]
    if isinstance(error, KeyboardInterrupt | SystemExit):
        raise error
    if isinstance(error, OSError | TimeoutError):
        # Dask's words ("Timed out trying to connect to ..."), one line.
        reason = " ".join(str(error).split()) or type(error).__name__
        raise InputError(
            f"cannot reach the Dask scheduler at {address}: {reason} (is 'dask scheduler' "
            "running there?)") from None
    # Anything else: what answered is not a Dask scheduler (a MemoryError for
    # a banner read as a frame length, a protocol error, a bad address).
    raise InputError(
        f"{address} did not answer as a Dask scheduler ({type(error).__name__}); give the "
        "address of a running 'dask scheduler', e.g. tcp://127.0.0.1:8786") from None


def _on_dask(fn: Callable[[Any], Any], tasks: Sequence[Any], scheduler: Any,
             on_done: Callable[[int, Any], None] | None) -> list[Any]:
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise InputError(
            f"--scheduler needs dask.distributed, which is not installed: {EXTRA_HINT}"
        ) from None
    own = not isinstance(scheduler, Client)
    client = _connect(Client, str(scheduler)) if own else scheduler
    futures: list[Any] = []
    try:
        futures = client.map(_dask_task, [fn] * len(tasks), list(tasks), pure=False)
        where = {future.key: i for i, future in enumerate(futures)}
        results: list[Any] = [None] * len(tasks)
        for future in as_completed(futures):
            i = where[future.key]
            results[i] = future.result()
            if on_done is not None:
                on_done(i, results[i])
        return results
    except BaseException:
        if futures:
            client.cancel(futures)
        raise
    finally:
        if own:
            client.close()

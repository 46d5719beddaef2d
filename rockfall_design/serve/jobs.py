"""Jobs of the app: a run, a check, an optimisation, a study or a calibration.

Each runs in a thread, with progress and cancel. :class:`JobStore` keeps
them: every finished job keeps its summary (a few kB), only the latest few
keep what their downloads are drawn from (a check's full evaluation, tens of
MB at 20,000 rocks), so that the app's memory stays flat however many checks
a page runs.
"""

from __future__ import annotations

import threading
import time
import uuid
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Any


class Cancelled(Exception):
    """Raised from a run's progress callback when its job was cancelled."""


@dataclass
class Job:
    """Work in a background thread: progress, cancel, and its result or error.

    ``kind`` is ``simulate``, ``check``, ``optimise``, ``study`` or
    ``calibrate``; ``stage`` the optimiser's stage (``search``, ``check``);
    ``result`` the JSON-ready answer of a finished check, optimise, study or
    calibration (their ``--json`` summaries), ``tables`` what the page shows
    of a study or calibration (``title``, ``columns``, ``rows``) and
    ``files`` what it offers for download (``design.yaml``, ``report.html``
    as ``--report`` writes it, and the figures as PNG and SVG, drawn on the
    first request).
    """

    kind: str
    total: int
    id: str = field(default_factory=lambda: uuid.uuid4().hex[:12])
    done: int = 0
    stage: str = ""
    state: str = "running"  # running, done, cancelled, failed
    error: str = ""
    result: dict[str, Any] | None = None
    files: dict[str, Any] = field(default_factory=dict)  # text, bytes, or a loader of bytes
    tables: list[dict[str, Any]] = field(default_factory=list)
    started: float = field(default_factory=time.monotonic)
    runtime_s: float = 0.0
    cancel_event: threading.Event = field(default_factory=threading.Event)
    #: Downloads dropped with the full evaluation they were drawn from (see JobStore).
    released: set[str] = field(default_factory=set)

    def progress(self, done: int) -> None:
        """Record ``done`` rocks; stop the run if the job was cancelled."""
        self.done = int(done)
        if self.cancel_event.is_set():
            raise Cancelled

    def staged(self, stage: str, done: int, total: int) -> None:
        """The optimiser's progress (``stage``, ``done`` of ``total``); stop if cancelled."""
        self.stage, self.total = stage, int(total)
        self.progress(done)

    def as_dict(self) -> dict[str, Any]:
        return {"id": self.id, "kind": self.kind, "state": self.state, "done": self.done,
                "total": self.total, "stage": self.stage, "error": self.error,
                "runtime_s": round(self.runtime_s or time.monotonic() - self.started, 3),
                "result": self.result, "files": sorted(self.files),
                "tables": self.tables}


#: Finished jobs whose full results (report and figures to draw) are kept.
KEEP_FULL = 4
#: Jobs kept at all (their summaries); the oldest finished ones are forgotten beyond.
KEEP_JOBS = 500


class JobStore:
    """The app's jobs by id: summaries for all, full results for the latest few.

    A finished job's downloads that are drawn on request (``report.html`` and
    the figures: loaders holding the check's full evaluation, or the
    optimiser's result) are kept for the ``keep_full`` jobs used last (least
    recently used first out: a download counts as a use); older jobs keep
    their summary, their tables and their small files (``design.yaml``), and
    their dropped downloads answer 410. Beyond ``keep_jobs`` jobs, the
    oldest finished ones are forgotten.

    Parameters
    ----------
    keep_full
        Finished jobs that keep their full results.
    keep_jobs
        Jobs kept at all.
    """

    def __init__(self, keep_full: int = KEEP_FULL, keep_jobs: int = KEEP_JOBS) -> None:
        self.keep_full = int(keep_full)
        self.keep_jobs = int(keep_jobs)
        self._jobs: OrderedDict[str, Job] = OrderedDict()
        self._lock = threading.Lock()

    def __len__(self) -> int:
        return len(self._jobs)

    def add(self, job: Job) -> None:
        """Keep ``job`` (the newest), and trim the older ones."""
        with self._lock:
            self._jobs[job.id] = job
            self._trim()

    def get(self, job_id: str) -> Job | None:
        """The job, or None if it was never started or has been forgotten."""
        with self._lock:
            job = self._jobs.get(job_id)
            if job is not None:
                self._trim()  # a job finished since the last look releases what it must
            return job

    def touch(self, job: Job) -> None:
        """Mark ``job`` used now: the last to lose its full results."""
        with self._lock:
            if job.id in self._jobs:
                self._jobs.move_to_end(job.id)

    def full(self) -> list[Job]:
        """The jobs that still hold full results (loaders of downloads)."""
        return [j for j in self._jobs.values() if any(callable(v) for v in j.files.values())]

    def _trim(self) -> None:
        finished = [j for j in self._jobs.values() if j.state != "running"]
        holding = [j for j in finished if any(callable(v) for v in j.files.values())]
        for job in holding[:max(0, len(holding) - self.keep_full)]:
            dropped = {k for k, v in job.files.items() if callable(v)}
            job.files = {k: v for k, v in job.files.items() if k not in dropped}
            job.released |= dropped
        for job in finished[:max(0, len(self._jobs) - self.keep_jobs)]:
            del self._jobs[job.id]

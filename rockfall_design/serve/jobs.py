"""Jobs of the app: a run, a check, an optimisation, a study or a calibration.

Each runs in a thread, with progress and cancel.
"""

from __future__ import annotations

import threading
import time
import uuid
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover
    pass


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

"""Fixtures of the browser app's tests: a copy of a bundled project in its own directory."""

from __future__ import annotations

import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("starlette", reason="rockfall-design serve needs the web extra")

#: The files design_two_zones.yaml reads (its catalogues).
TWO_ZONES_FILES = ("design_two_zones.yaml", "catalogue_products.yaml", "catalogue_costs.yaml")


@pytest.fixture(scope="module")
def project_copy(tmp_path_factory: pytest.TempPathFactory, projects_dir: Path) -> Path:
    """design_two_zones.yaml and its catalogues, copied into a directory of their own.

    The directory sits one level below a parent that holds a file too
    (``outside.txt``): what a request must never read or overwrite.
    """
    root = tmp_path_factory.mktemp("serve")
    (root / "outside.txt").write_text("not the project's\n")
    d = root / "project"
    d.mkdir()
    for name in TWO_ZONES_FILES:
        shutil.copy(projects_dir / name, d / name)
    return d / "design_two_zones.yaml"


def _default_sigint() -> None:
    """In the child before exec: SIGINT back to its default (a KeyboardInterrupt)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def start_server(*args: str, cwd: Path | None = None) -> tuple[subprocess.Popen, str]:
    """``rockfall-design serve ARGS --port 0`` in a process of its own, and the address it printed.

    The first lines of its stdout hold the address; the caller stops it
    with :func:`stop_server`.
    """
    # SIGINT as Ctrl-C has it: a suite started as a background job of a shell
    # hands its children an ignored SIGINT, which the command keeps ignored (as
    # it must for such a job), and stop_server then waited its 60 s twice.
    proc = subprocess.Popen(
        [sys.executable, "-m", "rockfall_design", "serve", *args, "--port", "0"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=cwd,
        preexec_fn=_default_sigint if sys.platform != "win32" else None)
    lines = []
    for _ in range(10):
        line = proc.stdout.readline()
        if not line:
            break
        lines.append(line)
        match = re.search(r"(http://\S+)", line)
        if match:
            return proc, match.group(1)
    proc.kill()
    out, err = proc.communicate()
    raise AssertionError(f"serve printed no address: {''.join(lines)}{out}{err}")


def stop_server(proc: subprocess.Popen) -> tuple[int, str]:
    """Stop the server as Ctrl-C does; its exit code and what it wrote on stderr."""
    proc.send_signal(signal.SIGINT)
    try:
        _, err = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        proc.kill()
        _, err = proc.communicate()
    return proc.returncode, err


def wait_job(client, job_id: str, polls: int = 4000) -> dict:
    """Poll a job of the app until it is no longer running (a run takes seconds)."""
    job: dict = {}
    for _ in range(polls):
        job = client.get(f"/api/jobs/{job_id}").json()
        if job["state"] != "running":
            return job
        time.sleep(0.05)
    raise AssertionError(f"job {job_id} still running: {job}")

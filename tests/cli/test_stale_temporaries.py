"""Temporary files never outlive a run (issue 34 item 7).

A run killed outright (``kill -9``) leaves its hidden temporary files
(``.rocks.csv.*.tmp``, ``.crossings.csv.*.tmp``, ``.summary.json.*.tmp``);
the next run into that folder removes them and says so in one line, but
never a temporary file of a run that is still alive (two runs into one
folder at once).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rockfall_design.report import temporaries
from rockfall_design.report.outputs import OutputSet, write_text

ROOT = Path(__file__).resolve().parents[2]
PROJECTS = ROOT / "projects"

#: Time allowed for a run to show that it is under way (numba's cache loaded).
STARTUP_S = 180.0


def _dead_pid() -> int:
    """The number of a process that has ended (and been reaped)."""
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


def _temporary(directory: Path, name: str, pid: int, host: str | None = None) -> Path:
    path = directory / f".{name}.{pid}-{host or temporaries._HOST}.abc123_x.tmp"
    path.write_bytes(b"half a table")
    return path


def test_only_the_temporaries_of_dead_runs_go(tmp_path, capsys):
    dead = _dead_pid()
    stale = [_temporary(tmp_path, n, dead) for n in ("rocks.csv", "summary.json")]
    mine = _temporary(tmp_path, "crossings.csv", os.getpid())
    elsewhere = _temporary(tmp_path, "rocks.csv", dead, host="0badc0de")  # another machine
    nameless = tmp_path / ".rocks.csv.k2j8x_0q.tmp"  # no owner in the name: not ours to judge
    nameless.write_bytes(b"")
    users = tmp_path / ".notes.tmp"
    users.write_bytes(b"")
    with subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"]) as live:
        theirs = _temporary(tmp_path, "rocks.csv", live.pid)
        try:
            write_text(tmp_path / "summary.json", "{}\n")
        finally:
            live.kill()
    assert not any(p.exists() for p in stale)
    assert all(p.exists() for p in (mine, elsewhere, nameless, users, theirs))
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert f"removed 2 temporary file(s) (0.0 MB) of earlier runs that were killed before " \
           f"they finished, in {tmp_path}" in err


def test_a_reused_process_number_does_not_keep_a_stale_file(tmp_path, capsys):
    # The number's process started after the file was last written: not its owner.
    with subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"]) as later:
        try:
            old = _temporary(tmp_path, "rocks.csv", later.pid)
            hour_ago = time.time() - 3600
            os.utime(old, (hour_ago, hour_ago))
            if temporaries._started_at(later.pid) is None:
                pytest.skip("no process start times on this system")
            with OutputSet() as files:
                files.write_text(tmp_path / "rocks.csv", "x\n")
        finally:
            later.kill()
    assert not old.exists()
    assert "removed 1 temporary file(s)" in capsys.readouterr().err


def _simulation(tmp_path: Path, rocks: int) -> Path:
    project = tmp_path / f"run{rocks}.yaml"
    project.write_text((PROJECTS / "standard_slope.yaml").read_text()
                       .replace("count: 1000", f"count: {rocks}")
                       .replace("  stations: [80]", "  stations: [80]\n  envelope_points: 2"))
    return project


def _start(tmp_path: Path, project: Path, out: Path, name: str) -> subprocess.Popen:
    err = open(tmp_path / f"{name}.err", "w")  # noqa: SIM115 - closed with the process
    return subprocess.Popen([sys.executable, "-m", "rockfall_design", "simulate", str(project),
                             "--out", str(out)], cwd=ROOT, stdin=subprocess.DEVNULL,
                            stdout=subprocess.DEVNULL, stderr=err)


def _streaming(out: Path, pid: int) -> list[Path]:
    """The temporary files of run ``pid`` in ``out``, once its rocks.csv has a first chunk."""
    own = [p for p in out.glob(f".*.{pid}-*.tmp")]
    if any(p.name.startswith(".rocks.csv.") and p.stat().st_size > 0 for p in own):
        return own
    return []


def _wait_streaming(out: Path, proc: subprocess.Popen) -> list[Path]:
    deadline = time.monotonic() + STARTUP_S
    while True:
        found = _streaming(out, proc.pid) if out.exists() else []
        if found:
            return found
        assert proc.poll() is None, f"the run ended early (exit {proc.returncode})"
        assert time.monotonic() < deadline, "no sign of the run"
        time.sleep(0.02)


# Slow set: three runs of the command, two of them held streaming (8 s).
@pytest.mark.slow
@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_the_next_run_removes_what_a_killed_run_left(tmp_path):
    out = tmp_path / "out"
    killed = _start(tmp_path, _simulation(tmp_path, 3_000_000), out, "killed")
    try:
        left = _wait_streaming(out, killed)
    finally:
        killed.send_signal(signal.SIGKILL)
        killed.wait()
    assert left and all(p.exists() for p in left)  # kill -9: nothing could clean up
    # The next run into the folder removes them, and is still running when a
    # third one writes there too: the live run's temporaries must stay.
    live = _start(tmp_path, _simulation(tmp_path, 3_000_001), out, "live")
    try:
        theirs = _wait_streaming(out, live)
        assert not any(p.exists() for p in left)
        # Held still (SIGSTOP) while the third run writes: still a live process,
        # owner of its files, but not taking the cores the third needs (its
        # rocks are thrown away: the test took 13.1 s of CPU, 11.7 and 10.5 so).
        live.send_signal(signal.SIGSTOP)
        third = subprocess.run(
            [sys.executable, "-m", "rockfall_design", "simulate",
             str(PROJECTS / "standard_slope.yaml"), "--rocks", "50", "--out", str(out)],
            cwd=ROOT, capture_output=True, text=True, timeout=600)
        assert all(p.exists() for p in theirs), "a live run's temporary file was removed"
    finally:
        live.send_signal(signal.SIGCONT)
        live.send_signal(signal.SIGTERM)
        live.wait(timeout=120)
    assert third.returncode in (0, 1), third.stderr
    assert "Traceback" not in third.stderr and "temporary file" not in third.stderr
    err = (tmp_path / "live.err").read_text()
    lines = [line for line in err.splitlines() if "temporary file" in line]
    assert len(lines) == 1 and f"removed {len(left)} temporary file(s)" in lines[0], err
    assert f"in {out}" in lines[0]
    # The live run, stopped politely, cleaned up after itself: nothing is left.
    assert [p.name for p in out.iterdir() if p.name.endswith(".tmp")] == []

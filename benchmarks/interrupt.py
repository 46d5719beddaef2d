"""Ctrl-C during ``calibrate``: the time from SIGINT to the process's exit.

Issue 34 asks that Ctrl-C stops a calibration within 2 s. The script copies
the bundled calibration project into a temporary folder, starts
``rockfall-design calibrate`` there, sends SIGINT after each of a few delays
(so the interrupt lands in different phases: the first fits, the replicates),
and prints when the "interrupted" line came and when the process had exited,
with the load average beside (the figures grow with the machine's load).

Run: ``python benchmarks/interrupt.py [--delays 6,10,14]``.
"""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

PROJECTS = Path(__file__).resolve().parents[1] / "projects"
FILES = ("calibrate_quarry.yaml", "materials.yaml", "quarry_stops_a.csv", "quarry_stops_b.csv")


def one(delay: float) -> tuple[float, float, int]:
    """Seconds to the 'interrupted' line and to the exit, and the exit code."""
    with tempfile.TemporaryDirectory() as folder:
        for name in FILES:
            shutil.copy(PROJECTS / name, folder)
        proc = subprocess.Popen(
            [sys.executable, "-m", "rockfall_design", "calibrate", FILES[0], "--out", "out"],
            cwd=folder, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        time.sleep(delay)
        t0 = time.perf_counter()
        proc.send_signal(signal.SIGINT)
        assert proc.stderr is not None
        proc.stderr.readline()
        said = time.perf_counter() - t0
        code = proc.wait()
        return said, time.perf_counter() - t0, code


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--delays", default="6,10,14",
                        help="seconds after the start at which to send SIGINT, comma-separated")
    args = parser.parse_args()
    print(f"{'SIGINT after':>12} {'message':>8} {'exit':>6} {'code':>4}  load (1 min)")
    for delay in (float(d) for d in args.delays.split(",")):
        said, gone, code = one(delay)
        print(f"{delay:10.1f} s {said:7.2f}s {gone:5.2f}s {code:4d}  {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()

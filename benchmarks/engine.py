"""Engine speed and memory: rocks per second, events per second, peak memory.

Run by hand (not part of the test suite):

    python benchmarks/engine.py [--rocks N]

The first call compiles (or loads from numba's cache) and is timed apart;
the figures are for runs after it. Peak traced memory (numpy and numba
allocations) comes from a second run under tracemalloc, which slows it down.
"""

from __future__ import annotations

import argparse
import resource
import time
import tracemalloc
from pathlib import Path

from rockfall_design.project import load_project
from rockfall_design.simulation import run_study

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rocks", type=int, default=100_000)
    args = ap.parse_args()
    for name in ("standard_slope", "quarry_road"):
        project = load_project(ROOT / "projects" / f"{name}.yaml")
        t0 = time.perf_counter()
        run_study(project, rocks=10)
        warm = time.perf_counter() - t0
        t0 = time.perf_counter()
        study = run_study(project, rocks=args.rocks)
        wall = time.perf_counter() - t0
        # Memory in a second run: tracemalloc slows numba's many small allocations.
        tracemalloc.start()
        run_study(project, rocks=args.rocks)
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        ev = study.result.events_total
        print(
            f"{name:16s} rocks={args.rocks:>9,d}  wall={wall:7.2f} s  "
            f"rocks/s={args.rocks / wall:>10,.0f}  events/s={ev / wall:>12,.0f}  "
            f"events/rock={ev / args.rocks:5.1f}  peak traced={peak / 2**20:7.1f} MiB  "
            f"(first call {warm:.1f} s)"
        )
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak resident memory of the process: {rss:.0f} MiB")


if __name__ == "__main__":
    main()

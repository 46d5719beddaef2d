"""Engine speed and memory: rocks per second, events per second, peak memory.

    python benchmarks/engine.py [--rocks 100000]

The reference case is projects/benchmark.yaml (the standard slope with an
rn_rt talus and roughness, one analysis station) at 100,000 rocks; two more
projects follow for scale. The first call compiles (or loads numba's cache)
and is timed apart. Peak memory: the traced peak of numpy and numba
allocations during the run (tracemalloc, in a second run, as tracing slows
numba's many small allocations) and the process's resident peak, which also
holds Python, numpy, scipy, numba and LLVM themselves.
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
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    for name in ("benchmark", "standard_slope", "quarry_road"):
        project = load_project(ROOT / "projects" / f"{name}.yaml")
        t0 = time.perf_counter()
        run_study(project, rocks=10)
        warm = time.perf_counter() - t0
        t0 = time.perf_counter()
        study = run_study(project, rocks=args.rocks)
        wall = time.perf_counter() - t0
        tracemalloc.start()
        run_study(project, rocks=args.rocks)
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        ev = study.result.events_total
        print(
            f"{name:16s} rocks={args.rocks:>9,d}  wall={wall:6.2f} s  "
            f"rocks/s={args.rocks / wall:>9,.0f}  events/s={ev / wall:>11,.0f}  "
            f"events/rock={ev / args.rocks:5.1f}  peak traced={peak / 2**20:6.1f} MiB  "
            f"(first call {warm:.1f} s)"
        )
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"resident memory: {rss0:.0f} MiB after imports, peak {rss:.0f} MiB")


if __name__ == "__main__":
    main()

"""Peak memory of ``simulate`` as the rock count grows: bounded when streamed.

    python benchmarks/memory.py [--rocks 10000 100000 1000000] [--project quarry_road]

The project (projects/<name>.yaml) gets ten analysis stations spread along
its section. Each rock count runs in a fresh process (the resident peak of
a process never goes down), through the same path as the command line:
runs up to ``EXACT_ROCKS`` rocks keep every result (exact statistics),
larger ones are streamed in chunks with their statistics accumulated in
histograms. Printed per run: wall time, rocks per second, the peak resident
memory of the process, its growth over the process after imports and
compilation, the memory the command line's guard estimated, and what
keeping every result would have needed.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[1]


def _project(name: str):
    from rockfall_design.project import load_project_text

    path = ROOT / "projects" / f"{name}.yaml"
    data = yaml.safe_load(path.read_text(encoding="utf-8"))
    xs = [p[0] for p in data["slope"]["points"]]
    # Ten stations inside the section (not at its ends).
    data["analysis"]["stations"] = [
        round(float(x), 3) for x in np.linspace(xs[0], xs[-1], 12)[1:-1]
    ]
    return load_project_text(yaml.safe_dump(data, sort_keys=False), str(path))


def _peak_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # kB on Linux


def one(name: str, rocks: int) -> dict[str, float]:
    """Run one size in this process; return its figures."""
    from rockfall_design.run.simulation import EXACT_ROCKS, simulate, simulation_memory

    project = _project(name)
    simulate(project, rocks=10)  # compile or load numba's cache
    base = _peak_mib()
    t0 = time.perf_counter()
    run = simulate(project, rocks=rocks)
    run.summary()
    run.envelopes()
    wall = time.perf_counter() - t0
    s = project.analysis.envelope_points + len(project.analysis.stations)
    keep_all = rocks * (32 * s + 40 * len(project.analysis.stations) + 200)
    return {
        "rocks": rocks,
        "streamed": rocks > EXACT_ROCKS,
        "wall_s": wall,
        "rocks_per_s": rocks / wall,
        "peak_mib": _peak_mib(),
        "base_mib": base,
        "estimate_mib": simulation_memory(project, rocks) / 2**20,
        "keep_all_mib": keep_all / 2**20,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rocks", type=int, nargs="+", default=[10_000, 100_000, 1_000_000])
    ap.add_argument("--project", default="quarry_road")
    ap.add_argument("--one", type=int, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.one:
        print(json.dumps(one(args.project, args.one)))
        return
    print(f"project {args.project} with ten analysis stations")
    for n in args.rocks:
        out = subprocess.run(
            [sys.executable, __file__, "--project", args.project, "--one", str(n)],
            check=True, capture_output=True, text=True,
        )
        r = json.loads(out.stdout.strip().splitlines()[-1])
        print(
            f"rocks={r['rocks']:>9,d} {'streamed' if r['streamed'] else 'exact   '}  "
            f"wall={r['wall_s']:7.1f} s  rocks/s={r['rocks_per_s']:>7,.0f}  "
            f"peak RSS={r['peak_mib']:6.0f} MiB (+{r['peak_mib'] - r['base_mib']:5.0f} over "
            f"imports)  guard estimate={r['estimate_mib']:6.0f} MiB  "
            f"keeping every result={r['keep_all_mib']:7.0f} MiB",
            flush=True,
        )


if __name__ == "__main__":
    main()

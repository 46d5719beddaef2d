"""Cost of measures: ``check`` against ``simulate`` on the same rocks.

    python benchmarks/check.py [--rocks N]

Runs projects/benchmark.yaml (three measures: a boulder row, a fence and a
ditch) through ``evaluate`` (what ``check`` does) and the same project
without measures through ``run_in_memory`` (what ``simulate`` does), on the same
rocks and seed, and prints rocks per second of each and their ratio. The
issue's target: check at no less than half the speed of simulate.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from rockfall_design.judge.evaluation import evaluate
from rockfall_design.plugins import load_registry
from rockfall_design.project import load_project
from rockfall_design.run.simulation import run_in_memory

ROOT = Path(__file__).resolve().parents[1]


def best_of(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rocks", type=int, default=50_000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    project = load_project(ROOT / "projects" / "benchmark.yaml")
    registry = load_registry()
    n = args.rocks
    evaluate(project, registry, rocks=10)  # compile / load numba's cache
    run_in_memory(project, rocks=10)
    t_sim = best_of(lambda: run_in_memory(project, rocks=n), args.repeat)
    t_chk = best_of(lambda: evaluate(project, registry, rocks=n), args.repeat)
    print(f"rocks: {n:,}  (best of {args.repeat})")
    print(f"simulate (no measures):   {t_sim:7.2f} s  {n / t_sim:>10,.0f} rocks/s")
    print(f"check (3 measures):       {t_chk:7.2f} s  {n / t_chk:>10,.0f} rocks/s")
    print(f"check speed / simulate speed: {t_sim / t_chk:.2f}  (target >= 0.5)")


if __name__ == "__main__":
    main()

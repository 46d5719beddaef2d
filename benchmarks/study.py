"""Speed of a study: 27 scenarios against one simulation, timed in the same run.

    python benchmarks/study.py [--rocks N] [--workers N] [--scheduler ADDRESS]

Runs projects/benchmark.yaml with a study of three inputs of three values
each (talus Rn and Rt, rock radius: 27 scenarios of ``--rocks`` rocks) on the
default local pool, threads (or on a Dask scheduler), then on a pool of
processes and in this process one scenario after the other (each checked to
give the same JSON numbers), and one ``simulate`` of the same
number of rocks on the same machine, on one core (``ROCKFALL_DESIGN_THREADS=1``)
and on every core, and prints them, the ratio of the study to the one-core
simulation and the ideal ratio, 27 / cores: the issue's target is a study
that takes about 27 times one simulation divided by the number of cores.
On a machine that other work shares, the ratios say little: the best of
three short simulations finds the cores idle, a study of many seconds does
not.

The one simulation is timed as the best of ``--repeat``; each study once
(its 27 runs average out). Timings include what a study adds to the runs:
checking each scenario's project, starting a process pool's processes (each
imports the package and loads numba's cache), and the statistics and
envelopes of each scenario; not what a process loads once whatever it runs
(numba's cache, the package's modules and plugins), loaded before timing.

Measured on the 2-core reference machine (shared with other work: figures
move by 10 to 15 % between runs), study of 27 scenarios against the ideal
27 / 2 x one simulation on one core:

=============  =========  ==========  ==============  ===========  ============
rocks/run      one sim.   threads s   processes s     in-process   threads/ideal
=============  =========  ==========  ==============  ===========  ============
10,000         0.04 s     0.72-0.75   1.39-1.40       0.94-0.96 s  1.37-1.41
50,000         0.19 s     3.14-3.20   3.74-3.96       4.04-4.28 s  1.22-1.27
=============  =========  ==========  ==============  ===========  ============

(Before the threads, the default process pool took 1.83 s and 4.24 s.) What
is left above the ideal is the statistics of each scenario, about a fifth of
a simulation's time, and the check of the scenarios before any runs.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import rockfall_design as rd
from rockfall_design.engine.ensemble import THREADS_ENV
from rockfall_design.project import load_project_text
from rockfall_design.simulation import simulate
from rockfall_design.study.executors import usable_cores

ROOT = Path(__file__).resolve().parents[1]

STUDY = """
study:
  vary:
    materials.talus.restitution: [0.3, 0.35, 0.4]
    materials.talus.tangential_restitution: [0.8, 0.85, 0.9]
    rocks.radius: [0.4, 0.5, 0.6]
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rocks", type=int, default=10_000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--workers", type=int, default=None,
                    help="processes of the local pool (default: every core)")
    ap.add_argument("--scheduler", default=None, help="a Dask scheduler's address")
    args = ap.parse_args()
    path = ROOT / "projects" / "benchmark.yaml"
    project = load_project_text(path.read_text() + STUDY, str(path))
    n = args.rocks
    simulate(project, rocks=10)  # load numba's cache in this process
    # What a process loads once, whatever it runs (the plugins, the modules
    # of the study and of its statistics, scipy), loaded here so that the
    # study's time is the study's, as numba's cache is loaded above.
    import importlib

    from rockfall_design.api import default_registry

    default_registry()
    for module in ("evaluate", "judge.bounds", "study.run", "study.result",
                   "study.sensitivity", "study.executors"):
        importlib.import_module(f"rockfall_design.{module}")

    def best(threads: str | None, summary: bool = False) -> float:
        saved = os.environ.get(THREADS_ENV)
        if threads is not None:
            os.environ[THREADS_ENV] = threads
        try:
            times = []
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                run = simulate(project, rocks=n)
                if summary:  # what `simulate --json` computes besides the run
                    run.summary()
                times.append(time.perf_counter() - t0)
            return min(times)
        finally:
            if saved is None:
                os.environ.pop(THREADS_ENV, None)
            else:
                os.environ[THREADS_ENV] = saved

    t_one = best("1")  # the unit: one simulation on one core
    t_json = best("1", summary=True)  # the same with its statistics, as simulate --json
    t_all = best(None)
    def timed(**kw: object) -> tuple[float, dict]:
        t0 = time.perf_counter()
        result = rd.study(project, rocks=n, **kw)
        return time.perf_counter() - t0, result.summary

    t_study, summary = timed(workers=args.workers, scheduler=args.scheduler)
    runs = []
    if args.scheduler is None:
        t_proc, other = timed(workers=args.workers, pool="processes")
        assert other["scenarios"] == summary["scenarios"], "the pools differ"
        runs.append(("on a local pool of processes (--pool processes)", t_proc))
    t_here, other = timed(workers=1)
    assert other["scenarios"] == summary["scenarios"], "in-process and pooled runs differ"
    runs.append(("in this process (--workers 1)", t_here))
    k = len(summary["scenarios"])
    cores = usable_cores()
    where = (f"Dask scheduler {args.scheduler}" if args.scheduler
             else f"local pool of {min(args.workers or cores, k)} threads (the default)")
    print(f"rocks per run: {n:,}; cores: {cores}")
    print(f"one simulation on one core (best of {args.repeat}):       {t_one:8.2f} s "
          f"{n / t_one:>10,.0f} rocks/s")
    print(f"the same with its JSON statistics (simulate --json):     {t_json:8.2f} s "
          f"{n / t_json:>10,.0f} rocks/s")
    print(f"one simulation on every core (best of {args.repeat}):     {t_all:8.2f} s "
          f"{n / t_all:>10,.0f} rocks/s")
    for what, t in ((f"on the {where}", t_study), *runs):
        print(f"study of {k} scenarios {what}: {t:8.2f} s {k * n / t:>10,.0f} rocks/s, "
              f"{t / t_one:6.2f} x one simulation")
    print(f"ideal: {k} / {cores} cores = {k / cores:.2f} x one simulation = "
          f"{k / cores * t_one:.2f} s; the {'cluster' if args.scheduler else 'default'} "
          f"run takes {t_study / (k / cores * t_one):.2f} x ideal "
          f"(efficiency {k / cores / (t_study / t_one):.0%})")
    # A scenario computes what simulate --json does (and its envelope and
    # bounds): against that unit, what the study adds is its own work.
    print(f"ideal with the statistics: {k} / {cores} x {t_json:.3f} s = "
          f"{k / cores * t_json:.2f} s; the run takes {t_study / (k / cores * t_json):.2f} x")


if __name__ == "__main__":
    main()

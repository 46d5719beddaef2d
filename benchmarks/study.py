"""Speed of a study: 27 scenarios against 27 simulations, timed in the same run.

    python benchmarks/study.py [--rocks N] [--rounds N] [--workers N] [--scheduler ADDRESS]

Runs projects/benchmark.yaml with a study of three inputs of three values
each (talus Rn and Rt, rock radius: 27 scenarios of ``--rocks`` rocks) and
compares it with the issue's yardstick, 27 times one simulation divided by
the number of cores. The yardstick is measured, not assumed: the same 27
scenarios run one after the other in this process with ``simulate`` and its
JSON statistics (``simulate --json``), each with the engine on one core.
The scenarios differ (a larger rock, more restitution: more events), so
their own simulations are the fair unit, not 27 copies of one.

Each round times, one after the other: the 27 simulations; the study as
``rockfall-design study --json`` runs it (the default local pool, threads;
or ``--scheduler``); and the study with every scenario's envelopes (as
``study --plot`` runs it). Rounds interleave so that a machine that other
work shares slows both alike; the ratio of each round and their median are
printed. Then, once, the study on a pool of processes and in this process
one scenario after the other (each checked to give the same JSON numbers).

Timings include what a study adds to the runs: checking each scenario's
project, starting a process pool's processes (each imports the package and
loads numba's cache), and the statistics of each scenario; not what a
process loads once whatever it runs (numba's cache, the package's modules
and plugins), loaded before timing.

Measured on the 2-core reference machine (a VM whose cores other work
shares: single figures move by 10 to 50 % between runs; the median ratio of
interleaved rounds moves far less), 10,000 rocks a scenario, five rounds:
see the README's "Parametric studies" for the figures of this version.
"""

from __future__ import annotations

import argparse
import statistics
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import rockfall_design as rd
from rockfall_design.engine.batching import ENGINE_THREADS
from rockfall_design.project import load_project_text
from rockfall_design.run.simulation import simulate
from rockfall_design.studies.executors import usable_cores
from rockfall_design.studies.runner import ScenarioTask, prepare

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
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--workers", type=int, default=None,
                    help="scenarios at once on the local pool (default: every core)")
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

    registry = default_registry()
    for module in ("judge.evaluation", "judge.bounds", "studies.runner", "studies.study_result",
                   "studies.sensitivity", "studies.executors"):
        importlib.import_module(f"rockfall_design.{module}")

    _, tasks = prepare(project, registry, rocks=n)
    k = len(tasks)
    cores = usable_cores()

    def one(task: ScenarioTask) -> None:
        """A scenario's own simulation with its statistics (simulate --json), one core."""
        token = ENGINE_THREADS.set(1)
        try:
            simulate(task.project, rocks=n, seed=task.seed).summary()
        finally:
            ENGINE_THREADS.reset(token)

    def yardstick() -> float:
        """The 27 scenarios' own simulations, one after the other on one core."""
        t0 = time.perf_counter()
        for task in tasks:
            one(task)
        return time.perf_counter() - t0

    def side_by_side() -> float:
        """The same 27 simulations on a plain pool of ``cores`` threads, nothing else.

        What this machine gives for them at best, with no study around them:
        where cores share caches, memory bandwidth or (virtual CPUs) one
        physical core, less than ``cores`` times one core.
        """
        t0 = time.perf_counter()
        with ThreadPoolExecutor(max_workers=cores) as threads:
            list(threads.map(one, tasks))
        return time.perf_counter() - t0

    def timed(**kw: object) -> tuple[float, dict]:
        t0 = time.perf_counter()
        result = rd.study(project, rocks=n, registry=registry, **kw)
        return time.perf_counter() - t0, result.summary

    where = dict(workers=args.workers, scheduler=args.scheduler)
    pool = (f"Dask scheduler {args.scheduler}" if args.scheduler
            else f"local pool of {min(args.workers or cores, k)} threads")
    print(f"rocks per scenario: {n:,}; scenarios: {k}; cores: {cores}; rounds: {args.rounds}")
    print("times in s; ratios: the study against the ideal (27 simulations / cores) and "
          "against the same simulations side by side on a plain thread pool")
    print(f"{'round':>5} {'27 sims':>8} {'ideal':>6} {'side by side':>13} {'study':>6} "
          f"{'/ideal':>7} {'/side':>6} {'+envelopes':>11} {'/ideal':>7}")
    ratios, ratios_env, ratios_side, speedups, studies, sticks = [], [], [], [], [], []
    summary: dict = {}
    for r in range(args.rounds):
        t_seq = yardstick()
        t_side = side_by_side()
        t_study, summary = timed(envelopes=False, **where)  # as study --json
        t_env, other = timed(**where)  # as study --plot
        assert other["scenarios"] == summary["scenarios"], "the envelopes changed a number"
        ideal = t_seq / cores
        ratios.append(t_study / ideal)
        ratios_env.append(t_env / ideal)
        ratios_side.append(t_study / t_side)
        speedups.append(t_seq / t_side)
        studies.append(t_study)
        sticks.append(t_seq)
        print(f"{r + 1:>5} {t_seq:>8.2f} {ideal:>6.2f} {t_side:>13.2f} {t_study:>6.2f} "
              f"{ratios[-1]:>7.2f} {ratios_side[-1]:>6.2f} {t_env:>11.2f} {ratios_env[-1]:>7.2f}")
    med = statistics.median
    print(f"median: the study on the {pool} (the default) takes {med(ratios):.2f} x the ideal "
          f"(range {min(ratios):.2f}-{max(ratios):.2f}), {med(ratios_side):.2f} x the "
          f"simulations side by side (range {min(ratios_side):.2f}-{max(ratios_side):.2f}); "
          f"with envelopes {med(ratios_env):.2f} x the ideal")
    print(f"this machine runs the simulations side by side {med(speedups):.2f} x as fast as one "
          f"after the other on one core ({cores} cores); "
          f"{k * n / med(studies):,.0f} rocks/s in the study, "
          f"{k * n / med(sticks):,.0f} rocks/s on one core")
    if args.scheduler is None:
        t_proc, other = timed(envelopes=False, pool="processes", workers=args.workers)
        assert other["scenarios"] == summary["scenarios"], "the pools differ"
        print(f"once: on a local pool of processes (--pool processes): {t_proc:.2f} s "
              f"({t_proc / (sticks[-1] / cores):.2f} x the last round's ideal)")
    t_here, other = timed(envelopes=False, workers=1)
    assert other["scenarios"] == summary["scenarios"], "in-process and pooled runs differ"
    print(f"once: in this process, one scenario after the other, each on every core "
          f"(--workers 1): {t_here:.2f} s ({t_here / (sticks[-1] / cores):.2f} x)")


if __name__ == "__main__":
    main()

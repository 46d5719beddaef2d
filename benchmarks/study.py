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
from pathlib import Path

import rockfall_design as rd
from rockfall_design.engine.ensemble import ENGINE_THREADS
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
    for module in ("evaluate", "judge.bounds", "study.run", "study.result",
                   "study.sensitivity", "study.executors"):
        importlib.import_module(f"rockfall_design.{module}")
    from rockfall_design.study.run import prepare

    _, tasks = prepare(project, registry, rocks=n)
    k = len(tasks)
    cores = usable_cores()

    def yardstick() -> float:
        """The 27 scenarios' own simulations with their statistics, one core, in turn."""
        token = ENGINE_THREADS.set(1)
        try:
            t0 = time.perf_counter()
            for task in tasks:
                simulate(task.project, rocks=n, seed=task.seed).summary()
            return time.perf_counter() - t0
        finally:
            ENGINE_THREADS.reset(token)

    def timed(**kw: object) -> tuple[float, dict]:
        t0 = time.perf_counter()
        result = rd.study(project, rocks=n, registry=registry, **kw)
        return time.perf_counter() - t0, result.summary

    where = dict(workers=args.workers, scheduler=args.scheduler)
    pool = (f"Dask scheduler {args.scheduler}" if args.scheduler
            else f"local pool of {min(args.workers or cores, k)} threads")
    print(f"rocks per scenario: {n:,}; scenarios: {k}; cores: {cores}; rounds: {args.rounds}")
    print(f"{'round':>5}  {'27 simulations':>14}  {'ideal':>6}  {'study':>6}  {'ratio':>5}  "
          f"{'+envelopes':>10}  {'ratio':>5}")
    ratios, ratios_env, studies, sticks = [], [], [], []
    summary: dict = {}
    for r in range(args.rounds):
        t_seq = yardstick()
        t_study, summary = timed(envelopes=False, **where)  # as study --json
        t_env, other = timed(**where)  # as study --plot
        assert other["scenarios"] == summary["scenarios"], "the envelopes changed a number"
        ideal = t_seq / cores
        ratios.append(t_study / ideal)
        ratios_env.append(t_env / ideal)
        studies.append(t_study)
        sticks.append(t_seq)
        print(f"{r + 1:>5}  {t_seq:>12.2f} s  {ideal:>4.2f} s  {t_study:>4.2f} s  "
              f"{ratios[-1]:>5.2f}  {t_env:>8.2f} s  {ratios_env[-1]:>5.2f}")
    print(f"median: the study on the {pool} (the default) takes "
          f"{statistics.median(ratios):.2f} x the ideal, 27 simulations / {cores} cores "
          f"(range {min(ratios):.2f}-{max(ratios):.2f}); with envelopes "
          f"{statistics.median(ratios_env):.2f} x; "
          f"{k * n / statistics.median(studies):,.0f} rocks/s, against "
          f"{k * n / statistics.median(sticks):,.0f} rocks/s of one simulation on one core")
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

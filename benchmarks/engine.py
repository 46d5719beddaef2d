"""Engine speed and memory, and PyRockfall 0.1.2 on the same slope, side by side.

    python benchmarks/engine.py [--rocks 100000 1000000] [--pyrockfall-python PATH]
    PYTHONPATH=OTHER_TREE python benchmarks/engine.py --kernel-only   # compare two engines

The reference case is projects/benchmark.yaml (the standard slope with an
rn_rt talus and roughness, one analysis station). For each number of rocks:

* kernel: ``run_ensemble`` alone on the project's rocks (compiled and warm),
  on every core and on one thread; rocks/s and events/s;
* whole process: ``rockfall-design simulate projects/benchmark.yaml --rocks N
  --json`` as a user runs it (a fresh interpreter: imports, project, plugins,
  the run, statistics and the JSON summary); wall time, rocks/s and the
  process's resident peak;
* PyRockfall 0.1.2 on the same slope (benchmarks/_pyrockfall_case.py, see
  there for how the case is set up), in its own interpreter because its
  dependencies (tensorflow, open3d, ...) stay out of rockfall-design's
  environment: the run alone ("kernel") and the whole process.

PyRockfall keeps every time step of every rock in memory (about 1.9 GB for
10,000 rocks on this slope), so it runs ``--pyrockfall-rocks`` rocks
(default 10,000) and the ratios compare rocks per second. Give the
interpreter that has it with --pyrockfall-python (default: this one, if it
can import pyrockfall).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PROJECT = ROOT / "projects" / "benchmark.yaml"
CHUNK = 100_000


def run_child(cmd: list[str], env: dict[str, str] | None = None) -> tuple[float, float, str]:
    """Run ``cmd``; its wall time (s), its own resident peak (MiB) and its stdout."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env, cwd=ROOT)
    chunks: dict[str, str] = {}
    readers = [threading.Thread(target=lambda k=k, f=f: chunks.__setitem__(k, f.read()))
               for k, f in (("out", proc.stdout), ("err", proc.stderr))]
    for r in readers:
        r.start()
    # wait4 gives this child's own resource usage (RUSAGE_CHILDREN would mix
    # every child's peak, PyRockfall's included).
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    for r in readers:
        r.join()
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{chunks.get('err', '')}")
    return wall, usage.ru_maxrss / 1024, chunks.get("out", "")


def kernel(n: int, threads: int | None) -> tuple[float, int, int]:
    """Seconds, events and threads of ``run_ensemble`` on n rocks of the benchmark project."""
    from rockfall_design.engine import run_ensemble
    from rockfall_design.engine.ensemble import default_threads
    from rockfall_design.project import load_project
    from rockfall_design.run.releases import (
        ReleaseStream,
        draw_releases,
        engine_key,
        engine_settings,
        section_from_project,
    )

    project = load_project(PROJECT)
    seed = project.rocks.seed
    section = section_from_project(project)
    stream = ReleaseStream(project, seed)
    parts = [stream.draw(min(CHUNK, n - first)) for first in range(0, n, CHUNK)]
    grid = __import__("numpy").linspace(section.x[0], section.x[-1],
                                        int(project.analysis.envelope_points))
    kw = dict(key=engine_key(seed), stations=list(project.analysis.stations), grid=grid,
              settings=engine_settings(project), threads=threads)
    run_ensemble(section, draw_releases(project, 100, seed), **kw)  # compiled and warm
    # In chunks of 100,000 rocks, as simulate streams a large run.
    events = 0
    t0 = time.perf_counter()
    for first, part in zip(range(0, n, CHUNK), parts, strict=True):
        events += run_ensemble(section, part, first_index=first, **kw).events_total
    return time.perf_counter() - t0, events, threads or default_threads()


def kernel_cpu(n: int, repeats: int = 5) -> tuple[float, int]:
    """Least CPU time (s) of ``repeats`` one-thread kernel runs of n rocks, and their events.

    CPU time of one thread, and the least of several runs, because wall time
    on a machine shared with other work varies by tens of percent from run to
    run; this is the figure to compare two versions of the engine by.
    """
    from rockfall_design.engine import run_ensemble
    from rockfall_design.project import load_project
    from rockfall_design.run.releases import (
        draw_releases,
        engine_key,
        engine_settings,
        section_from_project,
    )

    project = load_project(PROJECT)
    seed = project.rocks.seed
    section = section_from_project(project)
    releases = draw_releases(project, n, seed)
    grid = __import__("numpy").linspace(section.x[0], section.x[-1],
                                        int(project.analysis.envelope_points))
    kw = dict(key=engine_key(seed), stations=list(project.analysis.stations), grid=grid,
              settings=engine_settings(project), threads=1)
    run_ensemble(section, draw_releases(project, 100, seed), **kw)  # compiled and warm
    best, events = float("inf"), 0
    for _ in range(repeats):
        t0 = time.process_time()
        events = run_ensemble(section, releases, **kw).events_total
        best = min(best, time.process_time() - t0)
    return best, events


def has_pyrockfall(python: str) -> bool:
    code = "import importlib.util, sys; sys.exit(importlib.util.find_spec('pyrockfall') is None)"
    try:
        return subprocess.run([python, "-c", code]).returncode == 0
    except OSError:
        return False


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rocks", type=int, nargs="+", default=[100_000, 1_000_000])
    ap.add_argument("--pyrockfall-python", default=sys.executable)
    ap.add_argument("--pyrockfall-rocks", type=int, default=10_000)
    ap.add_argument("--kernel-only", action="store_true",
                    help="only the kernel figures (to compare two versions of the engine "
                         "in one session, e.g. with PYTHONPATH set to another tree)")
    args = ap.parse_args()
    if args.kernel_only:
        import rockfall_design

        print(f"engine from {Path(rockfall_design.__file__).parent}")
        for n in sorted(args.rocks):
            for threads in (None, 1):
                t, events, nthreads = kernel(n, threads)
                print(f"  kernel, {n:,} rocks, {nthreads} threads: {t:7.2f} s  "
                      f"{n / t:>10,.0f} rocks/s  {events / t:>12,.0f} events/s")
        n = min(args.rocks)
        t, events = kernel_cpu(n)
        print(f"  kernel, {n:,} rocks, 1 thread, least CPU time of 5: {t:7.3f} s  "
              f"{n / t:>10,.0f} rocks/s  {events / t:>12,.0f} events/s")
        return

    # Compile (or load the cache) once, so that no figure below includes it.
    run_child([sys.executable, "-m", "rockfall_design", "simulate", str(PROJECT),
               "--rocks", "10", "--json"])
    pyr = has_pyrockfall(args.pyrockfall_python)
    if not pyr:
        print(f"PyRockfall: not importable by {args.pyrockfall_python}; "
              "pass --pyrockfall-python (pip install pyrockfall==0.1.2 in another venv)")
    print(f"cores usable: {len(os.sched_getaffinity(0))}; project: {PROJECT.name}")
    # Child processes first, while this one is small: a child's resident peak
    # starts from its parent's size at the fork.
    whole = {}
    for n in sorted(args.rocks):
        wall, rss, out = run_child([sys.executable, "-m", "rockfall_design", "simulate",
                                    str(PROJECT), "--rocks", str(n), "--json"])
        whole[n] = (wall, rss, json.loads(out))
    peers = {}
    m = min(max(args.rocks), args.pyrockfall_rocks)
    if pyr:
        for conv in ("none", "gauss"):
            pw, prss, pout = run_child([args.pyrockfall_python,
                                        str(ROOT / "benchmarks" / "_pyrockfall_case.py"),
                                        str(m), conv])
            peers[conv] = (pw, prss, json.loads(pout))
    for n in sorted(args.rocks):
        t_all, events, nthreads = kernel(n, None)
        t_one, _, _ = kernel(n, 1)
        wall, rss, summary = whole[n]
        print(f"\nrockfall-design, {n:,} rocks ({events / n:.1f} events/rock, "
              f"{summary['stops']['stopped']:,} stopped)")
        print(f"  kernel, {nthreads} threads: {t_all:7.2f} s  {n / t_all:>10,.0f} rocks/s  "
              f"{events / t_all:>12,.0f} events/s")
        print(f"  kernel, 1 thread : {t_one:7.2f} s  {n / t_one:>10,.0f} rocks/s  "
              f"{events / t_one:>12,.0f} events/s")
        print(f"  whole process    : {wall:7.2f} s  {n / wall:>10,.0f} rocks/s  "
              f"peak resident {rss:,.0f} MiB")
        for conv, what in (("none", "no roughness: the rocks run down the slope"),
                           ("gauss", "roughness N(0, 5 deg): its rocks stop near x = 5 m")):
            if conv not in peers:
                continue
            pw, prss, p = peers[conv]
            prun = m / p["run_s"]
            pproc = m / pw
            print(f"  vs PyRockfall 0.1.2 ({m:,} rocks, {what}): run alone "
                  f"{p['run_s']:.2f} s = {prun:,.0f} rocks/s, whole process {pw:.2f} s = "
                  f"{pproc:,.0f} rocks/s, peak resident {prss:,.0f} MiB")
            print(f"    rockfall-design / PyRockfall in rocks/s: kernel "
                  f"{n / t_all / prun:.1f}x ({n / t_one / prun:.1f}x on one thread), "
                  f"whole process {n / wall / pproc:.1f}x")


if __name__ == "__main__":
    main()

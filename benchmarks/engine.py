"""Engine speed on the standard peer case: cold, warm and whole process, and the peer.

    python benchmarks/engine.py [--rocks 100000 1000000] [--peer-python PATH]
        [--peer-case DIR] [--repeats 3] [--no-first-compile] [--against TREE]
    PYTHONPATH=OTHER_TREE python benchmarks/engine.py --kernel-only   # compare two engines

The case is the standard peer case (../shared/peer-case/README.md):
``rockfall-design simulate projects/benchmark.yaml --rocks N --json`` against
PyRockfall 0.1.2's simulation alone (``rocks_per_s_sim`` of
``run_pyrockfall.py --n 20000 --seed 1 --model classical``, run in its own
interpreter from the peer-case folder), measured in the same run. Printed:

* cold: ``runtime_s`` of a fresh process at the smallest N (the engine run
  as the JSON reports it, loading of the compiled engine included), the best
  and the median of ``--repeats`` processes;
* warm: the same run in one process after a first one (``run_in_memory``, what
  ``runtime_s`` times), and the cost of that process's first run of 1 rock
  (loading the engine);
* whole process: wall time and resident peak of a fresh process at each N;
* first compile (left out with ``--no-first-compile``): ``simulate --rocks 10``
  in a fresh process with an empty cache (``XDG_CACHE_HOME`` set to a new
  temporary directory), its wall and CPU time; then, on the cache it left,
  the engine run as the optimiser runs it (read-only section, recorded
  speeds, resumed rocks), which must compile nothing more; and the load of
  the compiled engine in a fresh process (its first run of one rock less its
  second), through the kept machine code and through numba's cache;
* with ``--against TREE``: the same figures of another version's engine in
  the same run, alternated with this one's (first compile, cold
  ``runtime_s``, the least CPU time of one-thread kernel runs);
* the peer's rate and the ratios the aims are stated in (issue 27, item 11:
  cold ``runtime_s`` at least 20 times the peer's rate, whole process at
  1,000,000 rocks at least 10 times). Without a peer interpreter the peer's
  recorded 13,600 rocks/s (a quiet machine) is used, and said so.

A busy machine slows every figure; the load average is printed with them.
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
    wall, rss, out, _, _ = run_child_full(cmd, env)
    return wall, rss, out


def run_child_full(cmd: list[str],
                   env: dict[str, str] | None = None) -> tuple[float, float, str, str, float]:
    """Run ``cmd``; wall time (s), resident peak (MiB), stdout, stderr and CPU time (s).

    The CPU time (user and system, of the child alone) is the figure a busy
    machine moves least: a compile is single-threaded, so on a quiet machine
    its wall time is about its CPU time.
    """
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
    return (wall, usage.ru_maxrss / 1024, chunks.get("out", ""), chunks.get("err", ""),
            usage.ru_utime + usage.ru_stime)


def kernel(n: int, threads: int | None) -> tuple[float, int, int]:
    """Seconds, events and threads of ``run_ensemble`` on n rocks of the benchmark project."""
    from rockfall_design.engine import run_ensemble
    from rockfall_design.engine.batching import default_threads
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


PEER_RECORDED = 13_600
"""PyRockfall 0.1.2's simulation rate on the standard peer case (rocks/s), recorded on a
quiet machine (issue 27), used when no peer interpreter is given."""


def find_peer_case() -> Path | None:
    """The shared peer-case folder (``../shared/peer-case`` from a checkout's parent)."""
    for up in ROOT.parents:
        d = up / "shared" / "peer-case"
        if (d / "run_pyrockfall.py").is_file():
            return d
    return None


def peer_rate(python: str, case: Path, n: int = 20_000) -> float | None:
    """PyRockfall's rocks/s (simulation alone) on the standard case, or None if it cannot run."""
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "peer.json"
        try:
            subprocess.run([python, "run_pyrockfall.py", "--n", str(n), "--seed", "1",
                            "--model", "classical", "--json", str(out)], cwd=case,
                           capture_output=True, text=True, check=True, timeout=3600)
            return float(json.loads(out.read_text())["rocks_per_s_sim"])
        except (OSError, subprocess.SubprocessError, KeyError, ValueError):
            return None


def simulate_cmd(n: int) -> list[str]:
    return [sys.executable, "-m", "rockfall_design", "simulate", str(PROJECT), "--rocks",
            str(n), "--json"]


OPTIMISER_ARGS = r"""
# The engine run as the optimiser runs it: a read-only section (the plugin
# proxy's guard), speeds recorded, rocks resumed from recorded states.
import numpy as np
from rockfall_design.engine import Section, run_ensemble
from rockfall_design.project import load_project
from rockfall_design.run.releases import draw_releases, engine_key, section_from_project
import sys
project = load_project(sys.argv[1])
s = section_from_project(project)
ro = Section(s.x.copy(), s.y.copy(), s.segment_material.copy(), s.materials)
for a in (ro.x, ro.y, ro.segment_material):
    a.flags.writeable = False
rel = draw_releases(project, 20, 1)
first = run_ensemble(ro, rel, key=engine_key(1), grid=[10.0, 150.0], restart_stations=[50.0],
                     record_speed=True)
mask = ~np.isnan(first.restart_state[:, 0, 0])  # the rocks that passed the station
run_ensemble(ro, rel, key=engine_key(1), grid=[10.0, 150.0], record_speed=True,
             resume=(mask, first.restart_state[:, 0], first.restart_rng[:, 0]))
"""

LOAD_ENGINE = r"""
# A fresh process: import the engine, then its first run of one rock (loading
# the compiled kernel) and a second (warm); the difference is the load.
import json, sys, time
t0 = time.perf_counter()
from rockfall_design.engine import run_ensemble
from rockfall_design.project import load_project
from rockfall_design.run.releases import draw_releases, engine_key, section_from_project
t1 = time.perf_counter()
project = load_project(sys.argv[1])
sec, rel = section_from_project(project), draw_releases(project, 1, 1)
runs = []
for _ in range(2):
    t = time.perf_counter()
    run_ensemble(sec, rel, key=engine_key(1), threads=1)
    runs.append(time.perf_counter() - t)
print(json.dumps({"import": t1 - t0, "first": runs[0], "second": runs[1],
                  "numba_compiler": "numba.np.arraymath" in sys.modules}))
"""


def tree_env(tree: Path | None) -> dict[str, str]:
    """The environment of a child that runs the engine of ``tree`` (this one if None)."""
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    if tree is not None:
        env["PYTHONPATH"] = str(tree)
    return env


def first_compile(cache_home: Path, tree: Path | None = None) -> dict[str, float | bool | str]:
    """The first run after an install, in an empty cache: compile, and what follows.

    ``simulate --rocks 10`` of the benchmark project in a fresh process with
    ``XDG_CACHE_HOME`` set to ``cache_home`` (empty), its wall and CPU time
    and the compile time it reports; then, on the cache it left, the engine
    run as the optimiser runs it (:data:`OPTIMISER_ARGS`), which must not
    compile again, and the load of the compiled engine in a fresh process
    (:data:`LOAD_ENGINE`), through its kept machine code and through numba's
    own cache (``ROCKFALL_DESIGN_NATIVE=0``).
    """
    env = tree_env(tree)
    env["XDG_CACHE_HOME"] = str(cache_home)
    wall, _, _, err, cpu = run_child_full(simulate_cmd(10), env)
    said = [ln for ln in err.splitlines() if "engine compiled in" in ln]
    out: dict[str, float | bool | str] = {"wall": wall, "cpu": cpu,
                                          "said": said[0].split(": ", 1)[-1] if said else ""}
    wall, _, _, err, cpu = run_child_full(
        [sys.executable, "-c", OPTIMISER_ARGS, str(PROJECT)], env)
    out.update(opt_wall=wall, opt_cpu=cpu, opt_compiled="compiling" in err)
    for tag, native in (("native", "1"), ("numba", "0")):
        runs = []
        for _ in range(3):
            _, _, text, _, _ = run_child_full(
                [sys.executable, "-c", LOAD_ENGINE, str(PROJECT)],
                {**env, "ROCKFALL_DESIGN_NATIVE": native})
            runs.append(json.loads(text))
        mid = sorted(runs, key=lambda r: r["first"] - r["second"])[1]
        out[f"{tag}_import"] = mid["import"]
        out[f"{tag}_load"] = mid["first"] - mid["second"]
        out[f"{tag}_compiler"] = mid["numba_compiler"]
    return out


def print_first_compile(fc: dict[str, float | bool | str]) -> None:
    """Print :func:`first_compile`'s figures."""
    print(f"first compile, simulate --rocks 10 in an empty cache: wall {fc['wall']:.1f} s, "
          f"CPU {fc['cpu']:.1f} s (said: {fc['said'] or 'nothing'})")
    print(f"  then the optimiser's arguments (read-only section, resumed rocks): "
          f"wall {fc['opt_wall']:.1f} s, "
          f"{'COMPILED A SECOND VARIANT' if fc['opt_compiled'] else 'nothing compiled'}")
    for tag, what in (("native", "kept machine code"),
                      ("numba", "numba's cache, ROCKFALL_DESIGN_NATIVE=0")):
        print(f"cache load, fresh process ({what}; median of 3): engine import "
              f"{fc[f'{tag}_import']:.2f} s, load {fc[f'{tag}_load']:.3f} s"
              f", numba's compiler {'built' if fc[f'{tag}_compiler'] else 'not built'}")


KERNEL_ROCKS = 50_000
"""Rocks of the one-thread kernel runs that compare two trees (least CPU time of five)."""


def against(tree: Path, n: int, repeats: int) -> None:
    """This tree against ``tree`` in the same run: first compile, cold and warm.

    Each figure alternates the two trees (this one first), so that a change
    of the machine's load falls on both: the first compile in an empty cache
    (wall and CPU time, the helper process's included), ``runtime_s`` of
    fresh processes at n rocks, and the least CPU time of five one-thread
    kernel runs of :data:`KERNEL_ROCKS` rocks in one process (the warm kernel).
    """
    import tempfile

    trees = {"this tree": None, f"against {tree}": tree}
    for name, t in trees.items():
        with tempfile.TemporaryDirectory(prefix="rockfall-design-first-") as tmp:
            fc = first_compile(Path(tmp), t)
        print(f"{name}: first compile wall {fc['wall']:.1f} s, CPU {fc['cpu']:.1f} s "
              f"(said: {fc['said'] or 'nothing'}), optimiser's run "
              f"{'COMPILED A SECOND VARIANT' if fc['opt_compiled'] else 'compiled nothing'}, "
              f"load {fc['native_load']:.3f} s; load average {os.getloadavg()[0]:.1f}")
    cold: dict[str, list[float]] = {name: [] for name in trees}
    cpu: dict[str, list[float]] = {name: [] for name in trees}
    for t in trees.values():
        run_child_full(simulate_cmd(10), tree_env(t))  # compiled or loaded, not timed
    for _ in range(repeats):
        for name, t in trees.items():
            _, _, out, _, _ = run_child_full(simulate_cmd(n), tree_env(t))
            cold[name].append(json.loads(out)["runtime_s"])
    for _ in range(2):
        for name, t in trees.items():
            _, _, out, _, _ = run_child_full(
                [sys.executable, str(Path(__file__).resolve()), "--kernel-cpu",
                 str(KERNEL_ROCKS)], tree_env(t))
            cpu[name].append(json.loads(out)["cpu"])
    for name in trees:
        rt = sorted(cold[name])
        print(f"{name}: cold runtime_s at {n:,} rocks best {rt[0]:.3f} s, median "
              f"{rt[len(rt) // 2]:.3f} s; warm kernel, least CPU of 5 one-thread runs of "
              f"{KERNEL_ROCKS:,} rocks: {', '.join(f'{c:.3f}' for c in cpu[name])} s")
    print(f"load average {os.getloadavg()[0]:.1f}")


def warm(n: int, repeats: int) -> tuple[float, float, list[float]]:
    """In this process: the first 1-rock run (s), then ``repeats`` runs of n rocks (s each).

    Timed as ``runtime_s`` is (``run_in_memory``). Returns (first 1-rock run, first run of n
    after it, every run of n).
    """
    from rockfall_design.project import load_project
    from rockfall_design.run.simulation import run_in_memory

    project = load_project(PROJECT)
    first = run_in_memory(project, rocks=1).runtime_s
    runs = [run_in_memory(project, rocks=n).runtime_s for _ in range(repeats)]
    return first, runs[0], runs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rocks", type=int, nargs="+", default=[100_000, 1_000_000])
    ap.add_argument("--peer-python", default=os.environ.get("PEER_PYTHON"),
                    help="an interpreter with pyrockfall 0.1.2 (default: $PEER_PYTHON)")
    ap.add_argument("--peer-case", type=Path, default=None,
                    help="the shared peer-case folder (default: found above the checkout)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--no-first-compile", action="store_true",
                    help="leave out the first compile in an empty cache (a minute or more)")
    ap.add_argument("--kernel-only", action="store_true",
                    help="only the kernel figures (to compare two versions of the engine "
                         "in one session, e.g. with PYTHONPATH set to another tree)")
    ap.add_argument("--against", type=Path, default=None, metavar="TREE",
                    help="also measure the engine of TREE (a checkout or `git archive` of "
                         "another version) in the same run: first compile, cold, warm kernel")
    ap.add_argument("--kernel-cpu", type=int, default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.kernel_cpu:
        t, events = kernel_cpu(args.kernel_cpu)
        print(json.dumps({"cpu": t, "events": events}))
        return
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

    print(f"cores usable: {len(os.sched_getaffinity(0))}; load average "
          f"{os.getloadavg()[0]:.1f}; project: {PROJECT.name}")
    if not args.no_first_compile:
        import tempfile

        with tempfile.TemporaryDirectory(prefix="rockfall-design-first-") as tmp:
            print_first_compile(first_compile(Path(tmp)))
    # Compile (or load the cache) once, so that no figure below includes it.
    run_child(simulate_cmd(10))
    n0 = min(args.rocks)
    # Child processes first, while this one is small: a child's resident peak
    # starts from its parent's size at the fork.
    cold = []
    for _ in range(args.repeats):
        wall, rss, out = run_child(simulate_cmd(n0))
        cold.append((json.loads(out)["runtime_s"], wall, rss))
    whole = {n0: min(cold, key=lambda c: c[1])[1:]}
    for n in sorted(args.rocks):
        if n != n0:
            wall, rss, _ = run_child(simulate_cmd(n))
            whole[n] = (wall, rss)
    first, first_n, runs = warm(n0, args.repeats)

    case = args.peer_case or find_peer_case()
    rate = peer_rate(args.peer_python, case) if args.peer_python and case else None
    if rate is None:
        rate = PEER_RECORDED
        why = ("no --peer-python / $PEER_PYTHON" if not args.peer_python
               else "no peer-case folder" if not case else "the peer failed to run")
        peer_note = f"recorded {PEER_RECORDED:,} rocks/s ({why}; not measured here)"
    else:
        peer_note = f"measured now: {rate:,.0f} rocks/s (simulation alone, 20,000 rocks)"

    rt = sorted(c[0] for c in cold)
    best, median = rt[0], rt[len(rt) // 2]
    print(f"PyRockfall 0.1.2 on the standard peer case: {peer_note}")
    print(f"\ncold, a fresh process, simulate --rocks {n0:,} --json, runtime_s "
          f"({args.repeats} processes): best {best:.3f} s = {n0 / best:,.0f} rocks/s "
          f"({n0 / best / rate:.1f}x the peer), median {median:.3f} s "
          f"({n0 / median / rate:.1f}x)")
    print(f"warm, in one process: first run (1 rock, loading the engine) {first:.3f} s; "
          f"{n0:,} rocks: first {first_n:.3f} s, best {min(runs):.3f} s = "
          f"{n0 / min(runs):,.0f} rocks/s ({n0 / min(runs) / rate:.1f}x)")
    for n in sorted(whole):
        wall, rss = whole[n]
        print(f"whole process, {n:,} rocks: {wall:.2f} s = {n / wall:,.0f} rocks/s "
              f"({n / wall / rate:.1f}x the peer), peak resident {rss:,.0f} MiB")
    if args.against is not None:
        print()
        against(args.against.resolve(), n0, args.repeats)


if __name__ == "__main__":
    main()

"""Where the engine's first compile goes: per compiled function and per stage.

    python benchmarks/compile_profile.py [--project projects/benchmark.yaml]
        [--command simulate] [--top 25] [--json FILE]

Runs ``rockfall-design COMMAND PROJECT --rocks 10`` (``simulate`` by default)
in a child process with an empty engine cache (``XDG_CACHE_HOME`` set to a
new temporary directory) and times, for every function numba compiles, the
stages of its compile, each exclusive of the compiles nested in it (numba
compiles a callee while it types its caller):

* ``typing``: numba's type inference (``NopythonTypeInference``);
* ``lowering``: numba's lowering to LLVM IR (``NativeLowering`` less the
  LLVM work below);
* ``llvm fn``: LLVM's function passes on the function's own module;
* ``link``: linking the callees' modules into it;
* ``llvm module``: LLVM's module passes on the linked module (numba's
  ``cheap`` pass and its ``full`` one at ``NUMBA_OPT``);
* ``codegen``: LLVM's emission of the module's machine code (MCJIT);
* ``cache``: writing numba's cache files;
* ``other``: the rest (numba's other passes, its dispatcher).

numba's event API (``numba.core.event``) gives the compiles and the passes;
the LLVM stages are timed by wrapping numba's ``CPUCodeLibrary`` methods
(not public API: a profile, not part of the package). The size of each
library's linked module (instructions of LLVM IR before its module passes)
is printed beside it. Every figure is CPU time of the compiling thread (on a
shared machine the wall time is mostly waiting for a core), the profile's own
bookkeeping left out.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, sys, threading, time
from collections import defaultdict

STAGES = ("typing", "lowering", "llvm fn", "link", "llvm module", "codegen", "cache", "other")
TYPING_PASSES = {"NopythonTypeInference", "nopython_type_inference"}
LOWERING_PASSES = {"NativeLowering", "NativeParforLowering", "native_lowering",
                   "native_parfor_lowering"}

lock = threading.RLock()
stack = []  # [function, stage, start, child seconds, pass]
table = defaultdict(lambda: defaultdict(float))
passes = defaultdict(float)  # CPU seconds of numba's other passes, by name
sizes = defaultdict(int)
compiles = defaultdict(int)
t_all = [time.perf_counter(), time.process_time()]


# CPU time of the compiling thread: on a shared machine wall time is mostly waiting.
clock = time.thread_time


def push(fn, stage, pss=""):
    with lock:
        if fn is None:
            fn = stack[-1][0] if stack else "(outside a compile)"
        stack.append([fn, stage, clock(), 0.0, pss])


def pop():
    with lock:
        fn, stage, t0, child, pss = stack.pop()
        d = clock() - t0
        table[fn][stage] += d - child
        if pss:
            passes[pss] += d - child
        if stack:
            stack[-1][3] += d
        return fn


def untimed(seconds):
    # The profile's own work (counting IR) is charged to no one.
    with lock:
        if stack:
            stack[-1][3] += seconds


from numba.core import event, codegen, dispatcher


def name_of(disp):
    f = disp.py_func
    return f"{f.__module__.rsplit('.', 1)[-1]}.{f.__qualname__}"


class Compile(event.Listener):
    def on_start(self, ev):
        compiles[name_of(ev.data["dispatcher"])] += 1
        push(name_of(ev.data["dispatcher"]), "other")

    def on_end(self, ev):
        pop()


class Pass(event.Listener):
    def on_start(self, ev):
        name = ev.data["name"].split(" [", 1)[0]
        stage = ("typing" if name in TYPING_PASSES else
                 "lowering" if name in LOWERING_PASSES else "other")
        push(None, stage, name if stage == "other" else "")

    def on_end(self, ev):
        pop()


event.register("numba:compile", Compile())
event.register("numba:run_pass", Pass())


def wrap(cls, meth, stage, before=None):
    orig = getattr(cls, meth)

    def timed(self, *a, **k):
        if before is not None:
            before(self)
        push(None, stage)
        try:
            return orig(self, *a, **k)
        finally:
            pop()

    setattr(cls, meth, timed)


def count_ir(lib):
    t0 = clock()
    fn = stack[-1][0] if stack else "(outside a compile)"
    n = sum(1 for f in lib._final_module.functions for b in f.blocks for _ in b.instructions)
    sizes[fn] = max(sizes[fn], n)
    untimed(clock() - t0)


lib_cls = codegen.CPUCodeLibrary
wrap(lib_cls, "_optimize_functions", "llvm fn")
wrap(lib_cls, "_optimize_final_module", "llvm module", before=count_ir)
wrap(codegen.JITCodeLibrary, "_finalize_specific", "codegen")
orig_finalize = lib_cls.finalize


def finalize(self):
    # link = finalize less its module passes and codegen (timed inside)
    push(None, "link")
    try:
        return orig_finalize(self)
    finally:
        pop()


lib_cls.finalize = finalize
from numba.core import caching
wrap(caching.Cache, "save_overload", "cache")

from rockfall_design.cli.program import main
code = 0
try:
    code = main(sys.argv[1:])
except SystemExit as exc:
    code = exc.code
wall, cpu = time.perf_counter() - t_all[0], time.process_time() - t_all[1]
print("@@PROFILE@@" + json.dumps({"table": table, "sizes": sizes, "compiles": compiles,
                                  "passes": passes, "wall": wall, "cpu": cpu, "code": code}))
"""


def profile(project: Path, command: str) -> dict:
    """Run the child in an empty cache and return its table."""
    with tempfile.TemporaryDirectory(prefix="rockfall-compile-") as tmp:
        env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
        env["XDG_CACHE_HOME"] = tmp
        out_dir = Path(tmp) / "out"
        cmd = [sys.executable, "-c", CHILD, command, str(project), "--rocks", "10",
               "--out", str(out_dir)]
        proc = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=ROOT,
                              check=False)
    marks = [ln for ln in proc.stdout.splitlines() if ln.startswith("@@PROFILE@@")]
    if not marks:
        sys.exit(f"compile_profile: the child failed:\n{proc.stderr[-3000:]}")
    return json.loads(marks[-1][len("@@PROFILE@@"):])


STAGES = ("typing", "lowering", "llvm fn", "link", "llvm module", "codegen", "cache", "other")


def print_table(res: dict, top: int) -> None:
    """A markdown table: the ``top`` functions by time, then the total."""
    table, sizes, compiles = res["table"], res["sizes"], res["compiles"]
    rows = sorted(table, key=lambda f: -sum(table[f].values()))
    print("| function | compiles | IR instr. linked | "
          + " | ".join(STAGES) + " | total s |")
    print("|---|---:|---:|" + "---:|" * (len(STAGES) + 1))
    totals = dict.fromkeys(STAGES, 0.0)
    for i, fn in enumerate(rows):
        for s in STAGES:
            totals[s] += table[fn].get(s, 0.0)
        if i < top:
            cells = " | ".join(f"{table[fn].get(s, 0.0):.2f}" for s in STAGES)
            print(f"| {fn} | {compiles.get(fn, 0)} | {sizes.get(fn, 0):,} | {cells} | "
                  f"{sum(table[fn].values()):.2f} |")
    rest = len(rows) - min(top, len(rows))
    cells = " | ".join(f"{totals[s]:.2f}" for s in STAGES)
    print(f"| all {len(rows)} ({rest} not listed) | {sum(compiles.values())} | "
          f"{sum(sizes.values()):,} | {cells} | {sum(totals.values()):.2f} |")
    passes = sorted(res["passes"].items(), key=lambda kv: -kv[1])[:8]
    print("\nnumba's other passes (CPU s): "
          + ", ".join(f"{name} {sec:.2f}" for name, sec in passes))
    print(f"\nprocess: wall {res['wall']:.1f} s, CPU {res['cpu']:.1f} s; "
          f"load average {os.getloadavg()[0]:.1f} at the end")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--project", type=Path, default=ROOT / "projects" / "benchmark.yaml")
    ap.add_argument("--command", default="simulate")
    ap.add_argument("--top", type=int, default=25)
    ap.add_argument("--json", type=Path, help="also write the raw table here")
    args = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f} at the start")
    res = profile(args.project.resolve(), args.command)
    if args.json:
        args.json.write_text(json.dumps(res, indent=1))
    print_table(res, args.top)


if __name__ == "__main__":
    main()

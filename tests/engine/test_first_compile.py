"""The first compile: shared with a helper process, LLVM module passes once (issue 37)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from rockfall_design.engine import jit

ROOT = Path(__file__).resolve().parents[2]

FIRST_RUN = r"""
import json, sys
import numpy as np
from rockfall_design.engine import jit, ensemble, rock, run_ensemble, Section
from rockfall_design.project import load_project
from rockfall_design.run.releases import draw_releases, engine_key, section_from_project

project = load_project(sys.argv[1])
sec, rel = section_from_project(project), draw_releases(project, 20, 1)
run_ensemble(sec, rel, key=engine_key(1), stations=[80.0], threads=1)
after_simulate = {
    "rock_compiles": sum(rock.simulate_rock._cache_misses.values()),
    "path_compiles": sum(ensemble._path._cache_misses.values()),
    "path_loads": sum(ensemble._path._cache_hits.values()),
    "kernel_overloads": len(ensemble._run_batch.overloads),
}
# The optimiser's run: read-only section, speeds recorded, rocks resumed.
ro = Section(sec.x.copy(), sec.y.copy(), sec.segment_material.copy(), sec.materials)
for a in (ro.x, ro.y, ro.segment_material):
    a.flags.writeable = False
first = run_ensemble(ro, rel, key=engine_key(1), grid=[10.0, 150.0], restart_stations=[50.0],
                     record_speed=True)
mask = ~np.isnan(first.restart_state[:, 0, 0])
run_ensemble(ro, rel, key=engine_key(1), grid=[10.0, 150.0], record_speed=True,
             resume=(mask, first.restart_state[:, 0], first.restart_rng[:, 0]))
after_simulate["kernel_overloads_after_optimise"] = len(ensemble._run_batch.overloads)
print(json.dumps(after_simulate))
"""


@pytest.mark.slow
def test_the_first_compile_compiles_each_part_once(tmp_path):
    # In an empty cache: the event loop is compiled once (here, before the
    # kernel, for the kernel's own argument types), the sweep by the helper
    # (loaded here from the cache it filled) or here, and the optimiser's run
    # on the same cache compiles nothing more. A wrong guess of the types
    # would compile the event loop a second time inside the kernel's compile.
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
    env.update(XDG_CACHE_HOME=str(tmp_path), ROCKFALL_DESIGN_COMPILE_HELPER="1",
               ROCKFALL_DESIGN_NATIVE="0")
    out = subprocess.run([sys.executable, "-c", FIRST_RUN, str(ROOT / "projects" /
                                                                "benchmark.yaml")],
                         env=env, capture_output=True, text=True, timeout=3600, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout.splitlines()[-1])
    assert got["rock_compiles"] == 1
    if len(os.sched_getaffinity(0)) >= 2:
        assert got["path_compiles"] == 0 and got["path_loads"] == 1
    else:
        assert got["path_compiles"] == 1
    assert got["kernel_overloads"] == 1
    assert got["kernel_overloads_after_optimise"] == 1
    assert out.stderr.count("compiling") == 1, out.stderr


def test_a_failed_helper_leaves_the_compile_to_this_process(monkeypatch):
    # The caller's compile waits for the helper, finds nothing in the cache
    # and compiles the callee itself.
    from numba import njit

    callee = jit.one_variant(njit(cache=False)(lambda a: a + 1))

    @njit(cache=False)
    def caller(a):
        return callee(a) * 2

    monkeypatch.setattr(jit, "CACHE", True)
    monkeypatch.setenv("ROCKFALL_DESIGN_COMPILE_HELPER", "1")
    if not jit.compile_in_helper([callee], "raise SystemExit(3)", b""):
        pytest.skip("one core: no helper")
    assert caller(1) == 4


def test_no_helper_when_switched_off_or_without_a_cache(monkeypatch):
    monkeypatch.setenv("ROCKFALL_DESIGN_COMPILE_HELPER", "0")
    assert not jit.compile_in_helper([], "pass", b"")
    monkeypatch.setenv("ROCKFALL_DESIGN_COMPILE_HELPER", "1")
    monkeypatch.setattr(jit, "CACHE", False)
    assert not jit.compile_in_helper([], "pass", b"")
    jit.await_helper(object())  # nothing to wait for


def test_module_passes_are_left_to_the_caller_that_python_calls(monkeypatch):
    # A callee's module is optimised with its caller's (once), not on its own too.
    from numba import njit
    from numba.core import config

    monkeypatch.setattr(config, "LLVM_PASS_TIMINGS", True)  # numba records each pass run
    assert jit.optimise_once()
    assert jit.optimise_once()  # patched once, however often asked
    callee = jit.one_variant(njit(cache=False)(lambda a: a * 3.0))

    @njit(cache=False)
    def caller(a):
        return callee(a) + 1.0

    assert caller(2.0) == 7.0
    (cres,) = callee.overloads.values()
    (top,) = caller.overloads.values()
    full = "Module passes (full optimization)"
    assert full not in [t.name for t in cres.library.recorded_timings.list_longest_first()]
    assert full in [t.name for t in top.library.recorded_timings.list_longest_first()]
    assert callee(2.0) == 6.0  # still callable from Python

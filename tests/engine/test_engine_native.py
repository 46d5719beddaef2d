"""The batch kernel's kept machine code (engine.native_code, issue 27 item 11).

A fresh process runs the kernel from the object code kept beside numba's
cache, without building numba's compiler; these tests hold it to numba's
dispatcher (same results to the bit), to its checks (other sources or
argument types fall back), and to the point of it (no compiler loaded).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rockfall_design.engine import Material, ensemble, jit, native_code, run_ensemble
from tests.engine_helpers import section

ROOT = Path(__file__).resolve().parents[2]
STANDARD = [(0, 100), (30, 60), (60, 30), (80, 20), (120, 15), (200, 12)]


def talus() -> Material:
    return Material(impact_model="rn_rt", restitution=0.35, tangential_restitution=0.85,
                    friction=0.58, rolling_resistance=0.3, roughness_deg=5.0,
                    sd_restitution=0.05, sd_friction=0.05, sd_rolling_resistance=0.02)


def _releases(n: int):
    from rockfall_design.engine import Releases

    g = np.random.default_rng(2)
    return Releases(radius=g.choice([0.4, 0.5, 0.7], n), density=2650.0,
                    x=g.uniform(1.0, 20.0, n), height=g.uniform(0.0, 2.0, n),
                    vx=np.full(n, 0.6), vy=np.full(n, -0.8), spin=np.zeros(n),
                    spin_rolling=np.zeros(n, dtype=bool))


def _kernel():
    """The native kernel, made (by a run through the dispatcher) if need be."""
    if not jit.CACHE:
        pytest.skip("no cache directory: nothing is kept")
    sec = section(STANDARD, talus())
    run_ensemble(sec, _releases(4), key=1, threads=1, stations=[80.0], grid=[10.0, 150.0])
    # load() tries once per process: forget a try made before the code was kept.
    native_code._loaded.clear()
    kernel = native_code._load(ensemble._run_batch, jit.DIGEST)
    if kernel is None:
        # Made and used on Linux x86-64 (the reference platform); elsewhere
        # the dispatcher runs, which these tests cannot hold to anything.
        assert not sys.platform.startswith("linux"), "no native kernel was kept"
        pytest.skip("this platform keeps no native kernel (the dispatcher runs)")
    return kernel


def test_the_native_kernel_gives_the_dispatchers_results_to_the_bit(monkeypatch):
    _kernel()
    assert native_code.load(ensemble._run_batch, jit.DIGEST) is not None  # what run_ensemble uses
    sec = section(STANDARD, talus())
    kw = dict(key=9, stations=[40.0, 80.0], grid=np.linspace(0, 200, 11),
              n_trajectories=3, threads=2, record_speed=True)
    native = run_ensemble(sec, _releases(300), **kw)
    monkeypatch.setattr(ensemble.native_code, "load", lambda *a: None)
    numba = run_ensemble(sec, _releases(300), **kw)
    for name in ("status", "x_end", "y_end", "n_events", "max_x", "duration", "crossings",
                 "grid_height", "grid_energy", "grid_speed"):
        np.testing.assert_array_equal(getattr(native, name), getattr(numba, name), err_msg=name)
    for a, b in zip(native.trajectories, numba.trajectories, strict=True):
        np.testing.assert_array_equal(a, b)


def test_arguments_of_other_types_go_to_the_dispatcher():
    kernel = _kernel()
    x = np.arange(3.0)
    ro = x.copy()
    ro.flags.writeable = False
    assert native_code.arg_tags([x]) != native_code.arg_tags([ro])
    assert native_code.arg_tags([x]) != native_code.arg_tags([x.astype(np.float32)])
    assert native_code.arg_tags([x]) != native_code.arg_tags([np.arange(6.0)[::2]])
    assert not kernel.accepts([x])


def test_code_kept_from_other_sources_is_not_loaded():
    _kernel()
    assert native_code._load(ensemble._run_batch, "0" * 64) is None


def test_a_kept_kernel_for_another_cpu_is_not_loaded(tmp_path, monkeypatch):
    _kernel()
    obj, meta = native_code._paths(Path(ensemble._run_batch._cache._cache_path),
                                   ensemble._run_batch)
    data = json.loads(meta.read_text())
    data["host"]["cpu"] = "some-other-cpu"
    fake = tmp_path / meta.name
    fake.write_text(json.dumps(data))
    monkeypatch.setattr(native_code, "_paths", lambda *a: (obj, fake))
    assert native_code._load(ensemble._run_batch, jit.DIGEST) is None


def test_the_kept_kernel_files_go_with_a_stale_cache(tmp_path, monkeypatch):
    monkeypatch.setattr(jit, "CACHE", True)
    src = tmp_path / "src"
    src.mkdir()
    (src / "ensemble.py").write_text("a = 1\n")
    cache = tmp_path / "cache"
    cache.mkdir()
    kept = [cache / "ensemble._run_batch.native.nbo", cache / "ensemble._run_batch.native.nbj"]
    for f in kept:
        f.write_bytes(b"x")

    class Cache:
        _enabled = True
        _cache_path = str(cache)

    class Disp:
        _cache = Cache()

    assert jit.drop_stale_cache(Disp(), src) == 2
    assert not any(f.exists() for f in kept)


def test_a_fresh_process_runs_the_engine_without_numbas_compiler():
    # The point of the kept code: numba's typing and lowering registries (and
    # scipy.linalg, which numba's BLAS check imports) are never loaded.
    _kernel()
    code = (
        "import sys, time\n"
        "from rockfall_design.cli import main\n"
        f"main(['simulate', {str(ROOT / 'projects' / 'benchmark.yaml')!r}, '--rocks', '2000',"
        " '--json'])\n"
        "loaded = [m for m in ('numba.np.arraymath', 'numba.np.linalg', 'scipy.linalg')"
        " if m in sys.modules]\n"
        "sys.stderr.write('LOADED=' + ','.join(loaded))\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=ROOT, timeout=300)
    assert run.returncode == 0, run.stderr
    assert run.stderr.rsplit("LOADED=", 1)[1] == ""


def test_a_process_that_loads_numbas_cache_keeps_the_code_for_the_next():
    # The kernel loaded from numba's cache (not compiled in the process) has
    # its object code in numba's data file; it must be kept from there too.
    _kernel()
    obj, meta = native_code._paths(Path(ensemble._run_batch._cache._cache_path),
                                   ensemble._run_batch)
    obj.unlink()
    meta.unlink()
    code = (
        "from rockfall_design.cli import main\n"
        f"main(['simulate', {str(ROOT / 'projects' / 'benchmark.yaml')!r}, '--rocks', '20',"
        " '--json'])\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=ROOT, timeout=300)
    assert run.returncode == 0, run.stderr
    assert "compiling" not in run.stderr
    assert obj.is_file() and meta.is_file()
    assert json.loads(meta.read_text())["digest"] == jit.DIGEST

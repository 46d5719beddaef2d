"""The engine on several threads, numba's cache and the compile notice (issue 14)."""

from __future__ import annotations

import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_array_equal

from rockfall_design.engine import Material, Releases, Section, barrier_table, columns, run_ensemble
from rockfall_design.engine.batching import THREADS_ENV, default_threads
from rockfall_design.engine.jit import KEEP_SHARED, choose_cache_dir, shared_cache_dir

ROOT = Path(__file__).resolve().parents[2]


def _case(n: int = 300):
    x = np.array([0.0, 30, 60, 80, 120, 200])
    y = np.array([100.0, 60, 30, 20, 15, 12])
    mats = (
        Material(restitution=0.35, friction=0.58, rolling_resistance=0.3, roughness_deg=5,
                 sd_restitution=0.05, sd_friction=0.05, sd_rolling_resistance=0.02),
        Material(impact_model="rn_rt", restitution=0.35, tangential_restitution=0.85,
                 friction=0.5, rolling_resistance=0.2, roughness_deg=8, sd_restitution=0.05),
    )
    sec = Section(x, y, np.array([0, 0, 1, 1, 0]), mats)
    rng = np.random.default_rng(3)
    rel = Releases(
        radius=rng.uniform(0.2, 1.0, n), density=2650.0, x=rng.uniform(1.0, 20.0, n),
        height=rng.choice([0.0, 2.0], n), vx=np.full(n, 0.6), vy=np.full(n, -0.8),
        spin=np.zeros(n), spin_rolling=rng.random(n) < 0.5,
    )
    bars = [barrier_table(90.0, 2.0, 3e5, columns.B_NET)]
    return sec, rel, bars


def test_one_and_two_threads_give_identical_results():
    """Every rock draws from its own stream and writes its own rows: bit-identical."""
    sec, rel, bars = _case()
    kw = dict(key=17, stations=[50.0, 100.0], grid=np.linspace(0, 200, 21), barriers=bars,
              restart_stations=[70.0], record_speed=True, n_trajectories=40, batch_size=16)
    one = run_ensemble(sec, rel, threads=1, **kw)
    two = run_ensemble(sec, rel, threads=2, **kw)
    for name in ("status", "x_end", "y_end", "max_x", "n_impacts", "n_events", "duration",
                 "crossings", "grid_height", "grid_energy", "barrier_outcome",
                 "barrier_meeting", "caught_by", "grid_speed", "restart_state", "restart_rng"):
        assert_array_equal(getattr(one, name), getattr(two, name), err_msg=name)
    for a, b in zip(one.trajectories, two.trajectories, strict=True):
        assert_array_equal(a, b)
    # And the same as one batch on one thread.
    kw["batch_size"] = 4096
    whole = run_ensemble(sec, rel, threads=1, **kw)
    assert_array_equal(whole.grid_energy, two.grid_energy)


def test_progress_counts_every_rock_with_threads():
    sec, rel, _ = _case(100)
    seen: list[int] = []
    run_ensemble(sec, rel, key=1, threads=2, batch_size=7, progress=seen.append)
    assert seen == sorted(seen) and seen[-1] == 100


def test_threads_from_the_environment(monkeypatch):
    monkeypatch.setenv(THREADS_ENV, "3")
    assert default_threads() == 3
    monkeypatch.setenv(THREADS_ENV, "not a number")
    assert default_threads() >= 1
    monkeypatch.delenv(THREADS_ENV)
    assert default_threads() == len(os.sched_getaffinity(0))


def _unwritable(tmp_path: Path) -> Path:
    """A directory path nobody can create, root included: its parent is a file."""
    tmp_path.mkdir(parents=True, exist_ok=True)
    f = tmp_path / "a_file"
    f.write_text("")
    return f / "pkg"


def test_cache_dir_choice(tmp_path):
    pkg_ok, temp = tmp_path / "pkg", tmp_path / "tmp"
    pkg_ok.mkdir()
    temp.mkdir()
    pkg_ro = _unwritable(tmp_path)
    # The user's own setting, and numba's default beside a writable package, stay.
    assert choose_cache_dir({"NUMBA_CACHE_DIR": "/x"}, pkg_ro, temp) == (None, True)
    assert choose_cache_dir({}, pkg_ok, temp) == (None, True)
    # A read-only package: a private directory in the temp dir.
    d, enabled = choose_cache_dir({}, pkg_ro, temp)
    assert enabled and Path(d).parent == temp and Path(d).is_dir()
    assert stat.S_IMODE(Path(d).stat().st_mode) & 0o077 == 0
    # Nothing writable: no cache (the engine compiles in every run).
    assert choose_cache_dir({}, pkg_ro, _unwritable(tmp_path / "x")) == (None, False)


def test_cache_dir_that_others_can_write_is_not_used(tmp_path):
    temp = tmp_path / "tmp"
    temp.mkdir()
    shared = temp / f"rockfall-design-numba-{os.getuid()}"
    shared.mkdir()
    shared.chmod(0o777)
    assert choose_cache_dir({}, _unwritable(tmp_path), temp) == (None, False)


def test_read_only_package_and_home_cache_in_the_temp_dir(tmp_path):
    """A copy of the package whose __pycache__ cannot be made, HOME unwritable.

    numba alone would find no cache directory and refuse to import the engine;
    here the cache goes to a private directory under TMPDIR and works.
    """
    copy = tmp_path / "site"
    shutil.copytree(ROOT / "rockfall_design", copy / "rockfall_design",
                    ignore=shutil.ignore_patterns("__pycache__"))
    (copy / "rockfall_design" / "engine" / "__pycache__").write_text("not a directory")
    tmpdir = tmp_path / "tmp"
    tmpdir.mkdir()
    # Nor an XDG_CACHE_HOME of the caller's (a writable one would be used).
    env = {k: v for k, v in os.environ.items()
           if not k.startswith("NUMBA_") and k != "XDG_CACHE_HOME"}
    env.update(PYTHONPATH=str(copy), HOME=str(_unwritable(tmp_path)), TMPDIR=str(tmpdir),
               PYTHONDONTWRITEBYTECODE="1")
    code = (
        "import os, numpy as np\n"
        "from rockfall_design.engine import jit, rng\n"
        "print(jit.CACHE, os.environ['NUMBA_CACHE_DIR'])\n"
        "rng.stream_start(np.uint64(1), 2)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=300, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    enabled, where = out.stdout.split()
    assert enabled == "True"
    assert Path(where) == tmpdir / f"rockfall-design-numba-{os.getuid()}"
    assert list(Path(where).rglob("rng.stream_start-*.nbi")), list(Path(where).rglob("*"))


def test_shared_cache_is_named_by_the_engine_sources_and_private(tmp_path):
    src = tmp_path / "src"
    src.mkdir()
    (src / "rock.py").write_text("a = 1\n")
    home = tmp_path / "home"
    where = shared_cache_dir({}, src, home)
    assert where is not None and where.parent == home / ".cache" / "rockfall-design"
    assert where.name.startswith("engine-") and len(where.name) == len("engine-") + 16
    assert stat.S_IMODE(where.stat().st_mode) == 0o700
    # The same sources elsewhere (another copy of the package): the same directory.
    other = tmp_path / "other"
    shutil.copytree(src, other)
    assert shared_cache_dir({}, other, home) == where
    # Other sources: another directory; XDG_CACHE_HOME is honoured; the user's
    # NUMBA_CACHE_DIR wins; an unwritable home gives None (the old choice applies).
    (other / "rock.py").write_text("a = 2\n")
    assert shared_cache_dir({}, other, home) not in (None, where)
    xdg = shared_cache_dir({"XDG_CACHE_HOME": str(tmp_path / "xdg")}, src, home)
    assert xdg == tmp_path / "xdg" / "rockfall-design" / where.name
    assert shared_cache_dir({"NUMBA_CACHE_DIR": "/x"}, src, home) is None
    assert shared_cache_dir({}, src, _unwritable(tmp_path / "ro")) is None


def test_shared_cache_keeps_the_latest_few_of_other_sources(tmp_path):
    src = tmp_path / "src"
    src.mkdir()
    home = tmp_path / "home"
    ours = home / ".cache" / "rockfall-design"
    ours.mkdir(parents=True, mode=0o700)
    old = [ours / f"engine-{i:016x}" for i in range(KEEP_SHARED + 3)]
    for i, d in enumerate(old):
        d.mkdir()
        os.utime(d, (1_000_000 + i, 1_000_000 + i))
    where = shared_cache_dir({}, src, home)
    assert where.is_dir()
    assert sorted(d for d in ours.iterdir() if d != where) == old[3:]


def test_another_copy_of_the_same_sources_does_not_compile_again(tmp_path):
    """A copy of the package elsewhere (as an installed one beside a checkout) loads the cache."""
    from rockfall_design.engine import ensemble, jit

    here = Path(ensemble._run_batch._cache._cache_path)
    if here.parent.name != "rockfall-design":
        pytest.skip("the engine is not in the shared cache (NUMBA_CACHE_DIR, or no writable home)")
    copy = tmp_path / "site"
    shutil.copytree(ROOT / "rockfall_design", copy / "rockfall_design",
                    ignore=shutil.ignore_patterns("__pycache__"))
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
    env.update(PYTHONPATH=str(copy), PYTHONDONTWRITEBYTECODE="1")
    code = (
        "import rockfall_design as rd\n"
        "from rockfall_design.engine import ensemble\n"
        "print(rd.__file__, ensemble._run_batch._cache._cache_path)\n"
        f"rd.simulate({str(ROOT / 'projects' / 'standard_slope.yaml')!r}, rocks=1)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=300, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    module, where = out.stdout.split()
    assert Path(module).is_relative_to(copy) and Path(where) == here
    assert "compiling" not in out.stderr, out.stderr
    assert jit.CACHE


class _FakeCache:
    _enabled = True

    def __init__(self, path: Path) -> None:
        self._cache_path = str(path)


class _FakeDispatcher:
    def __init__(self, path: Path) -> None:
        self._cache = _FakeCache(path)


def test_a_cache_compiled_from_other_engine_sources_is_dropped(tmp_path, monkeypatch):
    # numba knows a cached function by its own file only; the engine's kernels
    # call functions of other files, so a change to any engine source must
    # drop the whole engine cache (and nothing else in that directory).
    from rockfall_design.engine import jit

    monkeypatch.setattr(jit, "CACHE", True)
    src = tmp_path / "src"
    src.mkdir()
    (src / "rock.py").write_text("a = 1\n")
    (src / "contact.py").write_text("b = 1\n")
    cache = tmp_path / "cache"
    cache.mkdir()
    ours = [cache / "rock.simulate_rock-58.py311.nbi", cache / "contact._accel-9.py311.1.nbc"]
    theirs = cache / "elsewhere.f-1.py311.nbi"
    for f in (*ours, theirs):
        f.write_bytes(b"x")
    disp = _FakeDispatcher(cache)
    # No mark yet: the cache's sources are unknown, so it goes.
    assert jit.drop_stale_cache(disp, src) == 2
    assert theirs.exists() and not any(f.exists() for f in ours)
    # Same sources: kept.
    for f in ours:
        f.write_bytes(b"x")
    assert jit.drop_stale_cache(disp, src) == 0
    assert all(f.exists() for f in ours)
    # A callee's file changed (not the caller's): dropped again.
    (src / "contact.py").write_text("b = 2\n")
    assert jit.drop_stale_cache(disp, src) == 2
    assert not any(f.exists() for f in ours)
    # Without a cache, or with a dispatcher numba no longer shapes so, nothing happens.
    monkeypatch.setattr(jit, "CACHE", False)
    assert jit.drop_stale_cache(disp, src) == 0
    monkeypatch.setattr(jit, "CACHE", True)
    assert jit.drop_stale_cache(object(), src) == 0


def test_simulate_of_a_bare_slope_loads_neither_pandas_nor_scipy(tmp_path):
    """`simulate` imports only what it needs: pandas and scipy cost a fifth of a second."""
    root = Path(__file__).resolve().parents[2]
    code = (
        "import sys\n"
        "from rockfall_design.cli.program import main\n"
        f"main(['simulate', {str(root / 'projects' / 'benchmark.yaml')!r}, '--rocks', '1',"
        " '--json'])\n"
        "loaded = [m for m in ('pandas', 'scipy.stats', 'scipy.special', 'scipy.optimize',"
        " 'matplotlib') if m in sys.modules]\n"
        "sys.stderr.write('LOADED=' + ','.join(loaded))\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=tmp_path, timeout=300)
    assert run.returncode == 0, run.stderr
    assert run.stderr.rsplit("LOADED=", 1)[1] == ""


def test_each_variant_compiled_is_announced_once(capsys):
    # The optimiser runs the batch kernel with other argument types than
    # simulate; the first process after the engine changed compiled that
    # variant too (some 30 s) without a word: the notice was once per function.
    from numba import njit

    from rockfall_design.engine.jit import compile_notice

    @njit(cache=False)
    def twice(a):
        return 2 * a

    done = compile_notice(twice, (3,))
    assert done is not None
    twice(3)
    done()
    assert compile_notice(twice, (4,)) is None  # the same types: compiled, and said
    other = compile_notice(twice, (3.5,))
    assert other is not None
    twice(3.5)
    other()
    err = capsys.readouterr().err
    assert err.count("compiling the trajectory engine for this machine") == 1
    assert err.count("compiling another variant of the trajectory engine") == 1
    assert err.count("engine compiled in") == 2


def _kernel_types(monkeypatch, *calls) -> list[tuple]:
    """numba's types of the batch kernel's arguments for each ``run_ensemble(**kw)`` (no run)."""
    from rockfall_design.engine import ensemble

    seen: list[tuple] = []

    def types_only(batch_args, batches, n, threads, progress):
        args = batch_args(0, n)
        seen.append(tuple(ensemble._run_batch.typeof_pyval(a) for a in args))
        args[-1].caught_by[:] = -1  # what run_ensemble reads back of the rows
        return n

    monkeypatch.setattr(ensemble, "_run_all", types_only)
    for sec, rel, kw in calls:
        run_ensemble(sec, rel, key=1, **kw)
    return seen


def _read_only(*arrays: np.ndarray) -> None:
    for a in arrays:
        a.flags.writeable = False


def test_the_optimisers_runs_use_the_kernel_variant_simulate_compiled(monkeypatch):
    # The optimiser hands the engine read-only sections (the plugin proxy's
    # guard) and resumes rocks from recorded states: numba types a read-only
    # array apart, and the first optimise after an install compiled a second
    # variant of the kernel (about 30 s). One variant serves both now.
    sec, rel, bars = _case(40)
    ro = Section(sec.x.copy(), sec.y.copy(), sec.segment_material.copy(), sec.materials)
    _read_only(ro.x, ro.y, ro.segment_material)
    n = len(rel)
    mask, states = np.zeros(n, dtype=bool), np.zeros((n, columns.N_RESTART_COLS))
    rngs = np.zeros(n, dtype=np.uint64)
    _read_only(mask, states, rngs)
    plain = (sec, rel, dict(stations=[80.0], grid=[10.0, 150.0]))
    optimiser = (ro, rel, dict(stations=[80.0], grid=[10.0, 150.0], barriers=np.vstack(bars),
                               record_speed=True, restart_stations=[50.0],
                               resume=(mask, states, rngs)))
    simulate_types, optimise_types = _kernel_types(monkeypatch, plain, optimiser)
    assert optimise_types == simulate_types
    assert ro.x.flags.writeable is False  # the caller's arrays are left as they were


def test_a_constant_argument_compiles_no_variant_of_its_own():
    # numba compiled a callee once for a constant argument (a literal type)
    # and again for a variable one: 14 engine functions twice.
    from numba import njit

    from rockfall_design.engine.jit import one_variant

    callee = one_variant(njit(cache=False)(lambda a, k: a + k))

    @njit(cache=False)
    def with_constant(a):
        return callee(a, 1)

    @njit(cache=False)
    def with_variable(a, k):
        return callee(a, k)

    assert with_constant(2.0) == 3.0
    assert with_variable(2.0, 5) == 7.0
    assert len(callee.overloads) == 1


def test_a_callee_that_needs_the_constant_still_gets_it():
    # A tuple of mixed types indexed by the argument types only with the
    # literal index: typing with the plain type fails, and numba's way applies.
    from numba import njit

    from rockfall_design.engine.jit import one_variant

    pick = one_variant(njit(cache=False)(lambda t, i: t[i]))

    @njit(cache=False)
    def second(t):
        return pick(t, 1)

    assert second((1, 2.5)) == 2.5

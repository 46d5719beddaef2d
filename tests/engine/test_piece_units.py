"""A rock's centre path from the radius-free part made once a batch (every_piece_units)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rockfall_design.engine import Material, Releases, Section, ensemble, run_ensemble
from rockfall_design.engine.ensemble import rock_path, rock_path_of
from rockfall_design.engine.profile import (
    centre_path,
    centre_path_of,
    element_codes,
    every_piece_units,
    near_path,
    path_elements,
    survey_path,
    sweep_centre_path,
)
from rockfall_design.engine.records import Ground

EMPTY = np.empty(0, dtype=np.int64)


def _ground(x: np.ndarray, y: np.ndarray) -> Ground:
    sec = Section(x, y, np.zeros(x.size - 1, dtype=np.int64), (Material(),))
    return Ground(sec.x, sec.y, sec.segment_material, sec.material_table())


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(2, 40), chord=st.sampled_from([2.0, 5.0, 10.0]))
def test_the_path_from_the_units_is_the_path_to_the_bit(seed, n, chord):
    rng = np.random.default_rng(seed)
    x = np.cumsum(rng.uniform(0.5, 20.0, n))
    y = np.cumsum(rng.normal(-3.0, 4.0, n))
    ground = _ground(x, y)
    mc = np.radians(chord)
    units = every_piece_units(ground.x, ground.y, mc)
    for r in rng.uniform(0.05, 2.0, 5):
        a = rock_path(ground, r, mc, EMPTY)
        b = rock_path_of(ground, r, mc, units)
        for name in ("px", "py", "pseg", "tree"):
            assert np.array_equal(getattr(a, name), getattr(b, name)), name


def test_the_units_do_not_depend_on_the_radius():
    # The level extensions' length is 2 r + 1; their direction is (1, 0)
    # exactly whatever it is, so the units made with any length serve every r.
    x = np.array([0.0, 30.0, 60.0, 80.0, 120.0, 200.0])
    y = np.array([100.0, 60.0, 30.0, 20.0, 15.0, 12.0])
    ground = _ground(x, y)
    units = every_piece_units(ground.x, ground.y, np.radians(5.0))
    assert units[0].size > 2 * (x.size - 1)  # the offsets and the arcs' edges
    for r in (0.01, 0.5, 3.0, 40.0):
        a = rock_path(ground, r, np.radians(5.0), EMPTY)
        b = rock_path_of(ground, r, np.radians(5.0), units)
        assert np.array_equal(a.px, b.px) and np.array_equal(a.py, b.py)



def test_paths_made_from_python_use_the_kernels_sweep_and_compile_nothing():
    # rock_path, rock_path_of, centre_path, survey_path, sweep_centre_path and
    # path_elements are plain functions over the sweep the kernel compiles
    # (ensemble._path, profile.centre_path_of): whatever arrays they are given
    # (read-only, strided, int32, float lists), they add at most that one
    # variant, loaded from the cache, and compile nothing; path_elements
    # compiles one variant of near_path.
    rng = np.random.default_rng(4)
    x = np.linspace(0.0, 200.0, 400)
    y = np.interp(x, [0.0, 80.0, 200.0], [100.0, 20.0, 12.0]) + rng.normal(0.0, 0.01, x.size)
    sec = Section(x, y, np.zeros(x.size - 1, dtype=np.int64), (Material(),))
    before = {d: (set(d.signatures), dict(d.stats.cache_misses))
              for d in (ensemble._path, centre_path_of, near_path)}
    run_ensemble(sec, Releases(radius=np.array([0.4, 0.6]), density=2650.0,
                               x=np.full(2, 1.0), height=np.zeros(2), vx=np.full(2, 0.6),
                               vy=np.full(2, -0.8), spin=np.zeros(2),
                               spin_rolling=np.zeros(2, dtype=bool)), key=1, threads=1)
    read_only = x.copy()
    read_only.flags.writeable = False
    mc = np.radians(5.0)
    strided = np.stack([y, y], axis=1)[:, 0]
    ground = Ground(read_only, strided, sec.segment_material.astype(np.int32),
                    sec.material_table())
    codes = element_codes(x.size)
    rock_path(ground, 0.5, mc, codes.astype(np.int32))
    rock_path_of(ground, 0.5, mc, every_piece_units(sec.x, sec.y, mc))
    centre_path(list(x), read_only, np.arange(x.size - 1, dtype=np.int32), 1, mc)
    survey_path(read_only, y, np.arange(x.size - 1), 0.5, mc, codes)
    sweep_centre_path(x, y, np.arange(x.size - 1), 0.5, mc, False, codes, False)
    path_elements(read_only, y, 0.3, 0.7, mc)
    sec.centre_path(0.5)
    for d, (sigs, misses) in before.items():
        assert len(set(d.signatures) - sigs) <= 1, d.py_func.__name__
        if d is not near_path:  # not the kernel's: compiled on a first run
            assert dict(d.stats.cache_misses) == misses, d.py_func.__name__

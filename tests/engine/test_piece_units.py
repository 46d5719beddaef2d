"""A rock's centre path from the radius-free part made once a batch (every_piece_units)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rockfall_design.engine import Material, Section
from rockfall_design.engine.ensemble import rock_path, rock_path_of
from rockfall_design.engine.profile import every_piece_units
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


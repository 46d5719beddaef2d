"""A run joined from chunks is the run of all its rocks at once, whenever its fields are read.

``EnsembleResult.joined`` joins a per-rock field when it is first read (the
optimiser's looks never read the envelope grid of the runs they go on
from). Whatever is read, in whatever order, before or after further joins,
every field must be bit for bit that of one run of all the rocks.
"""

from __future__ import annotations

import copy
import itertools
import pickle
from dataclasses import fields

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rockfall_design.engine import EnsembleResult, Material, Releases, columns, run_ensemble
from rockfall_design.engine.problem import barrier_table
from tests.engine_helpers import section

N = 48
SLOPE = section([(0, 60), (40, 30), (80, 12), (120, 6), (160, 4)],
                Material(restitution=0.3, friction=0.55, roughness_deg=6.0))
GRID = np.linspace(0.0, 160.0, 33)
STATIONS = np.array([70.0, 130.0])
BARRIERS = np.vstack([barrier_table(100.0, 2.0, 400e3, columns.B_NET)])


def _releases(n: int) -> Releases:
    rng = np.random.default_rng(7)  # the rocks' releases only; the engine's key is below
    return Releases(radius=rng.uniform(0.2, 0.6, n), density=2650.0,
                    x=rng.uniform(1.0, 30.0, n), height=np.full(n, 0.5),
                    vx=rng.uniform(0.0, 3.0, n), vy=np.zeros(n), spin=np.zeros(n),
                    spin_rolling=np.zeros(n, bool), zone=np.zeros(n, np.int64))


def _rows(rel: Releases, lo: int, hi: int) -> Releases:
    out = {f.name: getattr(rel, f.name) for f in fields(rel)}
    return Releases(**{k: v if np.ndim(v) == 0 else np.asarray(v)[lo:hi]
                       for k, v in out.items()})


def _run(rel: Releases, first: int = 0) -> EnsembleResult:
    return run_ensemble(SLOPE, rel, key=12345, stations=STATIONS, grid=GRID,
                        barriers=BARRIERS, record_speed=True, first_index=first,
                        n_trajectories=2)


RELEASES = _releases(N)
WHOLE = _run(RELEASES)
ROW_FIELDS = [f.name for f in fields(EnsembleResult) if f.name not in EnsembleResult._SHARED]


def _same(a: EnsembleResult, b: EnsembleResult) -> None:
    for name in ROW_FIELDS + ["stations", "grid", "restart_x"]:
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and x.shape == y.shape, name
        np.testing.assert_array_equal(x, y, err_msg=name)


@settings(max_examples=12, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(cuts=st.lists(st.integers(1, N - 1), min_size=1, max_size=4, unique=True),
       reads=st.lists(st.lists(st.sampled_from(ROW_FIELDS), max_size=4), min_size=5,
                      max_size=5))
def test_joined_chunks_are_the_whole_run_whatever_is_read_between(cuts, reads):
    bounds = [0, *sorted(cuts), N]
    chunks = [_run(_rows(RELEASES, lo, hi), lo) for lo, hi in itertools.pairwise(bounds)]
    out = chunks[0]
    for k, more in enumerate(chunks[1:]):
        for name in reads[k]:  # what a look reads before the next one goes on
            np.testing.assert_array_equal(getattr(out, name),
                                          getattr(WHOLE, name)[:out.status.size])
        out = out.joined(more)
    assert out.n == N
    _same(out, WHOLE)
    # The kept paths are the first chunk's (of its first rocks: as the whole run's).
    assert len(out.trajectories) == min(2, bounds[1])


def test_a_field_read_twice_is_joined_once_and_stays():
    a = _run(_rows(RELEASES, 0, 20))
    b = a.joined(_run(_rows(RELEASES, 20, N), 20))
    first = b.grid_height
    assert b.grid_height is first
    np.testing.assert_array_equal(first, WHOLE.grid_height)


def test_joined_runs_of_other_stations_are_refused():
    a = _run(_rows(RELEASES, 0, 10))
    other = run_ensemble(SLOPE, _rows(RELEASES, 10, 20), key=12345, stations=[50.0],
                         grid=GRID, barriers=BARRIERS, first_index=10)
    with pytest.raises(ValueError, match="differ in stations"):
        a.joined(other)


def test_an_unknown_attribute_is_still_an_attribute_error():
    b = _run(_rows(RELEASES, 0, 10)).joined(_run(_rows(RELEASES, 10, 20), 10))
    with pytest.raises(AttributeError, match="no_such_field"):
        _ = b.no_such_field
    assert not hasattr(b, "no_such_field")


def test_a_copy_or_a_pickle_of_a_joined_run_reads_alike():
    b = _run(_rows(RELEASES, 0, 25)).joined(_run(_rows(RELEASES, 25, N), 25))
    c = copy.copy(b)
    np.testing.assert_array_equal(c.grid_height, WHOLE.grid_height)  # joined in the copy
    np.testing.assert_array_equal(b.grid_height, WHOLE.grid_height)  # and still in b
    _same(pickle.loads(pickle.dumps(b)), WHOLE)
    _same(copy.deepcopy(b), WHOLE)

"""Which placements of a level the search screens when there are more than its cap
(optimiser.search: MAX_SCREENS_PER_LEVEL, ``_capped``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rockfall_design.judge.design_spec import resolve_design
from rockfall_design.judge.placing import PlacedMeasure, build_concept
from rockfall_design.optimiser import Screening, search
from rockfall_design.optimiser.search import BarrierSlots
from rockfall_design.project import load_project

PROJECTS = Path(__file__).resolve().parents[2] / "projects"


def test_what_the_search_counts_as_reaching_with_one_barrier_is_the_screenings(registry):
    """For one barrier ``BarrierSlots.reaching`` and its first barrier's point checks are
    exactly what the screening asks of a design on the point values of the search rocks:
    the cap can then tell, before screening, which placements may hold."""
    project = load_project(PROJECTS / "design_two_zones.yaml")
    spec = resolve_design(project, registry)
    concept = build_concept(project, registry)
    screen = Screening(project, registry, spec, concept, rocks=1500, seed=14)
    slots = BarrierSlots(screen)
    opts = slots.of(1)
    ks = np.random.default_rng(3).choice(len(opts), size=60, replace=False)
    rows = slots.reaching(1, ks, screen.bare, 0)
    holds = slots.first_holds(1, ks, screen.bare, 0)
    for k, row, first in zip(ks, rows, holds, strict=True):
        o = opts[k]
        sr = screen.screen_placed([PlacedMeasure(0, o.measure, o.footprint, o.label)],
                                  screen.bare, o.cost)
        assert int(row.sum()) == sr.residual
        assert sr.point_ok == (bool(first) and sr.residual <= screen.allowed_residual)


class _Slots:
    """Options of one barrier, each letting ``reach[k]`` of the rocks reach the zone."""

    def __init__(self, reach: list[int], n: int) -> None:
        self.rows = np.zeros((len(reach), n), dtype=np.float32)
        for k, r in enumerate(reach):
            self.rows[k, :r] = 1.0

    def reaching(self, ci, ks, table, table_id):
        return self.rows[ks]


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 12), st.booleans()), min_size=1, max_size=30),
       st.integers(1, 10), st.integers(0, 6))
def test_no_placement_that_may_hold_is_dropped_for_one_that_may_not(options, cap, allowed):
    """Ranked by rocks through for sure (``order``), the first ``cap`` of a level may all be
    placements that do not hold on the search rocks while one that does comes later
    (design_two_zones at seed 14: the 339,000 RX-500 at x = 137 m, past the 80th)."""
    n = 12
    reach = [r for r, _ in options]
    first = np.array([h for _, h in options])
    slots = _Slots(reach, n)
    screen = type("S", (), {"n": n, "allowed_residual": allowed})()
    order = np.random.default_rng(len(options)).permutation(len(options))
    old = search.MAX_SCREENS_PER_LEVEL
    search.MAX_SCREENS_PER_LEVEL = cap
    try:
        kept = search._capped(screen, slots, [0], [np.arange(len(options))],
                              np.ones(len(options), dtype=bool), first, order, None, 0)
    finally:
        search.MAX_SCREENS_PER_LEVEL = old
    may = first & (np.array(reach) <= allowed)
    assert len(kept) == min(cap, len(options))
    dropped = np.setdiff1d(order, kept)
    if dropped.size and may[dropped].any():
        assert may[kept].all()
    # Within each part the given order is kept.
    for part in (may[kept], ~may[kept]):
        sub = [k for k, p in zip(kept, part, strict=True) if p]
        assert sub == [k for k in order if k in set(sub)]

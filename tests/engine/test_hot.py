"""The rock's event loop is compiled without reference counting (``jit.hot``)."""

from __future__ import annotations

import numpy as np
import pytest

from rockfall_design.engine import jit
from rockfall_design.engine.barriers import barrier_hit, meet_barrier
from rockfall_design.engine.contact import start_from_rest
from rockfall_design.engine.flight import locate, next_landing, path_height
from rockfall_design.engine.impact import collide, draw_contact, impact
from rockfall_design.engine.recording import record_passage, record_restart
from rockfall_design.engine.rock import simulate_rock


@pytest.mark.parametrize("fn", [simulate_rock, collide, draw_contact, impact, next_landing, locate,
                                path_height, start_from_rest, barrier_hit, meet_barrier,
                                record_passage, record_restart])
def test_the_event_loop_counts_no_references(fn):
    # Every function the loop calls per event takes arrays: each one counted
    # would be two atomic operations per array and call (see jit.hot).
    assert fn.targetoptions.get("_nrt") is False


def test_a_hot_function_cannot_allocate():
    # The rule of a hot function (it only touches arrays its caller holds)
    # is enforced by numba, at compile time.
    import numba

    def allocates(n):
        return np.empty(n).sum()

    with pytest.raises(numba.core.errors.TypingError):
        jit.hot(allocates)(3)

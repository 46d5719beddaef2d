"""The rock's event loop is compiled without reference counting (``_jit.hot``)."""

from __future__ import annotations

import numpy as np
import pytest

from rockfall_design.engine import _jit
from rockfall_design.engine.barriers import _barrier_hit, _meet
from rockfall_design.engine.contact import _start_from_rest
from rockfall_design.engine.flight import locate, next_landing, path_height
from rockfall_design.engine.impact import _collide, _draw, impact
from rockfall_design.engine.recording import _record, _record_restart
from rockfall_design.engine.rock import simulate_rock


@pytest.mark.parametrize("fn", [simulate_rock, _collide, _draw, impact, next_landing, locate,
                                path_height, _start_from_rest, _barrier_hit, _meet, _record,
                                _record_restart])
def test_the_event_loop_counts_no_references(fn):
    # Every function the loop calls per event takes arrays: each one counted
    # would be two atomic operations per array and call (see _jit.hot).
    assert fn.targetoptions.get("_nrt") is False


def test_a_hot_function_cannot_allocate():
    # The rule of a hot function (it only touches arrays its caller holds)
    # is enforced by numba, at compile time.
    import numba

    def allocates(n):
        return np.empty(n).sum()

    with pytest.raises(numba.core.errors.TypingError):
        _jit.hot(allocates)(3)

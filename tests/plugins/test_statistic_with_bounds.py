"""A statistic and its two bounds from one partial sort are the three asked one by one.

``statistic_with_bounds`` serves the built-in limit-state checks (design
energy and height), which the optimiser calls tens of thousands of times:
it must give the very numbers of :func:`percentile`,
:func:`statistic_lower_bound` and :func:`statistic_upper_bound`, bit for
bit, or the optimiser's answers would move.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from rockfall_design_builtins.safety.shared import (
    percentile,
    percentile_label,
    statistic_lower_bound,
    statistic_upper_bound,
    statistic_with_bounds,
)

PERCENTS = st.one_of(st.sampled_from([50.0, 90.0, 95.0, 97.5, 99.0, 99.9, 100.0]),
                     st.floats(1.0, 100.0, allow_nan=False))


def _one_by_one(v: np.ndarray, statistic: str, confidence: float,
                percent: float) -> tuple[float, float | None, float | None]:
    return (percentile(v, percent), statistic_lower_bound(v, statistic, confidence),
            statistic_upper_bound(v, statistic, confidence))


def _bits(x: float | None) -> bytes | None:
    return None if x is None else np.float64(x).tobytes()


@settings(max_examples=300, deadline=None)
@given(n=st.integers(1, 3000), percent=PERCENTS, confidence=st.sampled_from([0.5, 0.9, 0.95,
                                                                              0.99, 0.999]),
       seed=st.integers(0, 2**32 - 1), ties=st.booleans(), own=st.booleans())
def test_one_partial_sort_gives_the_three_numbers_bit_for_bit(n, percent, confidence, seed,
                                                               ties, own):
    rng = np.random.default_rng(seed)
    v = rng.lognormal(1.0, 0.8, n)
    if ties:  # heights and masses repeat: many equal values
        v = np.round(v, 1)
    statistic = percentile_label(percent)
    # The checks take the percentile of the parameter itself, its bounds of the label.
    point_of = percent if own else float(statistic[1:])
    got = statistic_with_bounds(v, statistic, confidence, percent if own else None)
    want = _one_by_one(v, statistic, confidence, point_of)
    assert [_bits(x) for x in got] == [_bits(x) for x in want]


def test_a_percentile_whose_rank_is_not_the_quantiles_is_still_percentiles():
    # (n - 1) * 95 / 100 and (n - 1) * 0.95 differ in the last bit for some n:
    # there the point comes from percentile's own rank.
    differ = [n for n in range(2, 5000) if (n - 1) * 95.0 / 100.0 != (n - 1) * 0.95]
    assert differ  # the case exists
    v = np.random.default_rng(3).normal(10.0, 2.0, differ[0])
    got = statistic_with_bounds(v, "p95", 0.95)
    assert _bits(got[0]) == _bits(percentile(v, 95.0))

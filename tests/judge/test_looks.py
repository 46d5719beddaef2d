"""A look's values for the report (rockfall_design.judge.looks): JSON whatever the bounds, and
the rocks that would decide a design never fewer than the look already had."""

from __future__ import annotations

import json
import math

from hypothesis import given, settings
from hypothesis import strategies as st

from rockfall_design.judge.looks import look_values, rejections, rocks_to_decide
from rockfall_design.plugins.concept import Check

values = st.one_of(st.none(), st.floats(min_value=0.0, max_value=10.0),
                   st.sampled_from([math.inf, -math.inf, math.nan]))


@settings(deadline=None)  # the first example imports scipy's special functions
@given(value=values, bound=values, optimistic=values,
       target=st.floats(min_value=0.1, max_value=5.0),
       n=st.integers(min_value=1, max_value=100_000),
       reaching=st.one_of(st.none(), st.integers(min_value=0, max_value=100)),
       allowed=st.floats(min_value=1e-4, max_value=0.1))
def test_a_looks_values_are_json_and_more_rocks_than_it_had_decide_it(
        value, bound, optimistic, target, n, reaching, allowed):
    reaching = None if reaching is None else min(reaching, n)
    c = Check(name="height", value=value, target=target, ok=False, bound=bound,
              optimistic=optimistic)
    v = look_values([[c]], ["fence"], reaching, n, allowed, 0.95)
    out = v.to_json()
    json.dumps(out, allow_nan=False)  # no infinity, no NaN: JSON as the report writes it
    assert set(out) == {"rocks", "confidence", "checks", "residual"}
    assert list(out["checks"][0]) == ["measure", "name", "value", "bound", "optimistic",
                                      "target", "unit"]
    assert (out["residual"] is None) is (reaching is None)
    need = rocks_to_decide(v)
    assert need is None or need > n
    assert rejections([[c]], ["fence"], reaching, n, allowed, 0.95)  # never empty


def test_a_residual_whose_bounds_straddle_the_allowance_needs_more_rocks():
    """12 of 9,206 rocks (0.13 %) against 0.1 % allowed: the upper bound is above it and the
    lower one below, so about n (w / d)**2 rocks, more than 9,206, would decide it."""
    v = look_values([], [], 12, 9206, 0.001, 0.95)
    r = v.residual
    assert r is not None and r.lower <= r.allowed < r.upper
    need = rocks_to_decide(v)
    w = max(r.upper - r.fraction, r.fraction - r.lower)
    assert need == math.ceil(9206 * (w / abs(r.fraction - r.allowed)) ** 2) > 9206

"""A look's values for the report (rockfall_design.judge.looks): JSON whatever the bounds, and
the rocks that would decide a design never fewer than the look already had."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rockfall_design.judge.looks import (
    beyond_rocks,
    look_values,
    rejections,
    rocks_to_decide,
)
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


@pytest.mark.parametrize("value, bound, optimistic, target, decided", [
    # An upper limit (value <= target): 606.6 kJ against 500, its bounds 807 and 497:
    # fails at its point value, undecided (the optimistic bound is below the target).
    (606.6, 807.2, 497.0, 500.0, False),
    (606.6, 807.2, 503.0, 500.0, True),   # fails with confidence
    (450.0, 480.0, 420.0, 500.0, True),   # holds with confidence
    (450.0, 520.0, 420.0, 500.0, False),  # holds at its point value only
    # A lower limit (value >= target): the pessimistic bound is the lower one.
    (2.4, 1.9, 2.8, 2.0, False),
    (1.7, 1.5, 2.1, 2.0, False),
    (1.7, 1.5, 1.9, 2.0, True),
])
def test_a_check_is_undecided_whichever_way_it_runs_while_its_bounds_straddle_the_target(
        value, bound, optimistic, target, decided):
    """rocks_to_decide named a check that failed at its point value (606.6 kJ against a
    limit of 500) "on the target" because it read the bounds as if every check were a
    lower limit: the bounds' side of the target, not the check's direction, decides."""
    c = Check(name="energy", value=value, target=target, ok=False, bound=bound,
              optimistic=optimistic)
    need = rocks_to_decide(look_values([[c]], ["fence"], None, 1000, None, 0.95))
    if decided:
        assert need is None
    else:
        far = min(bound, optimistic) if value > target else max(bound, optimistic)
        w, d = abs(value - far), abs(value - target)
        assert need == math.ceil(1000 * (w / d) ** 2) or (need is None and w <= d)


def _look(value, bound, optimistic, target, limits, n=21_184):
    c = Check(name="design_energy", value=value, target=target, ok=value <= target,
              unit="kJ", bound=bound, optimistic=optimistic, limits=limits)
    return look_values([[c]], ["fence RX-050"], None, n, None, 0.995)


def test_a_bound_the_rocks_cannot_narrow_decides_the_rocks_to_decide():
    """design_quarry's RX-050 fence: design energy 606.6 kJ against 500, its optimistic
    bound 497 kJ. The rocks' part of the bound shrinks as 1/sqrt(n), the design block's
    survey part (limits: 0.82 and 1.33 times the point value) does not: with the survey's
    lower end at 498.9 kJ no number of rocks decides it; at 501.4 kJ about n (w / d)^2,
    d the 1.4 kJ from the end to the target, not the 106.6 from the value."""
    stuck = _look(606.6, 807.2, 497.0, 500.0, (498.9, 808.0))
    assert rocks_to_decide(stuck) is None
    assert "any number of rocks" in beyond_rocks(stuck)
    slow = _look(606.6, 807.2, 497.0, 500.0, (501.4, 808.0))
    assert rocks_to_decide(slow) == math.ceil(21_184 * ((501.4 - 497.0) / 1.4) ** 2)
    assert beyond_rocks(slow) is None
    plain = _look(606.6, 807.2, 497.0, 500.0, None)  # no limits: the bounds close on 606.6
    assert rocks_to_decide(plain) == math.ceil(21_184 * ((606.6 - 497.0) / 106.6) ** 2)
    assert plain.to_json()["checks"][0].keys() == {
        "measure", "name", "value", "bound", "optimistic", "target", "unit"}
    assert stuck.to_json()["checks"][0]["limits"] == [498.9, 808.0]


def test_a_fractile_scaled_by_a_survey_gives_the_limits_of_its_bounds():
    from rockfall_design_builtins.safety.limit_states import fractile_check

    rng = np.random.default_rng(5)
    values = rng.lognormal(5.0, 0.4, 30_000)
    plain = fractile_check("design_energy", values, 0.0, 500.0, "MEL", "kJ", 1.1, "gamma_F",
                           0.995)
    scaled = fractile_check("design_energy", values, 0.0, 500.0, "MEL", "kJ", 1.1, "gamma_F",
                            0.995, scale=(0.8, 1.3))
    assert plain.limits is None and "limits" not in plain.as_dict()
    lo, hi = scaled.limits
    assert lo == pytest.approx(0.8 * scaled.value) and hi == pytest.approx(1.3 * scaled.value)
    assert scaled.optimistic < lo < scaled.value < hi < scaled.bound


def test_a_listed_design_no_budget_decides_says_what_holds_it_back():
    from rockfall_design.optimiser.alternatives import Listed
    from rockfall_design.report.listed import what_decides

    stuck = _look(606.6, 807.2, 497.0, 500.0, (498.9, 808.0))
    m = Listed(family="fence", measures=[], labels=["fence RX-050"],
               cost=78_000.0, rocks=stuck.rocks, values=stuck, reason="marginal", decided=True)
    assert "any number of rocks" in what_decides(m) and "design_energy" in what_decides(m)


def test_a_design_not_decided_on_the_search_rocks_is_reckoned_without_its_limits():
    """On the search's few thousand rocks a point value is too rough for its limits (design
    quarry's RX-100 fences showed an upper end of 1,002-1,012 kJ against 1,000 at 5,296 and
    10,592 rocks, and held at 813 kJ on 643,884): a design the budget left undecided gets the
    plain 1/sqrt(n) reckoning, never 'no number of rocks'."""
    from rockfall_design.optimiser.alternatives import Listed
    from rockfall_design.report.listed import what_decides

    stuck = _look(606.6, 807.2, 497.0, 500.0, (498.9, 808.0), n=5_296)
    m = Listed(family="fence", measures=[], labels=["fence RX-050"], cost=78_000.0,
               rocks=stuck.rocks, values=stuck, reason="not decided", decided=False)
    assert m.rocks_to_decide == math.ceil(5_296 * ((606.6 - 497.0) / 106.6) ** 2)
    assert "any number of rocks" not in what_decides(m)
    assert "rocks would decide it" in what_decides(m)

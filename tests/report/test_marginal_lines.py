"""The terminal's line for a marginal or undecided cheaper design (report.terminal)."""

from rockfall_design.report.terminal import _marginal_values


def _design(bound, optimistic, value=0.66):
    check = {"name": "reach_factor", "value": value, "bound": bound, "optimistic": optimistic,
             "target": 1.0, "unit": "-"}
    return {"values": {"rocks": 4603, "confidence": 0.99, "checks": [check], "residual": None}}


def test_both_ends_read_as_a_range():
    assert "reach_factor 0.95 (0.90 to 1.04)" in _marginal_values(_design(0.90, 1.04, 0.95))


def test_one_end_is_not_shown_as_a_range_of_one_value():
    # Too few rocks at a ditch for an upper bound of its p95 reach: only the
    # optimistic end exists. It once read "0.66 (1.12 to 1.12)".
    line = _marginal_values(_design(None, 1.12))
    assert "1.12 to 1.12" not in line
    assert "reach_factor 0.66 (at best 1.12; too few rocks to bound it the other way)" in line
    assert "(with confidence 0.90)" in _marginal_values(_design(0.90, None, 0.95))
    assert "reach_factor 0.66, target" in _marginal_values(_design(None, None))

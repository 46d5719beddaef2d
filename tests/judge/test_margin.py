"""The checker's margin (rockfall_design.judge.margin): a look admits a design only when a
checker's check of its own rocks would confirm it with the chance asked for, and the two
errors of that decision stay within the look's share.

Every check comes down to a binomial count (rocks beyond a percentile check's limit, rocks
reaching the protected zone), so the chances below are exact binomial sums, not simulations.
"""

from __future__ import annotations

import math

import pytest
from scipy.special import bdtr

from rockfall_design.judge.bounds import fraction_upper_bound, quantile_upper_index
from rockfall_design.judge.margin import CheckerMargin, residual_rate


def _passes_below(n: int, q_level: float, confidence: float) -> int:
    """Most rocks beyond the limit with which the upper bound of the q_level-quantile of n
    values is still within it (the bound is x_(k), k 0-based: n - k - 1 values above it)."""
    k = quantile_upper_index(n, q_level, confidence)
    return -1 if k is None else n - k - 1


def _percentile_threshold(n: int, q_level: float, confidence: float, lower: bool) -> int:
    """As _passes_below for the upper bound; for the lower bound (lower=True): fewest
    rocks beyond the limit with which the lower bound is beyond it too."""
    if not lower:
        return _passes_below(n, q_level, confidence)
    from rockfall_design.judge.bounds import quantile_lower_index

    r = quantile_lower_index(n, q_level, confidence)
    return n + 1 if r is None else n - r


def _rate_at_power(n_c: int, m_c: int, power: float) -> float:
    """The rate at which Binomial(n_c, q) <= m_c with chance ``power`` (bisection)."""
    lo, hi = 0.0, 1.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if bdtr(m_c, n_c, mid) >= power:
            lo = mid
        else:
            hi = mid
    return lo


@pytest.mark.parametrize("q_level", [0.95, 0.99])
@pytest.mark.parametrize(("met", "look_c"), [(4_000, 0.99), (20_000, 0.99), (40_000, 0.98)])
@pytest.mark.parametrize("power", [0.8, 0.9, 0.95])
def test_a_percentile_check_admits_a_design_without_the_margin_rarely(q_level, met, look_c,
                                                                      power):
    """At the rate where the checker's check (twice the rocks, at 95 %) confirms the design
    with chance exactly ``power`` - the worst design the margin must keep out - the look
    admits it with at most its share of the error, and rejects a design right at the margin
    for being short of it with at most that share (the normal approximation the margin uses
    for percentiles, held to within a tenth of the share on these sizes: 0.27 to 1.04 of it)."""
    c = 0.95
    n_c = 2 * met
    m_c = _passes_below(n_c, q_level, c)
    q_p = _rate_at_power(n_c, m_c, power)
    margin = CheckerMargin(c, power).at_look(look_c, met, n_c, None)
    admit_at = _passes_below(met, q_level, margin.admit)
    assert admit_at >= 0
    alpha = 1.0 - look_c
    # admitted although a checker confirms it only with chance `power` (or less, above q_p)
    assert bdtr(admit_at, met, q_p) <= 1.1 * alpha
    # short of the margin although a checker confirms it with chance `power`
    short_from = (_passes_below(met, q_level, margin.short) + 1 if margin.short_pessimistic
                  else _percentile_threshold(met, q_level, margin.short, lower=True))
    assert 1.0 - bdtr(short_from - 1, met, q_p) <= 1.1 * alpha
    # and the margin is a margin: the look's limit is inside the checker's own
    assert admit_at / met < m_c / n_c < (1 - q_level)


@pytest.mark.parametrize("allowed", [0.001, 0.002, 0.01])
@pytest.mark.parametrize("n_c", [6_000, 20_000, 100_000])
@pytest.mark.parametrize("power", [0.5, 0.9, 0.99])
def test_the_residual_rate_is_exact(allowed, n_c, power):
    """q_p: the checker's check of n_c rocks (Clopper-Pearson at 95 %) confirms the residual
    with chance ``power`` at that rate, and the count it confirms is the largest."""
    q_p = residual_rate(allowed, n_c, 0.95, power)
    r = 0
    while fraction_upper_bound(r + 1, n_c, 0.95) <= allowed:
        r += 1
    assert fraction_upper_bound(r, n_c, 0.95) <= allowed
    assert math.isclose(bdtr(r, n_c, q_p), power, rel_tol=1e-9)
    assert q_p < allowed


def test_no_residual_rate_when_the_check_could_never_confirm():
    """With too few checker rocks to show the allowed fraction even with none reaching."""
    assert residual_rate(0.001, 1_000, 0.95, 0.9) == 0.0
    assert residual_rate(0.0, 100_000, 0.95, 0.9) == 0.0


def test_the_margin_grows_with_the_look_and_stays_a_confidence():
    """Bounds of later looks (more rocks than the checker's) are at higher confidences, never
    at 1 (which no bound has)."""
    m = CheckerMargin(0.95, 0.9)
    admits = [m.at_look(0.99, n, 20_000, 0.001).admit for n in (10_000, 20_000, 80_000,
                                                                   1_000_000)]
    assert admits == sorted(admits) and all(0.99 < a < 1.0 for a in admits)
    with pytest.raises(ValueError, match="power"):
        CheckerMargin(0.95, 1.0)

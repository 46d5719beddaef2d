"""Confidence bounds of design values: closed forms and the PHYSICS reference's figures."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose
from scipy import stats

from rockfall_design import (
    fraction_upper_bound,
    quantile_lower_bound,
    quantile_upper_bound,
    rocks_to_bound_quantile,
    rocks_to_show_fraction,
)
from rockfall_design.judge.bounds import quantile_upper_index


def test_zero_of_n_closed_form():
    # x = 0: 1 - (1 - c)^(1/n)
    for n in (1, 10, 2995, 50_000):
        assert_allclose(fraction_upper_bound(0, n, 0.95), 1 - 0.05 ** (1 / n), rtol=1e-12)


def test_rocks_to_show_residual_published_in_reference():
    # PHYSICS.md: below 0.1 % at c = 0.95 needs at least 2,995 rocks, below 0.05 % 5,990.
    assert rocks_to_show_fraction(0.001, 0.95) == 2995
    assert rocks_to_show_fraction(0.0005, 0.95) == 5990
    assert fraction_upper_bound(0, 2995, 0.95) <= 0.001 < fraction_upper_bound(0, 2994, 0.95)
    assert rocks_to_show_fraction(0.0, 0.95) is None


@pytest.mark.parametrize(("x", "n"), [(0, 100), (1, 3000), (7, 6000), (50, 50), (3, 10)])
def test_clopper_pearson_against_beta(x, n):
    expected = 1.0 if x >= n else stats.beta.ppf(0.95, x + 1, n - x)
    assert_allclose(fraction_upper_bound(x, n, 0.95), expected, rtol=1e-10)


@pytest.mark.parametrize("n", [59, 60, 100, 299, 1000, 3000, 12_345])
@pytest.mark.parametrize("q", [0.5, 0.95, 0.99])
def test_order_statistic_index_against_binomial(n, q):
    k = quantile_upper_index(n, q, 0.95)
    j = int(stats.binom.ppf(0.95, n, q))  # smallest j with cdf(j) >= c
    assert k == (j if j < n else None)


def test_too_few_rocks_to_bound():
    # 1 - q^n >= c: 59 rocks for p95, 299 for p99 at 95 %
    assert rocks_to_bound_quantile(0.95, 0.95) == 59
    assert rocks_to_bound_quantile(0.99, 0.95) == 299
    assert quantile_upper_index(58, 0.95, 0.95) is None
    assert quantile_upper_index(59, 0.95, 0.95) == 58  # the maximum of 59
    assert quantile_upper_bound(np.arange(58.0), 0.95, 0.95) is None


@given(st.lists(st.floats(-1e6, 1e6), min_size=60, max_size=400), st.sampled_from([0.9, 0.95]))
@settings(max_examples=60, deadline=None)
def test_bound_is_an_order_statistic_at_or_above_the_percentile(values, q):
    v = np.asarray(values)
    b = quantile_upper_bound(v, q, 0.95)
    assert b is not None and b in v
    # The bound never lies below the point estimate (type 7 interpolation).
    assert b >= np.percentile(v, 100 * q) - 1e-9 * max(1.0, abs(b))


def test_coverage_of_the_quantile_bound():
    # The bound of p95 from 200 exponential values covers the true p95 at least 95 % of the
    # time (distribution-free): 2,000 repetitions, allowing three binomial sd of slack.
    rng = np.random.default_rng(20261123)
    true = -np.log(0.05)
    hits = sum(quantile_upper_bound(rng.exponential(size=200), 0.95, 0.95) >= true
               for _ in range(2000))
    assert hits / 2000 >= 0.95 - 3 * np.sqrt(0.95 * 0.05 / 2000)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-1e6, 1e6, allow_nan=False), min_size=1, max_size=400),
       st.sampled_from([0.5, 0.9, 0.95, 0.99]), st.sampled_from([0.9, 0.95, 0.99, 0.999]))
def test_quantile_with_bounds_is_the_percentile_and_both_bounds(values, q, confidence):
    """One partial sort gives what numpy.percentile and the two bound functions give."""
    from rockfall_design import quantile_with_bounds

    v = np.array(values)
    value, lower, upper = quantile_with_bounds(v, q, confidence)
    assert value == pytest.approx(float(np.percentile(v, 100 * q)), rel=1e-12, abs=1e-9)
    assert lower == quantile_lower_bound(v, q, confidence)
    assert upper == quantile_upper_bound(v, q, confidence)

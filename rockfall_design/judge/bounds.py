"""One-sided upper confidence bounds of design values.

A design value taken from a Monte Carlo sample is an estimate. The bounds
here say how large the true value may be at confidence ``c``:

* the q-quantile of a sample of n values: the distribution-free bound from
  order statistics, ``x_(k)`` with ``k`` the smallest integer such that
  ``P[Binomial(n, q) <= k - 1] >= c`` (see e.g. Hahn & Meeker, *Statistical
  Intervals*, 1991, ch. 5). If no ``k <= n`` qualifies the sample is too
  small to bound that quantile at ``c``; :func:`rocks_to_bound_quantile`
  says how many values it needs (never the maximum instead);
* a fraction from ``x`` successes of ``n`` trials: the Clopper-Pearson bound,
  the c-quantile of Beta(x + 1, n - x); with ``x = 0`` it is
  ``1 - (1 - c)**(1/n)``.

Only :mod:`scipy.special` is used (the regularised incomplete beta function
and its inverse), which imports in milliseconds, unlike :mod:`scipy.stats`.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

__all__ = [
    "fraction_upper_bound",
    "quantile_upper_bound",
    "quantile_upper_index",
    "rocks_to_bound_quantile",
    "rocks_to_show_fraction",
]


def _check_confidence(confidence: float) -> None:
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must lie in (0, 1), got {confidence!r}")


@lru_cache(maxsize=65536)
def quantile_upper_index(n: int, q: float, confidence: float) -> int | None:
    """Index (0-based) into the sorted sample of the upper bound of its q-quantile.

    Parameters
    ----------
    n : int
        Sample size.
    q : float
        Quantile, 0 < q < 1 (0.95 for p95).
    confidence : float
        One-sided confidence, 0 < c < 1.

    Returns
    -------
    int or None
        ``k - 1`` with ``k`` the smallest integer such that
        ``P[Binomial(n, q) <= k - 1] >= confidence``; None if ``k > n``
        (the sample is too small to bound the quantile).
    """
    _check_confidence(confidence)
    if n <= 0:
        return None
    if not 0.0 < q < 1.0:
        raise ValueError(f"quantile must lie in (0, 1), got {q!r}")
    # scipy.special on first use: every command imports the judgement, and
    # scipy costs a tenth of a second that `simulate` of the bare slope need not pay.
    from scipy.special import bdtr

    # The binomial CDF is increasing in j: bisect for the smallest j with
    # cdf(j) >= c; k - 1 = j. cdf(n) = 1, so j <= n always exists.
    lo, hi = 0, n
    while lo < hi:
        mid = (lo + hi) // 2
        if bdtr(mid, n, q) >= confidence:
            hi = mid
        else:
            lo = mid + 1
    # j = n means P[B <= n - 1] < c: no order statistic of the sample bounds it.
    return lo if lo < n else None


def rocks_to_bound_quantile(q: float, confidence: float) -> int:
    """Smallest sample size whose largest value bounds the q-quantile at ``confidence``.

    ``1 - q**n >= confidence``, i.e. ``n >= log(1 - c) / log(q)`` (59 for
    p95 at 95 %, 299 for p99).
    """
    _check_confidence(confidence)
    return int(math.ceil(math.log1p(-confidence) / math.log(q) - 1e-12))


def quantile_upper_bound(values: np.ndarray, q: float, confidence: float) -> float | None:
    """Distribution-free upper confidence bound of the q-quantile of ``values``.

    Parameters
    ----------
    values : array_like
        The sample (any unit; the bound has the same).
    q : float
        Quantile, 0 < q < 1.
    confidence : float
        One-sided confidence, 0 < c < 1.

    Returns
    -------
    float or None
        The order statistic ``x_(k)`` (see the module docs), or None when the
        sample is too small (:func:`rocks_to_bound_quantile` says how large
        it must be).
    """
    v = np.asarray(values, dtype=float).ravel()
    k = quantile_upper_index(int(v.size), float(q), float(confidence))
    if k is None:
        return None
    return float(np.partition(v, k)[k])


def fraction_upper_bound(x: int, n: int, confidence: float) -> float:
    """Clopper-Pearson one-sided upper confidence bound of a fraction.

    Parameters
    ----------
    x : int
        Rocks counted (e.g. reaching the protected zone).
    n : int
        Rocks run.
    confidence : float
        One-sided confidence, 0 < c < 1.

    Returns
    -------
    float
        The c-quantile of Beta(x + 1, n - x); 1.0 when ``x >= n`` or ``n == 0``.
    """
    _check_confidence(confidence)
    if n <= 0 or x >= n:
        return 1.0
    from scipy.special import betaincinv  # on first use, as in quantile_upper_index

    return float(betaincinv(x + 1, n - x, confidence))


def rocks_to_show_fraction(allowed: float, confidence: float, reaching: int = 0) -> int | None:
    """Fewest rocks with which ``reaching`` rocks bound the fraction below ``allowed``.

    With ``reaching = 0``: ``n >= log(1 - c) / log(1 - allowed)`` (2,995
    rocks show a fraction below 0.1 % at 95 %). None if ``allowed <= 0``
    (no finite sample shows a zero fraction).
    """
    _check_confidence(confidence)
    if allowed <= 0.0:
        return None
    if allowed >= 1.0:
        return max(reaching, 1)
    n = max(reaching + 1, int(math.ceil(math.log1p(-confidence) / math.log1p(-allowed))))
    # Grow geometrically, then bisect: the bound falls as n grows for fixed x.
    hi = n
    while fraction_upper_bound(reaching, hi, confidence) > allowed:
        hi *= 2
    lo = max(reaching + 1, hi // 2)
    while lo < hi:
        mid = (lo + hi) // 2
        if fraction_upper_bound(reaching, mid, confidence) <= allowed:
            hi = mid
        else:
            lo = mid + 1
    return hi

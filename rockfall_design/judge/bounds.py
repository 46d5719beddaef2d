"""One-sided confidence bounds of design values.

A design value taken from a Monte Carlo sample is an estimate. The bounds
here say how large (upper) or how small (lower) the true value may be at
confidence ``c``:

* the q-quantile of a sample of n values: the distribution-free bound from
  order statistics, ``x_(k)`` with ``k`` the smallest integer such that
  ``P[Binomial(n, q) <= k - 1] >= c`` (see e.g. Hahn & Meeker, *Statistical
  Intervals*, 1991, ch. 5). If no ``k <= n`` qualifies the sample is too
  small to bound that quantile at ``c``; :func:`rocks_to_bound_quantile`
  says how many values it needs (never the maximum instead);
* its lower bound, the mirror image: ``x_(r)`` with ``r`` the largest integer
  such that ``P[Binomial(n, q) >= r] >= c``; none if ``(1 - q)**n > 1 - c``;
* a fraction from ``x`` successes of ``n`` trials: the Clopper-Pearson bound,
  the c-quantile of Beta(x + 1, n - x); with ``x = 0`` it is
  ``1 - (1 - c)**(1/n)``; the lower one is the (1 - c)-quantile of
  Beta(x, n - x + 1), 0 for ``x = 0``.

Both quantile bounds hold for any distribution, continuous or not: the
number of values below the true q-quantile is binomial with a probability
of at most q, the number at or below it with at least q. A lower and an
upper bound, each at ``c``, make a two-sided interval at ``2c - 1`` (the
union bound over its two sides).

Only :mod:`scipy.special` is used (the regularised incomplete beta function
and its inverse), which imports in milliseconds, unlike :mod:`scipy.stats`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from functools import lru_cache

import numpy as np

__all__ = [
    "fraction_lower_bound",
    "fraction_upper_bound",
    "quantile_indices",
    "quantile_lower_bound",
    "quantile_lower_index",
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


@lru_cache(maxsize=65536)
def quantile_lower_index(n: int, q: float, confidence: float) -> int | None:
    """Index (0-based) into the sorted sample of the lower bound of its q-quantile.

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
        ``r - 1`` with ``r`` the largest integer such that
        ``P[Binomial(n, q) >= r] >= confidence``; None if even ``r = 1``
        fails (``(1 - q)**n > 1 - confidence``: the sample is too small).
    """
    found = quantile_indices(n, q, (confidence,), "lower")[0]
    return None if found < 0 else int(found)


def quantile_indices(n: int, q: float, confidences: Sequence[float] | np.ndarray,
                     side: str) -> np.ndarray:
    """Indices (0-based) into a sorted sample of its q-quantile's bounds, many at once.

    Parameters
    ----------
    n : int
        Sample size.
    q : float
        Quantile, 0 < q < 1.
    confidences : sequence of float
        One-sided confidences, each 0 < c < 1.
    side : {"lower", "upper"}
        Which bound.

    Returns
    -------
    numpy.ndarray of int64
        Per confidence, the index of :func:`quantile_lower_index` or
        :func:`quantile_upper_index`; -1 where the sample is too small.

    Notes
    -----
    One bisection for all confidences together (``log2(n)`` calls of the
    binomial CDF on arrays), so a ladder of confidences costs little more
    than one. Both sides are "the smallest ``j`` with ``F(j) >= t``" for the
    binomial CDF ``F(j) = P[Binomial(n, q) <= j]``: the upper bound is
    ``x_(j+1)`` for ``t = c`` (0-based index ``j``), the lower one
    ``x_(j)`` for the smallest ``j`` with ``F(j) > 1 - c`` (index ``j - 1``).
    """
    c = np.asarray(confidences, dtype=float).ravel()
    if c.size and not (np.all(c > 0.0) and np.all(c < 1.0)):
        raise ValueError(f"confidence must lie in (0, 1), got {confidences!r}")
    if side not in ("lower", "upper"):
        raise ValueError(f"side must be 'lower' or 'upper', got {side!r}")
    if n <= 0:
        return np.full(c.size, -1, dtype=np.int64)
    if not 0.0 < q < 1.0:
        raise ValueError(f"quantile must lie in (0, 1), got {q!r}")
    from scipy.special import bdtr  # on first use, as in quantile_upper_index

    upper = side == "upper"
    target = c if upper else 1.0 - c
    lo = np.zeros(c.size, dtype=np.int64)
    hi = np.full(c.size, n, dtype=np.int64)  # F(n) = 1: the answer is <= n
    active = lo < hi
    while active.any():
        mid = (lo + hi) // 2
        cdf = bdtr(mid, n, q)
        ok = cdf >= target if upper else cdf > target
        hi = np.where(active & ok, mid, hi)
        lo = np.where(active & ~ok, mid + 1, lo)
        active = lo < hi
    if upper:  # j = n: P[B <= n - 1] < c, no order statistic bounds it
        return np.where(lo < n, lo, -1)
    return lo - 1  # j = 0: (1 - q)**n > 1 - c, -1 says none


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


def quantile_lower_bound(values: np.ndarray, q: float, confidence: float) -> float | None:
    """Distribution-free lower confidence bound of the q-quantile of ``values``.

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
        The order statistic ``x_(r)`` (see the module docs), or None when the
        sample is too small (``(1 - q)**n > 1 - c``).
    """
    v = np.asarray(values, dtype=float).ravel()
    k = quantile_lower_index(int(v.size), float(q), float(confidence))
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


def fraction_lower_bound(x: int, n: int, confidence: float) -> float:
    """Clopper-Pearson one-sided lower confidence bound of a fraction.

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
        The (1 - c)-quantile of Beta(x, n - x + 1); 0.0 when ``x <= 0`` or
        ``n == 0``; ``(1 - c)**(1/n)`` when ``x == n``.
    """
    _check_confidence(confidence)
    if n <= 0 or x <= 0:
        return 0.0
    from scipy.special import betaincinv  # on first use, as in quantile_upper_index

    return float(betaincinv(x, n - min(x, n) + 1, 1.0 - confidence))


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

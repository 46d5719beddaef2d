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
    "fraction_bounds",
    "fraction_lower_bound",
    "fraction_upper_bound",
    "quantile_index_table",
    "quantile_indices",
    "quantile_lower_bound",
    "quantile_lower_index",
    "quantile_upper_bound",
    "quantile_upper_index",
    "quantile_with_bounds",
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
    """
    return quantile_index_table([n], [q], confidences, side)[0]


def quantile_index_table(ns: Sequence[int], qs: Sequence[float],
                         confidences: Sequence[float] | np.ndarray, side: str) -> np.ndarray:
    """:func:`quantile_indices` of several samples and quantiles at once.

    Parameters
    ----------
    ns : sequence of int
        Sample size of each row.
    qs : sequence of float
        Quantile of each row, 0 < q < 1.
    confidences : sequence of float
        One-sided confidences, each 0 < c < 1, the same for every row.
    side : {"lower", "upper"}
        Which bound.

    Returns
    -------
    numpy.ndarray of int64, shape (rows, confidences)
        The indices; -1 where a sample is too small.

    Notes
    -----
    Both sides are "the smallest ``j`` with ``F(j) >= t``" for the binomial
    CDF ``F(j) = P[Binomial(n, q) <= j]``: the upper bound is ``x_(j+1)``
    for ``t = c`` (0-based index ``j``), the lower one ``x_(j)`` for the
    smallest ``j`` with ``F(j) > 1 - c`` (index ``j - 1``). F is evaluated
    in one vectorised call on a window of j around the normal approximation
    for every row and confidence together (a few hundred values a row for
    10,000 rocks), then searched; a row whose window misses an answer is
    bisected over all j instead. A scenario of a study bounds each of its
    design values at some thirty confidences (:mod:`~rockfall_design.studies.sensitivity`),
    and a scenario's statistics are timed.
    """
    c = np.asarray(confidences, dtype=float).ravel()
    if c.size and not (np.all(c > 0.0) and np.all(c < 1.0)):
        raise ValueError(f"confidence must lie in (0, 1), got {confidences!r}")
    if side not in ("lower", "upper"):
        raise ValueError(f"side must be 'lower' or 'upper', got {side!r}")
    n_arr = np.asarray(ns, dtype=np.int64).ravel()
    q_arr = np.asarray(qs, dtype=float).ravel()
    if n_arr.shape != q_arr.shape:
        raise ValueError("ns and qs must have one value per row")
    if np.any((n_arr > 0) & ~((q_arr > 0.0) & (q_arr < 1.0))):
        raise ValueError(f"quantile must lie in (0, 1), got {qs!r}")
    out = np.full((n_arr.size, c.size), -1, dtype=np.int64)
    rows = np.nonzero(n_arr > 0)[0]
    if rows.size == 0 or c.size == 0:
        return out
    upper = side == "upper"
    target = c if upper else 1.0 - c
    found = _first_reaching(n_arr[rows], q_arr[rows], target, strict=not upper)
    if upper:  # j = n: P[B <= n - 1] < c, no order statistic bounds it
        out[rows] = np.where(found < n_arr[rows, None], found, -1)
    else:  # j = 0: (1 - q)**n > 1 - c, -1 says none
        out[rows] = found - 1
    return out


def _first_reaching(n: np.ndarray, q: np.ndarray, target: np.ndarray,
                    strict: bool) -> np.ndarray:
    """Per row (n, q) and target t, the smallest j with ``F(j) >= t`` (``> t`` if strict),
    F the Binomial(n, q) CDF, from one window of j per row (see
    :func:`quantile_index_table`); rows whose window misses: bisection."""
    from scipy.special import bdtr, ndtri

    sd = np.sqrt(n * q * (1.0 - q))
    z = ndtri(np.clip(target, 1e-300, 1.0 - 1e-16))
    # half a standard deviation and 4 more of slack for the skew of the binomial
    # (checked below: a window that misses falls back to the bisection)
    start = np.maximum(0, np.floor(n * q + z.min() * sd - 0.5 * sd - 4.0)).astype(np.int64)
    stop = np.minimum(n, np.ceil(n * q + z.max() * sd + 0.5 * sd + 4.0)).astype(np.int64)
    # the rows' windows end to end, for one call of the CDF on all of them
    widths = stop - start + 1
    ends = np.cumsum(widths)
    j = np.arange(int(ends[-1]), dtype=np.int64) - np.repeat(ends - widths - start, widths)
    cdf = bdtr(j, np.repeat(n, widths), np.repeat(q, widths))
    found = np.empty((n.size, target.size), dtype=np.int64)
    for r in range(n.size):  # a handful of rows: the CDF above is the work
        row = cdf[ends[r] - widths[r]:ends[r]]
        at = np.searchsorted(row, target, side="right" if strict else "left")
        first = row[0] > target if strict else row[0] >= target
        missed = (start[r] > 0 and bool(np.any(first))) or bool(np.any(at >= widths[r]))
        if missed or bool(np.any(np.diff(row) < 0)):  # searchsorted needs F to rise
            found[r] = _first_reaching_bisect(int(n[r]), float(q[r]), target, strict)
        else:
            found[r] = start[r] + at
    return found


def _first_reaching_bisect(n: int, q: float, target: np.ndarray, strict: bool) -> np.ndarray:
    """As :func:`_first_reaching`, by bisection over all j in [0, n] (always works)."""
    from scipy.special import bdtr

    lo = np.zeros(target.size, dtype=np.int64)
    hi = np.full(target.size, n, dtype=np.int64)  # F(n) = 1: the answer is <= n
    active = lo < hi
    while active.any():
        mid = (lo + hi) // 2
        cdf = bdtr(mid, n, q)
        ok = cdf > target if strict else cdf >= target
        hi = np.where(active & ok, mid, hi)
        lo = np.where(active & ~ok, mid + 1, lo)
        active = lo < hi
    return lo


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


def quantile_with_bounds(values: np.ndarray, q: float, confidence: float
                         ) -> tuple[float, float | None, float | None]:
    """The q-quantile of ``values`` with its lower and upper confidence bounds, in one pass.

    The same numbers as ``numpy.percentile(values, 100 q)`` (linear, type 7),
    :func:`quantile_lower_bound` and :func:`quantile_upper_bound`, from one
    partial sort around the four order statistics they need: the optimiser
    asks for tens of thousands of them.

    Parameters
    ----------
    values : array_like
        The sample, not empty (any unit; the results have the same).
    q : float
        Quantile, 0 < q < 1.
    confidence : float
        One-sided confidence of each bound, 0 < c < 1.

    Returns
    -------
    value, lower, upper : float, float or None, float or None
        A bound is None when the sample is too small to give it.

    See Also
    --------
    quantile_lower_bound, quantile_upper_bound : the bounds alone.
    """
    v = np.asarray(values, dtype=float).ravel()
    n = int(v.size)
    if n == 0:
        raise ValueError("quantile of an empty sample")
    h = (n - 1) * float(q)
    lo = int(math.floor(h))
    hi = min(lo + 1, n - 1)
    k_up = quantile_upper_index(n, float(q), float(confidence))
    k_low = quantile_lower_index(n, float(q), float(confidence))
    kth = sorted({lo, hi} | {k for k in (k_up, k_low) if k is not None})
    part = np.partition(v, kth)
    value = float(part[lo] + (h - lo) * (part[hi] - part[lo]))
    return (value, None if k_low is None else float(part[k_low]),
            None if k_up is None else float(part[k_up]))


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


def fraction_bounds(x: int, n: int, confidences: Sequence[float] | np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Clopper-Pearson lower and upper bounds of a fraction at many confidences at once.

    Parameters
    ----------
    x : int
        Rocks counted.
    n : int
        Rocks run.
    confidences : sequence of float
        One-sided confidences, each 0 < c < 1.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        Per confidence, :func:`fraction_lower_bound` and
        :func:`fraction_upper_bound` (one call of the inverse beta each side).
    """
    c = np.asarray(confidences, dtype=float).ravel()
    if c.size and not (np.all(c > 0.0) and np.all(c < 1.0)):
        raise ValueError(f"confidence must lie in (0, 1), got {confidences!r}")
    from scipy.special import betaincinv  # on first use, as in quantile_upper_index

    if n <= 0:
        return np.zeros(c.size), np.ones(c.size)
    lower = np.zeros(c.size) if x <= 0 else betaincinv(x, n - min(x, n) + 1, 1.0 - c)
    upper = np.ones(c.size) if x >= n else betaincinv(x + 1, n - x, c)
    return np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)


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

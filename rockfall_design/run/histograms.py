"""Statistics of a large run in bounded memory: histograms that merge.

A run of a million rocks cannot keep every crossing of every station and
envelope point (that is gigabytes); it keeps, per column (a station's
quantity, an envelope point), the count, sum, minimum and maximum of the
values, which are exact, and a histogram from which percentiles are read
with a stated error:

* :class:`LogHistogram` for non-negative quantities over many decades
  (passing height, speed, energy): buckets of constant *relative* width, so
  every percentile is within a relative error ``rel_error`` of the exact
  one (the idea of the DDSketch of Masson, Rim & Lee, 2019).
* :class:`LinearHistogram` for a position on a known interval (where rocks
  stop): buckets of constant width, so every percentile is within half a
  bucket of the exact one.

Counts are integers, so the histograms of chunks add up to the histogram of
the whole run whatever the chunking; only the sums behind the means depend
on the order of the additions (in the last bits).

Percentiles follow ``numpy.percentile``'s default (linear interpolation
between the order statistics around the rank ``q / 100 * (n - 1)``): each
of the two order statistics is replaced by its bucket's representative (by
the exact minimum or maximum at the ends), and the result is clipped to the
exact minimum and maximum.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["LogHistogram", "LinearHistogram"]

# Values added per block (see _Histogram.add).
_BLOCK_VALUES = 1 << 19


class _Histogram:
    """Per-column counts of values in buckets; exact count, sum, min and max."""

    n_buckets: int

    def __init__(self, columns: int) -> None:
        self.columns = int(columns)
        self.counts = np.zeros((self.columns, self.n_buckets), dtype=np.int64)
        self.n = np.zeros(self.columns, dtype=np.int64)
        self.total = np.zeros(self.columns)
        self.min = np.full(self.columns, np.inf)
        self.max = np.full(self.columns, -np.inf)

    # What a subclass defines: which bucket a value falls in, and the value
    # that stands for a bucket.
    def _bucket(self, v: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def _representative(self, b: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    @property
    def nbytes(self) -> int:
        """Memory held by the histogram (bytes)."""
        return int(self.counts.nbytes + 4 * 8 * self.columns)

    #: Peak memory (bytes) of the temporaries of one :meth:`add`, beyond its input.
    ADD_TEMPORARY_BYTES = 16 * 8 * _BLOCK_VALUES

    def add(self, values: np.ndarray, scale: float = 1.0) -> None:
        """Add rows of values, shape (m, columns) or (m,) for one column.

        NaN (no value: the rock did not pass there) and infinities are left
        out. Each value is taken in float64 and divided by ``scale`` (a unit
        change, e.g. 1e3 from J to kJ) block by block, without a full copy.
        """
        v = np.asarray(values)
        if v.ndim == 1:
            v = v[:, None]
        if v.shape[1] != self.columns:
            raise ValueError(f"expected {self.columns} columns, got {v.shape[1]}")
        # A few blocks of rows at a time: the temporaries of one block (about
        # ten arrays of its size) stay small whatever the size of ``values``.
        step = max(1, _BLOCK_VALUES // self.columns)
        for a in range(0, v.shape[0], step):
            block = np.asarray(v[a : a + step], dtype=float)
            self._add_block(block / scale if scale != 1.0 else block)

    def _add_block(self, v: np.ndarray) -> None:
        ok = np.isfinite(v)
        self.n += ok.sum(axis=0)
        self.total += np.where(ok, v, 0.0).sum(axis=0)
        self.min = np.minimum(self.min, np.where(ok, v, np.inf).min(axis=0, initial=np.inf))
        self.max = np.maximum(self.max, np.where(ok, v, -np.inf).max(axis=0, initial=-np.inf))
        rows, cols = np.nonzero(ok)
        if cols.size == 0:
            return
        flat = cols * self.n_buckets + self._bucket(v[rows, cols])
        self.counts += np.bincount(flat, minlength=self.counts.size).reshape(self.counts.shape)

    def mean(self) -> np.ndarray:
        """Mean per column (NaN where no value was added)."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(self.n > 0, self.total / np.maximum(self.n, 1), np.nan)

    def maximum(self) -> np.ndarray:
        """Exact maximum per column (NaN where no value was added)."""
        return np.where(self.n > 0, self.max, np.nan)

    def percentile(self, q: float) -> np.ndarray:
        """The ``q``-th percentile (0..100) per column (NaN where no value was added)."""
        out = np.full(self.columns, np.nan)
        has = self.n > 0
        if not has.any():
            return out
        cum = np.cumsum(self.counts[has], axis=1)
        n = self.n[has]
        rank = q / 100.0 * (n - 1)
        lo = np.floor(rank).astype(np.int64)
        hi = np.minimum(lo + 1, n - 1)
        frac = rank - lo
        # First bucket whose cumulative count exceeds the (0-based) rank.
        b_lo = (cum > lo[:, None]).argmax(axis=1)
        b_hi = (cum > hi[:, None]).argmax(axis=1)
        # An infinite representative stands for "above the range": the maximum.
        v_lo = np.where(np.isinf(r := self._representative(b_lo)), self.max[has], r)
        v_hi = np.where(np.isinf(r := self._representative(b_hi)), self.max[has], r)
        # The extreme order statistics are known exactly.
        v_lo = np.where(lo == 0, self.min[has], v_lo)
        v_hi = np.where(hi == n - 1, self.max[has], v_hi)
        val = v_lo + frac * (v_hi - v_lo)
        out[has] = np.clip(val, self.min[has], self.max[has])
        return out


class LogHistogram(_Histogram):
    """Histogram of non-negative values in buckets of constant relative width.

    Bucket ``j`` holds the values in ``(gamma**(j-1), gamma**j]`` with
    ``gamma = (1 + a) / (1 - a)``, ``a = rel_error``; its representative
    ``2 gamma**j / (gamma + 1)`` is within ``a`` (relative) of every value
    in it. Values up to ``zero`` fall in one bucket represented by 0 (an
    absolute error of at most ``zero``); values above ``top`` in one bucket
    represented by the exact maximum.

    Parameters
    ----------
    columns : int
        Number of independent columns (stations, envelope points).
    rel_error : float
        Relative error of every percentile (-), e.g. 0.002 for 0.2 %.
    zero, top : float
        Values at or below ``zero`` count as 0; above ``top`` as the maximum
        (units of the quantity).
    """

    def __init__(
        self, columns: int, rel_error: float = 0.002, zero: float = 1e-6, top: float = 1e9
    ) -> None:
        if not 0.0 < rel_error < 1.0:
            raise ValueError("rel_error must be in (0, 1)")
        self.rel_error = float(rel_error)
        self.zero, self.top = float(zero), float(top)
        self._lg = math.log((1.0 + rel_error) / (1.0 - rel_error))
        self._j0 = math.ceil(math.log(self.zero) / self._lg)
        j1 = math.ceil(math.log(self.top) / self._lg)
        # [0]: <= zero; [1 .. j1 - j0 + 1]: log buckets; [-1]: above top.
        self.n_buckets = j1 - self._j0 + 3
        super().__init__(columns)

    def _bucket(self, v: np.ndarray) -> np.ndarray:
        b = np.zeros(v.shape, dtype=np.int64)
        mid = (v > self.zero) & (v <= self.top)
        j = np.ceil(np.log(v[mid]) / self._lg).astype(np.int64)
        # Rounding of the logarithm may put a value a hair outside the range.
        b[mid] = np.clip(j - self._j0 + 1, 1, self.n_buckets - 2)
        b[v > self.top] = self.n_buckets - 1
        return b

    def _representative(self, b: np.ndarray) -> np.ndarray:
        gamma = math.exp(self._lg)
        j = b + self._j0 - 1
        rep = 2.0 * np.exp(j * self._lg) / (gamma + 1.0)
        rep = np.where(b == 0, 0.0, rep)
        # percentile() puts the exact maximum in place of the top bucket's inf.
        return np.where(b == self.n_buckets - 1, np.inf, rep)


class LinearHistogram(_Histogram):
    """Histogram of values on ``[lo, hi]`` in ``bins`` buckets of equal width.

    Values outside the interval fall in the end buckets (clipped); every
    percentile of values inside it is within half a bucket width of the
    exact one.

    Parameters
    ----------
    lo, hi : float
        The interval (units of the quantity), ``lo < hi``.
    bins : int
        Number of buckets.
    columns : int
        Number of independent columns.
    """

    def __init__(self, lo: float, hi: float, bins: int, columns: int = 1) -> None:
        if not hi > lo:
            raise ValueError("hi must be greater than lo")
        self.lo, self.hi = float(lo), float(hi)
        self.n_buckets = int(bins)
        self.width = (self.hi - self.lo) / self.n_buckets
        super().__init__(columns)

    def _bucket(self, v: np.ndarray) -> np.ndarray:
        b = np.floor((v - self.lo) / self.width).astype(np.int64)
        return np.clip(b, 0, self.n_buckets - 1)

    def _representative(self, b: np.ndarray) -> np.ndarray:
        return self.lo + (b + 0.5) * self.width

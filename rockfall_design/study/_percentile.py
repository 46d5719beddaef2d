"""The percentile of each column of a table, compiled: a scenario's envelope in O(rocks).

A study keeps, per scenario, the p95 envelopes of passing height and energy
at every envelope station. Sorting the whole table (rocks x stations) for
them cost 12 % of a scenario's run, as much as all its other statistics;
selecting the two order statistics each percentile needs takes a fraction
of that. The numbers are the same, to the bit, as those of the sort (the
same order statistics, the same interpolation, in the same float64
operations; numba does not fuse or reorder them without ``fastmath``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..engine._jit import CACHE


@njit(cache=CACHE, nogil=True)
def column_percentile(values: np.ndarray, q: float) -> np.ndarray:  # pragma: no cover - compiled
    """The ``q``-th percentile (0..100) of each column's finite values; NaN if none.

    Linear interpolation between the order statistics ``lo`` and ``lo + 1``
    at ``(count - 1) q / 100``, numpy's default method.

    Parameters
    ----------
    values : ndarray, shape (rocks, stations)
        A table of float32 or float64 (NaN: the rock did not pass there).
    q : float
        The percentile, 0 to 100.

    Returns
    -------
    ndarray of float64, shape (stations,)
    """
    n, m = values.shape
    out = np.full(m, np.nan)
    buf = np.empty(n, dtype=values.dtype)
    for j in range(m):
        c = 0
        for i in range(n):
            v = values[i, j]
            if np.isfinite(v):
                buf[c] = v
                c += 1
        if c == 0:
            continue
        pos = (c - 1) * (q / 100.0)
        lo = int(np.floor(pos))
        part = np.partition(buf[:c], lo)
        # np.float64, not float(): numba's float() of a float32 stays float32,
        # and the interpolation must be in float64, as numpy's.
        low = np.float64(part[lo])
        # The next order statistic: the least of those the partition left above lo.
        high = np.float64(part[lo + 1:c].min()) if lo + 1 < c else low
        out[j] = low + (high - low) * (pos - lo)
    return out

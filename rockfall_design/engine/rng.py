"""Counter-based random numbers for the compiled engine.

Why not ``np.random.Generator`` inside the hot loop: every rock must own an
independent stream, so that rock *i* meets the same random numbers whatever
the other rocks do and however the ensemble is split into batches (common
random numbers for the optimiser, identical results for identical seeds).
SplitMix64 (Steele, Lea & Flood 2014, "Fast splittable pseudorandom number
generators", OOPSLA) is a counter-based generator: the state is one 64-bit
counter, and each output is a strong bijective mix of the counter. A rock's
stream starts at a counter derived from the run's seed sequence and the rock
index, so streams are reproducible, cheap to create and independent of order.

The state of a stream is a length-1 ``uint64`` array, mutated in place.
"""

from __future__ import annotations

import numpy as np

from .jit import hot

_GAMMA = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_S30 = np.uint64(30)
_S27 = np.uint64(27)
_S31 = np.uint64(31)
_S11 = np.uint64(11)
_TWO_PI = 2.0 * np.pi


@hot
def mix64(z: np.uint64) -> np.uint64:
    """SplitMix64 output function: a bijective avalanche mix of a 64-bit word."""
    z = (z ^ (z >> _S30)) * _M1
    z = (z ^ (z >> _S27)) * _M2
    return z ^ (z >> _S31)


@hot
def stream_start(key: np.uint64, index: np.int64) -> np.uint64:
    """Starting counter of the stream of rock ``index`` for the run key ``key``."""
    return mix64(key ^ mix64(np.uint64(index) * _GAMMA + _GAMMA))


@hot
def next_uniform(state: np.ndarray) -> float:
    """Next draw from U[0, 1) with 53 random bits; advances ``state[0]``."""
    state[0] = state[0] + _GAMMA
    return float(mix64(state[0]) >> _S11) * (1.0 / 9007199254740992.0)


@hot
def next_normal(state: np.ndarray) -> float:
    """Next draw from N(0, 1) by the Box-Muller transform (two uniforms)."""
    u1 = 1.0 - next_uniform(state)  # in (0, 1], so the log is finite
    u2 = next_uniform(state)
    return np.sqrt(-2.0 * np.log(u1)) * np.cos(_TWO_PI * u2)


@hot
def truncated_normal(state: np.ndarray, mean: float, sd: float, lo: float, hi: float) -> float:
    """Draw from N(mean, sd) truncated to [lo, hi] by rejection.

    With ``sd == 0`` the mean itself (clipped) is returned without a draw, so a
    run without scatter uses no random numbers for it. After 64 rejections
    (only possible when the mean lies far outside the interval) the clipped
    mean is returned rather than looping on.
    """
    if sd <= 0.0:
        return min(max(mean, lo), hi)
    for _ in range(64):
        v = mean + sd * next_normal(state)
        if lo <= v <= hi:
            return v
    return min(max(mean, lo), hi)


_FOREST_SALT = np.uint64(0xF0E5751A9D3C0B27)


@hot
def forest_stream(state: np.ndarray) -> None:
    """Start the forest's stream, ``state[1]``, from the rock's stream ``state[0]``.

    The stems a rock meets draw from a stream of their own, a bijective mix
    of the rock's, so that a rock's impacts draw the same numbers with or
    without a forest: its path is the same up to its first stem, which makes
    designs with and without a forest comparable rock by rock (common random
    numbers), and leaves every result without a forest as it was.
    """
    state[1] = mix64(state[0] ^ _FOREST_SALT)


@hot
def next_uniform_in(state: np.ndarray, i: int) -> float:
    """Next draw from U[0, 1) of the stream ``state[i]`` (as :func:`next_uniform`)."""
    state[i] = state[i] + _GAMMA
    return float(mix64(state[i]) >> _S11) * (1.0 / 9007199254740992.0)

"""Which rocks reach a point of the slope: the one rule, for the run and the judge.

A rock reaches ``x`` when its centre got there; a path that ended unresolved
(at the event limit) short of ``x`` counts too, because an unfinished path is
no evidence that the rock would have stopped short. ``simulate`` counts the
rocks reaching the protected zone with it, and the judge
(:mod:`rockfall_design.judge.outcomes`) counts the residual with it.
"""

from __future__ import annotations

import numpy as np

from ..engine.columns import UNRESOLVED


def reaches_protected_zone(max_x: np.ndarray, status: np.ndarray, x: float) -> np.ndarray:
    """Which rocks count as reaching the protected zone at ``x`` (m).

    A rock reaches it when its centre got to ``x``; a path that ended
    unresolved (at the event limit) short of ``x`` counts too, because an
    unfinished path is no evidence that the rock would have stopped short:
    the design is judged on the safe side, and the report says how many.

    Parameters
    ----------
    max_x : ndarray
        Farthest x (m) each rock's centre reached.
    status : ndarray
        Engine status code of each path.
    x : float
        Start of the protected zone (m).

    Returns
    -------
    ndarray of bool
    """
    return (max_x >= x) | (status == UNRESOLVED)


def protected_zone_counts(max_x: np.ndarray, status: np.ndarray, x: float) -> tuple[int, int]:
    """(rocks counted as reaching x, unresolved paths among them that had not reached it)."""
    short = (status == UNRESOLVED) & (max_x < x)
    return int(reaches_protected_zone(max_x, status, x).sum()), int(short.sum())

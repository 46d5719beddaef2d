"""What the engine's records mean, for the result objects that report them.

The engine writes a rock's path as event states (one row per event, columns
``T_*``) and its end as a status code. These functions turn them into what a
report draws or counts: the path of the rock's centre as points, and the
number of rocks per end state by name. The result objects
(:class:`~rockfall_design.run.simulation.SimulationRun` and its streamed twin) use them,
so that figures and tables never read an engine column.
"""

from __future__ import annotations

import numpy as np

from .columns import STATUS_NAMES, T_MODE, T_T, T_VX, T_VY, T_X, T_Y, G

__all__ = ["END_STATES", "centre_points", "end_counts"]

#: The end states of a rock, by name, as :func:`end_counts` gives them.
END_STATES = tuple(name for name in STATUS_NAMES if name != "running")


def centre_points(traj: np.ndarray, pts_per_flight: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """Points along a recorded path of a rock's centre (m).

    Parameters
    ----------
    traj : ndarray, shape (k, n_columns)
        Event states of one rock, as the engine records them.
    pts_per_flight : int
        Points per flight parabola.

    Returns
    -------
    x, y : ndarray
        Positions of the centre (m): each flight sampled along its parabola
        ``x = x0 + vx t``, ``y = y0 + vy t - g t^2 / 2``, each contact phase
        (rolling or sliding along a straight piece) by its two ends.
    """
    xs: list[np.ndarray] = []
    ys: list[np.ndarray] = []
    for i in range(len(traj) - 1):
        a = traj[i]
        if a[T_MODE] == 0:  # flight
            t = np.linspace(0.0, traj[i + 1, T_T] - a[T_T], pts_per_flight)
            xs.append(a[T_X] + a[T_VX] * t)
            ys.append(a[T_Y] + a[T_VY] * t - 0.5 * G * t**2)
        else:
            xs.append(np.array([a[T_X], traj[i + 1, T_X]]))
            ys.append(np.array([a[T_Y], traj[i + 1, T_Y]]))
    if not xs:
        return traj[:, T_X], traj[:, T_Y]
    return np.concatenate(xs), np.concatenate(ys)


def end_counts(counts: np.ndarray) -> dict[str, int]:
    """Rocks per end state by name, from counts indexed by the engine's status codes.

    Returns
    -------
    dict of str to int
        ``stopped``, ``exit_upslope``, ``exit_downslope``, ``unresolved``,
        ``caught`` (every name of :data:`END_STATES`).
    """
    c = np.asarray(counts)
    return {name: int(c[STATUS_NAMES.index(name)]) for name in END_STATES}

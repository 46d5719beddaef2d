"""The records the compiled engine passes around instead of dozens of arrays.

House style: a kernel takes a few well-named records. Each record here
is a named tuple of arrays (numba compiles attribute access on a named tuple
to a field read, so it costs nothing in the loop) or a float64 table with
named columns, built once per run by :func:`rockfall_design.engine.run_ensemble`:

* :class:`Ground`: the section as the batch kernel needs it (vertices and the
  material of each segment, the material table);
* :class:`Path`: the ground as one rock meets it (the centre path of its
  radius, the ground segment under each piece, the materials);
* the release table, one row per rock (columns ``REL_*``);
* :class:`Resume`: per rock, whether and from which state to resume;
* :class:`Stations`: the stations recorded, with the ground height there and
  the rows of the detail records they write to;
* :class:`RockOut`: what one rock writes (station passages, trajectory,
  barrier meetings, restart states);
* :class:`BatchOut`: what a batch of rocks writes, one row per rock.

The barrier table, the material table and the settings vector were already
single arrays with named columns (``engine.columns``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

# Columns of the release table (one row per rock).
REL_R = 0  #: radius (m)
REL_M = 1  #: mass (kg)
REL_X = 2  #: release x of the centre (m)
REL_H = 3  #: clearance above the centre path at release (m); 0 = on the ground
REL_VX = 4  #: initial velocity, x (m/s)
REL_VY = 5  #: initial velocity, y (m/s)
REL_W = 6  #: initial angular velocity (rad/s), ignored if REL_ROLLING
REL_ROLLING = 7  #: 1 = start with the spin of rolling without slip along the ground
N_REL_COLS = 8


class Ground(NamedTuple):
    """The slope section as the batch kernel reads it.

    Attributes
    ----------
    x, y : ndarray of float, shape (V,)
        Ground vertices (m).
    seg_mat : ndarray of int, shape (V - 1,)
        Material row of each segment.
    mats : ndarray of float, shape (n_materials, N_MAT_COLS)
        Material table (columns ``M_*``).
    """

    x: np.ndarray
    y: np.ndarray
    seg_mat: np.ndarray
    mats: np.ndarray


class Path(NamedTuple):
    """The ground as a rock of one radius meets it.

    Attributes
    ----------
    px, py : ndarray of float
        Centre path of the rock's radius (m), see ``profile.centre_path``.
    pseg : ndarray of int
        Ground segment under each piece of the centre path.
    seg_mat : ndarray of int
        Material row of each ground segment.
    mats : ndarray of float, shape (n_materials, N_MAT_COLS)
        Material table (columns ``M_*``).
    tree : ndarray of float
        Highest vertex of the centre path over blocks of vertices
        (``flight.path_tree``), so that a flight finds its landing in
        O(log n) on a survey of n vertices.
    """

    px: np.ndarray
    py: np.ndarray
    pseg: np.ndarray
    seg_mat: np.ndarray
    mats: np.ndarray
    tree: np.ndarray


class Stations(NamedTuple):
    """The stations at which passages are recorded, sorted by x.

    Attributes
    ----------
    x, yg : ndarray of float, shape (S,)
        Station (m) and the ground height there (m).
    user : ndarray of int, shape (S,)
        Row of the detail record (``RockOut.cross``) of each station, or -1
        for an envelope-only station.
    srow : ndarray of int, shape (S,)
        Row of the restart record (``RockOut.srec``) of each station, or -1.
    """

    x: np.ndarray
    yg: np.ndarray
    user: np.ndarray
    srow: np.ndarray


class Resume(NamedTuple):
    """Per rock: whether to resume a path, and where from.

    Attributes
    ----------
    mask : ndarray of bool, shape (N,)
        Resume this rock instead of releasing it.
    states : ndarray of float, shape (N, N_RESTART_COLS)
        The state to resume from (a row of a restart record).
    rngs : ndarray of uint64, shape (N,)
        The rock's random stream there.
    """

    mask: np.ndarray
    states: np.ndarray
    rngs: np.ndarray


class RockOut(NamedTuple):
    """What one rock writes; every array must come in as described.

    Attributes
    ----------
    grid_h, grid_e, grid_v : ndarray of float, shape (S,)
        Passing height (m), total kinetic energy (J) and speed (m/s) at the
        first downslope passage of each station; in as NaN.
    cross : ndarray of float, shape (U, N_CROSS_COLS)
        Detail of the first downslope passage of each user station; in as NaN.
    traj : ndarray of float, shape (T, N_TRAJ_COLS)
        The state at each event (T may be 0 to record nothing).
    bar_out : ndarray of int8, shape (B,)
        Outcome of the first meeting with each barrier (``O_*``); in as ``O_NOT_MET``.
    bar_rec : ndarray of float, shape (B, N_BMEET_COLS)
        Passing height (m), speed (m/s), total kinetic energy (J) and time (s)
        of that first meeting.
    srec : ndarray of float, shape (R, N_RESTART_COLS)
        The rock's full state at the first downslope passage of each restart
        station (columns ``RS_*``); in as NaN.
    srng : ndarray of uint64, shape (R,)
        The rock's random stream there.
    work : ndarray of float, shape (N_WORK,)
        The rock's scratch, any values in: ``work[:WORK_CTX]`` the
        restitution, friction and rolling resistance drawn for the segment it
        is on, ``work[WORK_CTX:WORK_STEM]`` the segment, impacts, events and
        largest x of a restart record, ``work[WORK_STEM:]`` the forest's
        state (``forest.F_*``: where the next stem stands, its material, the
        stems met, whether a stem stopped the rock). The caller allocates it once per batch, so that
        the rock's loop allocates nothing (see ``jit.hot``).
    """

    grid_h: np.ndarray
    grid_e: np.ndarray
    grid_v: np.ndarray
    cross: np.ndarray
    traj: np.ndarray
    bar_out: np.ndarray
    bar_rec: np.ndarray
    srec: np.ndarray
    srng: np.ndarray
    work: np.ndarray


#: ``RockOut.work``: where the context of a restart record starts, and its length.
WORK_CTX = 3
#: ``RockOut.work``: where the forest's state starts (``forest.F_*`` from there).
WORK_STEM = 7
N_WORK = 11


class BatchOut(NamedTuple):
    """What a batch of N rocks writes, one row per rock (the fields of ``EnsembleResult``).

    ``traj`` and ``n_traj`` have rows only for the recorded rocks (the first
    ones); ``grid_v`` has one scratch row when speeds are not kept.
    """

    status: np.ndarray
    x_end: np.ndarray
    y_end: np.ndarray
    n_imp: np.ndarray
    n_ev: np.ndarray
    max_x: np.ndarray
    dur: np.ndarray
    caught_by: np.ndarray
    n_stems: np.ndarray
    forest_stop: np.ndarray
    grid_h: np.ndarray
    grid_e: np.ndarray
    grid_v: np.ndarray
    cross: np.ndarray
    traj: np.ndarray
    n_traj: np.ndarray
    bar_out: np.ndarray
    bar_rec: np.ndarray
    srec: np.ndarray
    srng: np.ndarray

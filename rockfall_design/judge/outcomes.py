"""The one place where a rock counts as held by a measure, and as reaching the protected zone.

Both the exact run (``check``, the optimiser's verification) and the
optimiser's screening hand their per-rock facts to :func:`judge_measures`:

* for a barrier, the outcome of each rock's first meeting (an
  :class:`~rockfall_design.plugins.measure.Outcome` code) and its passing height,
  speed and energy there. The exact run takes them from the engine, which
  applies the barrier while the rock moves; the screening derives them from
  the rock's bare-slope passage with :func:`barrier_outcomes`, the same rule
  as the engine's (``engine.barriers.barrier_hit``: over the top, through a gap,
  beyond the capacity, else caught or returned, in that order);
* for every rock, how its path ended (:class:`RockFates`: farthest x, end x,
  status, mass, radius).

What a rock that met a measure counts as -- held, or not -- and how many
rocks reach the protected zone are decided here and nowhere else:

* a net or a row of blocks holds a rock it caught;
* a rigid barrier holds a rock it returned that stays upslope of it (it does
  not leave the section downslope and its centre never passes the station);
* a profile edit (ditch, berm) holds a rock that came to rest with its
  centre in its catch stretch; it met every rock whose centre reached the
  start of that stretch;
* a rock reaches the protected zone when its centre gets to ``protect.x``,
  or when its path ended unresolved short of it (an unfinished path is no
  evidence that the rock stops short). That rule is a fact of the path, so
  it is written once in the run (:mod:`rockfall_design.run.reach`, which
  ``simulate`` also counts with) and used here, never restated.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

# The engine's outcome codes (columns.O_*, the values of plugins.measure.Outcome)
# as plain ints: numpy compares an array with an IntEnum member several times
# slower (it looks the member up for array protocols on every call), and the
# screening compares millions of times.
from ..engine import columns
from ..engine.columns import EXIT_DOWNSLOPE, STOPPED
from ..plugins.measure import Barrier, BarrierBehaviour, MeasureResult, ProfileEdit
from ..run.reach import protected_zone_counts

if TYPE_CHECKING:  # pragma: no cover
    from .placing import PlacedMeasure

__all__ = [
    "Judgement",
    "RockFates",
    "barrier_outcomes",
    "braking_distances",
    "edit_outcomes",
    "held_by",
    "judge_measures",
]


@dataclass
class RockFates:
    """How every rock's path ended, with the design in place (arrays over the rocks).

    Attributes
    ----------
    max_x : ndarray
        Farthest x (m) the rock's centre reached.
    x_end : ndarray
        x (m) of the centre where the path ended.
    status : ndarray
        Engine status code (``engine.columns.STOPPED``, ``CAUGHT``, ...).
    mass : ndarray
        kg.
    radius : ndarray
        m.
    """

    max_x: np.ndarray
    x_end: np.ndarray
    status: np.ndarray
    mass: np.ndarray
    radius: np.ndarray


@dataclass
class Judgement:
    """What a design did to the rocks.

    Attributes
    ----------
    results : list of MeasureResult
        One per measure, in the order of ``placed``.
    held : list of ndarray of bool
        Per measure, the rocks it holds.
    outcomes : list of ndarray of int8
        Per measure, the outcome code of each rock's first meeting.
    reaching : int
        Rocks counted as reaching the protected zone (0 without one).
    unresolved : int
        Of those, paths that ended unresolved short of it.
    """

    results: list[MeasureResult]
    held: list[np.ndarray]
    outcomes: list[np.ndarray]
    reaching: int
    unresolved: int


def barrier_outcomes(
    fp: Barrier,
    height_m: np.ndarray,
    energy_kj: np.ndarray,
    radius_m: np.ndarray,
    u_gap: np.ndarray,
    alive: np.ndarray,
) -> np.ndarray:
    """Outcome of each rock's first meeting with a barrier, from its passage at the station.

    The engine's rule (``engine.barriers.barrier_hit``), for rocks whose passage
    is known without running them again: a rock whose centre passes above the
    top passes over; a row of blocks lets it through a gap with probability
    ``max(0, gap - 2 r) / spacing``; beyond the capacity it breaks through;
    otherwise a rigid barrier returns it and any other catches it.

    Parameters
    ----------
    fp : Barrier
    height_m : ndarray
        Passing height of each rock's centre above the ground at the station
        (m); NaN where the rock does not cross it.
    energy_kj : ndarray
        Total kinetic energy there (kJ).
    radius_m : ndarray
        m.
    u_gap : ndarray
        One uniform number in [0, 1) per rock for the gap passage. The engine
        draws it from the rock's own stream at the meeting, so for a row of
        blocks screening and exact run agree in distribution, not rock by rock.
    alive : ndarray of bool
        Rocks still moving when they reach the station (not held upslope).

    Returns
    -------
    ndarray of int8
        :class:`~rockfall_design.plugins.measure.Outcome` codes.
    """
    met = alive & np.isfinite(height_m)
    over = met & (height_m > fp.vertical_height_m)
    gap = np.zeros_like(met)
    if fp.behaviour == BarrierBehaviour.BLOCKS:
        p = (fp.gap_m - 2.0 * radius_m) / fp.spacing_m
        gap = met & ~over & (p > 0.0) & (u_gap < p)
    hit = met & ~over & ~gap
    broken = hit & (energy_kj > fp.capacity_kj)
    stopped = hit & ~broken
    out = np.full(height_m.shape, columns.O_NOT_MET, dtype=np.int8)
    out[over] = columns.O_PASSED_OVER
    out[gap] = columns.O_PASSED_THROUGH_GAP
    out[broken] = columns.O_BROKEN_THROUGH
    out[stopped] = (columns.O_REBOUNDED if fp.behaviour == BarrierBehaviour.RIGID
                    else columns.O_CAUGHT)
    return out


def braking_distances(fp: Barrier, energy_kj: np.ndarray) -> np.ndarray:
    """Braking distance (m) of each rock a net catches, from its energy there (kJ).

    The engine's rule (``engine.barriers.braking_distance``) over an array,
    for the optimiser's screening: 0 without an MEL elongation (and for any
    barrier but a net); the MEL elongation for every rock without an SEL
    elongation; else the SEL elongation up to the SEL (a third of the MEL
    where not given), the MEL elongation from the MEL on, linear in the
    energy between the tests (``numpy.interp`` clamps at both ends, which is
    that rule).

    Parameters
    ----------
    fp : Barrier
    energy_kj : ndarray
        Kinetic energy of each rock at the net (kJ).

    Returns
    -------
    ndarray
        m, the shape of ``energy_kj``.
    """
    e = np.asarray(energy_kj, dtype=float)
    d_mel, d_sel = fp.elongation_mel_m, fp.elongation_sel_m
    if fp.behaviour != BarrierBehaviour.NET or not d_mel > 0.0:
        return np.zeros_like(e)
    sel = fp.capacity_kj / 3.0 if np.isnan(fp.sel_kj) else fp.sel_kj
    if not d_sel > 0.0 or not fp.capacity_kj > sel:
        return np.full_like(e, d_mel)
    return np.interp(e, [sel, fp.capacity_kj], [d_sel, d_mel])


def held_by(fp: Barrier | ProfileEdit, outcome: np.ndarray, fates: RockFates) -> np.ndarray:
    """The rocks a measure holds (see the module docs for the rule)."""
    if isinstance(fp, Barrier):
        if fp.behaviour == BarrierBehaviour.RIGID:
            return ((outcome == columns.O_REBOUNDED) & (fates.max_x <= fp.x)
                    & (fates.status != EXIT_DOWNSLOPE))
        return outcome == columns.O_CAUGHT
    return (outcome != columns.O_NOT_MET) & (fates.status == STOPPED) & (
        fates.x_end >= fp.catch_from) & (fates.x_end <= fp.catch_to)


def edit_outcomes(fp: ProfileEdit, fates: RockFates) -> np.ndarray:
    """Outcome codes at a profile edit: met when the centre reached ``catch_from``."""
    met = fates.max_x >= fp.catch_from
    out = np.where(met, columns.O_PASSED_OVER, columns.O_NOT_MET).astype(np.int8)
    inside = (fates.status == STOPPED) & (fates.x_end >= fp.catch_from) & (
        fates.x_end <= fp.catch_to)
    out[met & inside] = columns.O_CAUGHT
    return out


def judge_measures(
    placed: Sequence[PlacedMeasure],
    outcomes: Sequence[np.ndarray | None],
    meetings: Sequence[np.ndarray | None],
    fates: RockFates,
    protect_x: float | None,
) -> Judgement:
    """Judge every measure of a design on one set of rocks.

    Parameters
    ----------
    placed : sequence of PlacedMeasure
    outcomes : sequence
        Per measure: for a barrier the outcome code of each rock's first
        meeting (int8, n); None for a profile edit (derived from ``fates``).
    meetings : sequence
        Per measure: for a barrier the (n, 3) record of the first meeting,
        passing height (m), speed (m/s) and energy (kJ), NaN where not met;
        None for a profile edit.
    fates : RockFates
    protect_x : float or None
        Start of the protected zone (m); also gives each barrier's
        ``clearance_m`` (None: no protected zone, no clearance).

    Returns
    -------
    Judgement
    """
    n = fates.max_x.shape[0]
    results, helds, outs = [], [], []
    for p, out, rec in zip(placed, outcomes, meetings, strict=True):
        fp = p.footprint
        res = MeasureResult(measure=p.measure, index=p.index, n_rocks=n)
        if isinstance(fp, Barrier):
            out = np.asarray(out)
            met = out != columns.O_NOT_MET
            # One pass over the rocks counts every outcome (the codes are 0..5).
            counts = np.bincount(out.astype(np.intp, copy=False), minlength=columns.N_OUTCOMES)
            res.passed_over = int(counts[columns.O_PASSED_OVER])
            res.broken_through = int(counts[columns.O_BROKEN_THROUGH])
            res.rebounded = int(counts[columns.O_REBOUNDED])
            res.passed_through_gap = int(counts[columns.O_PASSED_THROUGH_GAP])
            # Gathered by index: a boolean mask on a column of the (n, 3)
            # record costs about eight times as much (strided, 480 against
            # 60 us on 9,206 rocks), and the optimiser's screening judges
            # thousands of placements.
            rows = np.flatnonzero(met)
            res.passing_height_m = rec[rows, 0]
            res.passing_height_normal_m = res.passing_height_m * fp.slope_cos
            res.height_normal = fp.height_normal
            res.velocity_ms = rec[rows, 1]
            res.energy_kj = rec[rows, 2]
            if protect_x is not None:
                res.clearance_m = float(protect_x - fp.x)
        else:
            out = edit_outcomes(fp, fates)
            met = out != columns.O_NOT_MET
            rows = np.flatnonzero(met)
            res.reach_m = fates.max_x[rows] - fp.catch_from
        held = held_by(fp, out, fates)
        res.met = int(rows.size)
        res.caught = int(np.count_nonzero(held))
        if not isinstance(fp, Barrier):
            res.passed_over = res.met - res.caught
        res.mass_kg = fates.mass[rows]
        res.radius_m = fates.radius[rows]
        results.append(res)
        helds.append(held)
        outs.append(out)
    reaching, unresolved = (0, 0) if protect_x is None else protected_zone_counts(
        fates.max_x, fates.status, protect_x)
    return Judgement(results, helds, outs, reaching, unresolved)

"""The terms of a calibration's objective: one per observation set, summed with weights.

Each observation set (:class:`~.sets.ObservationSet`) adds a term of the
same kind as the stops' (:func:`~.distances.objective`)::

    D = sum over sets  w_i * T_i
    T_i = d(obs_i, sim_i)**2 / L_i  (+ sum over levels (p_obs - p_sim)**2, for stops)

with d the energy (or Wasserstein-1) distance of the observed and simulated
values, L_i the observed values' interquartile range (at least
:data:`~.distances.SPREAD_FLOOR` of the kind), and the simulated values:

- stops: the stop stations of the profile's rocks (a rock that left the
  section at its end);
- passing heights and speeds at a station: the heights (vertical or normal
  to the slope) or speeds the run records for every rock that passes the
  station downslope (its first passage: the analysis stations' records,
  :meth:`~rockfall_design.run.simulation.SimulationRun.crossing_arrays`). The
  observed marks are of blocks that passed, so the simulated values are of
  the rocks that passed too (how many reach the station is the stops'
  business). When no simulated rock passes, the simulated set is one value
  0: no height, no speed there, far from what was observed and nearer it
  as the ground lets rocks through.

Every term is dimensionless and of the order of a squared share, so that
weights of 1 give each set about the same say; a weight says how much
more (or less) a set is trusted.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from .distances import (
    SPREAD_FLOOR,
    FitStatistics,
    LevelShare,
    distance,
    fit_statistics,
    level_shares,
    objective,
    spread,
    verdict,
)

if TYPE_CHECKING:  # pragma: no cover
    from ..project import Project
    from .sets import ObservationSet

__all__ = ["QUANTITY", "ProfileRun", "SetStatistics", "Term", "passage_term", "scales_of",
           "set_statistics", "sets_objective", "terms_for"]

#: The run's record (crossing arrays' key) of each passage kind.
QUANTITY = {("passing_heights", "vertical"): "passing_height_m",
            ("passing_heights", "normal"): "passing_height_normal_m",
            ("speeds", "vertical"): "velocity_ms"}


@dataclass(frozen=True)
class Term:
    """One observation set's term of the objective.

    Attributes
    ----------
    kind : str
        ``stops``, ``passing_heights`` or ``speeds``.
    run : int
        The profile run it is measured on (0: the project's own section).
    station : int or None
        Index of its station in that run's stations (passage kinds).
    quantity : str or None
        The run's record compared (:data:`QUANTITY`).
    weight : float
    levels : dict
        Stops: name -> (from, to) (m).
    """

    kind: str
    run: int = 0
    station: int | None = None
    quantity: str | None = None
    weight: float = 1.0
    levels: dict[str, tuple[float, float]] = field(default_factory=dict)


@dataclass(frozen=True)
class ProfileRun:
    """Another profile of the site, as every evaluation runs it (picklable).

    Attributes
    ----------
    name : str
    project : Project
        The profile's project (validated, the site's materials).
    base : dict
        Its resolved data, the site's materials and the observation stations set.
    x_range : tuple of float
        First and last station of its section (m).
    sizes : dict or None
        The rock size fitted to its observed blocks, as set in ``base``.
    """

    name: str
    project: Project
    base: dict[str, Any]
    x_range: tuple[float, float]
    sizes: dict[str, Any] | None = None


def terms_for(sets: Sequence[ObservationSet], names: Sequence[str]
              ) -> tuple[tuple[Term, ...], list[list[float]]]:
    """The terms of ``sets`` and the stations each run records.

    Parameters
    ----------
    sets
        The observation sets, in order.
    names
        The profiles' names, in run order (run 0, the project's own section, is "").

    Returns
    -------
    (terms, stations)
        One term per set; per run, its observation stations (m), sorted.
    """
    stations: list[list[float]] = [sorted({float(s.station) for s in sets
                                           if s.station is not None and s.profile == name})
                                   for name in names]
    terms = []
    for s in sets:
        run = list(names).index(s.profile)
        if s.kind == "stops":
            terms.append(Term("stops", run, weight=s.weight, levels=dict(s.levels)))
        else:
            terms.append(Term(s.kind, run, stations[run].index(float(s.station)),
                              QUANTITY[(s.kind, s.measured if s.kind != "speeds"
                                        else "vertical")], s.weight))
    return tuple(terms), stations


def passage_term(observed: np.ndarray, simulated: np.ndarray, kind: str = "energy",
                 scale: float = 1.0) -> float:
    """``d(obs, sim)**2 / scale`` of passing heights (m) or speeds (m/s).

    No simulated rock passed: the simulated set is one value 0 (see the
    module's docstring).
    """
    sim = simulated if simulated.size else np.zeros(1)
    d = distance(observed, sim, kind)
    return d * d / scale


def sets_objective(observed: Sequence[np.ndarray], simulated: Sequence[np.ndarray],
                   terms: Sequence[Term], kind: str, scales: Sequence[float]) -> float:
    """The weighted sum of the sets' terms (the module's docstring)."""
    total = 0.0
    for obs, sim, term, scale in zip(observed, simulated, terms, scales, strict=True):
        if term.kind == "stops":
            value = objective(obs, sim, term.levels, kind, scale)
        else:
            value = passage_term(obs, sim, kind, scale)
        total += term.weight * value
    return total


def scales_of(observed: Sequence[np.ndarray], terms: Sequence[Term]) -> list[float]:
    """Each set's L: its observed values' interquartile range, at least the kind's floor."""
    return [spread(obs, SPREAD_FLOOR[t.kind]) for obs, t in zip(observed, terms, strict=True)]


@dataclass(frozen=True)
class SetStatistics:
    """How well one observation set is reproduced (:func:`set_statistics`).

    Attributes
    ----------
    kind : str
        ``stops``, ``passing_heights`` or ``speeds``.
    profile : str or None
        The profile's name; None for the project's own section.
    x : float or None
        The station of a passage (m).
    source : str
        The file the set was read from.
    count : int
        Observed values.
    weight : float
        Its term's weight in the objective (-).
    measured : str or None
        Passing heights: ``vertical`` or ``normal``; None for the other kinds.
    label : str
        The set's name in tables and warnings.
    levels : list of LevelShare
        Stops: each level's shares; empty for a passage.
    fit : FitStatistics or None
        In the set's unit (m, or m/s for speeds); None when no simulated rock
        passed the station.
    passed_share : float or None
        Passages: the share of the simulated rocks that passed the station (-).
    consistent : bool
        The two-sample Kolmogorov-Smirnov test at 5 % and the levels' shares pass.
    verdict : str
        The line that says so (:func:`~.distances.verdict`).
    """

    kind: str
    profile: str | None
    x: float | None
    source: str
    count: int
    weight: float
    measured: str | None
    label: str
    levels: list[LevelShare]
    fit: FitStatistics | None
    passed_share: float | None
    consistent: bool
    verdict: str

    def to_json(self) -> dict[str, Any]:
        """The entry of ``sets`` in ``--json`` (``passed_share`` for a passage only)."""
        out: dict[str, Any] = {
            "kind": self.kind, "profile": self.profile, "x": self.x, "source": self.source,
            "count": self.count, "weight": self.weight, "measured": self.measured,
            "label": self.label, "levels": [ls.as_dict() for ls in self.levels],
            "fit": None if self.fit is None else self.fit.to_json()}
        if self.kind != "stops":
            out["passed_share"] = self.passed_share
        out.update(consistent=self.consistent, verdict=self.verdict)
        return out


def set_statistics(sets: Sequence[ObservationSet], simulated: Sequence[np.ndarray],
                   kind: str, confidence: float, ranges: dict[str, tuple[float, float]],
                   rocks: int) -> list[SetStatistics]:
    """How well each set's simulated values match its observed ones (``--json``'s ``sets``).

    Parameters
    ----------
    sets, simulated
        The observation sets and each one's simulated values.
    kind
        The distance (:func:`~.distances.distance`).
    confidence
        Of the stops' level shares' Wilson intervals.
    ranges
        Profile name ("" the project's own) -> (first, last) station (m).
    rocks
        Simulated rocks per profile (for the share that passed a station).

    Returns
    -------
    list of SetStatistics
        Per set: the fields of :meth:`~.sets.ObservationSet.as_dict`, ``fit``
        (:func:`~.distances.fit_statistics`, in the set's unit: m, or m/s for
        speeds; None when no simulated rock passed the station), ``levels``
        (stops: :func:`~.distances.level_shares`), and for
        passages ``passed_share``: the share of the simulated rocks that
        passed the station; ``consistent`` and ``verdict``
        (:func:`~.distances.verdict`: the two-sample Kolmogorov-Smirnov test
        at 5 %, and the levels' shares).
    """
    out = []
    for s, sim in zip(sets, simulated, strict=True):
        shares: list[LevelShare] = []
        passed = None
        if s.kind == "stops":
            fit = fit_statistics(s.values, sim, kind, ranges[s.profile])
            shares = level_shares(s.values, sim, s.levels, confidence)
        else:
            fit = fit_statistics(s.values, sim, kind) if sim.size else None
            passed = float(sim.size) / max(int(rocks), 1)
        if fit is None:
            consistent, line = False, ("NOT consistent with the observations (no simulated "
                                       f"rock passed x = {s.station:g} m)")
        else:
            consistent, line = verdict(fit, shares, confidence)
        out.append(SetStatistics(
            kind=s.kind, profile=s.profile or None, x=s.station, source=s.source, count=s.n,
            weight=s.weight, measured=s.measured if s.kind == "passing_heights" else None,
            label=s.label, levels=shares, fit=fit, passed_share=passed,
            consistent=consistent, verdict=line))
    return out

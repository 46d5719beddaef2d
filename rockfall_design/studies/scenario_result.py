"""What one scenario of a study found: its run's blocks, its barriers and its bounds.

:class:`ScenarioResult` is what :func:`~.runner.run_scenario` returns for a
scenario (a task's result, picklable: it may come back from a worker or a
Dask cluster); :class:`~.study_result.StudyResult` and
:mod:`~.sensitivity` read it. Its ``to_json`` is the scenario's object in
``study --json``, before the study adds its joint bounds. The blocks of
``simulate --json`` (``stations``, ``stops``, ``protect``) stay as that
command's JSON gives them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["BarrierBlock", "BoundsLadder", "ScenarioBounds", "ScenarioResult"]


@dataclass(frozen=True)
class BarrierBlock:
    """Passing height and energy on the bare slope at one barrier's station.

    Attributes
    ----------
    index : int
        The barrier's index in ``measures``.
    label : str
        Its label (``fence at x=120``).
    x : float
        Its station (m).
    crossings : int
        Rocks that passed the station.
    passing_height_m, energy_kj : dict
        The statistics blocks of ``simulate --json`` at the station (m, kJ).
    """

    index: int
    label: str
    x: float
    crossings: int
    passing_height_m: dict[str, Any]
    energy_kj: dict[str, Any]

    def block(self, quantity: str) -> dict[str, Any]:
        """The statistics block of ``quantity`` (``passing_height_m`` or ``energy_kj``)."""
        return self.passing_height_m if quantity == "passing_height_m" else self.energy_kj

    def to_json(self) -> dict[str, Any]:
        """The entry of a scenario's ``measures`` in ``study --json``."""
        return {"index": self.index, "label": self.label, "x": self.x,
                "crossings": self.crossings, "passing_height_m": self.passing_height_m,
                "energy_kj": self.energy_kj}


@dataclass(frozen=True)
class BoundsLadder:
    """A scenario's bounds at the one-sided confidences the sensitivity may need.

    Attributes
    ----------
    scenarios : list of int
        The numbers of scenarios k the bounds are for (one rung per k).
    lower, upper : dict of str to list
        Design value name -> its bound per rung (its unit; None where too few
        rocks passed), at the one-sided confidence ``1 - (1 - c) / (2k)``.

    See Also
    --------
    rockfall_design.studies.sensitivity.joint_bounds : what reads it.
    """

    scenarios: list[int]
    lower: dict[str, list[float | None]]
    upper: dict[str, list[float | None]]

    def to_json(self) -> dict[str, Any]:
        """``scenarios``, ``upper``, ``lower``."""
        return {"scenarios": self.scenarios, "upper": self.upper, "lower": self.lower}


@dataclass(frozen=True)
class ScenarioBounds:
    """Confidence bounds of a scenario's design values, by name.

    Attributes
    ----------
    confidence : float
        The one-sided confidence c of ``upper`` and ``lower`` (-).
    upper, lower : dict of str to float or None
        Design value name -> its one-sided bound at c (its unit: m, kJ, or a
        fraction); None where too few rocks passed to bound it.
    ladder : BoundsLadder
        The bounds the study's sensitivity needs; left out of ``study --json``.
    """

    confidence: float
    upper: dict[str, float | None]
    lower: dict[str, float | None]
    ladder: BoundsLadder

    def to_json(self, ladder: bool = True, joint: dict[str, Any] | None = None
                ) -> dict[str, Any]:
        """``confidence``, ``upper``, ``lower``, then the ``ladder`` (``ladder`` True)
        and ``joint``, the study's joint bounds of this scenario (if given)."""
        out: dict[str, Any] = {"confidence": self.confidence, "upper": self.upper,
                               "lower": self.lower}
        if ladder:
            out["ladder"] = self.ladder.to_json()
        if joint is not None:
            out["joint"] = joint
        return out


@dataclass(frozen=True)
class ScenarioResult:
    """One scenario's run (:func:`~.runner.run_scenario`).

    Attributes
    ----------
    index, seed : int
        The scenario's index and rock seed.
    rocks, events : int
        Rocks run and their events.
    project_hash : str
        sha256 of the scenario's resolved project.
    stations : list of dict
        ``simulate --json``'s ``stations`` at the project's own stations.
    stops : dict
        ``simulate --json``'s ``stops``.
    bounds : ScenarioBounds
    runtime_s : float
        Wall time of the scenario (s); not part of the study's JSON.
    protect : dict or None
        ``simulate --json``'s ``protect`` (the bare slope), if the project has a zone.
    protect_with_measures : dict or None
        The residual with the project's measures in place, as ``check``
        counts it (``x``, ``reaching``, ``fraction``, ``unresolved``,
        ``measures``); None without measures.
    measures : list of BarrierBlock or None
        Per barrier, its station's blocks on the bare slope; None without barriers.
    envelope : dict or None
        x (m), crossings and the percentile envelopes of height (m) and energy
        (kJ), if the task asked for them.
    """

    index: int
    seed: int
    rocks: int
    events: int
    project_hash: str
    stations: list[dict[str, Any]]
    stops: dict[str, Any]
    bounds: ScenarioBounds
    runtime_s: float = 0.0
    protect: dict[str, Any] | None = None
    protect_with_measures: dict[str, Any] | None = None
    measures: list[BarrierBlock] | None = None
    envelope: dict[str, list[float]] | None = None

    def to_json(self, *, ladder: bool = True, envelope: bool = True, head: bool = True,
                joint: dict[str, Any] | None = None) -> dict[str, Any]:
        """The scenario as a JSON object, in the order of ``study --json``.

        Parameters
        ----------
        ladder
            Keep the bounds' ladder.
        envelope
            Keep the envelope and the run time (which differs between runs).
        head
            Begin with ``index`` and ``seed``.
        joint
            The study's joint bounds of this scenario, added to ``bounds``.
        """
        out: dict[str, Any] = {"index": self.index, "seed": self.seed} if head else {}
        out.update(rocks=self.rocks, events=self.events, project_hash=self.project_hash,
                   stations=self.stations, stops=self.stops)
        if self.protect is not None:
            out["protect"] = self.protect
        if self.protect_with_measures is not None:
            out["protect_with_measures"] = self.protect_with_measures
        if self.measures is not None:
            out["measures"] = [m.to_json() for m in self.measures]
        out["bounds"] = self.bounds.to_json(ladder=ladder, joint=joint)
        if envelope:
            if self.envelope is not None:
                out["envelope"] = self.envelope
            out["runtime_s"] = self.runtime_s
        return out

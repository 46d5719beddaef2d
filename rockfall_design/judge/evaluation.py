"""Design -> simulation -> per-measure outcomes and safety checks.

The measures of a project are resolved to plain objects once, through their
plugins: barriers become rows of the engine's barrier table, profile edits
are spliced into the ground. Then the same rocks as ``simulate`` (same seed,
same draws) run once on the edited section with the barriers in place, and
each measure's :class:`~rockfall_design.plugins.measure.MeasureResult` goes through
the project's safety concept.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..engine import Section, columns
from ..plugins import guard
from ..plugins.concept import Check, SafetyConcept
from ..plugins.manager import plugin_code
from ..plugins.measure import Barrier, MeasureResult, Outcome
from ..run.passages import Passages, barrier_values, property_marks, slope_deg_at
from ..run.releases import section_from_project
from ..run.simulation import SimulationRun, run_in_memory
from .bounds import fraction_lower_bound, fraction_upper_bound
from .outcomes import Judgement, RockFates, judge_measures
from .placing import (
    PlacedMeasure,
    barrier_rows,
    build_concept,
    build_measures,
    edited_section,
    place_measures,
)
from .plan import confidence_of, plan_for
from .records import CheckSummary, MeasureRecord, ProtectRecord

if TYPE_CHECKING:  # pragma: no cover
    from ..plugins import Registry
    from ..plugins.measure import ProtectiveMeasure
    from ..project import Project

__all__ = [
    "Evaluation",
    "PlacedMeasure",
    "build_measures",
    "build_concept",
    "place_measures",
    "edited_section",
    "evaluate",
    "evaluate_design",
    "protect_summary",
    "protect_record",
]


def protect_record(x: float, reaching: int, n: int, allowed: float, confidence: float,
                   unresolved: int = 0) -> ProtectRecord:
    """The rocks reaching a protected zone against what is allowed, as ``check`` reports it.

    Parameters
    ----------
    x : float
        Where the protected zone begins (m).
    reaching, n : int
        Rocks reaching it, of ``n`` rocks.
    allowed : float
        The allowed fraction (-).
    confidence : float
        One-sided confidence of the Clopper-Pearson bounds (-).
    unresolved : int
        Of ``reaching``, rocks whose paths did not finish (counted as reaching).

    Returns
    -------
    ProtectRecord
        The fraction with its Clopper-Pearson ``upper_fraction`` and
        ``lower_fraction``, ``ok`` (the fraction is allowed),
        ``ok_with_confidence`` (its upper bound is) and
        ``fails_with_confidence`` (its lower bound exceeds the allowance).
        :func:`~rockfall_design.judge.verdict.verdict_of` reads it.

    References
    ----------
    Clopper, C. J. and Pearson, E. S. (1934). The use of confidence or fiducial
    limits illustrated in the case of the binomial. Biometrika 26(4), 404-413.
    """
    fraction = reaching / n if n else 0.0
    upper = fraction_upper_bound(reaching, n, confidence)
    lower = fraction_lower_bound(reaching, n, confidence)
    return ProtectRecord(x=float(x), reaching=int(reaching), fraction=fraction,
                         unresolved=int(unresolved), upper_fraction=upper,
                         allowed_fraction=float(allowed), ok=fraction <= allowed,
                         ok_with_confidence=upper <= allowed, lower_fraction=lower,
                         fails_with_confidence=lower > allowed)


def protect_summary(x: float, reaching: int, n: int, allowed: float, confidence: float,
                    unresolved: int = 0) -> dict[str, Any]:
    """:func:`protect_record` as its JSON (``x``, ``reaching``, ``fraction``, ...)."""
    return protect_record(x, reaching, n, allowed, confidence, unresolved).to_json()


def check_slack(c: Check) -> float:
    """A check's relative slack: ``|b - t| / |t|``, negative where it does not hold.

    ``b`` is the value with the confidence bounds in place (the point value
    where there is no bound) and ``t`` the target; ``inf`` for a check with
    no value (nothing to judge).

    See Also
    --------
    Evaluation.margin : the least slack over a design's checks and its residual.
    """
    v = c.bound if c.bound is not None else c.value
    if v is None:
        return math.inf
    slack = abs(v - c.target) / max(abs(c.target), 1e-9)
    return slack if c.holds_with_confidence else -slack


@dataclass
class Evaluation:
    """A design evaluated on one set of rocks.

    Attributes
    ----------
    run : SimulationRun
        The run on the edited section (its ``section`` is the edited one).
    original_section : Section
        The bare section.
    placed : list of PlacedMeasure
    results : list of MeasureResult
        One per measure, in project order.
    checks : list of list of Check
        The safety concept's checks, one list per measure.
    concept : SafetyConcept
    """

    run: SimulationRun
    original_section: Section
    placed: list[PlacedMeasure]
    results: list[MeasureResult]
    checks: list[list[Check]]
    concept: SafetyConcept
    judgement: Judgement

    @property
    def confidence(self) -> float:
        """One-sided confidence of the bounds (``safety.confidence``, as the plan resolves it)."""
        return confidence_of(self.concept)

    @property
    def residual(self) -> ProtectRecord | None:
        """Rocks reaching the protected zone and whether that is within what is allowed.

        ``upper_fraction`` is the Clopper-Pearson upper bound of the fraction
        at :attr:`confidence`; ``ok_with_confidence`` compares it with the
        allowed fraction. ``lower_fraction`` is the Clopper-Pearson lower
        bound; ``fails_with_confidence`` says it exceeds the allowed fraction
        (the residual misses its target with confidence). None without
        ``protect:``.
        """
        p = self.run.project.protect
        if p is None:
            return None
        allowed = float(getattr(p, "allowed_fraction", 0.0))
        # A concept that sets the residual itself (reliability) tightens the allowance.
        by_concept = self.concept.allowed_residual_fraction()
        if by_concept is not None:
            allowed = min(allowed, by_concept) if allowed > 0.0 else by_concept
        return protect_record(float(p.x), self.judgement.reaching, self.run.result.n,
                              allowed, self.confidence, self.judgement.unresolved)

    @property
    def protect(self) -> dict[str, Any] | None:
        """:attr:`residual` as its JSON (the optimiser's and the studies' callers read it)."""
        prot = self.residual
        return None if prot is None else prot.to_json()

    @property
    def ok(self) -> bool:
        """True when every check of every measure holds and the residual is allowed."""
        checks_ok = all(c.ok for cs in self.checks for c in cs)
        prot = self.residual
        return checks_ok and (prot is None or prot.ok)

    @property
    def holds_with_confidence(self) -> bool:
        """``ok`` with every design value and the residual replaced by its upper bound."""
        checks_ok = all(c.holds_with_confidence for cs in self.checks for c in cs)
        prot = self.residual
        return checks_ok and (prot is None or prot.ok_with_confidence)

    @property
    def fails_with_confidence(self) -> bool:
        """Some check, or the residual, misses its target even with its favourable bound."""
        prot = self.residual
        return (any(c.rejects for cs in self.checks for c in cs)
                or (prot is not None and prot.fails_with_confidence))

    def margin(self) -> tuple[float, str]:
        """How far the design is from failing on these rocks: (relative slack, what binds).

        The smallest, over the checks and the residual, of ``|b - t| / |t|``
        with ``b`` the value with the confidence bounds in place (the point
        value where there is no bound) and ``t`` its target; negative where
        that fails. The residual's slack is ``(allowed - upper) / allowed`` of
        the fraction reaching the protected zone (its Clopper-Pearson bound).
        What binds is ``"<measure label>: <check name>"`` or ``"residual"``;
        ``(inf, "")`` when nothing is checked.

        See Also
        --------
        rockfall_design.judge.bounds : the bounds that ``b`` carries.
        """
        worst, what = math.inf, ""
        for p, cs in zip(self.placed, self.checks, strict=True):
            for c in cs:
                slack = check_slack(c)
                if slack < worst:
                    worst, what = slack, f"{p.label}: {c.name}"
        prot = self.residual
        if prot is not None and prot.allowed_fraction > 0:
            slack = (prot.allowed_fraction - prot.upper_fraction) / prot.allowed_fraction
            if slack < worst:
                worst, what = slack, "residual"
        return worst, what

    def _failed_checks(self, holds: Callable[[Check], bool]) -> Iterator[tuple[str, Check, str]]:
        """(measure label, check, " unit" or "") of every check that ``holds`` rejects."""
        for p, cs in zip(self.placed, self.checks, strict=True):
            for c in cs:
                if not holds(c):
                    yield p.label, c, "" if c.unit == "-" else f" {c.unit}"

    def failures(self) -> list[str]:
        """One line per failed check, for reports."""
        out = []
        for label, c, unit in self._failed_checks(lambda c: c.ok):
            value = "-" if c.value is None else f"{c.value:.2f}{unit}"
            out.append(f"{label}: {c.name} {value} does not meet its target "
                       f"{c.target:.2f}{unit} ({c.detail})")
        prot = self.residual
        if prot is not None and not prot.ok:
            unresolved = (
                f" ({prot.unresolved} of them unresolved paths, counted as reaching it; "
                "raise engine.max_events)" if prot.unresolved else ""
            )
            out.append(
                f"{prot.reaching} rocks ({100 * prot.fraction:.2f} %) reach the protected "
                f"zone at x >= {prot.x:g} m{unresolved}; allowed "
                f"{100 * prot.allowed_fraction:.2f} %"
            )
        return out

    def caught_by_measure(self) -> np.ndarray:
        """Per rock: the index (in ``measures:``) of the measure that stopped it, or -1.

        A rock is credited to a barrier that caught it, to a wall that returned it
        for good, or to the catch area (ditch, berm) it came to rest in.
        """
        r = self.run.result
        out = np.full(r.n, -1, dtype=np.int64)
        for res, held in zip(self.results, self.judgement.held, strict=True):
            out[held & (out < 0)] = res.index
        return out

    def outcomes_table(self) -> Any:
        """One row per rock and measure: outcome of the first meeting and its values."""
        import pandas as pd

        r = self.run.result
        frames = []
        names = {int(v): v.name.lower() for v in Outcome}
        for p, res, out in zip(self.placed, self.results, self.judgement.outcomes, strict=True):
            rec = self._meeting(p)
            frames.append(
                pd.DataFrame(
                    {
                        "rock": np.arange(r.n),
                        "measure": res.index,
                        "type": res.measure.kind,
                        "outcome": [names[int(o)] for o in out],
                        "passing_height_m": rec[:, columns.BM_H],
                        "velocity_ms": rec[:, columns.BM_V],
                        "energy_kj": rec[:, columns.BM_E] / 1e3,
                    }
                )
            )
        return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()

    def passages(self) -> list[Passages]:
        """The rocks that met each barrier, with the barrier's figures to draw on them.

        One :class:`~rockfall_design.run.passages.Passages` per barrier (a
        profile edit has no passage), in project order: every quantity of
        :data:`~rockfall_design.run.passages.QUANTITIES` per rock that met
        it, and the marks of its design properties (heights, capacities,
        whatever the product gives, read by their units).
        """
        out = []
        for p, res in zip(self.placed, self.results, strict=True):
            fp = p.footprint
            if not isinstance(fp, Barrier):
                continue
            slope = slope_deg_at(self.run.section, float(fp.x))
            values = barrier_values(res.passing_height_m, res.velocity_ms, res.energy_kj,
                                    res.mass_kg, res.radius_m, slope)
            with plugin_code():  # checked when placed; what it prints goes to stderr
                properties = res.measure.design_properties()
            out.append(Passages("measure", res.index, p.label, float(fp.x), slope, values,
                                property_marks(properties)))
        return out

    def statements(self) -> list[str]:
        """The safety concept's own sentences on this evaluation (``SafetyConcept.statements``)."""
        reaching = None if self.run.project.protect is None else self.judgement.reaching
        return list(self.concept.statements(reaching, self.run.result.n, self.results,
                                            [p.label for p in self.placed]))

    def resolved_project(self) -> Project:
        """The project with every measure's and the concept's parameters resolved."""
        measures = [
            {"type": p.measure.kind, **p.measure.params.model_dump(mode="json")}
            for p in self.placed
        ]
        safety = {"concept": self.concept.name, **self.concept.params.model_dump(mode="json")}
        return self.run.project.with_resolved_plugins(measures, safety)

    def summary(self) -> dict[str, Any]:
        """JSON-ready: the simulate summary plus ``measures``, ``protect`` and ``ok``.

        :meth:`record`'s ``to_json()`` (not yet judged: no ``verdict``).
        """
        return self.record().to_json()

    def record(self) -> CheckSummary:
        """The check's summary as an object: the run, the measures, the residual."""
        passing = {q.index: q.block() for q in self.passages()}
        measures = tuple(
            MeasureRecord(
                type=res.measure.kind, label=p.label, x=res.measure.x,
                params=res.measure.params.model_dump(mode="json"), met=res.met,
                caught=res.caught, passed_over=res.passed_over,
                broken_through=res.broken_through, rebounded=res.rebounded,
                passed_through_gap=res.passed_through_gap, checks=tuple(cs),
                # The distributions at a barrier (run.passages): None for a ground edit.
                passing=passing.get(res.index))
            for p, res, cs in zip(self.placed, self.results, self.checks, strict=True))
        return CheckSummary(
            run=self.run.run_summary(), safety_concept=self.concept.name, measures=measures,
            protect=self.residual, concept_statements=tuple(self.statements()), ok=self.ok,
            failures=tuple(self.failures()), confidence=self.confidence,
            holds_with_confidence=self.holds_with_confidence)

    def _meeting(self, p: PlacedMeasure) -> np.ndarray:
        """(n, 3) record of each rock's first meeting of a barrier (NaN for edits)."""
        r = self.run.result
        if not isinstance(p.footprint, Barrier):
            return np.full((r.n, 3), np.nan)
        _, owners = barrier_rows(self.placed)
        return r.barrier_meeting[:, owners.index(p.index), :3]


def _judge_run(placed: Sequence[PlacedMeasure], owners: list[int], run: SimulationRun,
               protect_x: float | None) -> Judgement:
    """Judge the exact run: barrier outcomes and meetings as the engine recorded them."""
    r = run.result
    outcomes: list[np.ndarray | None] = []
    meetings: list[np.ndarray | None] = []
    for p in placed:
        if isinstance(p.footprint, Barrier):
            b = owners.index(p.index)
            rec = r.barrier_meeting[:, b, :3].astype(float)
            rec[:, columns.BM_E] /= 1e3  # J -> kJ
            outcomes.append(r.barrier_outcome[:, b].copy())
            meetings.append(rec)
        else:
            outcomes.append(None)
            meetings.append(None)
    fates = RockFates(max_x=r.max_x, x_end=r.x_end, status=r.status, mass=r.mass,
                      radius=r.radius)
    return judge_measures(placed, outcomes, meetings, fates, protect_x)


def evaluate(
    project: Project,
    registry: Registry,
    *,
    rocks: int | None = None,
    seed: int | None = None,
    n_trajectories: int = 0,
    progress: Callable[[int], None] | None = None,
) -> Evaluation:
    """Run the project's rocks against its measures and check them.

    Parameters
    ----------
    project : Project
    registry : Registry
        The loaded plugins.
    rocks, seed : int, optional
        Override the project's count and seed.
    n_trajectories : int
        Keep the event states of the first rocks, for figures.
    progress : callable, optional
        Called with the number of rocks done.
    """
    plan = plan_for(project, registry)
    return _evaluate_placed(project, registry, plan.bare, list(plan.placed), plan.section,
                            plan.concept, rocks=rocks, seed=seed,
                            n_trajectories=n_trajectories, progress=progress,
                            record_speed=True)


def evaluate_design(
    project: Project,
    registry: Registry,
    measures: Sequence[ProtectiveMeasure],
    concept: SafetyConcept,
    *,
    rocks: int | None = None,
    seed: int | None = None,
    n_trajectories: int = 0,
    progress: Callable[[int], None] | None = None,
    after: Evaluation | None = None,
    bare: Section | None = None,
    envelope: bool = True,
) -> Evaluation:
    """Like :func:`evaluate`, for given measure and concept objects (the optimiser's designs).

    ``after``: an evaluation of the same design on the first rocks of this
    run (same project and seed, fewer rocks); only the rocks after them are
    simulated (``run_in_memory``'s ``after``) and the whole is judged again with
    ``concept``. A sequential look at more rocks goes on from the last look.
    ``bare``: the project's slope section, when the caller holds it (the
    optimiser's screening: every design of a search stands on one section).
    ``envelope``: record the envelope grid (``run_in_memory``'s ``envelope``);
    the optimiser's decisions do not, so that a look of a million rocks holds
    a few hundred MB; an ``after`` run must have been recorded the same way.
    """
    if after is not None:
        run = after.run
        return _evaluate_placed(project, registry, after.original_section, after.placed,
                                run.section, concept, rocks=rocks, seed=seed,
                                n_trajectories=0, progress=progress, after=run,
                                envelope=run.envelope_recorded)
    if bare is None:
        bare = section_from_project(project)
    placed = place_measures(project, registry, measures, bare)
    section = edited_section(project, bare, placed)
    return _evaluate_placed(project, registry, bare, placed, section, concept, rocks=rocks,
                            seed=seed, n_trajectories=n_trajectories, progress=progress,
                            envelope=envelope)


def _evaluate_placed(
    project: Project,
    registry: Registry,
    bare: Section,
    placed: list[PlacedMeasure],
    section: Section,
    concept: SafetyConcept,
    *,
    rocks: int | None,
    seed: int | None,
    n_trajectories: int,
    progress: Callable[[int], None] | None,
    after: SimulationRun | None = None,
    record_speed: bool = False,
    envelope: bool = True,
) -> Evaluation:
    """Run the rocks against measures already placed on ``bare`` (``section``: edited).

    ``record_speed``: keep the speeds along the section for the speed
    envelope (``check`` and the chosen design's figures; not the optimiser).
    ``envelope``: record the envelope grid (``run_in_memory``'s).
    """
    bars, owners = barrier_rows(placed)
    run = run_in_memory(project, rocks=rocks, seed=seed, n_trajectories=n_trajectories,
                        progress=progress, section=section, barriers=bars, after=after,
                        record_speed=record_speed, envelope=envelope)
    protect = project.protect
    judgement = _judge_run(placed, owners, run, None if protect is None else protect.x)
    checks = [guard(registry).concept(concept).checks(res) for res in judgement.results]
    return Evaluation(
        run=run,
        original_section=bare,
        placed=placed,
        results=judgement.results,
        checks=checks,
        concept=concept,
        judgement=judgement,
    )


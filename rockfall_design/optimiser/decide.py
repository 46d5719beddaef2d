"""Deciding a design sequentially: admitted, rejected or marginal, never by noise.

A design is looked at with more and more rocks (:mod:`rockfall_design.judge.sequential`):
admitted when every check and the residual hold with their upper confidence
bounds, rejected when one of them fails with its lower bound, and given
more rocks otherwise, up to ``design.max_rocks``, where it is *marginal*.
The looks and the confidence of each are fixed before the first rock runs,
so that looking again does not inflate either error.

Barrier designs whose every rock the screening judges exactly are looked at
through the screening (a run of more rocks on the bare slope, with the
stations of the designs under decision only, serves every such design); a
design the screening approximates (rocks breaking through or returned) or
that edits the ground is looked at by exact runs. An admission by the
screening is always confirmed by the exact run of the same rocks (the two
agree where nothing is approximated; the exact run is what the report shows).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..judge.bounds import fraction_lower_bound, fraction_upper_bound
from ..judge.evaluation import Evaluation, evaluate_design
from ..judge.sequential import LookSchedule, Verdict, plan_looks
from ..plugins import guard
from ..plugins.measure import Barrier

if TYPE_CHECKING:  # pragma: no cover
    from ..plugins import Registry
    from ..plugins.concept import Check, SafetyConcept
    from ..plugins.measure import ProtectiveMeasure
    from ..project import Project

from .screening import Screening, ScreenResult

__all__ = ["Decider", "Decision", "decide", "look_concept", "rocks_to_decide", "verify_fresh"]


@dataclass
class Decision:
    """The sequential decision of one design.

    Attributes
    ----------
    verdict : Verdict
        ADMITTED, REJECTED or MARGINAL.
    rocks : int
        Rocks of the look that decided (for MARGINAL, the last look's).
    evaluation : Evaluation or None
        The exact run of the deciding look (always there when admitted).
    reason : str
        Why it is not admitted (what fails with confidence, or why marginal).
    looks : int
        Looks taken.
    exact : int
        Exact runs made.
    simulated : int
        Rocks simulated for this decision (exact runs and look screenings).
    values : dict
        Point values and bounds of the deciding look (see :func:`look_values`).
    schedule : LookSchedule or None
        The looks planned (:func:`decide` sets it).
    """

    verdict: Verdict
    rocks: int
    evaluation: Evaluation | None
    reason: str = ""
    looks: int = 1
    exact: int = 0
    simulated: int = 0
    values: dict[str, Any] = field(default_factory=dict)
    schedule: LookSchedule | None = None

    @property
    def admitted(self) -> bool:
        return self.verdict is Verdict.ADMITTED


def look_concept(registry: Registry, concept: SafetyConcept, confidence: float) -> SafetyConcept:
    """The project's safety concept with its bounds at a look's ``confidence``."""
    params = concept.params.model_copy(update={"confidence": float(confidence)})
    return guard(registry).instantiate(type(concept), params)


def _verdict_of(ev: Evaluation) -> Verdict:
    if ev.holds_with_confidence:
        return Verdict.ADMITTED
    if ev.fails_with_confidence:
        return Verdict.REJECTED
    return Verdict.UNDECIDED


def _screen_verdict(sr: ScreenResult) -> Verdict:
    if sr.feasible:
        return Verdict.ADMITTED
    return Verdict.UNDECIDED if sr.near else Verdict.REJECTED


def _finite(x: float | None) -> float | None:
    """``x``, or None where it is not a finite number (JSON has no infinity: a factor
    over a demand whose lower bound is 0 is unbounded)."""
    return None if x is None or not math.isfinite(x) else float(x)


def look_values(checks: Sequence[Sequence[Check]], labels: Sequence[str], residual: int | None,
                n: int, allowed: float | None, confidence: float) -> dict[str, Any]:
    """Point values and both bounds of a look, for the report of a marginal design.

    Returns ``{rocks, confidence, checks: [{measure, name, value, bound,
    optimistic, target}], residual: {reaching, fraction, lower, upper,
    allowed}}`` (``residual`` None without a protected zone).
    """
    rows = [{"measure": lab, "name": c.name, "value": _finite(c.value),
             "bound": _finite(c.bound), "optimistic": _finite(c.optimistic),
             "target": c.target, "unit": c.unit}
            for lab, cs in zip(labels, checks, strict=True) for c in cs]
    res = None
    if residual is not None and allowed is not None:
        res = {"reaching": int(residual), "fraction": residual / max(n, 1),
               "lower": fraction_lower_bound(residual, n, confidence),
               "upper": fraction_upper_bound(residual, n, confidence),
               "allowed": allowed}
    return {"rocks": int(n), "confidence": confidence, "checks": rows, "residual": res}


def rocks_to_decide(values: dict[str, Any]) -> int | None:
    """About how many rocks would decide a marginal design (None: it sits on the target).

    Each bound's distance from its point value shrinks about as 1/sqrt(n)
    (order statistics and Clopper-Pearson alike): a check or residual whose
    point value is ``d`` from the target and whose bounds are ``w`` from the
    value at ``n`` rocks is decided at about ``n (w / d)**2`` rocks. The
    largest such count over the undecided items.
    """
    n = values["rocks"]
    need = 0.0
    for c in values["checks"]:
        v, t = c["value"], c["target"]
        if v is None:
            continue
        sides = [abs(b - v) for b in (c["bound"], c["optimistic"])
                 if b is not None and math.isfinite(b)]
        if not sides:
            continue
        w, d = max(sides), abs(v - t)
        holds = (c["bound"] is not None and (c["bound"] >= t if v >= t else c["bound"] <= t))
        rejects = c["optimistic"] is not None and not (
            c["optimistic"] >= t if v >= t else c["optimistic"] <= t)
        if holds or rejects:
            continue
        if d <= 0.0:
            return None
        need = max(need, n * (w / d) ** 2)
    r = values.get("residual")
    if r is not None and r["upper"] > r["allowed"] and r["lower"] <= r["allowed"]:
        d = abs(r["fraction"] - r["allowed"])
        w = max(r["upper"] - r["fraction"], r["fraction"] - r["lower"])
        if d <= 0.0:
            return None
        need = max(need, n * (w / d) ** 2)
    return int(math.ceil(need)) if need > n else None


def _reason(verdict: Verdict, values: dict[str, Any], failures: Sequence[str]) -> str:
    conf = f"{100 * values['confidence']:.4g} %"
    if verdict is Verdict.REJECTED:
        return f"fails with {conf} confidence on {values['rocks']:,} rocks: " + "; ".join(
            failures)
    need = rocks_to_decide(values)
    more = (f"about {need:,} rocks would decide it (--max-rocks)" if need else
            "its point value sits on the target")
    return (f"marginal: neither holds nor fails with {conf} confidence on "
            f"{values['rocks']:,} rocks; {more}")


def _rejections(checks: Sequence[Sequence[Check]], labels: Sequence[str], residual: int | None,
                n: int, allowed: float | None, confidence: float) -> list[str]:
    """One line per check (and the residual) that fails with confidence."""
    out = []
    for lab, cs in zip(labels, checks, strict=True):
        for c in cs:
            if c.rejects:
                unit = "" if c.unit == "-" else f" {c.unit}"
                best = "-" if c.optimistic is None else f"{c.optimistic:.2f}{unit}"
                out.append(f"{lab}: {c.name} at best {best}, target {c.target:.2f}{unit}")
    if residual is not None and allowed is not None:
        low = fraction_lower_bound(residual, n, confidence)
        if residual > 0 and low > allowed:
            out.append(f"{residual:,} of {n:,} rocks reach the protected zone: at least "
                       f"{100 * low:.3f} %, allowed {100 * allowed:.3f} %")
    return out or ["fails"]


def _ev_values(ev: Evaluation, allowed: float | None) -> tuple[dict[str, Any], list[str]]:
    prot = ev.protect
    residual = None if prot is None else int(prot["reaching"])
    labels = [p.label for p in ev.placed]
    n = ev.study.result.n
    args = (ev.checks, labels, residual, n, allowed, ev.confidence)
    return look_values(*args), _rejections(*args)


def decide(
    project: Project,
    registry: Registry,
    measures: Sequence[ProtectiveMeasure],
    concept: SafetyConcept,
    *,
    rocks: int,
    seed: int,
    max_rocks: int | None = None,
    looks: LookSchedule | None = None,
) -> Decision:
    """Decide a design sequentially by exact runs (see the module docs).

    Parameters
    ----------
    project, registry : Project, Registry
    measures : sequence of ProtectiveMeasure
    concept : SafetyConcept
        The project's concept (its ``confidence`` is the overall one).
    rocks, seed : int
        Rocks of the first look, and the seed of every look (nested rocks).
    max_rocks : int, optional
        Rocks of the last look (default ``rocks``: one look).
    looks : LookSchedule, optional
        The schedule (default :func:`~rockfall_design.judge.sequential.plan_looks`
        from ``rocks`` to ``max_rocks`` at the concept's confidence).
    """
    confidence = float(concept.params.confidence)
    if looks is None:
        looks = plan_looks(rocks, int(max_rocks or rocks), confidence)
    lc = look_concept(registry, concept, looks.look_confidence)
    allowed = project.protect.allowed_fraction if project.protect is not None else None
    simulated = 0
    ev: Evaluation | None = None
    for j, n in enumerate(looks.sizes):
        # Each look goes on from the last one's rocks (nested: the same seed).
        done = 0 if ev is None else ev.study.n
        ev = evaluate_design(project, registry, measures, lc, rocks=n, seed=seed, after=ev)
        simulated += n - done
        verdict = _verdict_of(ev)
        if verdict is Verdict.UNDECIDED and j + 1 < len(looks):
            continue
        values, fails = _ev_values(ev, allowed)
        if verdict is Verdict.UNDECIDED:
            verdict = Verdict.MARGINAL
        reason = "" if verdict is Verdict.ADMITTED else _reason(verdict, values, fails)
        return Decision(verdict, n, ev, reason, j + 1, j + 1, simulated, values, looks)
    raise AssertionError("a schedule has at least one look")  # pragma: no cover


def verify_fresh(
    project: Project,
    registry: Registry,
    measures: Sequence[ProtectiveMeasure],
    concept: SafetyConcept,
    *,
    rocks: int,
    seed: int,
    max_rocks: int,
) -> Decision:
    """Check an admitted design on fresh rocks: held, failed or marginal there too.

    The design that the search admitted is the cheapest of many that got
    their chance, so it is tested again on rocks it was not chosen on (an
    independent ``seed``). That test is sequential in its own right
    (:func:`decide`: looks from ``rocks`` doubling up to ``max_rocks``, the
    error ``1 - confidence`` spent over them): a design whose fresh bounds do
    not yet decide it gets more fresh rocks instead of being dropped on the
    noise of one look. A drop on one look made the answer hang on the seed:
    at one seed a design whose fresh point values held but whose bound fell
    just short was passed over for one 30 % dearer, which the next seed did
    not choose.

    Parameters
    ----------
    project, registry, measures, concept
        As :func:`decide` (``concept`` at the project's own confidence).
    rocks : int
        Fresh rocks of the first look (twice the rocks that decided the
        design, or ``design.fresh_rocks``).
    seed : int
        The fresh seed.
    max_rocks : int
        The last look (``design.max_rocks``; at least ``rocks``).

    Returns
    -------
    Decision
        ADMITTED (holds with confidence on fresh rocks), REJECTED (fails with
        confidence on them) or MARGINAL (neither, up to the last look).
    """
    return decide(project, registry, measures, concept, rocks=rocks, seed=seed,
                  max_rocks=max(int(max_rocks), int(rocks)))


class Decider:
    """Sequential decisions of one section's designs, through the screening where it is exact.

    Parameters
    ----------
    screen : Screening
        The search rocks' screening (the first look), built with the look
        concept (:func:`look_concept`).
    looks : LookSchedule
        ``looks.sizes[0]`` is ``screen.n``.
    """

    def __init__(self, screen: Screening, looks: LookSchedule) -> None:
        self.screen = screen
        self.looks = looks
        self._screens: dict[int, Screening] = {0: screen}
        self.simulated = 0  # rocks of the look screenings (each counted when run)
        self.screen_runs = 0

    def _screening(self, j: int, stations: Sequence[float]) -> Screening:
        """The screening of look ``j``, with at least ``stations`` (m) in its table."""
        sc = self._screens.get(j)
        want = {round(float(x), 6) for x in stations}
        if sc is not None and want <= {round(float(x), 6) for x in sc.grid}:
            return sc
        if sc is not None:
            want |= {round(float(x), 6) for x in sc.grid}
        s0 = self.screen
        sc = Screening(s0.project, s0.registry, s0.spec, s0.concept, rocks=self.looks.sizes[j],
                       seed=s0.seed, stations=np.array(sorted(want)))
        self.simulated += sc.n
        self.screen_runs += 1
        self._screens[j] = sc
        return sc

    def _exact(self, measures: Sequence[ProtectiveMeasure], j: int,
               after: Evaluation | None) -> Evaluation:
        """The exact run of look ``j``, going on from an earlier exact look's rocks."""
        s0 = self.screen
        return evaluate_design(s0.project, s0.registry, measures, s0.concept,
                               rocks=self.looks.sizes[j], seed=s0.seed, after=after)

    def decide(self, measures: Sequence[ProtectiveMeasure], first: ScreenResult) -> Decision:
        """Decide a design that the first look (the search's screening) did not reject."""
        s0 = self.screen
        allowed = s0.allowed_fraction
        fps = [guard(s0.registry).measure(m).footprint(s0.section) for m in measures]
        barriers_only = all(isinstance(fp, Barrier) for fp in fps)
        stations = [fp.x for fp in fps if isinstance(fp, Barrier)]
        sizes = self.looks.sizes
        j, sr, ev = 0, first, None
        last: Evaluation | None = None  # the latest exact look, which the next goes on from
        verdict = _screen_verdict(sr)
        exact = simulated = 0
        by_exact = first.approximate  # the screening cannot decide what it approximates
        while True:
            if ev is None and (verdict is Verdict.ADMITTED or by_exact):
                # Confirm an admission, or decide what the screening approximates.
                ev = self._exact(measures, j, last)
                exact += 1
                simulated += sizes[j] - (0 if last is None else last.study.n)
                last = ev
                verdict = _verdict_of(ev)
            if verdict is not Verdict.UNDECIDED or j + 1 == len(sizes):
                break
            j += 1
            ev = None
            if barriers_only and not by_exact:
                sc = self._screening(j, stations)
                sr = sc.screen(measures)
                verdict = _screen_verdict(sr)
                by_exact = sr.approximate
            else:
                by_exact = True
        if ev is not None:
            values, fails = _ev_values(ev, allowed)
        else:
            prot = None if s0.project.protect is None else sr.residual
            args = (sr.checks, sr.labels, prot, sizes[j], allowed, s0.confidence)
            values, fails = look_values(*args), _rejections(*args)
        if verdict is Verdict.UNDECIDED:
            verdict = Verdict.MARGINAL
        reason = "" if verdict is Verdict.ADMITTED else _reason(verdict, values, fails)
        return Decision(verdict, sizes[j], ev, reason, j + 1, exact, simulated, values)

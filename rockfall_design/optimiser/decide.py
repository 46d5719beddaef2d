"""Deciding a design sequentially: admitted, rejected or marginal, never by noise.

A design is looked at with more and more rocks (:mod:`rockfall_design.judge.sequential`):
admitted when every check and the residual hold with their upper confidence
bounds, rejected when one of them fails with its lower bound, and given
more rocks otherwise, up to ``design.max_rocks``, where it is *marginal*.
The looks and the confidence of each are fixed before the first rock runs,
so that looking again does not inflate either error.

Designs whose every rock the screening judges exactly are looked at through
the screening: a run of more rocks on the bare slope, with the stations of the
designs under decision only, serves every such design; one that keeps the rocks'
states at a restart station serves the ground edits below it, whose rocks are
resumed there. A design the screening approximates (rocks breaking through or
returned, forest) is looked at by exact runs. An admission by the
screening is always confirmed by the exact run of the same rocks (the two
agree where nothing is approximated; the exact run is what the report shows).
Every look's verdict, with the checker's margin, is the judge's
(:mod:`rockfall_design.judge.looks`).
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..judge.evaluation import Evaluation, evaluate_design
from ..judge.looks import (
    LookValues,
    beyond_rocks,
    checks_at,
    judge_look,
    look_concept,
    look_values,
    rejections,
    rocks_to_decide,
    with_margin,
)
from ..judge.margin import CheckerMargin
from ..judge.plan import confidence_of
from ..judge.sequential import LookSchedule, Verdict, plan_looks
from ..plugins import guard
from ..plugins.measure import Barrier, ProfileEdit
from ..run.releases import draw_releases

if TYPE_CHECKING:  # pragma: no cover
    from ..engine import Section
    from ..plugins import Registry
    from ..plugins.concept import SafetyConcept
    from ..plugins.measure import ProtectiveMeasure
    from ..project import Project

from .screening import Screening, ScreenResult, restart_index, restart_margin

__all__ = ["SHORT", "Decider", "Decision", "decide", "verify_fresh"]


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
    values : LookValues or None
        Point values and bounds of the deciding look
        (:func:`~rockfall_design.judge.looks.look_values`; None
        across scenarios, which have one set each).
    schedule : LookSchedule or None
        The looks planned (:func:`decide` sets it).
    short_of_margin : bool
        REJECTED because a checker's check would confirm it too seldom
        (:mod:`rockfall_design.judge.margin`), not because it fails.
    margin_undecided : bool
        MARGINAL although it holds with the last look's bounds: the checker's
        margin is what that many rocks could not decide.
    """

    verdict: Verdict
    rocks: int
    evaluation: Evaluation | None
    reason: str = ""
    looks: int = 1
    exact: int = 0
    simulated: int = 0
    values: LookValues | None = None
    schedule: LookSchedule | None = None
    short_of_margin: bool = False
    margin_undecided: bool = False

    @property
    def admitted(self) -> bool:
        return self.verdict is Verdict.ADMITTED


#: The tally's words for a design rejected for the checker's margin (not for failing).
SHORT = "short of the checker's margin with confidence"


def _screen_verdict(sr: ScreenResult) -> Verdict:
    if sr.feasible:
        return Verdict.ADMITTED
    return Verdict.UNDECIDED if sr.near else Verdict.REJECTED


def _reason(verdict: Verdict, values: LookValues, failures: Sequence[str],
            short: Sequence[str] = ()) -> str:
    conf = f"{100 * values.confidence:.4g} %"
    if verdict is Verdict.REJECTED and short:
        return (f"short of the checker's margin with {conf} confidence on "
                f"{values.rocks:,} rocks: " + "; ".join(short))
    if short:  # marginal: holds, the margin undecided
        return "marginal: " + "; ".join(short) + "; more rocks would decide it (--max-rocks)"
    if verdict is Verdict.REJECTED:
        return f"fails with {conf} confidence on {values.rocks:,} rocks: " + "; ".join(
            failures)
    need = rocks_to_decide(values)
    more = (f"about {need:,} rocks would decide it (--max-rocks)" if need else
            beyond_rocks(values) or "its point value sits on the target")
    return (f"marginal: neither holds nor fails with {conf} confidence on "
            f"{values.rocks:,} rocks; {more}")


def _decided(dec: Decision, failures: Sequence[str], short: Sequence[str]) -> Decision:
    """The decision at its last look: undecided there is MARGINAL; why, unless admitted.

    ``short``: the checker's margin's one line (:func:`~rockfall_design.judge.looks.judge_look`).
    """
    if dec.verdict is Verdict.UNDECIDED:
        dec.verdict = Verdict.MARGINAL
    if dec.verdict is not Verdict.ADMITTED:
        dec.reason = _reason(dec.verdict, dec.values, failures, short)
    dec.short_of_margin = dec.verdict is Verdict.REJECTED and bool(short)
    dec.margin_undecided = dec.verdict is Verdict.MARGINAL and bool(short)
    return dec


def _ev_values(ev: Evaluation, allowed: float | None) -> tuple[LookValues, list[str]]:
    prot = ev.residual
    residual = None if prot is None else int(prot.reaching)
    labels = [p.label for p in ev.placed]
    n = ev.run.result.n
    args = (ev.checks, labels, residual, n, allowed, ev.confidence)
    return look_values(*args), rejections(*args)


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
    margin: CheckerMargin | None = None,
    checker_rocks: int | None = None,
    bare: Section | None = None,
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
    margin : CheckerMargin, optional
        Admit only with the checker's margin (:func:`~rockfall_design.judge.looks.judge_look`).
    checker_rocks : int, optional
        Rocks of the checker's check the margin is for (default: twice
        each look's rocks, the check design.yaml asks for if that look decides).
    bare : Section, optional
        The project's slope section (the screening's; default: built from the
        project).
    """
    confidence = confidence_of(concept)
    if looks is None:
        looks = plan_looks(rocks, int(max_rocks or rocks), confidence)
    lc = look_concept(registry, concept, looks.look_confidence)
    allowed = project.protect.allowed_fraction if project.protect is not None else None
    simulated = 0
    ev: Evaluation | None = None
    for j, n in enumerate(looks.sizes):
        # Each look goes on from the last one's rocks (nested: the same seed).
        done = 0 if ev is None else ev.run.n
        ev = evaluate_design(project, registry, measures, lc, rocks=n, seed=seed, after=ev,
                             bare=bare, envelope=False)
        simulated += n - done
        verdict, short = judge_look(ev, registry, margin, checker_rocks or 2 * n,
                                    checker_rocks or 2 * looks.sizes[-1])
        if verdict is Verdict.UNDECIDED and j + 1 < len(looks):
            continue
        values, fails = _ev_values(ev, allowed)
        return _decided(Decision(verdict, n, ev, "", j + 1, j + 1, simulated, values, looks),
                        fails, short)
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
    margin: CheckerMargin | None = None,
    bare: Section | None = None,
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
    margin : CheckerMargin, optional
        The checker's margin, for a check of ``rocks`` (the first look's).
    bare : Section, optional
        The project's slope section, as :func:`decide`.

    Returns
    -------
    Decision
        ADMITTED (holds with confidence on fresh rocks), REJECTED (fails with
        confidence on them) or MARGINAL (neither, up to the last look).
    """
    return decide(project, registry, measures, concept, rocks=rocks, seed=seed,
                  max_rocks=max(int(max_rocks), int(rocks)), margin=margin,
                  checker_rocks=int(rocks), bare=bare)


#: Chains of look screenings of ground edits kept (by restart station, least recently
#: used dropped): each holds its looks' rocks' states at its one station, 14 float64
#: per rock (45 MB at 400,000 rocks; peak memory: docs/speed.md).
EDIT_CHAINS_KEPT = 2
#: How far (m) above a design's own restart station a kept chain's may serve it:
#: resuming more rocks costs less than a new chain's bare runs (docs/speed.md).
CHAIN_REACH_M = 10.0


class Decider:
    """Sequential decisions of one section's designs, through the screening where it is exact.

    Parameters
    ----------
    screen : Screening
        The search rocks' screening (the first look), built with the look
        concept (:func:`~rockfall_design.judge.looks.look_concept`).
    looks : LookSchedule
        ``looks.sizes[0]`` is ``screen.n``.
    margin : CheckerMargin, optional
        Admit only with the checker's margin for a check of twice the
        deciding look's rocks (:func:`~rockfall_design.judge.looks.judge_look`).
    """

    #: Look at ground edits by exact runs after the first look (the way before the
    #: look screenings of edits; the tests compare the two).
    edits_by_exact: bool = False

    def __init__(self, screen: Screening, looks: LookSchedule,
                 margin: CheckerMargin | None = None) -> None:
        self.screen = screen
        self.looks = looks
        self.margin = margin
        # The chains of look screenings (look -> screening), by restart station (None:
        # barriers only).
        self._chains: OrderedDict[float | None, dict[int, Screening]] = OrderedDict(
            [(None, {0: screen})])
        self._restart_margin: float | None = None
        self.simulated = 0  # rocks of the look screenings' bare runs (each counted when run)

    def _chain(self, restart: float | None) -> dict[int, Screening]:
        """The chain of looks resumed at ``restart`` (m), made if new (EDIT_CHAINS_KEPT)."""
        chain = self._chains.get(restart)
        if chain is None:
            if len(self._chains) > EDIT_CHAINS_KEPT:  # the barriers' chain stays
                oldest = next(k for k in self._chains if k is not None)
                del self._chains[oldest]
            chain = self._chains[restart] = {0: self.screen}
        self._chains.move_to_end(restart)
        return chain

    def restart_for(self, edits: Sequence[ProfileEdit]) -> float | None:
        """The search's restart station (m) from which the looks resume a design's edits.

        Upslope of the first edit by the margin of the largest look's rocks
        (:func:`~.screening.restart_margin`), so that every look of the chain
        resumes there: a kept chain's station up to :data:`CHAIN_REACH_M`
        above the last such station, else that station; None when the search
        has none so far up (the design is then looked at by exact runs).
        """
        if self._restart_margin is None:
            s0 = self.screen
            radius = draw_releases(s0.project, self.looks.sizes[-1], s0.seed).radius
            self._restart_margin = restart_margin(float(np.max(radius)))
        rx = self.screen.restart_x
        q = restart_index(rx, edits, self._restart_margin)
        if q < 0:
            return None
        kept = [x for x in self._chains if x is not None and rx[q] - CHAIN_REACH_M <= x <= rx[q]]
        return max(kept, default=float(rx[q]))

    def _screening(self, j: int, stations: Sequence[float],
                   restart: float | None = None) -> Screening:
        """The screening of look ``j``, with at least ``stations`` (m) in its table.

        Look ``j`` goes on from look ``j - 1``'s rocks (the first look's are
        the search's, whose table has every station): only its new rocks run,
        ``sizes[j] - sizes[j - 1]`` of them. A station new to look ``j`` is
        added to every earlier look it is missing from, each again only with
        its own new rocks, so a look of ``2n`` rocks is never a fresh ``2n``.
        ``restart`` (m): the chain keeping the rocks' states there only (ground edits).
        """
        chain = self._chain(restart)
        sc = chain.get(j)
        want = {round(float(x), 6) for x in stations}
        if sc is not None and want <= {round(float(x), 6) for x in sc.grid}:
            return sc
        if sc is not None:
            want |= {round(float(x), 6) for x in sc.grid}
        s0 = self.screen
        # A barrier's station is one of the search table's (the candidates'
        # ranges on the grid), so the search's rocks have it; one that is not
        # (none known) makes the look a run of all its rocks, as before.
        # The search's own station values (not their rounding), so that the
        # rocks of every look are recorded at the same x.
        exact = {round(float(x), 6): float(x) for x in s0.grid}
        prev: Screening | None = None
        if want <= exact.keys():
            prev = self._screening(j - 1, sorted(want), restart) if j > 1 else s0
        xs = np.array(sorted(exact.get(k, k) for k in want))
        sc = Screening(s0.project, s0.registry, s0.spec, s0.concept, rocks=self.looks.sizes[j],
                       seed=s0.seed, stations=xs, after=prev, section=s0.section,
                       restart_stations=None if restart is None else np.array([restart]))
        self.simulated += sc.rocks_run
        chain[j] = sc
        return sc

    def _exact(self, measures: Sequence[ProtectiveMeasure], j: int,
               after: Evaluation | None) -> Evaluation:
        """The exact run of look ``j``, going on from an earlier exact look's rocks."""
        s0 = self.screen
        return evaluate_design(s0.project, s0.registry, measures, s0.concept,
                               rocks=self.looks.sizes[j], seed=s0.seed, after=after,
                               bare=s0.section, envelope=False)

    def _screen_verdict(self, sr: ScreenResult, n: int) -> tuple[Verdict, list[str]]:
        """A screening look's verdict, with the margin where the screening judged every rock
        exactly (then it is the exact run's, without the run: a run is made only to
        confirm an admission)."""
        verdict = _screen_verdict(sr)
        if self.margin is None or sr.approximate or verdict is Verdict.REJECTED:
            return verdict, []
        s0 = self.screen
        reaching = None if s0.project.protect is None else int(sr.residual)
        return with_margin(verdict, lambda c: checks_at(s0.registry, s0.concept, sr.results, c),
                            sr.labels, reaching, s0.allowed_fraction, n, s0.confidence,
                            self.margin, 2 * n, 2 * self.looks.sizes[-1])

    def _look_plan(self, measures: Sequence[ProtectiveMeasure]
                   ) -> tuple[bool, list[float], float | None]:
        """Are the looks after the first screened; at which stations; resumed where
        (:meth:`restart_for`; None: barriers only, on the bare table)."""
        s0 = self.screen
        fps = [guard(s0.registry).measure(m).footprint(s0.section) for m in measures]
        stations = [fp.x for fp in fps if isinstance(fp, Barrier)]
        edits = [fp for fp in fps if isinstance(fp, ProfileEdit)]
        if len(stations) + len(edits) < len(fps):  # a footprint of another kind
            return False, stations, None
        if not edits:
            return True, stations, None
        restart = None if self.edits_by_exact else self.restart_for(edits)
        return restart is not None, stations, restart

    def _look(self, measures: Sequence[ProtectiveMeasure], j: int, stations: Sequence[float],
              restart: float | None) -> tuple[ScreenResult, int]:
        """Look ``j`` through its screening: the result, and the rocks resumed for it."""
        sc = self._screening(j, stations, restart)
        before = sc.edit_rocks
        sr = sc.screen(measures)
        sc.drop_edit_tables()  # each design is judged once per look
        return sr, sc.edit_rocks - before

    def decide(self, measures: Sequence[ProtectiveMeasure], first: ScreenResult) -> Decision:
        """Decide a design that the first look (the search's screening) did not reject.

        Looks are screened (:meth:`_look`) while they judge every rock exactly; an
        exact run confirms an admission, or decides a look that could not."""
        s0 = self.screen
        allowed = s0.allowed_fraction
        screened, stations, restart = self._look_plan(measures)
        sizes = self.looks.sizes
        j, sr, ev = 0, first, None
        last: Evaluation | None = None  # the latest exact look, which the next goes on from
        verdict, short = self._screen_verdict(sr, sizes[0])
        exact = simulated = 0
        by_exact = first.approximate  # the screening cannot decide what it approximates
        while True:
            if ev is None and (verdict is Verdict.ADMITTED or by_exact):
                # Confirm an admission, or decide what the screening approximates.
                ev = self._exact(measures, j, last)
                exact += 1
                simulated += sizes[j] - (0 if last is None else last.run.n)
                last = ev
                verdict, short = judge_look(ev, s0.registry, self.margin, 2 * sizes[j],
                                            2 * sizes[-1])
            if verdict is not Verdict.UNDECIDED or j + 1 == len(sizes):
                break
            j += 1
            ev, short = None, []
            if screened and not by_exact:
                sr, resumed = self._look(measures, j, stations, restart)
                simulated += resumed
                verdict, short = self._screen_verdict(sr, sizes[j])
                # A design the look could not judge (sr.reason) goes to the exact run.
                by_exact = sr.approximate or bool(sr.reason)
            else:
                by_exact = True
        if ev is not None:
            values, fails = _ev_values(ev, allowed)
        else:
            prot = None if s0.project.protect is None else sr.residual
            args = (sr.checks, sr.labels, prot, sizes[j], allowed, s0.confidence)
            values, fails = look_values(*args), rejections(*args)
        return _decided(Decision(verdict, sizes[j], ev, "", j + 1, exact, simulated, values),
                        fails, short)

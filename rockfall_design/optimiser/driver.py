"""The optimiser's one driver: a section, or the scenarios of a study, family by family.

A single section is a study of one scenario. :func:`optimise` sets every
scenario up alike (:func:`~.scenario.set_up`), searches the families of
candidate measures (:func:`search_families`) and, in each family, merges
the scenarios' screened designs into one stream in order of cost, decided
by :class:`~.settle.FamilyDecision`; with ground edits, the lattice next to
the chosen design is run too (:meth:`~.search.EditSearch.around`). With
``design.scenarios`` a design must hold in the study's required scenarios,
each with its own rocks and seed, never rocks pooled across them.
"""

from __future__ import annotations

import functools
import heapq
import math
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..judge.bounds import fraction_upper_bound
from ..run.reach import reaches_protected_zone
from ..studies.sampling import ScenarioRun, required_scenarios, scenario_runs
from .alternatives import (
    FRESH_OFFSET,
    SEARCH_SEED,
    AcrossOutcome,
    Alternative,
    Listed,
    SearchOutcome,
)
from .scenario import Scenario, set_up
from .search import EditSearch, Screened, Tally, barrier_designs
from .settle import FamilyDecision
from .space import families, family_name

if TYPE_CHECKING:  # pragma: no cover
    from ..judge.candidates import CandidateSpec
    from ..plugins import Registry
    from ..project import Project

__all__ = ["FamilyTask", "FamiliesSearched", "optimise", "search_families"]


@dataclass(frozen=True)
class FamilyTask:
    """One family to search, as the loop hands it to ``search_family``.

    Attributes
    ----------
    family : tuple of int
        Its candidates' indices.
    seed : int
        The seed of its search over ground edits: the same for every run seed,
        since which geometries are tried should not change with the rocks.
    limit : float
        Cost of the cheapest design that holds so far (inf before one does): a
        dearer design cannot be the answer.
    """

    family: tuple[int, ...]
    seed: int
    limit: float


@dataclass
class FamiliesSearched:
    """What the loop found: every family's alternative, the best, the work done."""

    alternatives: list[Alternative]
    best: Alternative | None
    exact_evaluations: int
    rocks_simulated: int
    marginal: list[Listed]


def search_families(
    fams: Sequence[tuple[int, ...]],
    candidates: Sequence[CandidateSpec],
    currency: str,
    search_family: Callable[[Alternative, FamilyTask], int],
    evaluations: Callable[[], int],
    progress: Callable[[str, int, int], None] | None = None,
) -> FamiliesSearched:
    """Search every family with ``search_family``; the cheapest that holds is the best.

    Parameters
    ----------
    fams : sequence of tuple of int
        The families of candidate measures (``optimise.space.families``).
    candidates : sequence of CandidateSpec
        The design section's candidates (for the families' names).
    currency : str
        For the reason of a family cut short by a cheaper one.
    search_family : callable
        ``search_family(alt, task) -> rocks simulated``: searches and decides
        one family, filling ``alt`` (its design, proof, marginal and undecided
        designs, and its own reason when no design holds).
    evaluations : callable
        The screening's evaluations so far (for each family's count).
    progress : callable, optional
        Called as ``progress(stage, done, total)`` with stages ``search`` and
        ``check``.

    Returns
    -------
    FamiliesSearched
    """
    # Families with fewer measures first: the cheapest design that holds so far
    # bounds what the later families need to look at (a dearer design cannot be
    # the answer), and the report says so for a family cut short by it.
    order = sorted(range(len(fams)), key=lambda i: (len(fams[i]), i))
    found: dict[int, Alternative] = {}
    limit = math.inf
    exact_total = simulated = 0
    for done, fi in enumerate(order):
        fam = fams[fi]
        if progress:
            progress("search", done, len(fams))
        ft = time.perf_counter()
        ev0 = evaluations()
        alt = Alternative(name=family_name(candidates, fam), family=fam)
        fam_seed = int(np.random.SeedSequence([SEARCH_SEED, fi]).generate_state(1)[0])
        simulated += search_family(alt, FamilyTask(fam, fam_seed, limit))
        if progress:
            progress("check", done + 1, len(fams))
        alt.evaluations = evaluations() - ev0
        alt.wall_s = time.perf_counter() - ft
        if not alt.holds_on_fresh_rocks and not alt.dominated:
            if math.isfinite(limit):
                alt.reason = (f"no design of this family cheaper than the best so far "
                              f"({limit:,.0f} {currency}) holds: {alt.reason}")
        elif alt.holds:
            limit = min(limit, alt.cost)
        exact_total += alt.exact_evaluations
        found[fi] = alt
    alternatives = [found[i] for i in range(len(fams))]
    pool = [a for a in alternatives if a.holds]
    best = min(pool, key=lambda a: a.cost) if pool else None
    # Marginal designs cheaper than the chosen one (all of them when none holds).
    top = math.inf if best is None else best.cost
    marginal = sorted((m for a in alternatives for m in a.marginal if m.cost < top),
                      key=lambda m: m.cost)
    return FamiliesSearched(alternatives=alternatives, best=best, exact_evaluations=exact_total,
                            rocks_simulated=simulated, marginal=marginal)


def optimise(
    project: Project,
    registry: Registry,
    *,
    rocks: int | None = None,
    seed: int | None = None,
    progress: Callable[[str, int, int], None] | None = None,
) -> SearchOutcome:
    """The cheapest design of every family that holds, proven on fresh rocks.

    Parameters
    ----------
    project : Project
        With a ``design:`` section (and ``study:`` with ``design.scenarios``
        for a design across scenarios).
    registry : Registry
    rocks : int, optional
        Search rocks of every scenario (default ``rocks.count``; at least the
        rocks that can show the residual target).
    seed : int, optional
        The run seed (default ``rocks.seed``); the scenarios' seeds derive from it.
    progress : callable, optional
        Called as ``progress(stage, done, total)``.

    Returns
    -------
    SearchOutcome
        An :class:`~.alternatives.AcrossOutcome` with ``design.scenarios``.

    Notes
    -----
    Each family's designs are screened cheapest first
    (:func:`~.search.barrier_designs`, :class:`~.search.EditSearch`); those
    that pass the screening, or miss it within its margin, are decided in
    order of cost (:class:`~.settle.FamilyDecision`: admitted only with the
    confidence bounds, in the required scenarios) and the first admitted one
    is verified on fresh rocks: an independent seed and at least twice the
    rocks that decided it. A design that fails there is not chosen; the next
    one in order of cost is decided. The best design overall is the cheapest
    family design that holds.
    """
    t0 = time.perf_counter()
    s = int(project.rocks.seed if seed is None else seed)
    across = project.design is not None and project.design.scenarios is not None
    runs = scenario_runs(project, s) if across else [ScenarioRun(0, {}, s, project)]
    share = project.design.scenario_share if across else None
    share = 1.0 if share is None else share
    required = required_scenarios(share, len(runs))
    scs = [set_up(run, registry, rocks) for run in runs]
    spec = scs[0].spec
    fams = families(spec.candidates, spec.max_measures)
    currency = getattr(spec.cost_model.params, "currency", "")
    per_family: dict[str, dict[str, Any]] = {}
    if min(sc.allowed for sc in scs) <= 0.0:
        # No number of rocks shows that none reaches the zone: nothing can be
        # admitted with confidence, whatever the search found. Say so, at once.
        why = ("design.residual allows no rock to reach the protected zone: no number of "
               "rocks shows that with confidence, so no design can be admitted; write the "
               "fraction you can accept, e.g. residual: {fraction: 0.001}")
        searched = FamiliesSearched([Alternative(name=family_name(spec.candidates, fam),
                                                 family=fam, reason=why) for fam in fams],
                                    None, 0, 0, [])
        return _result(scs, searched, why, s, t0, currency, across, share, required,
                       per_family)

    searched = search_families(fams, spec.candidates, currency,
                               functools.partial(search_family, scs, required, per_family),
                               lambda: sum(sc.screen.evaluations for sc in scs), progress)
    reason = "" if searched.best is not None else (
        "no family of candidate measures has a design that holds"
        + (f" in {required} of {len(scs)} scenarios" if across else "")
        + f" with {100 * scs[0].looks.confidence:g} % confidence and on fresh rocks; "
        "see each family's reason")
    return _result(scs, searched, reason, s, t0, currency, across, share, required, per_family)


def search_family(scs: Sequence[Scenario], required: int,
                  per_family: dict[str, dict[str, Any]], alt: Alternative,
                  task: FamilyTask) -> int:
    """Search and decide one family in every scenario; returns the rocks simulated.

    The ``search_family`` of :func:`search_families` (with the scenarios,
    the scenarios required and where the chosen design's scenario report
    goes bound first). Each scenario's screened designs (barriers
    enumerated, ground edits searched, :mod:`.search`) are merged in order
    of cost and decided (:meth:`~.settle.FamilyDecision.settle`); with
    ground edits, the lattice next to the chosen design is run and decided
    too until no cheaper design holds there.
    """
    tallies = [Tally() for _ in scs]
    family = FamilyDecision(alt, scs, required, tallies)
    edits: list[EditSearch | None] = []
    streams: list[Iterable[Screened]] = []
    for sc, tally in zip(scs, tallies, strict=True):
        edits.append(None)
        if any(ci in sc.screen.edit_candidates for ci in task.family):
            edits[-1] = EditSearch(sc.screen, sc.slots, task.family, tally, task.limit)
            streams.append(edits[-1].run(task.seed))
        else:
            streams.append(barrier_designs(sc.screen, sc.slots, list(task.family), [],
                                           0.0, sc.screen.bare, 0, tally,
                                           cost_limit=task.limit))
    rocks = family.settle(_merged(streams))
    while any(edits) and alt.holds:
        # The lattice next to the chosen ground edit, which the search's
        # samples may have missed at this seed (EditSearch.around), in every
        # scenario (each has its own rocks, so its own lattice runs).
        chosen = alt.cost
        near = [[] if e is None else e.around(alt.measures, chosen) for e in edits]
        if not any(near):
            break
        rocks += family.settle(_merged(near))
        if not alt.cost < chosen:
            break
        # What was listed as cheaper than the earlier choice and is not
        # cheaper than this one is no longer an alternative to it.
        alt.marginal = [m for m in alt.marginal if m.cost < alt.cost]
    if not alt.holds_on_fresh_rocks and not alt.dominated:
        alt.reason = alt.reason or family.cause()
    elif alt.holds:
        alt.proof = family.proof()
        if family.scenarios_report is not None:
            per_family[alt.name] = family.scenarios_report
    return rocks


def _merged(streams: Sequence[Iterable[Screened]]) -> Iterator[Screened]:
    """The scenarios' streams as one, in order of cost, each design once (tagged with its
    scenario: the first whose stream reached it)."""
    if len(streams) == 1:
        yield from streams[0]
        return
    seen: set[tuple] = set()
    for d in heapq.merge(*(_tagged(j, st) for j, st in enumerate(streams)),
                         key=lambda d: d.cost):
        key = tuple(sorted((m.kind, repr(sorted(m.params.model_dump(mode="json").items())))
                           for m in d.measures))
        if key not in seen:
            seen.add(key)
            yield d


def _tagged(j: int, stream: Iterable[Screened]) -> Iterator[Screened]:
    """Scenario ``j``'s designs, each tagged as found by its search."""
    for d in stream:
        d.scenario = j
        yield d


def _result(scs: Sequence[Scenario], searched: FamiliesSearched, reason: str, s: int,
            t0: float, currency: str, across: bool, share: float, required: int,
            per_family: dict[str, dict[str, Any]]) -> SearchOutcome:
    """The search's result (with the scenarios' report across a study)."""
    best, n = searched.best, max(sc.screen.n for sc in scs)
    spec = scs[0].spec
    # Without a design, the fresh seed of the run seed (each scenario has its own).
    fresh_seed = (best.fresh_seed if best is not None and best.fresh_seed is not None
                  else int(spec.fresh_seed) if spec.fresh_seed is not None
                  else s + FRESH_OFFSET)
    common = dict(
        alternatives=searched.alternatives, best=best, reason=reason,
        rocks=best.decision_rocks if best is not None else n, seed=s,
        fresh_rocks=best.fresh_rocks if best is not None else 2 * n, fresh_seed=fresh_seed,
        wall_s=time.perf_counter() - t0,
        evaluations=sum(sc.screen.evaluations for sc in scs),
        edit_runs=sum(sc.screen.edit_runs for sc in scs), currency=currency, search_rocks=n,
        confidence=scs[0].looks.confidence, exact_evaluations=searched.exact_evaluations,
        rocks_simulated=searched.rocks_simulated + sum(
            sc.screen.n + sc.screen.edit_rocks + sc.decider.simulated for sc in scs),
        marginal=list(searched.marginal), decided=sum(a.exact_evaluations
                                                for a in searched.alternatives))
    if across:
        return AcrossOutcome(**common, share=share, required=required,
                             runs=[sc.run for sc in scs], per_family=per_family)
    return SearchOutcome(**common, looks=scs[0].looks,
                         bare_slope=bare_slope(scs[0]))


def bare_slope(sc: Scenario) -> dict[str, Any] | None:
    """The bare slope's residual on the search rocks, and whether it already meets the target.

    A project whose bare slope meets its residual target with confidence
    needs no measure for it; every design then holds by the residual alone,
    and the cheapest is only the cheapest place where a measure meets no rock.
    The report says so at its head. One look at the search rocks with the
    Clopper-Pearson upper bound at the project's confidence.

    Returns ``{x, reaching, rocks, upper, allowed, holds}`` (None without a
    protected zone).

    See Also
    --------
    rockfall_design.judge.bounds.fraction_upper_bound
    """
    screen = sc.screen
    if screen.project.protect is None:
        return None
    reach = reaches_protected_zone(screen.bare.max_x, screen.bare.status, screen.protect_x)
    k, n = int(np.count_nonzero(reach)), screen.n
    upper = fraction_upper_bound(k, n, sc.looks.confidence)
    return {"x": float(screen.protect_x), "reaching": k, "rocks": n, "upper": upper,
            "allowed": float(sc.allowed), "holds": bool(upper <= sc.allowed)}

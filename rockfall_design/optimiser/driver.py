"""The one family loop of the optimiser, for one section and for the scenarios of a study.

Both drivers (:func:`rockfall_design.optimiser.section.optimise` and
:func:`rockfall_design.optimiser.across.optimise_across`) search the families
of candidate measures the same way: families with fewer measures first, each
with its own search seed, the cheapest design that holds so far bounding what
the later families need to look at, progress by stage, and the best design
the cheapest family design that holds. What differs is how one family is
searched and decided, which each driver gives as ``search_family``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .alternatives import SEARCH_SEED, Alternative
from .space import family_name

if TYPE_CHECKING:  # pragma: no cover
    from ..judge.candidates import CandidateSpec


@dataclass(frozen=True)
class FamilyTask:
    """One family to search, as the loop hands it to a driver.

    Attributes
    ----------
    index : int
        The family's index in ``families(...)`` (the report's order).
    family : tuple of int
        Its candidates' indices.
    seed : int
        The seed of its search over ground edits: the same for every run seed,
        since which geometries are tried should not change with the rocks.
    limit : float
        Cost of the cheapest design that holds so far (inf before one does): a
        dearer design cannot be the answer.
    """

    index: int
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
    marginal: list[dict[str, Any]]


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
        simulated += search_family(alt, FamilyTask(fi, fam, fam_seed, limit))
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
    marginal = sorted((m for a in alternatives for m in a.marginal if m["cost"] < top),
                      key=lambda m: m["cost"])
    return FamiliesSearched(alternatives=alternatives, best=best, exact_evaluations=exact_total,
                            rocks_simulated=simulated, marginal=marginal)

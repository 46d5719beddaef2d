"""Least-cost design: the cheapest admissible design of every family, proven on fresh rocks.

How it works, with common random numbers (every design sees the same rocks):

1. One run of the search rocks on the bare slope keeps, at stations every
   :data:`STATION_STEP_M` along every barrier candidate's range, each rock's
   passing height, energy and speed at its first passage downslope, and at
   restart stations upslope of every ground-edit candidate each rock's full
   state (``engine.run_ensemble``).
2. Screening (:class:`Screening`) judges a design on those rocks through the
   one judgement (:mod:`rockfall_design.judge.outcomes`): barriers from the
   table, ground edits by a run of only the rocks that pass the restart
   station just upslope of the edit, resumed from their saved state.
3. Search. Catalogue choices (products and heights, options) are discrete
   and few: they are enumerated, in increasing order of cost. Barrier
   positions are enumerated on the station grid: for each combination of
   catalogue choices the rocks reaching the protected zone are counted for
   every combination of stations at once (bit sets), and the combinations
   within the residual target are screened in full. Ground edits (ditch,
   berm), whose every geometry costs a run, are searched with
   ``scipy.optimize.differential_evolution`` over their lattice, the
   barriers beside them enumerated exactly for each geometry.
4. Decision (:class:`~.decide.Decider`), sequential. The screening rejects
   a design only when some check or the residual fails with confidence
   (its favourable bound misses the target) on rocks it judged exactly.
   The rest is decided in order of cost, look by look with more rocks
   (:mod:`rockfall_design.judge.sequential`: the looks and the confidence
   of each fixed in advance, so that looking again inflates neither
   error): admitted when every check and the residual hold with their
   upper bounds, rejected when one fails with its lower bound, and
   *marginal* when still undecided at ``design.max_rocks``: never admitted,
   and listed when it is cheaper than the chosen design.
5. Verification. The first admitted design of a family is checked on fresh
   rocks: an independent seed and at least twice the rocks that decided it.
   If it fails there, the next design in order of cost is decided: a family
   is never dropped because its first candidate failed.

What the screening leaves out (a rock that breaks through a barrier goes on
with its bare-slope path and full energy; a rock returned by a wall stays
upslope of it; the gap passage of a boulder row is drawn from another
stream) is settled by the exact decision, which is why designs that miss the
screening by a small margin are decided exactly too.

The strategy seam: a family's designs come from :mod:`.search`
(:func:`~.search.barrier_designs` with :class:`~.search.BarrierSlots`,
:class:`~.search.EditSearch`), are decided by :class:`~.settle.FamilyDecision`
in every scenario (:mod:`.scenario`; one on a single section), and
:func:`~.driver.optimise` drives the families. What a search found is a
:class:`~.alternatives.SearchOutcome` (:mod:`.alternatives`, with each
family's :class:`~.alternatives.Alternative`), which the API hands out inside
the public :class:`rockfall_design.results.OptimiseResult`.

A design that does not fit (a measure's ``footprint`` raises ValueError, two
measures stand in one place) or that the cost model has no price for (its
``cost`` raises KeyError or ValueError) is not part of the design space.
Any other failure of plugin code is a
:class:`~rockfall_design.errors.PluginError` that stops the search (exit 3).
"""

from __future__ import annotations

from .alternatives import Alternative, SearchOutcome
from .decide import Decider, Decision, decide
from .driver import optimise
from .screening import RESTART_STEP_M, Screening, ScreenResult
from .space import (
    BARRIER_RANGE_STEPS,
    EDIT_STEP_M,
    RANGE_STEPS,
    STATION_STEP_M,
    candidate_name,
    families,
    family_name,
)

__all__ = [
    "BARRIER_RANGE_STEPS",
    "EDIT_STEP_M",
    "RANGE_STEPS",
    "RESTART_STEP_M",
    "STATION_STEP_M",
    "Alternative",
    "Decider",
    "Decision",
    "SearchOutcome",
    "ScreenResult",
    "Screening",
    "candidate_name",
    "decide",
    "families",
    "family_name",
    "optimise",
]



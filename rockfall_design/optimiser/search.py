"""Search: a family's designs, cheapest first, screened.

Catalogue choices in increasing order of cost; for each, every combination
of barrier stations at once (the rocks each barrier lets on for sure, one
matrix product), the first barrier's own checks as a filter, full screening
of the rest (:func:`barrier_designs`). Ground edits by
``scipy.optimize.differential_evolution`` over their lattice, the barriers
beside them enumerated for each geometry (:class:`EditSearch`).
"""

from __future__ import annotations

import heapq
import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from itertools import chain
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy.optimize import differential_evolution

from ..engine import columns
from ..errors import ProjectError
from ..judge.evaluation import check_slack
from ..judge.outcomes import RockFates, barrier_outcomes, judge_measures
from ..judge.placing import MIN_BARRIER_SPACING_M, PlacedMeasure, edited_section, place_measures
from ..plugins import guard
from ..plugins.measure import Barrier, BarrierBehaviour, ProfileEdit
from ..run.reach import reaches_protected_zone

if TYPE_CHECKING:  # pragma: no cover
    from ..plugins.measure import ProtectiveMeasure

from .screening import Screening, ScreenResult, Table
from .space import (
    STATION_STEP_M,
    Option,
    decode,
    discrete_choices,
    lattice,
    variables_of,
)

#: Placements of one combination of catalogue choices screened in full: those that may
#: hold on the search rocks first, then fewest through (:func:`_capped`).
MAX_SCREENS_PER_LEVEL = 80
#: Designs of one combination of catalogue choices decided exactly, at most.
MAX_EXACT_PER_LEVEL = 3
#: The search over ground edits ranks a design the search rocks leave undecided
#: as this many times its cost (one they admit at its cost, one they reject
#: above every design's cost).
UNDECIDED_HANDICAP = 1.1


class BarrierSlots:
    """The barrier options of every barrier candidate, built and priced once per run.

    Per table (bare, or edited by a ground edit) and option, lazily: which
    rocks it lets on for sure (neither stopped nor broken through, see
    :meth:`passes`), which reach the protected zone with it alone as the
    screening counts them (:meth:`reaching`) and whether its checks hold
    as the first barrier the rocks meet (:meth:`first_ok`, :meth:`first_holds`).
    """

    def __init__(self, screen: Screening) -> None:
        self.screen = screen
        self.options: dict[int, list[Option]] = {}
        self.skipped: dict[int, Counter] = {}
        self._rows: dict[tuple[int, int, int], np.ndarray] = {}
        self._alone: dict[tuple[int, int], np.ndarray] = {}
        self._stations: dict[int, np.ndarray] = {}  # per candidate: each option's table column
        self._reach: dict[tuple[int, int, int], np.ndarray] = {}
        # Outcome codes first_ok computed, for passes() of the same level (both
        # ask for the options of the level at hand): (ci, k, table key) -> codes.
        self._recent: dict[tuple[int, int, int], np.ndarray] = {}

    def of(self, ci: int) -> list[Option]:
        """Options of candidate ``ci`` (every catalogue choice at every grid station)."""
        if ci in self.options:
            return self.options[ci]
        sc = self.screen
        c = sc.spec.candidates[ci]
        out: list[Option] = []
        skipped: Counter = Counter()
        for d in discrete_choices(c):
            for x in lattice(*c.x_range, STATION_STEP_M):
                params = {**d, "x": float(x)}
                try:
                    (m,) = sc.measures([(ci, params)])
                    fp = guard(sc.registry).measure(m).footprint(sc.section)
                    guard(sc.registry).measure(m).design_properties()
                except ValueError as exc:
                    # Does not fit here: not part of the space.
                    skipped[f"does not fit: {exc}"] += 1
                    continue
                try:
                    cost = sc.cost([m])
                except (KeyError, ValueError) as exc:
                    # The cost model's contract: no price skips the design.
                    why = exc.args[0] if exc.args else type(exc).__name__
                    skipped[f"cost model {sc.spec.cost_model.name!r} has no price for this "
                            f"design: {why}"] += 1
                    continue
                if not isinstance(fp, Barrier):
                    continue
                out.append(Option(ci, params, m, fp, cost,
                                   guard(sc.registry).measure(m).label(), sc.station(fp.x)))
        self.options[ci] = out
        self.skipped[ci] = skipped
        return out

    @staticmethod
    def _table_key(j: int, table: Table, table_id: int) -> int:
        # Stations upslope of an edit's restart see the bare table: share them.
        return 0 if (table.rows is None or j < table.first_col) else table_id

    def _outcome(self, o: Option, table: Table) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                           np.ndarray]:
        sc = self.screen
        h, e_kj, v = table.column(o.j)
        out = barrier_outcomes(o.footprint, h, e_kj, sc.radius, sc.u_gap,
                               np.ones(sc.n, dtype=bool))
        return out, h, e_kj, v

    def passes(self, ci: int, ks: np.ndarray, table: Table, table_id: int) -> np.ndarray:
        """(len(ks), rocks) float32: 1 where option k lets the rock on for sure.

        A rock it stops (catches or returns) is 0, and so is one whose further
        path the screening only approximates (broken through; any rock at a
        row of blocks, whose gap draws come from another stream).
        """
        opts = self.options[ci]
        out = np.empty((len(ks), self.screen.n), dtype=np.float32)
        for i, k in enumerate(ks):
            key = (ci, int(k), self._table_key(opts[k].j, table, table_id))
            row = self._rows.get(key)
            if row is None:
                o = opts[k]
                oc = self._recent.get(key)
                if oc is None:
                    oc = self._outcome(o, table)[0]
                row = (oc == columns.O_NOT_MET) | (oc == columns.O_PASSED_OVER) | (
                    oc == columns.O_PASSED_THROUGH_GAP)
                if o.footprint.behaviour == BarrierBehaviour.BLOCKS:
                    row = oc == columns.O_NOT_MET
                if len(self._rows) > 100_000:
                    self._rows.clear()
                self._rows[key] = row
            out[i] = row
        return out

    def first_ok(self, ci: int, ks: np.ndarray, table: Table, table_id: int) -> np.ndarray:
        """Do options ks pass their checks as the first barrier the rocks meet?

        The first barrier of a design meets every rock that crosses its station
        on the table, so these are exactly its checks in any design in which no
        other barrier stands upslope of it (edits upslope are in the table).
        Only checks that fail with confidence (their favourable bound misses
        the target) count as failed: the rest is left to more rocks.
        """
        return self.first_codes(ci, ks, table, table_id) >= 1

    def first_holds(self, ci: int, ks: np.ndarray, table: Table, table_id: int) -> np.ndarray:
        """Do options ks meet their checks on the point values as the first barrier?

        As :meth:`first_ok`, with the point values in place of the bounds: a
        design whose first barrier misses them does not hold on the search rocks.
        """
        return self.first_codes(ci, ks, table, table_id) == 2

    def first_codes(self, ci: int, ks: np.ndarray, table: Table, table_id: int) -> np.ndarray:
        """Per option, its checks as the first barrier: 0 some fails with confidence, 1 none
        does but some misses on its point value, 2 every one meets its target there
        (:meth:`first_ok` is ``>= 1``, :meth:`first_holds` ``== 2``).

        Judged once per option and table (an option upslope of an edit's first
        changed station shares the bare table's); the rest is a look-up, by
        array: a level asks for every station of its catalogue choices.
        """
        ks = np.asarray(ks, dtype=np.intp)
        js = self._stations.get(ci)
        if js is None:
            js = self._stations[ci] = np.array([o.j for o in self.options[ci]], dtype=np.intp)
        # The table each option reads (_table_key, for all of ks at once).
        keys = (np.zeros(ks.size, dtype=np.intp) if table.rows is None
                else np.where(js[ks] < table.first_col, 0, table_id))
        out = np.empty(ks.size, dtype=np.int8)
        for tk in np.unique(keys).tolist():
            sel = keys == tk
            arr = self._alone.get((ci, tk))
            if arr is None:
                arr = self._alone[(ci, tk)] = np.full(len(self.options[ci]), -1, dtype=np.int8)
            for k in ks[sel][arr[ks[sel]] < 0].tolist():
                if arr[k] < 0:  # (a k given twice is judged once)
                    arr[k] = self._judge_first(ci, k, tk, table)
            out[sel] = arr[ks[sel]]
        return out

    def _judge_first(self, ci: int, k: int, tk: int, table: Table) -> int:
        """The code of :meth:`first_codes` of option ``k`` of candidate ``ci`` on ``table``."""
        sc = self.screen
        o = self.options[ci][k]
        oc, h, e_kj, v = self._outcome(o, table)
        if len(self._recent) >= 4096:
            self._recent.clear()
        self._recent[(ci, k, tk)] = oc
        placed = PlacedMeasure(0, o.measure, o.footprint, o.label)
        fates = RockFates(max_x=table.max_x, x_end=table.x_end, status=table.status,
                          mass=sc.mass, radius=sc.radius)
        (res,) = judge_measures([placed], [oc], [np.column_stack([h, v, e_kj])],
                                fates, None).results
        checks = guard(sc.registry).concept(sc.concept).checks(res)
        return 0 if any(c.rejects for c in checks) else 2 if all(c.ok for c in checks) else 1

    def reaching(self, ci: int, ks: np.ndarray, table: Table, table_id: int) -> np.ndarray:
        """(len(ks), rocks) float32: 1 where the rock reaches the protected zone with option
        k alone on the table, as the screening counts it
        (:meth:`~.screening.Screening.reaching_with`): a rock it lets on or breaks through
        goes on along its path.

        A rock reaches with several barriers only if it reaches with each alone
        (the product of their rows), but for a rock a net upslope carries into
        the zone by its braking distance: the product is a lower bound of the
        screening's count, exact for one barrier.
        """
        opts = self.options[ci]
        out = np.empty((len(ks), self.screen.n), dtype=np.float32)
        for i, k in enumerate(ks):
            o = opts[k]
            # Its outcomes are those of the bare table upslope of an edit, but
            # the rocks' fates below it are the table's own: one row per table.
            key = (ci, int(k), table_id)
            row = self._reach.get(key)
            if row is None:
                oc = self._recent.get((ci, int(k), self._table_key(o.j, table, table_id)))
                if oc is None:
                    oc = self._outcome(o, table)[0]
                if len(self._reach) > 100_000:
                    self._reach.clear()
                row = self._reach[key] = self.screen.reaching_with(o.footprint, oc, table)
            out[i] = row
        return out


@dataclass
class Screened:
    """A design that passed the screening (or missed it within the margin).

    Attributes
    ----------
    cost : float
        In the cost model's currency.
    measures : list of ProtectiveMeasure
    result : ScreenResult
        Its screening on the search rocks of its scenario.
    level : tuple
        Its combination of catalogue choices (or edit geometry): the
        decisions of one level are budgeted together.
    scenario : int
        The scenario whose search found it (0 on a single section).
    """

    cost: float
    measures: list[ProtectiveMeasure]
    result: ScreenResult
    level: tuple
    scenario: int = 0


@dataclass
class Tally:
    """What the designs of a family that were ruled out failed on (for the report).

    One per scenario and family: the search counts the designs it screened and
    why they failed, the decisions what they ruled out (``reasons``).
    """

    reasons: Counter = field(default_factory=Counter)
    designs: int = 0
    capped_levels: int = 0
    best_fail: ScreenResult | None = None
    min_residual: int | None = None
    over_limit: float | None = None  # cost of the first design past the cost limit
    why: str = ""  # why the first design that did not fit did not
    searched: bool = False  # ground edits searched by scipy, not enumerated

    @staticmethod
    def merged(tallies: Sequence[Tally]) -> Tally:
        """One tally of several scenarios' (itself for one): reasons summed, the designs and
        capped levels of the scenario with most (each searches the same space)."""
        if len(tallies) == 1:
            return tallies[0]
        out = Tally(designs=max(t.designs for t in tallies),
                    capped_levels=max(t.capped_levels for t in tallies),
                    searched=any(t.searched for t in tallies))
        for t in tallies:
            out.reasons.update(t.reasons)
        return out

    def fail(self, sr: ScreenResult) -> None:
        """Count a design the screening rejected, and keep the one closest to holding."""
        names = [c.name for cs in sr.checks for c in cs if not c.ok]
        if sr.reason:
            names = ["does not fit"]
        for nm in names:
            self.reasons[nm] += 1
        if sr.residual > 0 and not names:
            self.reasons["residual"] += 1
        if self.best_fail is None or sr.violation < self.best_fail.violation:
            self.best_fail = sr


def _through(reach: np.ndarray, passes: Sequence[np.ndarray]) -> np.ndarray:
    """Rocks through every barrier for each combination of options: (n1, n2, ...).

    ``sum_r reach[r] * P1[a, r] * P2[b, r] * ...``: one matrix product for
    one or two barriers (float32 counts are exact below 2**24 rocks).
    Only the rocks that reach the zone and that some option of every barrier
    lets on can count: the sum runs over those alone (often a few dozen of
    thousands once a barrier stands upslope; the others add zero to every
    combination).
    """
    cols = reach > 0
    for p in passes:
        cols &= p.any(axis=0)
    keep = np.flatnonzero(cols)
    reach = reach[keep]
    passes = [p[:, keep] for p in passes]
    first = passes[0] * reach
    if len(passes) == 1:
        return np.rint(first.sum(axis=1)).astype(np.int64)
    if len(passes) == 2:
        return np.rint(first @ passes[1].T).astype(np.int64)
    return np.stack([_through(first[a], list(passes[1:])) for a in range(first.shape[0])])


def _level_combos(levels: list[np.ndarray]) -> Any:
    """Tuples of level indices, one per slot, in increasing order of summed cost."""
    start = tuple(0 for _ in levels)
    heap = [(float(sum(lv[0] for lv in levels)), start)]
    seen = {start}
    while heap:
        cost, idx = heapq.heappop(heap)
        yield cost, idx
        for s in range(len(levels)):
            if idx[s] + 1 < len(levels[s]):
                nxt = idx[:s] + (idx[s] + 1,) + idx[s + 1:]
                if nxt not in seen:
                    seen.add(nxt)
                    c = cost - levels[s][idx[s]] + levels[s][idx[s] + 1]
                    heapq.heappush(heap, (c, nxt))


def barrier_designs(
    screen: Screening,
    slots: BarrierSlots,
    barrier_cis: Sequence[int],
    fixed: Sequence[ProtectiveMeasure],
    fixed_cost: float,
    table: Table,
    table_id: int,
    tally: Tally,
    cost_limit: float = math.inf,
    level_id: int | None = None,
) -> Any:
    """Designs of ``fixed`` measures plus one barrier per ``barrier_cis``, cheapest first.

    Every combination of the barriers' catalogue choices and grid stations is
    considered. Catalogue choices are taken in increasing order of cost; for
    each, the rocks reaching the protected zone are counted for every
    combination of stations at once (bit sets of the rocks each barrier would
    stop, judged by :func:`~rockfall_design.judge.outcomes.barrier_outcomes`);
    the combinations within the residual target (plus the screening margin)
    are screened in full, fewest reaching first, and those that pass (or
    miss within the margin) are yielded as :class:`Screened`, in order of
    cost. Yields nothing more once the cost exceeds ``cost_limit``. A design's level
    begins with ``level_id`` (``table_id`` by default; see :meth:`EditSearch._level_id`).
    """
    fixed = list(fixed)
    level_id = table_id if level_id is None else level_id
    if not barrier_cis:
        if fixed_cost <= cost_limit:
            sr = screen.screen(fixed)
            tally.designs += 1
            if sr.feasible or sr.near:
                # One level per geometry, its stations together: MAX_EXACT_PER_LEVEL
                # counts the placements of a geometry.
                yield Screened(sr.cost, fixed, sr, (level_id,))
            else:
                tally.fail(sr)
        return
    opts = [slots.of(ci) for ci in barrier_cis]
    if any(not o for o in opts):
        return
    costs = [np.array([o.cost for o in op]) for op in opts]
    levels = [np.unique(c) for c in costs]
    members = [[np.flatnonzero(c == lv) for lv in lvs] for c, lvs in zip(costs, levels,
                                                                          strict=True)]
    reach = reaches_protected_zone(table.max_x, table.status, screen.protect_x).astype(
        np.float32)
    edits = [guard(screen.registry).measure(m).footprint(screen.section) for m in fixed]
    stretches = [(e.x_start, e.x_end) for e in edits if isinstance(e, ProfileEdit)]
    limit = _most_through(screen)
    k_slots = len(opts)
    for level_cost, idx in _level_combos(levels):
        total = fixed_cost + level_cost
        if total > cost_limit:
            tally.over_limit = total if tally.over_limit is None else min(tally.over_limit, total)
            return
        ks = [members[s][idx[s]] for s in range(k_slots)]
        valid, all_ok, first_holds = _placements(slots, barrier_cis, opts, ks, stretches,
                                                 table, table_id, tally)
        if not valid.any():
            continue
        residual = _residuals(slots, barrier_cis, ks, valid, reach, table, table_id, tally)
        ok = residual <= limit
        tally.reasons["residual"] += int((valid & ~ok).sum())
        cand = np.flatnonzero(ok.ravel())
        if cand.size == 0:
            continue
        # Placements whose every barrier holds on its own first, then fewest through.
        order = cand[np.lexsort((residual.ravel()[cand], ~all_ok.ravel()[cand]))]
        if order.size > MAX_SCREENS_PER_LEVEL:
            tally.capped_levels += 1
            order = _capped(screen, slots, barrier_cis, ks, valid, first_holds, order,
                            table, table_id)
        found = _screen_placements(screen, opts, ks, fixed, order, residual.shape, table,
                                   (level_id,) + tuple(idx), tally)
        # Within one level of cost, designs that pass come before those within the margin.
        found.sort(key=lambda d: (d.cost, not d.result.feasible, d.result.violation,
                                  d.result.residual))
        yield from found


def _capped(screen: Screening, slots: BarrierSlots, barrier_cis: Sequence[int],
            ks: list[np.ndarray], valid: np.ndarray, first_holds: np.ndarray,
            order: np.ndarray, table: Table, table_id: int) -> np.ndarray:
    """The :data:`MAX_SCREENS_PER_LEVEL` placements of a level screened, of ``order``.

    Those that may hold on the search rocks come first: their first barrier
    meets its checks on the point values (it meets every rock) and no more
    rocks reach the zone than allowed with every barrier standing alone
    (:meth:`BarrierSlots.reaching`: a lower bound of the screening's count).
    A placement that fails either does not hold there. For one barrier the
    two are exactly what the screening asks of a design on point values, so
    no placement that holds is dropped for one that does not. Ranked by
    rocks through for sure alone, design_two_zones at seed 14 never screened
    the 339,000 RX-500 at x = 137 to 139 m, which holds on the search rocks
    (more rocks through for sure, fewer broken through), while 80 placements
    nearer the toe that do not hold were. ``order`` (every barrier holding
    on its own first, then fewest through) is kept within each part.
    """
    reaching = _counts(slots.reaching, barrier_cis, ks, valid,
                       np.ones(screen.n, dtype=np.float32), table, table_id)
    may = (first_holds & (reaching <= screen.allowed_residual)).ravel()[order]
    return order[np.argsort(~may, kind="stable")][:MAX_SCREENS_PER_LEVEL]


def _shaped(a: np.ndarray, s: int, k_slots: int) -> np.ndarray:
    """``a`` along axis ``s`` of a ``k_slots``-dimensional grid of placements."""
    return a.reshape([a.shape[0] if u == s else 1 for u in range(k_slots)])


def _placements(slots: BarrierSlots, barrier_cis: Sequence[int], opts: list[list[Option]],
                ks: list[np.ndarray], stretches: list[tuple[float, float]], table: Table,
                table_id: int, tally: Tally) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Which placements of one level may hold, which have every barrier's checks hold
    on its own, and which have the first barrier's checks met on the point values:
    (valid, all_ok, first_holds), one axis per barrier.

    A placement is out when a barrier stands on a ground edit's stretch, two
    stand closer than :data:`~rockfall_design.judge.placing.MIN_BARRIER_SPACING_M`
    (or two of one candidate in the other order), or the first barrier the
    rocks meet fails its own checks: it meets every rock that crosses it, so
    its checks decide whatever stands downslope.
    """
    k_slots = len(opts)
    xs = [np.array([opts[s][k].footprint.x for k in ks[s]]) for s in range(k_slots)]
    valid = np.ones([len(k) for k in ks], dtype=bool)
    for s in range(k_slots):
        xv = _shaped(xs[s], s, k_slots)
        for lo, hi in stretches:
            valid &= ~((xv > lo + 1e-6) & (xv < hi - 1e-6))
        for t in range(s):
            xt = _shaped(xs[t], t, k_slots)
            valid &= np.abs(xv - xt) >= MIN_BARRIER_SPACING_M
            if barrier_cis[t] == barrier_cis[s]:
                valid &= xt < xv  # one order of two barriers of one candidate
    tally.designs += int(valid.size)
    xb = np.stack(np.broadcast_arrays(*[_shaped(xs[s], s, k_slots) for s in range(k_slots)]))
    first = np.argmin(xb, axis=0)
    codes = [slots.first_codes(barrier_cis[s], ks[s], table, table_id) for s in range(k_slots)]
    alone = [c >= 1 for c in codes]  # slots.first_ok
    holds = [c == 2 for c in codes]  # slots.first_holds
    first_ok = np.zeros(valid.shape, dtype=bool)
    first_holds = np.zeros(valid.shape, dtype=bool)
    all_ok = np.ones(valid.shape, dtype=bool)
    for s in range(k_slots):
        ok_s = np.broadcast_to(_shaped(alone[s], s, k_slots), valid.shape)
        first_ok |= (first == s) & ok_s
        first_holds |= (first == s) & np.broadcast_to(_shaped(holds[s], s, k_slots),
                                                      valid.shape)
        all_ok &= ok_s
    tally.reasons["first barrier's checks"] += int((valid & ~first_ok).sum())
    return valid & first_ok, all_ok, first_holds


def _residuals(slots: BarrierSlots, barrier_cis: Sequence[int], ks: list[np.ndarray],
               valid: np.ndarray, reach: np.ndarray, table: Table, table_id: int,
               tally: Tally) -> np.ndarray:
    """Rocks through every barrier for sure, per valid placement (int64 max elsewhere)."""
    residual = _counts(slots.passes, barrier_cis, ks, valid, reach, table, table_id)
    big = np.iinfo(np.int64).max
    rmin = int(residual.min())
    if rmin < big:
        tally.min_residual = rmin if tally.min_residual is None else min(tally.min_residual,
                                                                        rmin)
    return residual


def _counts(rows: Any, barrier_cis: Sequence[int], ks: list[np.ndarray], valid: np.ndarray,
            weights: np.ndarray, table: Table, table_id: int) -> np.ndarray:
    """``sum_r weights[r] * prod_s rows_s[r]`` per valid placement (int64 max elsewhere).

    ``rows(ci, ks, table, table_id)`` gives each option's row over the rocks
    (:meth:`BarrierSlots.passes`, :meth:`BarrierSlots.reaching`).
    """
    k_slots = len(ks)
    # Count only over the options that appear in some admissible placement.
    used = [np.flatnonzero(valid.any(axis=tuple(u for u in range(k_slots) if u != s)))
            for s in range(k_slots)]
    sub = _through(weights, [rows(barrier_cis[s], ks[s][used[s]], table, table_id)
                             for s in range(k_slots)])
    big = np.iinfo(np.int64).max
    out = np.full(valid.shape, big, dtype=np.int64)
    out[np.ix_(*used)] = sub
    return np.where(valid, out, big)


def _most_through(screen: Screening) -> int:
    """The most rocks through for sure that do not yet fail the residual with confidence.

    Rocks through for sure (the table knows their fate; the exact run can
    only add to them) rule a placement out only when they exceed the target
    with confidence (their Clopper-Pearson lower bound).
    """
    lo, hi = 0, screen.n
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if screen.residual_rejects(mid):
            hi = mid - 1
        else:
            lo = mid
    return lo


def _screen_placements(screen: Screening, opts: list, ks: list, fixed: list,
                       order: np.ndarray, shape: tuple, table: Table, level: tuple,
                       tally: Tally) -> list[Screened]:
    """Screen a level's placements in ``order`` (flat indices into ``shape``) in full.

    Stops once :data:`MAX_EXACT_PER_LEVEL` pass: more than the decisions this
    combination of catalogue choices gets.
    """
    k_slots = len(opts)
    found: list[Screened] = []
    passed = 0
    for flat in order:
        pos = np.unravel_index(flat, shape)
        chosen = [opts[s][ks[s][pos[s]]] for s in range(k_slots)]
        ms = fixed + [o.measure for o in chosen]
        if fixed:
            sr = screen.screen(ms)
        else:
            # Built, placed and priced once per option; their spacing is checked above.
            placed = [PlacedMeasure(i, o.measure, o.footprint, o.label)
                      for i, o in enumerate(chosen)]
            keys = [(o.ci, int(ks[s][pos[s]])) for s, o in enumerate(chosen)]
            sr = screen.screen_placed(placed, table, sum(o.cost for o in chosen), keys=keys)
        if sr.feasible or sr.near:
            found.append(Screened(sr.cost, ms, sr, level))
            passed += sr.feasible
            if passed >= MAX_EXACT_PER_LEVEL:
                break  # more than the decisions this combination gets
        else:
            tally.fail(sr)
    return found


#: Station shifts (lattice steps either way) tried with each cheaper step of a geometry.
POLISH_SHIFTS = 4


class EditSearch:
    """The search of one family with ground edits: its objective and the designs it kept.

    Every ground edit costs a run of the rocks below its restart station, so
    the edits' stations, options and continuous parameters (on a lattice, so
    that the search comes back to geometries it has run) are searched with
    ``scipy.optimize.differential_evolution`` (:meth:`run`); for each edit
    geometry the family's barriers are enumerated exactly on its table
    (:func:`barrier_designs`). Every design that passed the screening on the
    way is kept, cheapest first, for the exact decision. :meth:`around` then
    runs the lattice next to the design the decisions chose.
    """

    def __init__(self, screen: Screening, slots: BarrierSlots, fam: tuple[int, ...],
                 tally: Tally, cost_limit: float = math.inf) -> None:
        self.screen, self.slots, self.tally, self.cost_limit = screen, slots, tally, cost_limit
        self.cands = screen.spec.candidates
        tally.searched = True
        self.edit_slots = tuple(ci for ci in fam if ci in screen.edit_candidates)
        self.barrier_cis = [ci for ci in fam if ci not in screen.edit_candidates]
        self.variables = variables_of(self.cands, self.edit_slots, screen.edit_candidates)
        self.big = screen.penalty_floor
        self.seen: dict[tuple, float] = {}
        self.kept: dict[tuple, Screened] = {}
        #: A level id per edit geometry, its stations aside (see :meth:`_level_id`).
        self.geometries: dict[tuple, int] = {}

    def objective(self, vec: np.ndarray) -> float:
        """The search's value of a vector: the cost of its cheapest design the screening
        admits, with a handicap if only undecided, a penalty above every cost if none."""
        screen, tally, big = self.screen, self.tally, self.big
        decoded = decode(self.cands, self.edit_slots, self.variables, vec)
        key = tuple((ci, tuple(sorted(p.items()))) for ci, p in decoded)
        if key in self.seen:
            return self.seen[key]
        try:
            edits = screen.measures(decoded)
            # Placing first: a geometry that does not fit is out of the space
            # before the cost model is asked to price it.
            placed = place_measures(screen.project, screen.registry, edits, screen.section)
            fixed_cost = screen.cost(edits)
            if fixed_cost > self.cost_limit:
                # Dearer than a design that already holds: not worth a run.
                tally.over_limit = min(tally.over_limit or math.inf, fixed_cost)
                self.seen[key] = big + fixed_cost
                return self.seen[key]
            edited = edited_section(screen.project, screen.section, placed)
            table = screen.table_for([p.footprint for p in placed], edited)
        except (KeyError, ValueError, ProjectError) as exc:
            tally.reasons["does not fit"] += 1
            tally.why = tally.why or getattr(exc, "message", None) or str(exc)
            self.seen[key] = 4.0 * big
            return self.seen[key]
        first = next(iter(barrier_designs(screen, self.slots, self.barrier_cis, edits,
                                           fixed_cost, table, table.serial, tally,
                                           self.cost_limit, self._level_id(key))), None)
        if first is None:
            value = big + fixed_cost
        else:
            self.kept[key + tuple((m.kind, m.x) for m in first.measures)] = first
            # Admitted on the search rocks: its cost. Undecided (only more rocks
            # can tell): its cost with a handicap, so that the search still
            # explores cheap geometries that may hold, but prefers those shown.
            value = first.cost if first.result.feasible else UNDECIDED_HANDICAP * first.cost
        self.seen[key] = value
        return value

    def _level_id(self, key: tuple) -> int:
        """One level id for every station of one edit geometry (``key`` without its x):
        its placements share :data:`MAX_EXACT_PER_LEVEL` decisions, as a barrier
        product's stations do (why: docs/sequential-decisions.md, the family's decisions).
        """
        geometry = tuple((ci, tuple(kv for kv in params if kv[0] != "x")) for ci, params in key)
        return self.geometries.setdefault(geometry, len(self.geometries))

    def _designs(self, keys: Any, limit: float) -> list[Screened]:
        # Of one cost (one geometry at several stations) the placement likeliest
        # to hold first: a level's budget goes to those. Placements that pass the
        # screening all have no violation; of them the one with most slack.
        return sorted((self.kept[k] for k in keys if self.kept[k].cost <= limit),
                      key=lambda d: (d.cost, not d.result.feasible, d.result.violation,
                                     -min(map(check_slack, chain(*d.result.checks)),
                                          default=math.inf)))

    def run(self, seed: int) -> list[Screened]:
        """Differential evolution over the lattice; the designs kept, cheapest first."""
        bounds = [(v.low, v.high) for v in self.variables]
        integrality = np.array([v.integer for v in self.variables])
        differential_evolution(
            self.objective, bounds, integrality=integrality, seed=seed, popsize=6,
            maxiter=12, tol=1e-3, mutation=(0.5, 1.0), recombination=0.7, polish=False,
            init="sobol" if len(self.variables) > 1 else "latinhypercube",
        )
        return self._designs(list(self.kept), self.cost_limit)

    def _vector(self, measures: Sequence[Any]) -> np.ndarray | None:
        """The search vector of a design's ground edits (None: not one this search makes)."""
        mine: dict[str, list[Any]] = {}
        for m in sorted(measures, key=lambda m: m.x):
            mine.setdefault(m.kind, []).append(m)
        by_slot = []
        for ci in self.edit_slots:
            same = mine.get(self.cands[ci].kind) or []
            if not same:
                return None
            by_slot.append(same.pop(0))
        vec = np.empty(len(self.variables))
        for i, v in enumerate(self.variables):
            m = by_slot[v.slot]
            if v.role == "x":
                vec[i] = float(m.x)
            elif v.role == "range":
                vec[i] = float(getattr(m.params, v.name))
            elif v.role == "option":
                value = getattr(m.params, v.name)
                if value not in v.options:
                    return None
                vec[i] = float(v.options.index(value))
            else:  # a catalogue choice of a ground edit: not walked
                return None
        return vec

    def around(self, measures: Sequence[Any], limit: float) -> list[Screened]:
        """Designs next to ``measures`` on the lattice and cheaper than ``limit``, newly run.

        The search samples the lattice through its own seed, but what it
        finds depends on the rocks: a geometry one step cheaper than the
        chosen design, a metre or two from it, is run at some seeds and not
        at others, and the chosen cost moves with the seed
        (design_ditch_or_fence: a ditch 5.25 m wide at x = 109 m, chosen at
        four of seeds 11 to 15, was never run at the fifth, which chose one
        5.5 m wide at 107 m, 4 % dearer, and did not name the cheaper one).
        Every step of one geometry coordinate that makes the design cheaper
        is run here with the station shifted by up to :data:`POLISH_SHIFTS`
        lattice steps either way; the new designs are decided like the rest.
        """
        start = self._vector(measures)
        if start is None:
            return []
        before = set(self.kept)
        x_vars = [i for i, v in enumerate(self.variables) if v.role == "x"]
        for i, v in enumerate(self.variables):
            if v.role == "x":
                continue
            step = v.lattice_step
            for sign in (-1.0, 1.0):
                moved = start.copy()
                moved[i] = min(max(moved[i] + sign * step, v.low), v.high)
                if moved[i] == start[i] or not self._cost(moved) < limit:
                    continue
                for shift in range(-POLISH_SHIFTS, POLISH_SHIFTS + 1):
                    vec = moved.copy()
                    for j in x_vars:
                        xv = self.variables[j]
                        vec[j] = min(max(vec[j] + shift * STATION_STEP_M, xv.low), xv.high)
                    self.objective(vec)
        return self._designs([k for k in self.kept if k not in before], limit - 1e-9)

    def _cost(self, vec: np.ndarray) -> float:
        """The fixed cost of a vector's ground edits, without a run (inf: no price, or
        a geometry that does not fit)."""
        screen = self.screen
        try:
            edits = screen.measures(decode(self.cands, self.edit_slots, self.variables, vec))
            # Placing first, as objective() does: a step may leave a geometry that
            # does not fit (a ditch too narrow for its new depth), which is out of
            # the space, not a fault of the measure's quantities().
            place_measures(screen.project, screen.registry, edits, screen.section)
            return float(screen.cost(edits))
        except (KeyError, ValueError, ProjectError):
            return math.inf


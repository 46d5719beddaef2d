"""Screening: every candidate design judged on the same search rocks, fast.

One run of the search rocks on the bare slope keeps, at the table stations
(every :data:`~rockfall_design.optimiser.space.STATION_STEP_M` along every
barrier candidate's range), each rock's passing height, energy and speed at
its first passage downslope, and at restart stations upslope of every
ground-edit candidate each rock's full state. A design is judged through the
one judgement (:mod:`rockfall_design.judge.outcomes`): barriers from the
table, ground edits by a run of only the rocks that pass the restart station
just upslope of the edit, resumed from their saved state.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING, Any

import numpy as np

from ..engine import Releases, Section, columns, run_ensemble
from ..errors import ProjectError
from ..judge.bounds import fraction_lower_bound, fraction_upper_bound
from ..judge.candidates import build_candidate_measure
from ..judge.costing import design_cost
from ..judge.outcomes import (
    Judgement,
    RockFates,
    barrier_outcomes,
    braking_distances,
    judge_measures,
)
from ..judge.placing import PlacedMeasure, edited_section, place_measures
from ..judge.plan import confidence_of
from ..plugins import guard
from ..plugins.concept import Check
from ..plugins.measure import Barrier, BarrierBehaviour, MeasureResult, ProfileEdit
from ..run.reach import reaches_protected_zone
from ..run.releases import draw_releases, engine_key, engine_settings, section_from_project

if TYPE_CHECKING:  # pragma: no cover
    from ..judge.design_spec import DesignSpec
    from ..plugins import Registry
    from ..plugins.measure import ProtectiveMeasure
    from ..project import Project

from .space import STATION_STEP_M, decode, variables_of

#: Spacing (m) of the restart stations upslope of ground-edit candidates.
RESTART_STEP_M = 2.0
#: First barriers of the search's placements whose judgement is kept (see
#: :meth:`Screening.screen_placed`), least recently used dropped first.
FIRST_BARRIERS_KEPT = 512


def restart_margin(radius_max: float) -> float:
    """Least distance (m) of a restart station upslope of its edit, for rocks of radius
    up to ``radius_max`` (m): a rock there has not yet touched ground the edit changes."""
    return 2.0 * float(radius_max) + 0.5


def restart_index(restart_x: np.ndarray, edits: Sequence[ProfileEdit], margin: float) -> int:
    """Index into ``restart_x`` (m) of the last restart station upslope of the first of
    ``edits`` by ``margin`` (m, :func:`restart_margin`); -1 when there is none."""
    first = min(e.x_start for e in edits)
    return int(np.searchsorted(restart_x, first - margin, side="right")) - 1


# ---- screening --------------------------------------------------------------------


@dataclass
class ScreenResult:
    """One design judged on the search rocks.

    ``labels`` are the measures' labels, in the order of ``results``;
    ``reason`` says why a design that could not be judged is infeasible.
    ``feasible``: admitted with the look's confidence bounds on rocks whose
    paths were all judged exactly; ``near``: undecided (neither admitted
    nor rejected with confidence, or resting on approximated rocks), so it
    is left to more rocks and the exact decision; neither: rejected, some
    check or the residual fails with confidence where nothing was
    approximated.
    """

    cost: float
    feasible: bool
    violation: float
    checks: list[list[Check]]
    results: list[MeasureResult]
    residual: int
    reason: str = ""
    labels: list[str] = field(default_factory=list)
    near: bool = False
    approximate: bool = False  # some rock's path only approximated (see Screening.judge)
    point_ok: bool = False  # every check and the residual meet their targets on point values


@dataclass
class _Approx:
    """Where a screening rests on rocks whose paths it approximates (see Screening.judge)."""

    reaching: int  # approximated rocks among those counted as reaching the protected zone
    any: bool  # any approximated rock at all
    touched: list[bool]  # per measure: met by approximated rocks from upslope


@dataclass
class Table:
    """Per rock: first downslope passage at the table stations, and how its path ended.

    A table for an edited section shares the bare table and overlays only what
    changed: the rows of the resumed rocks at the stations downslope of the
    restart station.
    """

    h: np.ndarray  # (N, S) m
    e_kj: np.ndarray  # (N, S) kJ
    v: np.ndarray  # (N, S) m/s
    max_x: np.ndarray
    x_end: np.ndarray
    status: np.ndarray
    rows: np.ndarray | None = None  # resumed rocks
    first_col: int = 0  # first overlaid station
    oh: np.ndarray | None = None  # (len(rows), S - first_col)
    oe: np.ndarray | None = None
    ov: np.ndarray | None = None
    #: The resumed rocks crossed forested ground: a resumed rock draws its next
    #: stem afresh (engine.forest), so its path is not the full run's; the
    #: screening treats those rocks as approximated and the exact run decides.
    resumed_approximate: bool = False
    #: Which table this is, for the search's caches (0: the bare slope). Never
    #: ``id()``: a table dropped from the cache of edited tables frees its id
    #: for the next one, whose rocks would then be looked up under the old
    #: table's outcomes.
    serial: int = 0

    def column(self, j: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Passing height (m), energy (kJ) and speed (m/s) of every rock at station j."""
        if self.rows is None or j < self.first_col:
            return self.h[:, j], self.e_kj[:, j], self.v[:, j]
        k = j - self.first_col
        h, e, v = self.h[:, j].copy(), self.e_kj[:, j].copy(), self.v[:, j].copy()
        h[self.rows] = self.oh[:, k]
        e[self.rows] = self.oe[:, k]
        v[self.rows] = self.ov[:, k]
        return h, e, v


def _columns_of(have: np.ndarray, want: np.ndarray) -> np.ndarray:
    """Indices into the stations ``have`` (m) of every station of ``want`` (all there)."""
    idx = np.searchsorted(have, want)
    idx = np.minimum(idx, max(have.size - 1, 0))
    if want.size and (have.size == 0 or not np.allclose(have[idx], want, rtol=0.0,
                                                         atol=1e-9)):
        raise ValueError("a screening goes on only from one with all of its stations")
    return idx


def _rows(releases: Any, first: int) -> Any:
    """The rocks of ``releases`` from index ``first`` on."""
    out = {}
    for f in fields(releases):
        a = getattr(releases, f.name)
        out[f.name] = a if np.ndim(a) == 0 else np.asarray(a)[first:]
    return type(releases)(**out)


def _joined_tables(before: Table, cols: np.ndarray, more: Table) -> Table:
    """The bare table ``before`` at its stations ``cols``, followed by ``more``'s rocks."""
    if before.rows is not None:
        raise ValueError("only a bare table goes on")
    return Table(
        h=np.concatenate([before.h[:, cols], more.h]),
        e_kj=np.concatenate([before.e_kj[:, cols], more.e_kj]),
        v=np.concatenate([before.v[:, cols], more.v]),
        max_x=np.concatenate([before.max_x, more.max_x]),
        x_end=np.concatenate([before.x_end, more.x_end]),
        status=np.concatenate([before.status, more.status]),
    )


def _check_after(sc: Screening, after: Screening) -> int:
    """The rocks of ``after`` that ``sc`` goes on from (see :meth:`Screening.__init__`)."""
    if (after.seed != sc.seed or after.n > sc.n or after.project is not sc.project
            or not np.array_equal(after.releases.x, sc.releases.x[:after.n])):
        raise ValueError("a screening goes on only from the first rocks of the same run")
    return after.n


class Screening:
    """Fast, common-random-number evaluation of candidate designs (see module docs)."""

    def __init__(
        self,
        project: Project,
        registry: Registry,
        spec: DesignSpec,
        concept: Any,
        *,
        rocks: int,
        seed: int,
        progress: Callable[[str], None] | None = None,
        stations: np.ndarray | None = None,
        rock_progress: Callable[[int], None] | None = None,
        restart_stations: np.ndarray | None = None,
        after: Screening | None = None,
        section: Section | None = None,
    ) -> None:
        """Run the search rocks on the bare slope and keep the table (see the class docs).

        ``stations`` (m), when given, replaces the table stations (every
        candidate's range on the grid) and drops the restart stations: a
        later look at a few barrier designs with more rocks needs only
        their stations (and memory grows with rocks x stations).
        ``rock_progress``, when given, is called with the rocks done of the
        bare run after each batch; an exception it raises stops the run
        (``rockfall-design serve`` shows progress and cancels this way).
        ``restart_stations`` (m), when given with ``stations``, are kept as
        restart stations, so that ground edits can still be judged.
        ``after``, when given, is a screening of the first rocks of this one
        (same project and seed, at most ``rocks``, its stations and restart
        stations a superset of this one's): its rocks are not run again, only
        the rocks after them (:meth:`_run_bare`). A later look of ``2n`` rocks
        is then the look of ``n`` and ``n`` new ones, bit for bit the table of
        all ``2n`` run at once (each rock draws from its own stream, and the
        stations a run records at do not change its paths).
        ``section``, when given, is the project's slope section (the plan's),
        so that a command builds it once.
        """
        self.project = project
        self.registry = registry
        self.spec = spec
        self.concept = concept
        self.n = int(rocks)
        self.seed = int(seed)
        self._build = build_candidate_measure
        self._measure_cache: dict[tuple, Any] = {}
        # The plan's section when the caller passes it: one per command.
        self.section = section_from_project(project) if section is None else section
        self.releases = draw_releases(project, self.n, self.seed)
        self.key = engine_key(self.seed)
        self.settings = engine_settings(project)
        self.protect_x = float(project.protect.x)
        allowed = spec.residual_count
        if spec.residual_fraction is not None:
            allowed = int(math.floor(spec.residual_fraction * self.n + 1e-9))
        self.allowed_residual = int(allowed or 0)
        self.allowed_fraction = (spec.residual_fraction if spec.residual_fraction is not None
                                 else self.allowed_residual / max(self.n, 1))
        self.max_rocks = max(self.n, int(spec.max_rocks))
        self.confidence = confidence_of(concept)
        self.margin = restart_margin(float(np.max(self.releases.radius)))
        self.edit_candidates = {i for i, c in enumerate(spec.candidates) if self._is_edit(i)}
        self.grid, self.restart_x = self._stations(stations, restart_stations)
        #: Rocks this screening ran (those of ``after`` are not run again).
        self.rocks_run = self.n - (0 if after is None else after.n)
        self._run_bare(rock_progress, after)
        # One uniform per rock for the gaps of a boulder row (common to all designs).
        self.u_gap = np.random.default_rng(np.random.SeedSequence([self.seed, 7919])).random(
            self.n)
        self._edit_cache: dict[tuple, Table] = {}
        # The first barrier of the search's placements, judged once per option and
        # table (see screen_placed): key -> (outcomes, result, held, checks).
        self._first: OrderedDict[tuple, tuple[np.ndarray, MeasureResult, np.ndarray,
                                              list[Check]]] = OrderedDict()
        # A cost above any design's: infeasible designs cost at least this much.
        self.penalty_floor = 1e3 + 1e5 * spec.max_measures * max(1.0, spec.length_m)
        self.evaluations = 0
        self.edit_runs = 0
        self.edit_rocks = 0

    def _stations(self, stations: np.ndarray | None,
                  restart_stations: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        """The table's stations and the restart stations (m), see :meth:`__init__`.

        By default every barrier candidate's range at STATION_STEP_M, and
        restart stations upslope of every edit candidate's range; always the
        protected zone's station.
        """
        x0, x1 = self.section.x[0], self.section.x[-1]
        sts, restarts = [], [np.zeros(0)]
        for i, c in enumerate(self.spec.candidates):
            lo, hi = c.x_range
            sts.append(np.arange(lo, hi + 1e-9, STATION_STEP_M))
            if i in self.edit_candidates:
                # Profile edits may start upslope of their x (a berm's cut face).
                lo_r = max(x0, lo - 30.0 - self.margin)
                restarts.append(np.arange(lo_r, hi + 1e-9, RESTART_STEP_M))
        if stations is not None:
            sts, restarts = [np.asarray(stations, dtype=float)], [np.zeros(0)]
            if restart_stations is not None:
                restarts = [np.asarray(restart_stations, dtype=float)]
        grid = np.unique(np.clip(np.concatenate(sts + [np.array([self.protect_x])]), x0, x1))
        return grid, np.unique(np.clip(np.concatenate(restarts), x0, x1))

    def _run_bare(self, rock_progress: Callable[[int], None] | None,
                  after: Screening | None = None) -> None:
        """Run the search rocks on the bare slope: the table, and the restart states.

        With ``after`` (see :meth:`__init__`) only the rocks after its ``n``
        run (``first_index``: each draws from its own stream) and its rows,
        at this screening's stations, come first.
        """
        first = 0 if after is None else _check_after(self, after)
        releases = self.releases if after is None else _rows(self.releases, first)
        bare = run_ensemble(
            self.section, releases, key=self.key, grid=self.grid,
            restart_stations=self.restart_x, settings=self.settings, record_speed=True,
            progress=rock_progress, first_index=first,
        )
        cols = np.searchsorted(bare.grid, self.grid)
        table = Table(
            h=bare.grid_height[:, cols].astype(float),
            e_kj=bare.grid_energy[:, cols].astype(float) / 1e3,
            v=bare.grid_speed[:, cols].astype(float),
            max_x=bare.max_x, x_end=bare.x_end, status=bare.status,
        )
        state, rng = bare.restart_state, bare.restart_rng
        mass, radius = bare.mass, bare.radius
        if after is not None:
            table = _joined_tables(after.bare, _columns_of(after.grid, self.grid), table)
            q = _columns_of(after.restart_x, self.restart_x)
            state = np.concatenate([after.restart_state[:, q], state])
            rng = np.concatenate([after.restart_rng[:, q], rng])
            mass = np.concatenate([after.mass, mass])
            radius = np.concatenate([after.radius, radius])
        self.bare = table
        self.restart_state = state
        self.restart_rng = rng
        self.mass = mass
        self.radius = radius

    def _is_edit(self, ci: int) -> bool:
        """Does candidate ``ci`` edit the ground? Asked of its own footprint, never its name.

        Designs across its space (the middle, then the far ends of every
        range and the last of every option) are tried until one fits; a
        candidate none of whose designs fits has no designs at all, and is
        searched (and reported) as a barrier.
        """
        cands = self.spec.candidates
        variables = variables_of(cands, (ci,))
        probes = [[0.5 * (v.low + v.high) if not v.integer else 0 for v in variables],
                  [v.high for v in variables], [v.low for v in variables]]
        for vec in probes:
            try:
                (m,) = self.measures(decode(cands, (ci,), variables, vec))
                footprint = guard(self.registry).measure(m).footprint(self.section)
            except ValueError:
                continue
            return isinstance(footprint, ProfileEdit)
        return False

    # -- measures -----------------------------------------------------------------
    def measures(self, decoded: Sequence[tuple[int, dict[str, Any]]]) -> list[ProtectiveMeasure]:
        """The measures of a decoded design, built once per set of parameters.

        Raises
        ------
        ValueError
            The values are not valid for a measure (see ``build_candidate_measure``).
        PluginError
            A measure's class failed to instantiate or to label itself.
        """
        cands = self.spec.candidates
        out = []
        for ci, p in decoded:
            key = (ci, tuple(sorted(p.items())))
            m = self._measure_cache.get(key)
            if m is None:
                if len(self._measure_cache) > 20000:
                    self._measure_cache.clear()
                m = self._build(cands[ci], self.registry, p)
                # The report labels the designs it lists itself, also those that
                # never got as far as place_measures: a faulty label() shows here.
                guard(self.registry).measure(m).label()
                self._measure_cache[key] = m
            out.append(m)
        return out

    def cost(self, measures: Sequence[ProtectiveMeasure]) -> float:
        """Cost of a design (currency units).

        Raises
        ------
        KeyError or ValueError
            From the cost model: it has no price for one of the measures.
        """
        return design_cost(self.registry, self.spec, measures, self.section)

    # -- tables -------------------------------------------------------------------
    def table_for(self, edits: Sequence[ProfileEdit], edited: Section | None) -> Table:
        """The table of the search rocks on ground reshaped by ``edits``.

        Only the rocks that pass the last restart station upslope of the
        first edit run again, from their state saved there, on ``edited``
        (the section with the edits applied); the others keep their bare
        slope's row. Tables are cached per set of edits (their stations,
        shapes, materials and stands of trees).

        Parameters
        ----------
        edits
            The profile edits (ditches, berms) of a design; none gives the
            bare slope's table.
        edited
            The section with ``edits`` applied.

        Raises
        ------
        ValueError
            No restart station upslope of the first edit.
        """
        if not edits:
            return self.bare
        key = tuple((round(e.x_start, 6), round(e.x_end, 6),
                     tuple(np.round(np.asarray(e.points, float).ravel(), 6)), e.material,
                     e.forest)
                    for e in edits)
        hit = self._edit_cache.get(key)
        if hit is not None:
            return hit
        q = restart_index(self.restart_x, edits, self.margin)
        if q < 0:
            raise ValueError("no restart station upslope of the edit")
        xs = self.restart_x[q]
        state = self.restart_state[:, q]
        go = np.isfinite(state[:, columns.RS_X])
        idx = np.flatnonzero(go)
        t = Table(h=self.bare.h, e_kj=self.bare.e_kj, v=self.bare.v,
                   max_x=self.bare.max_x.copy(), x_end=self.bare.x_end.copy(),
                   status=self.bare.status.copy(), serial=self.edit_runs + 1)
        if idx.size:
            sub = Releases(
                radius=self.releases.radius[idx], density=self.releases.density,
                x=self.releases.x[idx], height=self.releases.height[idx],
                vx=self.releases.vx[idx], vy=self.releases.vy[idx],
                spin=self.releases.spin[idx], spin_rolling=self.releases.spin_rolling[idx],
            )
            first = int(np.searchsorted(self.grid, xs, side="right"))
            res = run_ensemble(
                edited, sub, key=self.key, grid=self.grid[first:], settings=self.settings,
                record_speed=True,
                resume=(np.ones(idx.size, bool), state[idx], self.restart_rng[idx, q]),
            )
            cols = np.searchsorted(res.grid, self.grid[first:])
            t.rows = idx
            t.first_col = first
            t.resumed_approximate = bool(edited.forested)
            t.oh = res.grid_height[:, cols].astype(float)
            t.oe = res.grid_energy[:, cols].astype(float) / 1e3
            t.ov = res.grid_speed[:, cols].astype(float)
            t.max_x[idx] = res.max_x
            t.x_end[idx] = res.x_end
            t.status[idx] = res.status
        self.edit_runs += 1
        self.edit_rocks += int(idx.size)
        if len(self._edit_cache) > 256:
            self._edit_cache.clear()
        self._edit_cache[key] = t
        return t

    def drop_edit_tables(self) -> None:
        """Forget the tables of edited ground (:meth:`table_for` keeps 256; about 10 MB
        each at 400,000 rocks): the decider's looks judge each design once."""
        self._edit_cache.clear()

    # -- one design -----------------------------------------------------------------
    def screen(self, measures: Sequence[ProtectiveMeasure]) -> ScreenResult:
        """Judge a design on the search rocks, through the one judgement (see module docs)."""
        self.evaluations += 1
        try:
            placed = place_measures(self.project, self.registry, measures, self.section)
        except ProjectError as exc:
            # A measure that does not fit, or two in one place: an infeasible
            # design, not an error. A PluginError (a fault) goes on up.
            return ScreenResult(math.inf, False, math.inf, [], [], self.n, reason=exc.message)
        edits = [p.footprint for p in placed if isinstance(p.footprint, ProfileEdit)]
        edited = edited_section(self.project, self.section, placed) if edits else None
        try:
            table = self.table_for(edits, edited)
        except ValueError as exc:
            return ScreenResult(math.inf, False, math.inf, [], [], self.n, reason=str(exc))
        try:
            cost = self.cost([p.measure for p in placed])
        except (KeyError, ValueError) as exc:
            # The cost model's contract: no price for a measure skips the design.
            why = exc.args[0] if exc.args else type(exc).__name__
            return ScreenResult(
                math.inf, False, math.inf, [], [], self.n, labels=[p.label for p in placed],
                reason=f"cost model {self.spec.cost_model.name!r} has no price for this "
                       f"design: {why}")
        return self._verdict(placed, table, cost)

    def screen_placed(self, placed: Sequence[PlacedMeasure], table: Table,
                      cost: float, keys: Sequence[Hashable] | None = None) -> ScreenResult:
        """Judge measures already placed and priced on ``table`` (the search's fast path).

        The search builds, places and prices every barrier option once, and
        keeps only placements that fit (spacing, not inside a ground edit); a
        design of them needs only the judgement and the safety checks.

        ``keys``, when given, name each placed barrier's option for the whole
        run (the search's ``(candidate, option)``): the barrier the rocks meet
        first meets every rock of the table, so its outcomes, result and
        checks are those of every placement that begins with it, and are
        judged once (:meth:`_judge`, an LRU of :data:`FIRST_BARRIERS_KEPT`).
        """
        self.evaluations += 1
        return self._verdict(placed, table, cost, keys)

    def _verdict(self, placed: Sequence[PlacedMeasure], table: Table,
                 cost: float, keys: Sequence[Hashable] | None = None) -> ScreenResult:
        judgement, approx, first = self._judge(placed, table, keys)
        concept = guard(self.registry).concept(self.concept)
        checks = []
        for i, res in enumerate(judgement.results):
            if first is not None and i == first[0] and first[1] in self._first:
                checks.append(self._first[first[1]][3])
                continue
            checks.append(concept.checks(res))
        if first is not None and first[1] not in self._first:
            i, key = first
            # Least recently used out first: an entry holds the first barrier's
            # met rocks (about 0.4 MB on 9,206 search rocks), and the placements
            # come level by level, each level's few first barriers many times.
            if len(self._first) >= FIRST_BARRIERS_KEPT:
                self._first.popitem(last=False)
            self._first[key] = (judgement.outcomes[i], judgement.results[i],
                                judgement.held[i], checks[i])
        elif first is not None:
            self._first.move_to_end(first[1])
        labels = [p.label for p in placed]
        approximate = approx.any
        violation = self.violation(checks, judgement.reaching)
        # The screening admits only what it judged exactly (no rock whose path it
        # approximates) and holds with the bounds; it rejects only what fails with
        # confidence where no approximated rock could be the cause; everything
        # else is undecided and goes on to more rocks and the exact decision.
        admitted = not approximate and self.admits(checks, judgement.reaching)
        rejected = self.rejects(checks, judgement.reaching, approx)
        return ScreenResult(cost, admitted, violation, checks, judgement.results,
                            judgement.reaching, labels=labels,
                            near=not admitted and not rejected, approximate=approximate,
                            point_ok=all(c.ok for cs in checks for c in cs)
                            and judgement.reaching <= self.allowed_residual)

    def judge(self, placed: Sequence[PlacedMeasure], table: Table) -> tuple[Judgement, _Approx]:
        """The design's outcomes on the search rocks, by the one judgement.

        See :meth:`_judge`.
        """
        judgement, approx, _ = self._judge(placed, table, None)
        return judgement, approx

    def _judge(self, placed: Sequence[PlacedMeasure], table: Table,
               keys: Sequence[Hashable] | None) -> tuple[Judgement, _Approx,
                                                        tuple[int, tuple] | None]:
        """The design's outcomes on the search rocks, by the one judgement.

        Barriers are met in the order of their stations; a rock a barrier
        stops (caught, or returned by a rigid one) ends its path there, so the
        measures downslope of it never meet it. A rock that passes a barrier
        goes on along its path of the table (bare or edited ground).

        Returns the judgement and where it rests on rocks whose paths the
        screening only approximates (:class:`_Approx`): rocks that broke
        through a barrier (the exact run lets them go on with the surplus
        energy only), were returned by a rigid one (they may come back over
        it), or met a row of blocks (its gap draws come from another stream).
        """
        fates = RockFates(max_x=table.max_x.copy(), x_end=table.x_end.copy(),
                          status=table.status.copy(), mass=self.mass, radius=self.radius)
        alive = np.ones(self.n, dtype=bool)
        approx = np.zeros(self.n, dtype=bool)
        if table.resumed_approximate and table.rows is not None:
            approx[table.rows] = True
        upstream: list[tuple[float, np.ndarray]] = []  # (station, rocks approximated there)
        outcomes: list[np.ndarray | None] = [None] * len(placed)
        meetings: list[np.ndarray | None] = [None] * len(placed)
        first: tuple[int, tuple] | None = None  # (index in placed, key in self._first)
        known = None  # what self._first holds for it
        for i in sorted(range(len(placed)), key=lambda k: _start(placed[k].footprint)):
            fp = placed[i].footprint
            if not isinstance(fp, Barrier):
                continue
            j = self.station(fp.x)
            h, e_kj, v = table.column(j)
            if keys is not None and first is None:
                # The first barrier: every rock is still moving when it gets there.
                first = (i, (keys[i], placed[i].index, table.serial, j))
                known = self._first.get(first[1])
            if known is not None and i == first[0]:
                out = known[0]
            else:
                out = barrier_outcomes(fp, h, e_kj, self.radius, self.u_gap, alive)
                meetings[i] = np.column_stack([h, v, e_kj])
            stopped = (out == columns.O_CAUGHT) | (out == columns.O_REBOUNDED)
            here = (out == columns.O_BROKEN_THROUGH) | (out == columns.O_REBOUNDED)
            if fp.behaviour == BarrierBehaviour.BLOCKS:
                here = out != columns.O_NOT_MET
            approx |= here
            upstream.append((fp.x, here))
            self._stop(fates, fp, out, stopped, e_kj)
            alive &= ~stopped
            outcomes[i] = out
        if known is None:
            judgement = judge_measures(placed, outcomes, meetings, fates, self.protect_x)
        else:
            # The first barrier's result as judged before; the others now. Each
            # measure's result depends on its own outcomes and the rocks' fates
            # only (a rock the first barrier stops has its fate set there).
            i0 = first[0]
            rest = [k for k in range(len(placed)) if k != i0]
            part = judge_measures([placed[k] for k in rest], [outcomes[k] for k in rest],
                                  [meetings[k] for k in rest], fates, self.protect_x)
            results, helds, outs = part.results, part.held, part.outcomes
            results.insert(i0, known[1])
            helds.insert(i0, known[2])
            outs.insert(i0, known[0])
            judgement = Judgement(results, helds, outs, part.reaching, part.unresolved)
        touched = self._touched(placed, judgement, upstream)
        uncertain = int((approx & reaches_protected_zone(fates.max_x, fates.status,
                                                         self.protect_x)).sum())
        return judgement, _Approx(uncertain, bool(approx.any()), touched), first

    def reaching_with(self, fp: Barrier, out: np.ndarray, table: Table) -> np.ndarray:
        """Which rocks reach the protected zone with barrier ``fp`` alone on ``table``.

        ``out`` are its outcomes (:func:`~rockfall_design.judge.outcomes.barrier_outcomes`
        on all rocks). Counted as :meth:`_judge` counts them: a rock it catches
        or returns ends there (a net carries it on by its braking distance),
        every other goes on along the table's path.

        Returns
        -------
        ndarray of float32
            1 where the rock counts as reaching, 0 elsewhere (rocks,).
        """
        fates = RockFates(max_x=table.max_x.copy(), x_end=table.x_end.copy(),
                          status=table.status.copy(), mass=self.mass, radius=self.radius)
        stopped = (out == columns.O_CAUGHT) | (out == columns.O_REBOUNDED)
        self._stop(fates, fp, out, stopped, table.column(self.station(fp.x))[1])
        return reaches_protected_zone(fates.max_x, fates.status,
                                      self.protect_x).astype(np.float32)

    def _stop(self, fates: RockFates, fp: Barrier, out: np.ndarray, stopped: np.ndarray,
              e_kj: np.ndarray) -> None:
        """End the paths of the rocks a barrier stopped (caught, or returned) at it."""
        # In place under the mask (no gather and scatter of the stopped rocks:
        # thousands of placements are judged on thousands of rocks).
        np.minimum(fates.max_x, fp.x, out=fates.max_x, where=stopped)
        np.copyto(fates.x_end, fp.x, where=stopped)
        if fp.behaviour == BarrierBehaviour.NET and fp.elongation_mel_m > 0.0:
            # A net carries what it catches on by its braking distance (the engine's
            # rule, clipped to the section as the engine does).
            caught = np.flatnonzero(out == columns.O_CAUGHT)
            x_stop = np.minimum(fp.x + braking_distances(fp, e_kj[caught]),
                                float(self.section.x[-1]))
            fates.max_x[caught] = x_stop
            fates.x_end[caught] = x_stop
        np.copyto(fates.status, np.where(out == columns.O_CAUGHT, columns.CAUGHT,
                                         columns.STOPPED), where=stopped, casting="unsafe")

    def _touched(self, placed: Sequence[PlacedMeasure], judgement: Judgement,
                 upstream: Sequence[tuple[float, np.ndarray]]) -> list[bool]:
        """Does each measure's judgement rest on approximated rocks (such rocks, from a
        barrier upslope of it, met it)?"""
        touched = []
        for p, out in zip(placed, judgement.outcomes, strict=True):
            start = _start(p.footprint)
            before = np.zeros(self.n, dtype=bool)
            for x, m in upstream:
                if x < start:
                    before |= m
            touched.append(bool((before & (out != columns.O_NOT_MET)).any()))
        return touched

    def station(self, x: float) -> int:
        """Index of the table station nearest ``x`` (m)."""
        k = int(np.searchsorted(self.grid, x))
        if k > 0 and (k == self.grid.size or x - self.grid[k - 1] <= self.grid[k] - x):
            k -= 1
        return k

    def admits(self, checks: Sequence[Sequence[Check]], residual: int) -> bool:
        """Every check and the residual hold with their upper bounds (the look's confidence)."""
        return (all(c.holds_with_confidence for cs in checks for c in cs)
                and fraction_upper_bound(residual, self.n, self.confidence)
                <= self.allowed_fraction)

    def rejects(self, checks: Sequence[Sequence[Check]], residual: int,
                approx: _Approx | None = None) -> bool:
        """Some check, or the residual, fails with confidence on rocks judged exactly.

        A check counts only where no rock with an approximated path met its
        measure (``approx.touched``); the residual only with the rocks whose
        fate the screening knows (``residual - approx.reaching``): the exact
        run can only add to those (a rock the screening lets break through
        with its full energy may stop in the exact run, never the reverse
        for a rock that reaches the zone without meeting such a barrier).
        """
        touched = approx.touched if approx is not None else [False] * len(checks)
        uncertain = approx.reaching if approx is not None else 0
        for cs, t in zip(checks, touched, strict=True):
            if not t and any(c.rejects for c in cs):
                return True
        return self.residual_rejects(residual - uncertain)

    def residual_rejects(self, reaching: int) -> bool:
        """The Clopper-Pearson lower bound of ``reaching`` of the rocks exceeds the target."""
        return (reaching > 0 and fraction_lower_bound(reaching, self.n, self.confidence)
                > self.allowed_fraction)

    def violation(self, checks: Sequence[Sequence[Check]], residual: int) -> float:
        """How far a design misses its targets on the point values (0: it meets them).

        Used to rank designs that fail (the report names the one that comes
        closest), never to decide: that is :meth:`admits` and :meth:`rejects`.
        """
        violation = 0.0
        for cs in checks:
            for c in cs:
                if c.ok:
                    violation += 0.0 if c.holds_with_confidence else 1e-3
                elif c.value is None or not math.isfinite(c.value):
                    violation += 1.0
                else:
                    violation += abs(c.value - c.target) / max(abs(c.target), 1e-9)
        if residual > self.allowed_residual:
            violation += 1.0 + (residual - self.allowed_residual) / max(self.n, 1) * 100.0
        elif fraction_upper_bound(residual, self.n, self.confidence) > self.allowed_fraction:
            violation += 1e-3
        return violation


def _start(fp: Barrier | ProfileEdit) -> float:
    return fp.x if isinstance(fp, Barrier) else fp.x_start

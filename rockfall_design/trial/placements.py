"""Trial placements: measures placed by hand, judged from the screening's table.

The browser app's page drags a fence along the section and wants the
verdict within milliseconds. :func:`trial_run` runs the project's rocks on
the bare slope once, as the optimiser's screening does
(:class:`~rockfall_design.optimiser.screening.Screening`), keeping every
rock's passing height, energy and speed at dense stations and its full
state at coarser restart stations. :meth:`TrialRun.place` then judges any
measures placed on that slope from the table, through the one judgement of
:mod:`rockfall_design.judge.outcomes`: a barrier at the table station
nearest to it, a ditch or berm by running again only the rocks that pass
the restart station just above it, on the edited ground.

The front end (:mod:`rockfall_design.serve`) reaches all of this through
:func:`rockfall_design.api.trial_run` and turns the objects here into JSON.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..engine import Releases, run_ensemble
from ..engine.columns import STOPPED
from ..engine.trajectory import centre_points
from ..errors import InputError
from ..judge.bounds import quantile_lower_bound, quantile_upper_bound
from ..judge.design_spec import DesignSpec
from ..judge.evaluation import protect_summary
from ..judge.placing import PlacedMeasure, edited_section, place_measures
from ..judge.plan import design_of, plan_for
from ..judge.verdict import DesignVerdict, verdict_of
from ..optimiser.screening import Screening, ScreenResult
from ..plugins.measure import ProfileEdit
from ..project.schema import Protect
from ..run.reach import reaches_protected_zone

if TYPE_CHECKING:  # pragma: no cover
    from ..engine import Section
    from ..plugins import Registry
    from ..plugins.measure import ProtectiveMeasure
    from ..project import Project

__all__ = ["Trial", "TrialRun", "trial_run", "trial_spec"]


def trial_spec(project: Project, registry: Registry) -> DesignSpec:
    """The project's design section, or targets alone for a project without one.

    Without ``design:`` the residual is judged as ``check`` judges it: against
    ``protect.allowed_fraction`` (0 without a protected zone), and nothing is
    priced.
    """
    if project.design is not None:
        return design_of(project, registry)
    allowed = float(project.protect.allowed_fraction) if project.protect is not None else 0.0
    return DesignSpec(max_measures=4, residual_count=None, residual_fraction=allowed,
                      fresh_rocks=None, fresh_seed=None, length_m=1.0, candidates=(),
                      cost_model=None, products={})


@dataclass(frozen=True)
class Trial:
    """Measures placed by hand, judged on the trial run's rocks.

    Attributes
    ----------
    placed : tuple of PlacedMeasure
        The measures with their footprints on the bare section.
    result : ScreenResult
        The screening's judgement: per measure its counts and checks, the
        rocks reaching the protected zone, admitted / near / approximate.
    cost : float
        The design's cost by the project's cost model; NaN without one or
        without a price for one of the measures.
    protect : dict
        The residual as ``check`` reports it
        (:func:`~rockfall_design.judge.evaluation.protect_summary`) against
        the screening's allowance.
    reshapes_ground : bool
        Some measure edits the profile (a ditch, a berm).
    rerun_rocks : int
        Rocks run again on the edited ground (0 for barriers alone).
    """

    placed: tuple[PlacedMeasure, ...]
    result: ScreenResult
    cost: float
    protect: dict[str, Any]
    reshapes_ground: bool
    rerun_rocks: int


@dataclass
class TrialRun:
    """The bare slope's rocks kept at dense stations, ready to judge measures placed by hand.

    Attributes
    ----------
    screening : Screening
        The optimiser's screening of the run's rocks (its table, restart
        states, allowance and confidence).
    runtime_s : float
        Wall time of the run (s).
    section : Section
        The bare section.
    paths : list of ndarray
        The first rocks' centre paths, each ``(k, 2)``: x and y (m).
    reaching : int
        Rocks reaching the protected zone on the bare slope (0 without
        ``protect:``).
    """

    screening: Screening
    runtime_s: float
    section: Section
    paths: list[np.ndarray]
    reaching: int

    @property
    def grid(self) -> np.ndarray:
        """Stations of the table (m)."""
        return self.screening.grid

    @property
    def ground(self) -> np.ndarray:
        """Ground height at the table's stations (m)."""
        return self.section.ground_height(self.screening.grid)

    @property
    def stopped_x(self) -> np.ndarray:
        """Where the rocks that stopped on the section came to rest (m)."""
        t = self.screening.bare
        return t.x_end[t.status == STOPPED]

    def table_station(self, x: float) -> float:
        """The table's station (m) nearest ``x``, where a barrier at ``x`` is judged."""
        sc = self.screening
        return float(sc.grid[sc.station(x)])

    def p95_bounds(self, a: np.ndarray) -> list[tuple[float | None, float | None]]:
        """Per column of ``a`` (rocks x stations): (lower, upper) bound of its 95th percentile.

        The distribution-free order-statistic bounds of the finite values at
        the screening's confidence; None where too few rocks passed to bound
        it.

        See Also
        --------
        rockfall_design.judge.bounds.quantile_upper_bound
        """
        confidence = self.screening.confidence
        out = []
        for j in range(a.shape[1]):
            v = a[:, j]
            v = v[np.isfinite(v)]
            lo = quantile_lower_bound(v, 0.95, confidence) if v.size else None
            hi = quantile_upper_bound(v, 0.95, confidence) if v.size else None
            out.append((_finite(lo), _finite(hi)))
        return out

    def place(self, project: Project, registry: Registry,
              measures: Sequence[ProtectiveMeasure]) -> Trial:
        """Judge ``measures`` placed on the bare slope, from the table.

        Raises
        ------
        ProjectError
            A measure that does not fit on the section (or overlaps another).
        InputError
            A profile edit with no restart station upslope of it; the message
            names the measures.
        """
        sc = self.screening
        placed = place_measures(project, registry, list(measures), sc.section)
        edits = [p.footprint for p in placed if isinstance(p.footprint, ProfileEdit)]
        table = sc.bare
        if edits:
            try:
                table = sc.table_for(edits, edited_section(project, sc.section, placed))
            except ValueError as exc:
                raise InputError(f"{' + '.join(p.label for p in placed)}: {exc}") from None
        cost = _cost(sc, placed)
        res = sc.screen_placed(placed, table, cost)
        # The residual as check reports it (judge.evaluation), against the
        # screening's allowance; the foot of the section stands in without protect:.
        prot = protect_summary(sc.protect_x, int(res.residual), sc.n, sc.allowed_fraction,
                               sc.confidence)
        return Trial(tuple(placed), res, cost, prot, bool(edits),
                     int(table.rows.size) if table.rows is not None else 0)

    def verdict(self, measures: Sequence[dict[str, Any]],
                protect: dict[str, Any] | None) -> DesignVerdict:
        """What ``check`` would say of these numbers.

        :func:`~rockfall_design.judge.verdict.verdict_of` of them:
        ``measures`` are the per-measure records of ``check --json``
        (``label``, ``type``, ``met``, ``checks``); ``protect`` the residual
        (None: no protected zone in the project).
        """
        sc = self.screening
        return verdict_of({"rocks": sc.n, "confidence": sc.confidence, "protect": protect,
                           "measures": list(measures)})


def trial_run(project: Project, registry: Registry, rocks: int, seed: int, *,
              table_step_m: float, restart_step_m: float, paths_drawn: int,
              progress: Callable[[int], None] | None = None) -> TrialRun:
    """Run the rocks on the bare slope once and keep the screening table.

    Parameters
    ----------
    project, registry
        The project and its plugins.
    rocks, seed
        Rocks of the run and its seed (the same rocks as ``simulate`` and
        the optimiser's screening draw for this seed).
    table_step_m
        Spacing of the table's stations along the whole section (m).
    restart_step_m
        Spacing of the restart stations (m), where a ditch or berm resumes
        the rocks.
    paths_drawn
        Rocks whose paths are kept (the first rocks of the run).
    progress
        Called with the rocks done; an exception it raises stops the run.
    """
    plan = plan_for(project, registry)
    section = plan.bare
    x0, x1 = float(section.x[0]), float(section.x[-1])
    judged = project
    if project.protect is None:
        # The screening counts rocks reaching a protected zone; without one,
        # the foot of the section stands in (the page says there is none).
        judged = project.model_copy(update={"protect": Protect(x=x1)})
    t0 = time.perf_counter()
    sc = Screening(judged, registry, trial_spec(project, registry), plan.concept,
                   rocks=rocks, seed=seed,
                   stations=np.arange(x0, x1 + 1e-9, table_step_m), rock_progress=progress,
                   restart_stations=np.arange(x0, x1 + 1e-9, restart_step_m),
                   section=section)
    runtime = time.perf_counter() - t0
    t = sc.bare
    reaching = 0
    if project.protect is not None:
        reaching = int(reaches_protected_zone(t.max_x, t.status, float(project.protect.x)).sum())
    return TrialRun(sc, runtime, section, _first_paths(sc, section, min(paths_drawn, rocks)),
                    reaching)


def _first_paths(sc: Screening, section: Section, k: int) -> list[np.ndarray]:
    """The first ``k`` rocks' centre paths, from the same random streams as the table.

    Rock i draws from stream i of the run's key, so these are the table's
    own rocks, drawn.
    """
    rel = sc.releases
    sub = Releases(radius=rel.radius[:k], density=rel.density, x=rel.x[:k],
                   height=rel.height[:k], vx=rel.vx[:k], vy=rel.vy[:k], spin=rel.spin[:k],
                   spin_rolling=rel.spin_rolling[:k])
    tr = run_ensemble(section, sub, key=sc.key, settings=sc.settings, n_trajectories=k)
    out = []
    for traj in tr.trajectories:
        px, py = centre_points(traj, 12)
        out.append(np.column_stack([px, py]))
    return out


def _cost(sc: Screening, placed: Sequence[PlacedMeasure]) -> float:
    """The design's cost by the project's cost model; NaN without one or without a price."""
    if sc.spec.cost_model is None:
        return math.nan
    try:
        return float(sc.cost([p.measure for p in placed]))
    except (KeyError, ValueError):
        return math.nan  # the cost model has no price for it: shown as unknown


def _finite(v: float | None) -> float | None:
    return None if v is None or not math.isfinite(float(v)) else float(v)


"""One scenario of the search: its rocks, screening, looks and decider, set up once.

A single section is a study of one scenario (the project as written, its own
seed); with ``design.scenarios`` each scenario of the study is one, with the
study's values set and its own seed. :func:`set_up` sets each up alike.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..judge.design_spec import DesignSpec, with_residual_target
from ..judge.looks import checker_margin, look_concept
from ..judge.plan import confidence_of, design_of, plan_for
from ..judge.sequential import LookSchedule, plan_looks
from ..studies.sampling import ScenarioRun
from .alternatives import FRESH_OFFSET
from .decide import Decider
from .screening import Screening
from .search import BarrierSlots

if TYPE_CHECKING:  # pragma: no cover
    from ..plugins import Registry
    from ..plugins.concept import SafetyConcept
    from ..project import Project


@dataclass
class Scenario:
    """A scenario's search state.

    Attributes
    ----------
    run : ScenarioRun
        Its index, values, seed and project (index 0, no values: the project
        as written).
    project : Project
        Its project with the design's residual target as the protected
        zone's allowance (:func:`~rockfall_design.judge.design_spec.with_residual_target`).
    spec : DesignSpec
        Its resolved design section.
    concept : SafetyConcept
        Its safety concept at the project's own confidence (the fresh rocks').
    screen : Screening
        The search rocks' screening, built with the look concept (the first look).
    slots : BarrierSlots
        The barrier options of its screening.
    looks : LookSchedule
        The looks of every decision, fixed before any rock runs.
    decider : Decider
        Its sequential decisions (through the screening where it is exact).
    allowed : float
        The residual target as a fraction of the rocks (0: none may reach).
    """

    run: ScenarioRun
    project: Project
    spec: DesignSpec
    concept: SafetyConcept
    screen: Screening
    slots: BarrierSlots
    looks: LookSchedule
    decider: Decider
    allowed: float

    @property
    def fresh_seed(self) -> int:
        """Seed of its fresh rocks: ``design.fresh_seed``, or its own seed + FRESH_OFFSET."""
        if self.spec.fresh_seed is not None:
            return int(self.spec.fresh_seed)
        return self.run.seed + FRESH_OFFSET


def set_up(run: ScenarioRun, registry: Registry, rocks: int | None) -> Scenario:
    """A scenario's screening and decider, with the rocks that can show its residual target.

    Parameters
    ----------
    run : ScenarioRun
        The scenario (its project has a ``design:`` section).
    registry : Registry
    rocks : int, optional
        Search rocks (default ``rocks.count``); raised to the fewest with
        which none reaching shows the residual target at the look's
        confidence (:func:`~rockfall_design.judge.sequential.plan_looks`).
    """
    plan = plan_for(run.project, registry)
    concept = plan.concept
    # Without a design section, design_of says so at the project's line.
    spec = design_of(run.project, registry)
    confidence = confidence_of(concept)
    n = int(run.project.rocks.count if rocks is None else rocks)
    # The design's residual target becomes the protected zone's allowance, so
    # that the exact checks, the fresh rocks and `check` of design.yaml agree.
    project, allowed = with_residual_target(run.project, spec, n)
    # The looks of every decision, fixed before any rock runs: the search rocks
    # are the first look.
    looks = plan_looks(n, max(n, int(spec.max_rocks)), confidence,
                       allowed if allowed > 0 else None)
    lc = look_concept(registry, concept, looks.look_confidence)
    screen = Screening(project, registry, spec, lc, rocks=looks.sizes[0], seed=run.seed,
                       section=plan.bare)
    return Scenario(run, project, spec, concept, screen, BarrierSlots(screen), looks,
                    Decider(screen, looks, checker_margin(spec, confidence)), allowed)

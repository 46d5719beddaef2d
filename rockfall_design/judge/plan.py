"""The plan of a run: a project resolved against its plugins, once per command.

Every command validates the whole project file against the plugins (the
measures' parameters and footprints, the safety concept, the design
section) before it runs a rock. What that validation builds is the plan:
the bare section, the measures and their footprints on it, the edited
section, the safety concept and the ``design:`` section (what the optimiser
may build, resolved by :func:`rockfall_design.judge.design_spec.resolve_design`
with the plan's section and concept). :func:`plan_for` builds it once and
keeps it with the project, so the run that follows uses the same objects
instead of asking the plugins again (a plugin is asked for a measure's
footprint once per command, and a misbehaving one fails before any rock
runs), and the slope's section and the design are made once per command
(tests/judge/test_plan_once.py counts them).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

from ..plugins.concept import DEFAULT_CONFIDENCE
from .design_spec import DesignSpec, resolve_design

if TYPE_CHECKING:  # pragma: no cover
    from ..engine import Section
    from ..plugins import Registry
    from ..plugins.concept import SafetyConcept
    from ..plugins.measure import ProtectiveMeasure
    from ..project import Project
    from .placing import PlacedMeasure

__all__ = ["Plan", "plan_for", "design_of", "planned_section", "confidence_of",
           "validate_plugin_sections"]


@dataclass(frozen=True)
class Plan:
    """A project resolved against its plugins.

    Attributes
    ----------
    project : Project
    registry : Registry
        The plugins it was resolved with.
    measures : tuple of ProtectiveMeasure
        The project's ``measures:``, in file order.
    placed : tuple of PlacedMeasure
        Their footprints on :attr:`bare`, checked for fit and overlap.
    concept : SafetyConcept
        The project's safety concept.
    bare : Section
        The slope section as the project gives it.
    section : Section
        The section with the measures' profile edits applied.
    design : DesignSpec or None
        The ``design:`` section resolved against the plugins (None for a
        project without one): what the optimiser may build, its targets and
        prices. Resolved on first use, once, with this plan's section and
        concept (a copy of a design project made to check the chosen
        measures never asks for it).
    """

    project: Project
    registry: Registry
    measures: tuple[ProtectiveMeasure, ...]
    placed: tuple[PlacedMeasure, ...]
    concept: SafetyConcept
    bare: Section
    section: Section

    @cached_property
    def design(self) -> DesignSpec | None:
        """The resolved ``design:`` section (see the class docs); None without one."""
        if self.project.design is None:
            return None
        return resolve_design(self.project, self.registry, bare=self.bare, concept=self.concept)

    @property
    def confidence(self) -> float:
        """One-sided confidence of every bound of the command (``safety.confidence``, -)."""
        return confidence_of(self.concept)

    @property
    def protect_x(self) -> float | None:
        """Station of the protected zone (m); None without ``protect:``."""
        protect = self.project.protect
        return None if protect is None else float(protect.x)


def confidence_of(concept: SafetyConcept) -> float:
    """The one-sided confidence of a safety concept's bounds (``safety.confidence``, -).

    The one place that reads it: every concept's parameters inherit
    ``confidence`` from :class:`~rockfall_design.plugins.concept.SafetyParams`,
    which gives its default; the plan, the evaluation, the optimiser's
    screening and the verdict take it from here (and a verdict carries it).
    A concept whose parameter model does not inherit it (the contract asks
    that it does) is given the contract's default.
    """
    return float(getattr(concept.params, "confidence", DEFAULT_CONFIDENCE))


def plan_for(project: Project, registry: Registry, *, bare: Section | None = None) -> Plan:
    """The plan of ``project`` with ``registry``, built on the first call and then kept.

    The plan is kept on the project object for the registry it was built
    with (by identity): another registry (e.g. one with a plugin blocked),
    or a copy of the project with other measures, gets its own plan.

    Parameters
    ----------
    project : Project
    registry : Registry
    bare : Section, optional
        The project's slope section, when the caller holds it already: a copy
        of a planned project with other measures stands on the same ground
        (the chosen design's check after ``optimise``), so its section is
        not built again. Ignored when the plan exists.

    Raises
    ------
    ProjectError
        Exit code 2, located at the offending key (see
        :func:`rockfall_design.api.validate_project`).
    PluginError
        Exit code 3, if a plugin misbehaves.
    """
    cached = project._plan
    # A copy (model_copy) carries its original's private attributes, so the
    # plan must be this very project's.
    if cached is not None and cached.project is project and cached.registry is registry:
        return cached
    # Imported here: the judgement sits downstream of the project and the
    # plugins, and `rockfall_design.judge` stays cheap to import.
    from ..run.releases import section_from_project
    from .placing import build_concept, build_measures, edited_section, place_measures

    measures = build_measures(project, registry)
    concept = build_concept(project, registry)
    if bare is None:
        bare = section_from_project(project)
    placed = place_measures(project, registry, measures, bare)
    section = edited_section(project, bare, placed)
    plan = Plan(project=project, registry=registry, measures=tuple(measures),
                placed=tuple(placed), concept=concept, bare=bare, section=section)
    project._plan = plan
    return plan


def planned_section(project: Project) -> Section | None:
    """The slope section of ``project``'s plan, if it has one (None: not planned yet).

    The bare section does not depend on the plugins, so the plan of any
    registry serves: ``simulate`` runs on the section its validation built.
    """
    cached = project._plan
    return cached.bare if cached is not None and cached.project is project else None


def design_of(project: Project, registry: Registry) -> DesignSpec:
    """The project's resolved ``design:`` section, from its plan (see :func:`plan_for`).

    Raises
    ------
    ProjectError
        Exit code 2 at the project's line when it has no ``design:`` section,
        or where the section is wrong.
    """
    design = plan_for(project, registry).design
    if design is None:
        return resolve_design(project, registry)  # says that there is no design section
    return design


def validate_plugin_sections(project: Project, registry: Registry) -> None:
    """The checks of the sections that plugins own: measures, safety concept and design.

    :func:`rockfall_design.api.validate_project` runs them and then the
    study's; a varied project of a study (which has no study) runs them alone
    (:func:`rockfall_design.studies.check_study`, the study's and the
    scenario checks' runs).

    Raises
    ------
    ProjectError
        Exit code 2, located at the offending key.
    PluginError
        Exit code 3, if a plugin misbehaves.
    """
    _ = plan_for(project, registry).design  # resolved (and so checked) when there is one

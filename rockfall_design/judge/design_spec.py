"""The ``design:`` section resolved against the plugins: what the optimiser may build.

:func:`resolve_design` turns the project's raw design section (shapes checked
by :mod:`rockfall_design.project`) into a :class:`DesignSpec` of plain,
frozen objects, once, before any search: candidate measures with their fixed
parameters, continuous ranges and discrete options, the catalogue products
they may use, and the instantiated cost model. Every problem is a
:class:`~rockfall_design.errors.ProjectError` at its line, in the project file
or in a catalogue file.

:func:`build_candidate_measure` then makes one measure of a candidate from the
values the optimiser picked (no file lines there: a ValueError).

What a plugin declares
----------------------
Each field of a measure's ``Params`` may declare its design role in its
metadata, ``json_schema_extra={"design": ...}`` (read by
:func:`~rockfall_design.plugins.measure.design_role`; the vocabulary is in
``hookspecs.py``): a free variable with bounds or options, or a catalogue
choice. :func:`~rockfall_design.plugins.declared.declared_design` collects them per
measure class. A plugin written before these declarations keeps today's
conventions: a field named ``product`` is the catalogue product, ``height``
its height and ``capacity_kj`` its energy class, and ``design_variables``
gives bounds.

Products
--------
A measure with a catalogue product field (fence and wall among the
built-ins) is always built from a catalogue product: the optimiser picks the
product among :attr:`CandidateSpec.products` and the height among that
product's heights; the capacity field is the product's energy class, and
other keys of the product that are parameters of the measure (a wall's
``thickness``) are set from it. Such a candidate therefore must not give the
height, the capacity or those keys itself.

Defaults
--------
A parameter the candidate does not give is searched within the bounds (or
options) its field declares; a required parameter without a declaration
becomes a continuous range with the plugin's ``design_variables`` bounds (a
ditch's ``width`` 2..20 m) where they are finite; otherwise it is an error.

Prices
------
Before any search, :func:`resolve_design` prices a sample design of every
candidate: a quantity of its bill that the cost catalogue does not price at
all is an error at ``design.costs`` naming the candidate and the quantity
(:func:`design_cost` prices the designs of the search).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ..plugins.cost_model import CostModel
from ..plugins.declared import DeclaredDesign, declared_design
from ..project.schema import DEFAULT_MAX_ROCKS
from .candidates import (
    CandidateSpec,
    Product,
    build_candidate_measure,
    resolve_candidate,
)
from .costing import check_prices, design_bill, design_cost, resolve_cost_model
from .margin import DEFAULT_CHECKER_POWER
from .placing import build_concept, required_figures_problem, unknown_measure_type

if TYPE_CHECKING:  # pragma: no cover

    from ..engine import Section
    from ..plugins import Registry
    from ..plugins.concept import SafetyConcept
    from ..project import Project

__all__ = [
    "CandidateSpec",
    "DesignSpec",
    "Product",
    "DeclaredDesign",
    "build_candidate_measure",
    "declared_design",
    "design_bill",
    "design_cost",
    "resolve_design",
    "with_residual_target",
    "unknown_measure_type",
]


@dataclass(frozen=True)
class DesignSpec:
    """The design section, resolved: everything the optimiser needs besides the rocks.

    Attributes
    ----------
    max_measures : int
        Largest number of measures in one design.
    residual_count, residual_fraction : int or None, float or None
        Rocks allowed to reach the protected zone (``protect.x``): a count or
        a fraction of the rocks; exactly one is set.
    fresh_rocks, fresh_seed : int or None
        Rocks and seed of the independent re-check; None: the optimiser's
        defaults (twice the rocks that decided the design; the run's seed +
        1000003). The re-check never has fewer than twice the deciding rocks.
    max_rocks : int
        Most rocks a design near a limit is decided with.
    checker_power : float or None
        The chance with which a checker's check of twice the deciding rocks,
        at a seed of their own, confirms the chosen design with confidence
        (:mod:`rockfall_design.judge.margin`); None: no such margin.
    length_m : float
        Length of slope to protect (m).
    candidates : tuple of CandidateSpec
        In the order of ``design.candidates``.
    cost_model : CostModel
        The instantiated cost model.
    products : dict of str to dict of str to Product
        The whole catalogue: measure type -> product name -> Product.
    """

    max_measures: int
    residual_count: int | None
    residual_fraction: float | None
    fresh_rocks: int | None
    fresh_seed: int | None
    length_m: float
    candidates: tuple[CandidateSpec, ...]
    cost_model: CostModel
    products: dict[str, dict[str, Product]]
    max_rocks: int = DEFAULT_MAX_ROCKS
    checker_power: float | None = DEFAULT_CHECKER_POWER


def _products(catalogue: dict[str, dict[str, dict]]) -> dict[str, dict[str, Product]]:
    """The catalogue's products (as loaded from ``design.catalogue``), by kind and name."""
    return {
        kind: {
            name: Product(
                name=name,
                kind=kind,
                capacity_kj=float(entry["capacity_kj"]),
                heights=tuple(sorted(float(h) for h in entry["heights"])),
                extra={k: v for k, v in entry.items() if k not in ("capacity_kj", "heights")},
            )
            for name, entry in table.items()
        }
        for kind, table in catalogue.items()
    }


def resolve_design(project: Project, registry: Registry, *, bare: Section | None = None,
                   concept: SafetyConcept | None = None) -> DesignSpec:
    """Resolve the project's ``design:`` section against the plugins.

    A command reads it from its plan (:func:`~rockfall_design.judge.plan.design_of`).

    Parameters
    ----------
    project
        A loaded project with a ``design:`` section.
    registry
        The plugins (measures and cost models).
    bare, concept
        The project's slope section and safety concept, if the caller has
        them (the plan); default: built from the project.

    Returns
    -------
    DesignSpec

    Raises
    ------
    ProjectError
        At the line of the problem, in the project file or a catalogue file:
        no design section; an unknown measure type, parameter, product or
        cost model (with "did you mean"); a fixed value, range end or option
        that the measure's parameter model rejects; a candidate with a
        ``product`` parameter but no catalogue products, or giving what its
        products set (``height``, ``capacity_kj``); a required parameter
        with neither a value nor plugin bounds; a catalogue product the
        measure rejects; cost parameters the cost model rejects.
    PluginError
        If the cost model's class fails to instantiate.
    """
    design = project.design
    if design is None:
        raise project.error_at(
            ("design",), "the project has no design: section (what the optimiser may build)"
        )
    catalogue = _products(design.catalogue)
    candidates = tuple(
        resolve_candidate(project, registry, i, raw, catalogue)
        for i, raw in enumerate(design.candidates)
    )
    cost_model = resolve_cost_model(project, registry)
    check_prices(project, registry, candidates, cost_model, bare)
    if concept is None:
        concept = build_concept(project, registry)
    _check_required_figures(project, registry, concept)
    residual_count, residual_fraction = design.residual_count, design.residual_fraction
    by_concept = concept.allowed_residual_fraction()
    if by_concept is not None:
        # The stricter of the concept's and the design's fraction; a count (or a
        # fraction of 0, the default) gives way to the concept's.
        residual_fraction = (min(residual_fraction, by_concept)
                             if residual_fraction else by_concept)
        residual_count = None
    return DesignSpec(
        max_measures=design.max_measures,
        residual_count=residual_count,
        residual_fraction=residual_fraction,
        fresh_rocks=design.fresh_rocks,
        fresh_seed=design.fresh_seed,
        length_m=design.site.length_m,
        candidates=candidates,
        cost_model=cost_model,
        products=catalogue,
        max_rocks=design.max_rocks,
        checker_power=design.checker_power,
    )




def _check_required_figures(project: Project, registry: Registry, concept: Any) -> None:
    """Every catalogue product gives what the safety concept requires of its measure.

    Raises
    ------
    ProjectError
        At the product's line in the catalogue: e.g. a fence without its EAD
        340059 test figures under an EAD concept.
    """
    design = project.design
    assert design is not None
    for kind, table in design.catalogue.items():
        cls = registry.measures.get(kind)
        if cls is None:
            continue
        for name, entry in table.items():
            why = required_figures_problem(concept, cls, entry)
            if why:
                raise design.products_locator.error_at((kind, name), f"{kind} product {name!r}: "
                                                       f"{why}")


def with_residual_target(project: Project, spec: DesignSpec,
                         rocks: int) -> tuple[Project, float]:
    """The project with the design's residual target as the protected zone's allowance.

    So that the optimiser's exact checks, its fresh rocks and ``check`` of
    design.yaml all judge the residual against the same fraction.

    Parameters
    ----------
    project : Project
        With a ``protect:`` section.
    spec : DesignSpec
        Its resolved design section.
    rocks : int
        The search rocks: a target given as a count is that share of them.

    Returns
    -------
    project, allowed : Project, float
        The project with ``protect.allowed_fraction`` set, and that fraction (-).
    """
    allowed = spec.residual_fraction
    if allowed is None:
        allowed = (spec.residual_count or 0) / max(int(rocks), 1)
    return project.model_copy(update={"protect": project.protect.model_copy(
        update={"allowed_fraction": allowed})}), float(allowed)

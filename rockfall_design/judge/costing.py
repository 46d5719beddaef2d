"""Prices of designs: the cost model resolved once, a design's cost and its bill.

Before any search every candidate's sample design is priced
(:func:`check_prices`): a quantity the cost catalogue does not price is an
error at ``design.costs``; then :func:`design_cost` prices the designs of
the search and :func:`design_bill` itemises the chosen one.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from ..plugins import guard
from ..plugins.cost_model import CostModel
from .candidates import (
    CandidateSpec,
    build_candidate_measure,
    sample_params,
)
from .placing import unknown_plugin_name
from .records import Bill, BillLine

if TYPE_CHECKING:  # pragma: no cover
    from collections.abc import Sequence

    from ..engine import Section
    from ..plugins import Registry
    from ..plugins.measure import ProtectiveMeasure
    from ..project import Project
    from .design_spec import DesignSpec


def design_cost(
    registry: Registry, spec: DesignSpec, measures: Sequence[ProtectiveMeasure], section: Section
) -> float:
    """Cost of a design (currency units): its measures' bills, priced by the cost model.

    Parameters
    ----------
    registry
        The plugins.
    spec
        The resolved design section (its cost model and length of slope).
    measures
        The measures of the design.
    section
        The bare slope section the measures stand on.

    Returns
    -------
    float

    Raises
    ------
    KeyError or ValueError
        From the cost model: it has no price for one of the measures.
    PluginError
        A measure's ``bill``/``quantities`` or the cost model broke its contract.
    """
    model, total = spec.cost_model, 0.0
    # A cost model written before bills existed implements cost() only: call
    # that, so that a fault is named in the method its author wrote.
    by_bill = type(model).price is not CostModel.price
    for m in measures:
        quantities = guard(registry).measure(m).quantities(section)
        if by_bill:
            bill = guard(registry).measure(m).bill(section)
            value = guard(registry).cost_model(model).price(m, bill, quantities,
                                                             spec.length_m)
        else:
            value = guard(registry).cost_model(model).cost(m, quantities, spec.length_m)
        total += float(value)
    return total


def _bill_lines(registry: Registry, spec: DesignSpec, m: ProtectiveMeasure, section: Section,
                where: str) -> tuple[float, list[BillLine]]:
    """One measure's price and its lines: itemised where the parts add up, else a lump sum."""
    model, length = spec.cost_model, spec.length_m
    priced = guard(registry).cost_model(model)
    by_bill = type(model).price is not CostModel.price
    label = guard(registry).measure(m).label()
    quantities = guard(registry).measure(m).quantities(section)
    if not by_bill:
        whole = float(priced.cost(m, quantities, length))
        return whole, [BillLine(label, "the measure as priced", 1.0, "lump sum", whole, whole,
                                None, where)]
    bill = guard(registry).measure(m).bill(section)
    whole = float(priced.price(m, bill, quantities, length))
    try:
        fixed = float(priced.price(m, [], quantities, length))
        parts = [float(priced.price(m, [q], quantities, length)) - fixed for q in bill]
    except (KeyError, ValueError):
        parts = None
    if parts is None or not math.isclose(fixed + sum(parts), whole, rel_tol=1e-9, abs_tol=1e-6):
        return whole, [BillLine(label, "the measure as priced", 1.0, "lump sum", whole, whole,
                                None, where)]
    lines = []
    if fixed:
        lines.append(BillLine(label, "fixed cost of the measure", 1.0, "each", fixed, fixed,
                              None, where))
    for q, amount in zip(bill, parts, strict=True):
        count = q.amount * length
        what = " ".join(str(b) for b in (
            q.name, q.product, None if q.size is None else f"{q.size:g} m") if b is not None)
        lines.append(BillLine(label, what, count, q.unit, amount / count if count else 0.0,
                              amount, q.amount, where))
    if not lines:  # a measure priced at nothing
        lines.append(BillLine(label, "the measure as priced", 1.0, "lump sum", whole, whole,
                              None, where))
    return whole, lines


def design_bill(
    registry: Registry, spec: DesignSpec, measures: Sequence[ProtectiveMeasure], section: Section,
    source: str = "",
) -> Bill:
    """The bill of a design: per measure its quantities, unit prices and amounts.

    Built from the very numbers :func:`design_cost` adds up: each measure's
    amount is the cost model's ``price`` of its whole bill, as there. A cost
    model that prices by bill (``price``) is asked again with the fixed part
    alone (an empty bill) and with each quantity alone, which itemises the
    measure's price into its fixed cost and one line per quantity; when
    those lines do not add up to the whole (a model with discounts, say), or
    the model prices the older way (``cost``), the measure is one lump-sum
    line of its price.

    Parameters
    ----------
    registry, spec, measures, section
        As :func:`design_cost`.
    source : str
        Where the prices come from (the cost catalogue file), for the bill's
        ``source`` of each line.

    Returns
    -------
    Bill
        Its lines (:class:`~rockfall_design.judge.records.BillLine`), the
        ``total`` (the sum of the measures' prices, what :func:`design_cost`
        returns), ``length_m`` and the cost ``model``; ``to_json()`` gives
        the ``bill`` of ``optimise --json``.

    Raises
    ------
    KeyError or ValueError
        From the cost model, as :func:`design_cost`.
    """
    where = f"cost model {spec.cost_model.name}" + (f", {source}" if source else "")
    items: list[BillLine] = []
    total = 0.0
    for m in measures:
        whole, lines = _bill_lines(registry, spec, m, section, where)
        total += whole
        items += lines
    return Bill(tuple(items), total, spec.length_m, spec.cost_model.name)


def check_prices(
    project: Project, registry: Registry, candidates: Sequence[CandidateSpec], model: CostModel,
    bare: Section | None = None,
) -> None:
    """Every candidate's quantities have a price: else an error at ``design.costs``.

    A sample design of each candidate is built, its bill taken on the bare
    section (``bare``, the plan's; default: built from the project), and the
    cost model asked whether it prices every quantity
    (:meth:`CostModel.missing_price`). A candidate none of whose samples fits
    on the section is left to the search (which reports designs that do not
    fit, or have no price).
    """
    from ..run.releases import section_from_project

    design = project.design
    assert design is not None
    if type(model).missing_price is CostModel.missing_price:
        return  # the model says nothing in advance: the search reports what it cannot price
    section = section_from_project(project) if bare is None else bare
    source = (f"catalogue {design.costs.file}" if design.costs.file
              else "catalogue in design.costs.params")
    for spec in candidates:
        for params in sample_params(spec):
            try:
                measure = build_candidate_measure(spec, registry, params)
                guard(registry).measure(measure).footprint(section)
            except ValueError:
                continue  # this sample does not fit: try the next
            # quantities() first: a fault there is named as such, not as one of
            # the bill() that the default bill asks it from.
            guard(registry).measure(measure).quantities(section)
            bill = guard(registry).measure(measure).bill(section)
            why = guard(registry).cost_model(model).missing_price(measure, bill)
            if why:
                raise project.error_at(
                    ("design", "costs"),
                    f"candidate design.candidates[{spec.index}] ({spec.kind}): {why} "
                    f"({source}, cost model {model.name!r})",
                )
            break


def resolve_cost_model(project: Project, registry: Registry) -> CostModel:
    """The cost model named in ``design.costs``, instantiated with its checked parameters."""
    design = project.design
    assert design is not None
    name = design.costs.model
    cls = registry.cost_models.get(name)
    if cls is None:
        raise unknown_plugin_name(project, registry, "cost", ("design", "costs", "model"), name)
    params = design.costs_locator.validate_params((), cls.Params, design.cost_params)
    return guard(registry).instantiate(cls, params)

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

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ..errors import PluginError
from ..judge.placing import unknown_measure_type, unknown_plugin_name
from ..plugins import guard
from ..plugins.cost_model import CostModel
from ..plugins.declared import DeclaredDesign, declared_design
from ..project import params_problem

if TYPE_CHECKING:  # pragma: no cover
    from collections.abc import Sequence

    from ..engine import Section
    from ..plugins import Registry
    from ..plugins.measure import ProtectiveMeasure
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
    "unknown_measure_type",
]

@dataclass(frozen=True)
class Product:
    """A catalogue product.

    Attributes
    ----------
    name : str
        Catalogue name, e.g. ``RX-100``.
    kind : str
        Measure type it is a product of, e.g. ``fence``.
    capacity_kj : float
        Energy class (kJ).
    heights : tuple of float
        Heights it comes in (m), ascending.
    extra : dict
        Its other keys as in the catalogue (e.g. ``thickness``); those that are
        parameters of the measure are set from the product.
    """

    name: str
    kind: str
    capacity_kj: float
    heights: tuple[float, ...]
    extra: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class CandidateSpec:
    """A measure the optimiser may use, resolved against its plugin.

    Attributes
    ----------
    index : int
        Position in ``design.candidates``.
    kind : str
        Measure type.
    x_range : (float, float)
        Station range (m) the optimiser may place it in.
    products : tuple of Product
        For measures with a ``product`` parameter: the products allowed, in
        catalogue order (else ``()``).
    fixed : dict
        Fixed parameters, as given.
    ranges : dict of str to (float, float)
        Continuous parameters: name -> (low, high), the candidate's or, for a
        required parameter not given, the plugin's design-variable bounds.
    options : dict of str to tuple
        Discrete parameters: name -> the options.
    declared : DeclaredDesign
        What the measure's plugin declares: which fields take the catalogue
        product, height and capacity.
    """

    index: int
    kind: str
    x_range: tuple[float, float]
    products: tuple[Product, ...]
    fixed: dict[str, Any]
    ranges: dict[str, tuple[float, float]]
    options: dict[str, tuple[Any, ...]]
    declared: DeclaredDesign = field(default_factory=DeclaredDesign, compare=False)

    @property
    def product_field(self) -> str | None:
        """The parameter that takes the catalogue product (None without products)."""
        return self.declared.product if self.products else None

    @property
    def height_field(self) -> str | None:
        """The parameter that takes one of the product's heights (m), or None."""
        return self.declared.height if self.products else None

    def product(self, name: str) -> Product:
        """The allowed product ``name``; KeyError if it is not one of :attr:`products`."""
        for product in self.products:
            if product.name == name:
                return product
        allowed = ", ".join(p.name for p in self.products) or "none"
        raise KeyError(f"product {name!r} is not allowed for this {self.kind} (allowed: {allowed})")


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
    max_rocks: int = 50_000


def _fmt(value: Any) -> str:
    return format(value, ".12g") if isinstance(value, float) else str(value)


def _product_params(product: Product, fields: Any, declared: DeclaredDesign) -> dict[str, Any]:
    """Parameters a product sets on a measure with these Params fields (height excluded)."""
    assert declared.product is not None
    params: dict[str, Any] = {declared.product: product.name}
    if declared.capacity is not None:
        params[declared.capacity] = product.capacity_kj
    for key, value in product.extra.items():
        if key in fields and key not in (declared.product, declared.height):
            params[key] = value
    return params


def resolve_design(project: Project, registry: Registry) -> DesignSpec:
    """Resolve the project's ``design:`` section against the plugins.

    Parameters
    ----------
    project
        A loaded project with a ``design:`` section.
    registry
        The plugins (measures and cost models).

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
    catalogue = {
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
        for kind, table in design.catalogue.items()
    }
    candidates = tuple(
        _resolve_candidate(project, registry, i, raw, catalogue)
        for i, raw in enumerate(design.candidates)
    )
    cost_model = _resolve_cost_model(project, registry)
    _check_prices(project, registry, candidates, cost_model)
    return DesignSpec(
        max_measures=design.max_measures,
        residual_count=design.residual_count,
        residual_fraction=design.residual_fraction,
        fresh_rocks=design.fresh_rocks,
        fresh_seed=design.fresh_seed,
        length_m=design.site.length_m,
        candidates=candidates,
        cost_model=cost_model,
        products=catalogue,
        max_rocks=design.max_rocks,
    )


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


def design_bill(
    registry: Registry, spec: DesignSpec, measures: Sequence[ProtectiveMeasure], section: Section,
    source: str = "",
) -> dict[str, Any]:
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
    dict
        ``items``: one dict per line, ``measure`` (its label), ``quantity``
        (what is billed), ``count`` (how many ``unit``: over the whole site
        length), ``unit``, ``unit_price`` (currency per unit), ``amount``
        (currency), ``per_m`` (amount of the quantity per running metre of
        slope, or None), ``source``; ``total`` (the sum of the measures'
        prices, what :func:`design_cost` returns), ``length_m``, ``model``.

    Raises
    ------
    KeyError or ValueError
        From the cost model, as :func:`design_cost`.
    """
    model, length = spec.cost_model, spec.length_m
    priced = guard(registry).cost_model(model)
    by_bill = type(model).price is not CostModel.price
    where = f"cost model {model.name}" + (f", {source}" if source else "")
    items: list[dict[str, Any]] = []
    total = 0.0
    for m in measures:
        label = guard(registry).measure(m).label()
        quantities = guard(registry).measure(m).quantities(section)
        if by_bill:
            bill = guard(registry).measure(m).bill(section)
            whole = float(priced.price(m, bill, quantities, length))
        else:
            bill = []
            whole = float(priced.cost(m, quantities, length))
        total += whole
        lines: list[dict[str, Any]] = []
        if by_bill:
            try:
                fixed = float(priced.price(m, [], quantities, length))
                parts = [float(priced.price(m, [q], quantities, length)) - fixed for q in bill]
            except (KeyError, ValueError):
                parts = None
            if parts is not None and math.isclose(fixed + sum(parts), whole, rel_tol=1e-9,
                                                  abs_tol=1e-6):
                if fixed:
                    lines.append({"measure": label, "quantity": "fixed cost of the measure",
                                  "count": 1.0, "unit": "each", "unit_price": fixed,
                                  "amount": fixed, "per_m": None, "source": where})
                for q, amount in zip(bill, parts, strict=True):
                    count = q.amount * length
                    what = " ".join(str(b) for b in (
                        q.name, q.product, None if q.size is None else f"{q.size:g} m")
                        if b is not None)
                    lines.append({"measure": label, "quantity": what, "count": count,
                                  "unit": q.unit, "unit_price": amount / count if count else 0.0,
                                  "amount": amount, "per_m": q.amount, "source": where})
        if not lines:
            lines.append({"measure": label, "quantity": "the measure as priced", "count": 1.0,
                          "unit": "lump sum", "unit_price": whole, "amount": whole,
                          "per_m": None, "source": where})
        items += lines
    return {"items": items, "total": total, "length_m": length, "model": model.name}


def _sample_params(spec: CandidateSpec) -> list[dict[str, Any]]:
    """A few designs of a candidate to price before the search (the middle first)."""
    out = []
    for t in (0.5, 0.0, 1.0):
        params: dict[str, Any] = {"x": spec.x_range[0] + t * (spec.x_range[1] - spec.x_range[0])}
        for name, (low, high) in spec.ranges.items():
            params[name] = low + t * (high - low)
        for name, opts in spec.options.items():
            params[name] = opts[0] if t < 1.0 else opts[-1]
        if spec.products and spec.product_field is not None:
            product = spec.products[0]
            params[spec.product_field] = product.name
            if spec.height_field is not None:
                params[spec.height_field] = product.heights[0]
        out.append(params)
    return out


def _check_prices(
    project: Project, registry: Registry, candidates: Sequence[CandidateSpec], model: CostModel
) -> None:
    """Every candidate's quantities have a price: else an error at ``design.costs``.

    A sample design of each candidate is built, its bill taken on the bare
    section, and the cost model asked whether it prices every quantity
    (:meth:`CostModel.missing_price`). A candidate none of whose samples fits
    on the section is left to the search (which reports designs that do not
    fit, or have no price).
    """
    from ..run.releases import section_from_project

    design = project.design
    assert design is not None
    if type(model).missing_price is CostModel.missing_price:
        return  # the model says nothing in advance: the search reports what it cannot price
    section = section_from_project(project)
    source = (f"catalogue {design.costs.file}" if design.costs.file
              else "catalogue in design.costs.params")
    for spec in candidates:
        for params in _sample_params(spec):
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


def _resolve_cost_model(project: Project, registry: Registry) -> CostModel:
    design = project.design
    assert design is not None
    name = design.costs.model
    cls = registry.cost_models.get(name)
    if cls is None:
        raise unknown_plugin_name(project, registry, "cost", ("design", "costs", "model"), name)
    params = design.costs_locator.validate_params((), cls.Params, design.cost_params)
    return guard(registry).instantiate(cls, params)


def _declared(registry: Registry, cls: Any, kind: str) -> DeclaredDesign:
    """:func:`declared_design`, a malformed declaration being the plugin's fault (exit 3)."""
    try:
        return declared_design(cls)
    except ValueError as exc:
        provider = registry.provider.get(("measure", kind))
        who = f"measure {kind!r}" + (f" (from {provider})" if provider else "")
        raise PluginError(
            f"{who}: bad design declaration in its Params: {exc}; "
            "this is a bug in the plugin, not in the project"
        ) from None


def _resolve_candidate(
    project: Project,
    registry: Registry,
    i: int,
    raw: dict[str, Any],
    catalogue: dict[str, dict[str, Product]],
) -> CandidateSpec:
    design = project.design
    assert design is not None
    at = ("design", "candidates", i)
    kind = raw["type"]
    cls = registry.measures.get(kind)
    if cls is None:
        raise unknown_measure_type(project, registry, at + ("type",), kind)
    fields = cls.Params.model_fields
    if "x" not in fields:
        raise project.error_at(
            at + ("x",),
            f"measure type {kind!r} has no station parameter x, so the optimiser cannot place it",
        )
    for key in raw:
        if key != "type" and key not in fields:
            raise project.unknown_name(at + (key,), key, list(fields), f"{kind} parameter")
    declared = _declared(registry, cls, kind)

    # products
    product_field = declared.product
    products: tuple[Product, ...] = ()
    supplied: set[str] = set()
    if product_field is not None:
        products = _candidate_products(project, i, raw, kind, catalogue, product_field)
        supplied = {product_field} | {
            f for f in (declared.height, declared.capacity) if f is not None}
        for product in products:
            supplied |= set(_product_params(product, fields, declared))
        for key in raw:
            if key in supplied and key != product_field:
                if key == declared.height:
                    why = "the optimiser chooses it among the heights of the catalogue products"
                elif key == declared.capacity:
                    why = "it is the energy class of the catalogue product"
                else:
                    why = "the catalogue product sets it"
                raise project.error_at(
                    at + (key,),
                    f"do not give {key} for a {kind} candidate: {why} (design.products); "
                    f"restrict the products with {product_field}: [NAME, ...] instead",
                )

    # fixed values, ranges, options
    x_low, x_high = (float(v) for v in raw["x"])
    fixed: dict[str, Any] = {}
    ranges: dict[str, tuple[float, float]] = {}
    options: dict[str, tuple[Any, ...]] = {}
    for key, value in raw.items():
        if key in ("type", "x", product_field):
            continue
        if isinstance(value, list):
            ranges[key] = (float(value[0]), float(value[1]))
        elif isinstance(value, dict):
            options[key] = tuple(value["options"])
        else:
            fixed[key] = value

    # what the candidate does not give: the plugin's declarations; a required
    # parameter without one takes design_variables bounds, or is an error
    for name, info in fields.items():
        if name in raw or name in supplied or name == "x":
            continue
        if name in declared.ranges:
            ranges[name] = declared.ranges[name]
            continue
        if name in declared.options:
            options[name] = declared.options[name]
            continue
        if not info.is_required():
            continue
        if name in declared.fallback_bounds:
            ranges[name] = declared.fallback_bounds[name]
            continue
        about = f" ({info.description.rstrip('.')})" if info.description else ""
        raise project.error_at(
            at,
            f"required {kind} parameter {name!r} is missing{about}: give a value, "
            "a range [min, max] or {options: [...]}",
        )

    # check every value through the measure's Params: the fixed ones together,
    # each range end and option on its own, the others at the plugin's example
    base: dict[str, Any] = {k: v for k, v in cls.example.items() if k in fields}
    base.update(fixed)
    base["x"] = x_low
    for key, opts in options.items():
        base.setdefault(key, opts[0])
    if products:
        base.update(_product_params(products[0], fields, declared))
        if declared.height is not None:
            base[declared.height] = products[0].heights[0]

    def check(values: dict[str, Any], where: tuple) -> None:
        problem = params_problem(cls.Params, {**base, **values})
        if problem is None:
            return
        loc, message = problem
        if loc and loc[0] in values:
            path = where + tuple(loc[1:])
        elif loc and loc[0] in raw:
            path = at + tuple(loc)
        else:
            path = at
        raise project.error_at(path, message)

    for product in products:
        _check_product(project, cls, kind, product, base, fields, declared)
    check({}, at)
    for key, (low, high) in ranges.items():
        not_numeric = _range_problem(cls.Params, key)
        if not_numeric:
            raise project.error_at(at + (key,) if key in raw else at, not_numeric)
        for end, value in enumerate((low, high)):
            check({key: value}, at + (key, end) if key in raw else at)
    for key, opts in options.items():
        for k, value in enumerate(opts):
            check({key: value}, at + (key, "options", k) if key in raw else at)
    for end, value in enumerate((x_low, x_high)):
        check({"x": value}, at + ("x", end))

    return CandidateSpec(
        index=i,
        kind=kind,
        x_range=(x_low, x_high),
        products=products,
        fixed=fixed,
        ranges=ranges,
        options=options,
        declared=declared,
    )


def _range_problem(model: Any, key: str) -> str:
    """Why parameter ``key`` cannot be a continuous range ('' if it can)."""
    info = model.model_fields[key]
    annotation = info.annotation
    args = getattr(annotation, "__args__", None) or (annotation,)
    if float in args:
        return ""
    if int in args:
        return (
            f"{key} is an integer parameter, it cannot vary continuously: "
            "give {options: [...]} instead of a range"
        )
    return f"{key} is not a number, it cannot be a range [min, max]: give {{options: [...]}}"


def _candidate_products(
    project: Project,
    i: int,
    raw: dict[str, Any],
    kind: str,
    catalogue: dict[str, dict[str, Product]],
    product_field: str = "product",
) -> tuple[Product, ...]:
    """The products a candidate may use: those it names (in ``product_field``), or all."""
    design = project.design
    assert design is not None
    at = ("design", "candidates", i)
    table = catalogue.get(kind, {})
    if product_field not in raw:
        if not table:
            kinds = ", ".join(catalogue) or "none"
            source = (
                f"the catalogue {design.products}"
                if isinstance(design.products, str)
                else "design.products"
                if design.products
                else "no catalogue (design.products is not given)"
            )
            raise project.error_at(
                at,
                f"a {kind} candidate needs catalogue products (its {product_field} and what "
                f"the product sets come from them), but {source} has no {kind} products "
                f"(measure types in it: {kinds})",
            )
        return tuple(table.values())
    value = raw[product_field]
    if isinstance(value, str):
        names, paths = [value], [at + (product_field,)]
    elif isinstance(value, dict):
        names = list(value["options"])
        paths = [at + (product_field, "options", k) for k in range(len(names))]
    else:
        names = list(value)
        paths = [at + (product_field, k) for k in range(len(names))]
    chosen = []
    for name, path in zip(names, paths, strict=True):
        if name not in table:
            raise project.unknown_name(path, name, table, f"{kind} product")
        chosen.append(table[name])
    return tuple(chosen)


def _check_product(
    project: Project,
    cls: Any,
    kind: str,
    product: Product,
    base: dict[str, Any],
    fields: Any,
    declared: DeclaredDesign,
) -> None:
    """A product the measure rejects is an error in the catalogue, at the product's line.

    A problem with a parameter the product does not set is left to the
    candidate's own checks (reported in the project file).
    """
    locator = project.design.products_locator  # type: ignore[union-attr]
    at = (kind, product.name)
    params = {**base, **_product_params(product, fields, declared)}
    heights = product.heights if declared.height is not None else (None,)
    for height in heights:
        values = dict(params)
        if height is not None:
            values[declared.height] = height
        problem = params_problem(cls.Params, values)
        if problem is None:
            continue
        loc, message = problem
        key = loc[0] if loc else None
        if key is not None and key == declared.height:
            raw_heights = project.design.catalogue[kind][product.name]["heights"]  # type: ignore[union-attr]
            path = at + ("heights", raw_heights.index(height))
        elif key is not None and key == declared.capacity:
            path = at + ("capacity_kj",)
        elif key in product.extra:
            path = at + (key,)
        elif key is not None and key == declared.product:
            path = at
        else:
            continue
        raise locator.error_at(path, f"{kind} product {product.name!r}: {message}")


def build_candidate_measure(
    spec: CandidateSpec, registry: Registry, params: dict[str, Any]
) -> ProtectiveMeasure:
    """A measure of candidate ``spec`` with the values the optimiser picked.

    Parameters
    ----------
    spec
        The candidate.
    registry
        The plugins (the same as given to :func:`resolve_design`).
    params
        The picked values, by parameter name: ``x`` (m), one value per range
        and option parameter, and for a candidate with products its product
        field (:attr:`CandidateSpec.product_field`, a name) and, if the
        measure has one, its height field (m, one of the product's heights).
        The candidate's fixed parameters and the product's capacity (and
        other parameters) are added here; a value in ``params`` overrides a
        fixed one.

    Returns
    -------
    ProtectiveMeasure

    Raises
    ------
    ValueError
        If the values are not valid for the measure's parameter model, ``x``
        or a range value lies outside its range, an option value is not one of
        the options, or the product is not allowed or lacks that height.
    PluginError
        If the measure's class fails to instantiate.
    """
    cls = registry.measure(spec.kind)
    fields = cls.Params.model_fields
    label = f"candidate {spec.index} ({spec.kind})"
    values: dict[str, Any] = dict(spec.fixed)
    declared = spec.declared
    if spec.products:
        assert declared.product is not None
        name = params.get(declared.product)
        if name is None:
            raise ValueError(f"{label}: needs a {declared.product} (one of its catalogue "
                             "products)")
        try:
            product = spec.product(name)
        except KeyError as exc:
            raise ValueError(f"{label}: {exc.args[0]}") from None
        values.update(_product_params(product, fields, declared))
        if declared.height is not None:
            height = params.get(declared.height)
            if height is None:
                raise ValueError(f"{label}: needs a height (one of {product.heights} m)")
            if not any(
                math.isclose(height, h, rel_tol=1e-9, abs_tol=1e-9) for h in product.heights
            ):
                raise ValueError(
                    f"{label}: product {product.name!r} does not come in height {_fmt(height)} m "
                    f"(heights: {', '.join(_fmt(h) for h in product.heights)} m)"
                )
    values.update(params)
    checks = [("x", spec.x_range)] + list(spec.ranges.items())
    for key, (low, high) in checks:
        if key not in values:
            continue
        value = values[key]
        slack = 1e-9 * max(1.0, abs(low), abs(high))
        if isinstance(value, int | float) and not low - slack <= value <= high + slack:
            raise ValueError(
                f"{label}: {key} = {_fmt(value)} is outside its range [{_fmt(low)}, {_fmt(high)}]"
            )
    for key, opts in spec.options.items():
        if key in values and values[key] not in opts:
            raise ValueError(
                f"{label}: {key} = {_fmt(values[key])} is not one of its options "
                f"({', '.join(_fmt(o) for o in opts)})"
            )
    problem = params_problem(cls.Params, values)
    if problem is not None:
        loc, message = problem
        where = ".".join(str(p) for p in loc)
        raise ValueError(f"{label}: {where + ': ' if where else ''}{message}")
    return guard(registry).instantiate(cls, cls.Params.model_validate(values))

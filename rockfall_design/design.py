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

Products
--------
A measure whose parameters include ``product`` (fence and wall among the
built-ins) is always built from a catalogue product: the optimiser picks the
product among :attr:`CandidateSpec.products` and the height among that
product's heights; ``capacity_kj`` is the product's energy class, and other
keys of the product that are parameters of the measure (a wall's
``thickness``) are set from it. Such a candidate therefore must not give
``height``, ``capacity_kj`` or those keys itself.

Defaults
--------
A required parameter that the candidate does not give becomes a continuous
range with the plugin's own ``design_variables`` bounds (a ditch's ``width``
2..20 m) where the plugin declares finite ones; otherwise it is an error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from .costs import CostModel
from .plugins import guard
from .project import params_problem

if TYPE_CHECKING:  # pragma: no cover
    from .measures import ProtectiveMeasure
    from .plugins import Registry
    from .project import Project

__all__ = [
    "CandidateSpec",
    "DesignSpec",
    "Product",
    "build_candidate_measure",
    "resolve_design",
]

#: Parameters a product sets, besides ``product`` itself.
_FROM_PRODUCT = ("capacity_kj", "height")


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
    """

    index: int
    kind: str
    x_range: tuple[float, float]
    products: tuple[Product, ...]
    fixed: dict[str, Any]
    ranges: dict[str, tuple[float, float]]
    options: dict[str, tuple[Any, ...]]

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


def _product_params(product: Product, fields: Any) -> dict[str, Any]:
    """Parameters a product sets on a measure with these Params fields (height excluded)."""
    params: dict[str, Any] = {"product": product.name}
    if "capacity_kj" in fields:
        params["capacity_kj"] = product.capacity_kj
    for key, value in product.extra.items():
        if key in fields and key not in ("product", "height"):
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


def _resolve_cost_model(project: Project, registry: Registry) -> CostModel:
    design = project.design
    assert design is not None
    name = design.costs.model
    cls = registry.cost_models.get(name)
    if cls is None:
        raise project.unknown_name(
            ("design", "costs", "model"), name, registry.cost_models, "cost model"
        )
    params = design.costs_locator.validate_params((), cls.Params, design.cost_params)
    return guard(registry).instantiate(cls, params)


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
        raise project.unknown_name(at + ("type",), kind, registry.measures, "measure type")
    fields = cls.Params.model_fields
    if "x" not in fields:
        raise project.error_at(
            at + ("x",),
            f"measure type {kind!r} has no station parameter x, so the optimiser cannot place it",
        )
    for key in raw:
        if key != "type" and key not in fields:
            raise project.unknown_name(at + (key,), key, list(fields), f"{kind} parameter")

    # products
    uses_products = "product" in fields
    products: tuple[Product, ...] = ()
    supplied: set[str] = set()
    if uses_products:
        products = _candidate_products(project, i, raw, kind, catalogue)
        supplied = {"product"} | {k for k in _FROM_PRODUCT if k in fields}
        for product in products:
            supplied |= set(_product_params(product, fields))
        for key in raw:
            if key in supplied and key != "product":
                if key == "height":
                    why = "the optimiser chooses it among the heights of the catalogue products"
                elif key == "capacity_kj":
                    why = "it is the energy class of the catalogue product"
                else:
                    why = "the catalogue product sets it"
                raise project.error_at(
                    at + (key,),
                    f"do not give {key} for a {kind} candidate: {why} (design.products); "
                    "restrict the products with product: [NAME, ...] instead",
                )

    # fixed values, ranges, options
    x_low, x_high = (float(v) for v in raw["x"])
    fixed: dict[str, Any] = {}
    ranges: dict[str, tuple[float, float]] = {}
    options: dict[str, tuple[Any, ...]] = {}
    for key, value in raw.items():
        if key in ("type", "x", "product"):
            continue
        if isinstance(value, list):
            ranges[key] = (float(value[0]), float(value[1]))
        elif isinstance(value, dict):
            options[key] = tuple(value["options"])
        else:
            fixed[key] = value

    # required parameters not given: plugin bounds, or an error
    variables = getattr(cls, "design_variables", {}) or {}
    for name, info in fields.items():
        if not info.is_required() or name in raw or name in supplied or name == "x":
            continue
        bounds = variables.get(name)
        if bounds is not None:
            low, high = (float(b) for b in bounds)
            if math.isfinite(low) and math.isfinite(high):
                ranges[name] = (low, high)
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
    if products:
        base.update(_product_params(products[0], fields))
        if "height" in fields:
            base["height"] = products[0].heights[0]

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
        _check_product(project, cls, kind, product, base, fields)
    check({}, at)
    for key, (low, high) in ranges.items():
        not_numeric = _range_problem(cls.Params, key)
        if not_numeric:
            raise project.error_at(at + (key,) if key in raw else at, not_numeric)
        for end, value in enumerate((low, high)):
            check({key: value}, at + (key, end) if key in raw else at)
    for key, opts in options.items():
        for k, value in enumerate(opts):
            check({key: value}, at + (key, "options", k))
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
) -> tuple[Product, ...]:
    """The products a candidate may use: those it names, or all of its kind."""
    design = project.design
    assert design is not None
    at = ("design", "candidates", i)
    table = catalogue.get(kind, {})
    if "product" not in raw:
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
                f"a {kind} candidate needs catalogue products (its product, capacity_kj and "
                f"height come from them), but {source} has no {kind} products "
                f"(measure types in it: {kinds})",
            )
        return tuple(table.values())
    value = raw["product"]
    if isinstance(value, str):
        names, paths = [value], [at + ("product",)]
    elif isinstance(value, dict):
        names = list(value["options"])
        paths = [at + ("product", "options", k) for k in range(len(names))]
    else:
        names = list(value)
        paths = [at + ("product", k) for k in range(len(names))]
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
) -> None:
    """A product the measure rejects is an error in the catalogue, at the product's line.

    A problem with a parameter the product does not set is left to the
    candidate's own checks (reported in the project file).
    """
    locator = project.design.products_locator  # type: ignore[union-attr]
    at = (kind, product.name)
    params = {**base, **_product_params(product, fields)}
    heights = product.heights if "height" in fields else (None,)
    for height in heights:
        values = dict(params)
        if height is not None:
            values["height"] = height
        problem = params_problem(cls.Params, values)
        if problem is None:
            continue
        loc, message = problem
        key = loc[0] if loc else None
        if key == "height":
            raw_heights = project.design.catalogue[kind][product.name]["heights"]  # type: ignore[union-attr]
            path = at + ("heights", raw_heights.index(height))
        elif key == "capacity_kj" or key in product.extra:
            path = at + (key,)
        elif key == "product":
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
        The picked values: ``x`` (m), one value per range and option
        parameter, and for a candidate with products ``product`` (a name)
        and, if the measure has it, ``height`` (m, one of the product's
        heights). The candidate's fixed parameters and the product's
        ``capacity_kj`` (and other parameters) are added here; a value in
        ``params`` overrides a fixed one.

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
    if spec.products:
        name = params.get("product")
        if name is None:
            raise ValueError(f"{label}: needs a product (one of its catalogue products)")
        try:
            product = spec.product(name)
        except KeyError as exc:
            raise ValueError(f"{label}: {exc.args[0]}") from None
        values.update(_product_params(product, fields))
        if "height" in fields:
            height = params.get("height")
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

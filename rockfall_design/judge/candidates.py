"""Candidate measures of the design section: their parameters, ranges, options and products.

What a candidate may be built from (:class:`CandidateSpec`, its catalogue
:class:`Product`s), resolved against the measure's plugin (its declared
design variables), and one measure built from the values the optimiser
picked (:func:`build_candidate_measure`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ..errors import PluginError
from ..plugins import guard
from ..plugins.declared import DeclaredDesign, declared_design
from ..project import params_problem
from ..project.locator import validated_params
from .placing import unknown_measure_type

if TYPE_CHECKING:  # pragma: no cover

    from ..plugins import Registry
    from ..plugins.measure import ProtectiveMeasure
    from ..project import Project


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


def sample_params(spec: CandidateSpec) -> list[dict[str, Any]]:
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


def _candidate_class(project: Project, registry: Registry, at: tuple, raw: dict[str, Any]
                     ) -> type[ProtectiveMeasure]:
    """The measure class of a candidate: a known type with a station x and known parameters."""
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
    return cls


def _split_values(raw: dict[str, Any], product_field: str | None
                  ) -> tuple[dict[str, Any], dict[str, tuple[float, float]],
                             dict[str, tuple[Any, ...]]]:
    """A candidate's values: fixed ones, ranges ``[low, high]`` and ``{options: [...]}``."""
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
    return fixed, ranges, options


def _check_candidate_values(project: Project, cls: type[ProtectiveMeasure], at: tuple,
                            raw: dict[str, Any], base: dict[str, Any], spec: CandidateSpec
                            ) -> None:
    """Every value through the measure's Params: the fixed ones together, each range end
    and option on its own, the others at ``base`` (the plugin's example)."""

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

    fields = cls.Params.model_fields
    for product in spec.products:
        _check_product(project, cls, spec.kind, product, base, fields, spec.declared)
    check({}, at)
    for key, (low, high) in spec.ranges.items():
        not_numeric = _range_problem(cls.Params, key)
        if not_numeric:
            raise project.error_at(at + (key,) if key in raw else at, not_numeric)
        for end, value in enumerate((low, high)):
            check({key: value}, at + (key, end) if key in raw else at)
    for key, opts in spec.options.items():
        for k, value in enumerate(opts):
            check({key: value}, at + (key, "options", k) if key in raw else at)
    for end, value in enumerate(spec.x_range):
        check({"x": value}, at + ("x", end))


def resolve_candidate(
    project: Project,
    registry: Registry,
    i: int,
    raw: dict[str, Any],
    catalogue: dict[str, dict[str, Product]],
) -> CandidateSpec:
    """The ``i``-th entry of ``design.candidates`` (``raw``) as a checked candidate spec.

    Its measure type, station and design variables are checked against the
    plugin's parameter model and ``catalogue``; a problem is the project's
    error at ``design.candidates[i]``.
    """
    design = project.design
    assert design is not None
    at = ("design", "candidates", i)
    kind = raw["type"]
    cls = _candidate_class(project, registry, at, raw)
    fields = cls.Params.model_fields
    declared = _declared(registry, cls, kind)
    products, supplied = _candidate_supply(project, i, raw, kind, catalogue, declared, fields)
    x_low, x_high = (float(v) for v in raw["x"])
    fixed, ranges, options = _split_values(raw, declared.product)
    _declared_defaults(project, at, kind, raw, supplied, fields, declared, ranges, options)
    base: dict[str, Any] = {k: v for k, v in cls.example.items() if k in fields}
    base.update(fixed)
    base["x"] = x_low
    for key, opts in options.items():
        base.setdefault(key, opts[0])
    if products:
        base.update(_product_params(products[0], fields, declared))
        if declared.height is not None:
            base[declared.height] = products[0].heights[0]
    spec = CandidateSpec(index=i, kind=kind, x_range=(x_low, x_high), products=products,
                         fixed=fixed, ranges=ranges, options=options, declared=declared)
    _check_candidate_values(project, cls, at, raw, base, spec)
    return spec


def _candidate_supply(project: Project, i: int, raw: dict[str, Any], kind: str,
                      catalogue: dict[str, dict[str, Product]], declared: DeclaredDesign,
                      fields: dict[str, Any]) -> tuple[tuple[Product, ...], set[str]]:
    """A candidate's catalogue products and the parameters they set.

    A measure with a product field is built from catalogue products only: the
    candidate may restrict the products but must not give what they set
    (height, capacity, other product keys).
    """
    at = ("design", "candidates", i)
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

    return products, supplied


def _declared_defaults(project: Project, at: tuple, kind: str, raw: dict[str, Any],
                       supplied: set[str], fields: dict[str, Any], declared: DeclaredDesign,
                       ranges: dict[str, tuple[float, float]],
                       options: dict[str, tuple[Any, ...]]) -> None:
    """Fill ``ranges`` and ``options`` with what the candidate does not give.

    The plugin's declarations first; a required parameter without one takes
    the ``design_variables`` bounds, or is an error at the candidate.
    """
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


def _picked_product(spec: CandidateSpec, fields: dict[str, Any], params: dict[str, Any],
                    label: str) -> dict[str, Any]:
    """The parameters a picked product sets; its picked height must be one it comes in."""
    declared = spec.declared
    assert declared.product is not None
    name = params.get(declared.product)
    if name is None:
        raise ValueError(f"{label}: needs a {declared.product} (one of its catalogue "
                         "products)")
    try:
        product = spec.product(name)
    except KeyError as exc:
        raise ValueError(f"{label}: {exc.args[0]}") from None
    values = _product_params(product, fields, declared)
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
    return values


def _check_picked(spec: CandidateSpec, values: dict[str, Any], label: str) -> None:
    """Every picked value within its range (a hair of slack for rounding) or among its options."""
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


def build_candidate_measure(
    spec: CandidateSpec, registry: Registry, params: dict[str, Any]
) -> ProtectiveMeasure:
    """A measure of candidate ``spec`` with the values the optimiser picked.

    Parameters
    ----------
    spec
        The candidate.
    registry
        The plugins (the same as given to :func:`~.design_spec.resolve_design`).
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
    label = f"candidate {spec.index} ({spec.kind})"
    values: dict[str, Any] = dict(spec.fixed)
    if spec.products:
        values.update(_picked_product(spec, cls.Params.model_fields, params, label))
    values.update(params)
    _check_picked(spec, values, label)
    params, problem = validated_params(cls.Params, values)
    if problem is not None:
        loc, message = problem
        where = ".".join(str(p) for p in loc)
        raise ValueError(f"{label}: {where + ': ' if where else ''}{message}")
    return guard(registry).instantiate(cls, params)

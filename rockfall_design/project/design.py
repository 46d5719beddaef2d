"""Design: the ``design:`` section, what the least-cost optimiser may build.

Candidates, the allowed residual, the site, the product catalogue and the
cost model's parameters (inline or in files the project names); shapes are
checked here, the plugins resolve them later.
"""

import math
from typing import Annotated, Any

from pydantic import BeforeValidator, Field, PrivateAttr, WithJsonSchema, model_validator

from .fields import (
    Fraction,
    Integer,
    Positive,
    SectionModel,
    String,
    as_number,
    check_typed_item,
    lines_of_text,
    one_line,
    plugin_data,
)
from .locator import Locator
from .messages import describe, did_you_mean, fail, fmt
from .schema import (
    DEFAULT_CHECKER_POWER,
    DEFAULT_MAX_ROCKS,
    MAX_COORDINATE_M,
    MAX_DESIGN_MEASURES,
    MAX_FAMILIES,
    MAX_ROCKS,
)

# --------------------------------------------------------------------------------------
# The design section (least-cost optimiser): shapes checked here, plugins resolve it later
# --------------------------------------------------------------------------------------


class ResidualFraction(SectionModel):
    """``residual: {fraction: F}``: the fraction of rocks allowed in the protected zone."""

    fraction: Fraction = Field(
        description="Fraction of the rocks allowed to reach the protected zone (-), 0..1."
    )


def _parse_residual(value: Any) -> Any:
    """``residual``: a count of rocks (integer >= 0) or ``{fraction: F}``."""
    forms = "a count of rocks (an integer >= 0) or {fraction: F}"
    if isinstance(value, ResidualFraction):
        return value
    if isinstance(value, dict):
        for key in value:
            if key != "fraction":
                hint = did_you_mean(key, ["fraction"]) if isinstance(key, str) else ""
                raise fail(f"unknown key {key!r}{hint}; expected {forms}", (key,))
        if "fraction" not in value:
            raise fail(f"required key 'fraction' is missing; expected {forms}")
        fraction = as_number(value["fraction"], ("fraction",))
        if not 0.0 <= fraction <= 1.0:
            raise fail(f"expected a number in 0..1, got {fmt(fraction)}", ("fraction",))
        return ResidualFraction(fraction=fraction)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise fail(f"expected {forms}, got {describe(value)}")
    if isinstance(value, float) and not (math.isfinite(value) and value.is_integer()):
        raise fail(f"expected {forms}, got {describe(value)}")
    if value < 0:
        raise fail(f"expected {forms}, got {fmt(value)}")
    return int(value)


class Site(SectionModel):
    """The site: how much slope the measures span."""

    length_m: Annotated[Positive, Field(le=MAX_COORDINATE_M)] = Field(
        description="Length of slope to protect, along the contour (m): what the measures "
        "span; at most 1,000 km (costs scale with it; 1e300 overflowed the optimiser)."
    )


_CATALOGUE_FORM = "measure type -> product name -> {capacity_kj: E, heights: [h, ...]}"


#: Optional figures of a fence kit's MEL test (ETAG 027 / EAD 340059): key -> (low, high,
#: what it is), the value in (low, high]; checked here so that a bad figure is an error
#: at its line.
_MEL_KEYS = {
    "sel_kj": (0.0, math.inf, "service energy level (SEL), kJ, below capacity_kj (the MEL)"),
    "max_elongation_m": (0.0, MAX_COORDINATE_M,
                         "maximum elongation (braking distance) in the MEL test, m"),
    "elongation_sel_m": (0.0, MAX_COORDINATE_M, "elongation in the SEL test, m"),
    "residual_height_fraction": (0.0, 1.0,
                                 "residual height after the MEL test as a fraction of the "
                                 "nominal height, e.g. 0.5 for category A"),
}


def _mel_figures(entry: dict[str, Any], where: tuple) -> dict[str, float]:
    """The optional MEL-test figures of a product, checked: ``{key: number}``.

    ``max_elongation_m`` (m) is a number > 0; ``residual_height_fraction``
    (-) a number in (0, 1]: the residual height after the MEL test over the
    nominal height, as EAD 340059 states it (category A >= 0.5, B 0.3 to
    0.5, C <= 0.3).
    """
    out: dict[str, float] = {}
    for key, (low, high, what) in _MEL_KEYS.items():
        if key not in entry:
            continue
        value = as_number(entry[key], where + (key,))
        if not low < value <= high:
            raise fail(
                f"expected a number > {fmt(low)} and <= {fmt(high)} (the product's {what}), "
                f"got {fmt(value)}",
                where + (key,),
            )
        out[key] = value
    if "sel_kj" in out and "capacity_kj" in entry and not out["sel_kj"] < as_number(
            entry["capacity_kj"], where + ("capacity_kj",)):
        raise fail(f"expected the SEL below capacity_kj = {fmt(entry['capacity_kj'])} kJ "
                    f"(the MEL), got {fmt(out['sel_kj'])}", where + ("sel_kj",))
    return out


def check_products(value: Any) -> dict[str, dict[str, dict[str, Any]]]:
    """A product catalogue, normalised: ``{kind: {name: {capacity_kj, heights, ...}}}``.

    ``capacity_kj`` (kJ) is a number > 0, ``heights`` (m) a non-empty list of
    distinct numbers > 0; the optional MEL-test figures ``max_elongation_m``
    (m) and ``residual_height_fraction`` (-) are checked by :func:`_mel_figures`;
    other keys of a product are kept as plain data.
    """
    if not isinstance(value, dict):
        raise fail(f"expected a mapping {_CATALOGUE_FORM}, got {describe(value)}")
    catalogue: dict[str, dict[str, dict[str, Any]]] = {}
    for kind, table in value.items():
        if not isinstance(kind, str) or not kind.strip():
            raise fail(f"expected the name of a measure type, got {describe(kind)}", (kind,))
        one_line(kind, (kind,))
        if not isinstance(table, dict):
            raise fail(
                f"expected a mapping of product name -> {{capacity_kj: E, heights: [h, ...]}}, "
                f"got {describe(table)}",
                (kind,),
            )
        products: dict[str, dict[str, Any]] = {}
        for name, entry in table.items():
            where = (kind, name)
            if not isinstance(name, str) or not name.strip():
                raise fail(
                    f"expected a product name, got {describe(name)} (quote names such as '100')",
                    where,
                )
            one_line(name, where)
            if not isinstance(entry, dict):
                raise fail(
                    f"expected a mapping {{capacity_kj: E, heights: [h, ...]}}, "
                    f"got {describe(entry)}",
                    where,
                )
            for key in ("capacity_kj", "heights"):
                if key not in entry:
                    what = "energy class (kJ)" if key == "capacity_kj" else "heights (m)"
                    raise fail(f"required key {key!r} is missing (the product's {what})", where)
            capacity = as_number(entry["capacity_kj"], where + ("capacity_kj",))
            if capacity <= 0:
                raise fail(
                    f"expected a number > 0, got {fmt(capacity)}", where + ("capacity_kj",)
                )
            heights_raw = entry["heights"]
            if not isinstance(heights_raw, list | tuple) or not heights_raw:
                raise fail(
                    f"expected a non-empty list of heights (m), got {describe(heights_raw)}",
                    where + ("heights",),
                )
            heights: list[float] = []
            for j, item in enumerate(heights_raw):
                h = as_number(item, where + ("heights", j))
                if h <= 0:
                    raise fail(f"expected a number > 0, got {fmt(h)}", where + ("heights", j))
                if h in heights:
                    raise fail(f"height {fmt(h)} is listed twice", where + ("heights", j))
                heights.append(h)
            rest = {k: v for k, v in entry.items() if k not in ("capacity_kj", "heights")}
            products[name] = {
                "capacity_kj": capacity,
                "heights": heights,
                **plugin_data(rest, where),
                **_mel_figures(entry, where),
            }
        catalogue[kind] = products
    return catalogue


def _parse_products(value: Any) -> Any:
    """``design.products``: a catalogue file (a path) or an inline catalogue."""
    if value is None:
        return None
    if isinstance(value, str):
        if not value.strip():
            raise fail("must not be empty (a catalogue file, e.g. catalogue_products.yaml)")
        return value
    if not isinstance(value, dict):
        raise fail(
            f"expected a catalogue file (a path) or a mapping {_CATALOGUE_FORM}, "
            f"got {describe(value)}"
        )
    return check_products(value)


def _parse_cost_params(value: Any) -> Any:
    if value is None:
        return None
    if not isinstance(value, dict):
        raise fail(f"expected a mapping of the cost model's parameters, got {describe(value)}")
    lines_of_text(value)
    return plugin_data(value, number_keys=True)


class DesignCosts(SectionModel):
    """``design.costs``: the cost model and its parameters (a file or inline)."""

    model: Annotated[String, Field(min_length=1)] = Field(
        "unit_prices", description="Name of the cost-model plugin."
    )
    file: Annotated[String, Field(min_length=1)] | None = Field(
        None, description="YAML file of the cost model's parameters, relative to the project."
    )
    params: Annotated[Any, BeforeValidator(_parse_cost_params)] = Field(
        None, description="The cost model's parameters, inline (instead of file)."
    )

    @model_validator(mode="after")
    def _one_source(self) -> "DesignCosts":
        if self.file is None and self.params is None:
            raise fail(
                "give the cost model's parameters: file: PATH (a YAML file) or params: {...}"
            )
        if self.file is not None and self.params is not None:
            raise fail("give only one of file and params", ("params",))
        return self


_VALUE_FORMS = "a value (fixed), a range [min, max] or {options: [a, b, ...]}"


def _check_options(value: Any, subpath: tuple) -> list:
    if set(value) != {"options"}:
        extra = next((k for k in value if k != "options"), None)
        if extra is not None:
            hint = did_you_mean(extra, ["options"]) if isinstance(extra, str) else ""
            raise fail(
                f"unknown key {extra!r}{hint}; expected {{options: [...]}}", subpath + (extra,)
            )
        raise fail("required key 'options' is missing: expected {options: [...]}", subpath)
    options = value["options"]
    where = subpath + ("options",)
    if not isinstance(options, list | tuple) or not options:
        raise fail(f"expected a non-empty list of options, got {describe(options)}", where)
    seen: list = []
    for k, item in enumerate(options):
        if item is None or not isinstance(item, bool | int | float | str):
            raise fail(
                f"expected a number, string or boolean, got {describe(item)}", where + (k,)
            )
        plugin_data(item, where + (k,))
        if any(type(item) is type(s) and item == s for s in seen):
            raise fail(f"option {fmt(item)} is listed twice", where + (k,))
        seen.append(item)
    return list(options)


def _check_candidate_value(value: Any, subpath: tuple) -> Any:
    """A candidate parameter: a fixed value, a range [min, max] or {options: [...]}."""
    if isinstance(value, list | tuple):
        if len(value) != 2:
            raise fail(
                f"expected a range [min, max] of two numbers, got {describe(value)}; "
                "for a choice write {options: [...]}",
                subpath,
            )
        for k, item in enumerate(value):
            if isinstance(item, bool) or not isinstance(item, int | float):
                raise fail(
                    f"a range [min, max] needs numbers, got {describe(item)}; "
                    "for a choice write {options: [...]}",
                    subpath + (k,),
                )
        low, high = as_number(value[0], subpath + (0,)), as_number(value[1], subpath + (1,))
        if not low < high:
            raise fail(
                f"expected a range [min, max] with min < max, got [{fmt(low)}, {fmt(high)}]; "
                "for a fixed value give the number",
                subpath,
            )
        return list(value)
    if isinstance(value, dict):
        return {"options": _check_options(value, subpath)}
    if value is None or not isinstance(value, bool | int | float | str):
        raise fail(f"expected {_VALUE_FORMS}, got {describe(value)}", subpath)
    return plugin_data(value, subpath)


def _check_product_choice(value: Any, subpath: tuple) -> Any:
    """``product``: a name, a list of names or {options: [names]}."""
    names = value
    where = subpath
    if isinstance(value, dict):
        names = _check_options(value, subpath)
        where = subpath + ("options",)
    elif isinstance(value, str):
        names = [value]
    elif not isinstance(value, list | tuple) or not value:
        raise fail(
            f"expected a product name or a non-empty list of names, got {describe(value)}",
            subpath,
        )
    for k, name in enumerate(names):
        at = where if isinstance(value, str) else where + (k,)
        if not isinstance(name, str) or not name.strip():
            raise fail(f"expected a product name, got {describe(name)}", at)
        if name in names[:k]:
            raise fail(f"product {name!r} is listed twice", at)
    return plugin_data(value, subpath)


def _parse_candidates(value: Any) -> list[dict[str, Any]]:
    """``design.candidates``: a non-empty list of mappings with ``type`` and ``x: [min, max]``."""
    if not isinstance(value, list | tuple) or not value:
        raise fail(
            "expected a non-empty list of candidate measures (mappings such as "
            f"{{type: fence, x: [60, 110]}}), got {describe(value)}"
        )
    candidates = []
    for i, item in enumerate(value):
        check_typed_item(
            item, i, "a candidate measure (a mapping such as {type: fence, x: [60, 110]})"
        )
        if "x" not in item:
            raise fail(
                "required key 'x' is missing (the station range [min, max] (m) where the "
                "optimiser may place the measure)",
                (i,),
            )
        x = item["x"]
        if not isinstance(x, list | tuple) or len(x) != 2:
            raise fail(
                f"expected a station range [min, max] (m), got {describe(x)}; the optimiser "
                "places the measure within it",
                (i, "x"),
            )
        low, high = as_number(x[0], (i, "x", 0)), as_number(x[1], (i, "x", 1))
        if not low < high:
            raise fail(
                f"expected a station range [min, max] with min < max, "
                f"got [{fmt(low)}, {fmt(high)}]",
                (i, "x"),
            )
        candidate: dict[str, Any] = {"type": item["type"], "x": [x[0], x[1]]}
        for key, item_value in item.items():
            if key in ("type", "x"):
                continue
            if not isinstance(key, str):
                raise fail(f"keys must be names, got {describe(key)}", (i, key))
            if key == "product":
                candidate[key] = _check_product_choice(item_value, (i, key))
            else:
                candidate[key] = _check_candidate_value(item_value, (i, key))
        candidates.append(candidate)
    return candidates


def _parse_scenarios(value: Any) -> Any:
    """``design.scenarios``: None, ``"all"`` or ``{"share": S}`` with 0 < S <= 1."""
    if value is None or value == "all":
        return value
    if isinstance(value, dict) and set(value) == {"share"}:
        share = value["share"]
        if (isinstance(share, int | float) and not isinstance(share, bool)
                and math.isfinite(share) and 0 < share <= 1):
            return {"share": float(share)}
        raise fail(f"expected a number > 0 and <= 1, got {describe(share)}", ("share",))
    if isinstance(value, dict):
        extra = sorted(str(k) for k in value if k != "share")
        if extra:
            raise fail(f"unknown key {extra[0]!r}; expected share", (extra[0],))
        raise fail("expected {share: S}", ())
    raise fail(f"expected all or {{share: S}} (0 < S <= 1), got {describe(value)}")


class Design(SectionModel):
    """``design:``, what the least-cost optimiser may build and how it checks a design.

    Candidate parameters are kept raw (the measure plugins are loaded later,
    see :func:`rockfall_design.judge.design_spec.resolve_design`), their shapes checked:
    ``x`` is a station range ``[min, max]`` (m) inside the section; any other
    value is fixed (a number, string or boolean), a range ``[a, b]`` of
    numbers with a < b (a continuous design variable) or ``{options: [...]}``
    (a discrete one); ``product`` is a catalogue name or a list of names.

    The product catalogue and the cost model's parameters may come from files
    (paths relative to the project file); :func:`~.loading.load_project` reads them and
    keeps their line numbers: :attr:`catalogue` / :attr:`products_locator`
    and :attr:`cost_params` / :attr:`costs_locator`.
    """

    max_measures: Annotated[Integer, Field(ge=1, le=MAX_DESIGN_MEASURES)] = Field(
        2, description="Largest number of measures in one design, 1..10."
    )
    residual: Annotated[
        Any,
        BeforeValidator(_parse_residual),
        WithJsonSchema(
            {
                "anyOf": [
                    {"type": "integer", "minimum": 0},
                    {
                        "type": "object",
                        "properties": {"fraction": {"type": "number", "minimum": 0, "maximum": 1}},
                        "required": ["fraction"],
                        "additionalProperties": False,
                    },
                ]
            }
        ),
    ] = Field(
        0,
        description="Rocks allowed to reach the protected zone: a count, or {fraction: F}.",
    )
    fresh_rocks: Annotated[Integer, Field(ge=1, le=MAX_ROCKS)] | None = Field(
        None,
        description="Rocks of the independent re-check of a family's chosen design; at least "
        "(and by default) twice the rocks that decided it.",
    )
    max_rocks: Annotated[Integer, Field(ge=1, le=2_000_000)] = Field(
        DEFAULT_MAX_ROCKS,
        description="Rocks of the last look of every sequential decision: a design near a "
        "limit is looked at with more and more rocks up to this (the looks stop as soon as "
        "it is decided); one still undecided here is marginal (never admitted; the report "
        "lists it with the rocks that would decide it).",
    )
    fresh_seed: Annotated[Integer, Field(ge=0)] | None = Field(
        None, description="Seed of the re-check; default: the run's seed + 1000003."
    )
    checker_power: Annotated[float, Field(ge=0.5, le=0.999)] | None = Field(
        DEFAULT_CHECKER_POWER,
        description="Chance with which a checker's check of twice the deciding rocks, at a "
        "seed of their own, confirms the chosen design with confidence (-): a design is "
        "admitted only with that margin. null: admitted when it holds with its bounds.",
        json_schema_extra={"unit": "-"},
    )
    site: Site = Field(description="The site: length of slope to protect.")
    products: Annotated[Any, BeforeValidator(_parse_products)] = Field(
        None,
        description="Product catalogue: a YAML file relative to the project file, or inline "
        f"({_CATALOGUE_FORM}).",
    )
    costs: DesignCosts = Field(description="Cost model and its parameters.")
    candidates: Annotated[list[dict[str, Any]], BeforeValidator(_parse_candidates)] = Field(
        description="Measures the optimiser may use: mappings with 'type', 'x': [min, max] "
        "and the measure's parameters (fixed, [min, max] or {options: [...]})."
    )

    scenarios: Annotated[
        Any,
        BeforeValidator(_parse_scenarios),
        WithJsonSchema(
            {
                "anyOf": [
                    {"const": "all"},
                    {
                        "type": "object",
                        "properties": {"share": {"type": "number", "exclusiveMinimum": 0,
                                                 "maximum": 1}},
                        "required": ["share"],
                        "additionalProperties": False,
                    },
                ]
            }
        ),
    ] = Field(
        None,
        description="With a study: section, the scenarios a design must hold in: 'all', or "
        "{share: S}, at least that share of them (0 < S <= 1); none: the project as written.",
    )

    _catalogue: dict | None = PrivateAttr(default=None)
    _products_locator: "Locator | None" = PrivateAttr(default=None)
    _cost_params: dict | None = PrivateAttr(default=None)
    _costs_locator: "Locator | None" = PrivateAttr(default=None)

    @model_validator(mode="after")
    def _check_families(self) -> "Design":
        # The optimiser searches every multiset of 1..max_measures candidates:
        # C(n + m, m) - 1 families, each a search of its own.
        n, m = len(self.candidates), self.max_measures
        count = math.comb(n + m, m) - 1
        if count > MAX_FAMILIES:
            raise fail(
                f"{n} candidates with max_measures {m} make {count:,} families of designs to "
                f"search, at most {MAX_FAMILIES:,} are allowed: lower max_measures or "
                "merge candidates",
                ("max_measures",),
            )
        return self

    @property
    def residual_count(self) -> int | None:
        """Allowed number of rocks in the protected zone, or None if a fraction is given."""
        return self.residual if isinstance(self.residual, int) else None

    @property
    def residual_fraction(self) -> float | None:
        """Allowed fraction of the rocks in the protected zone, or None if a count is given."""
        return self.residual.fraction if isinstance(self.residual, ResidualFraction) else None

    @property
    def scenario_share(self) -> float | None:
        """The share of a study's scenarios a design must hold in (1.0 for ``all``), or None."""
        if self.scenarios is None:
            return None
        return 1.0 if self.scenarios == "all" else float(self.scenarios["share"])

    @property
    def catalogue(self) -> dict[str, dict[str, dict[str, Any]]]:
        """The product catalogue: ``{kind: {name: {capacity_kj, heights, ...}}}`` ({} if none)."""
        if self._catalogue is not None:
            return self._catalogue
        if isinstance(self.products, str):
            raise RuntimeError("the product catalogue file is read by load_project/_text")
        return self.products or {}

    @property
    def products_locator(self) -> "Locator":
        """Where the catalogue's nodes are: key paths start at the catalogue's top level."""
        if self._products_locator is not None:
            return self._products_locator
        return Locator("<string>", {}, ("design", "products"))

    @property
    def cost_params(self) -> dict[str, Any]:
        """The cost model's raw parameters (from ``costs.file`` or ``costs.params``)."""
        if self._cost_params is not None:
            return self._cost_params
        if self.costs.params is None:
            raise RuntimeError("the cost parameter file is read by load_project/_text")
        return self.costs.params

    @property
    def costs_locator(self) -> "Locator":
        """Where the cost parameters' nodes are: key paths start at the parameters' mapping."""
        if self._costs_locator is not None:
            return self._costs_locator
        return Locator("<string>", {}, ("design", "costs", "params"))

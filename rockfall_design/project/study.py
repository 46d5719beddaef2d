"""Study: the ``study:`` section, a parametric study over inputs of the project.

.. code-block:: yaml

    study:
      vary:
        materials.talus.restitution: [0.28, 0.32, 0.36]   # a list of values
        rocks.volume.lognormal.0: {range: [0.5, 2.0], levels: 3}
      scenarios: grid          # or {sample: latin_hypercube, n: 50, seed: 3}
      seeds: independent       # or common: every scenario runs the same rocks

Each key under ``vary:`` is the path of an input in the project file (dots
between keys, ``[i]`` or ``.i`` for list items); its value is a list of the
values to try, or ``{range: [lo, hi]}`` (with ``levels: N``, evenly spaced
values, for a grid). This module checks the section's shape; whether each
path exists and each value is valid there is checked against the project
itself, by :func:`rockfall_design.studies.paths.with_values`.
"""

import math
from collections.abc import Mapping
from typing import Annotated, Any, Literal

from pydantic import (
    BeforeValidator,
    Field,
    PlainSerializer,
    PlainValidator,
    WithJsonSchema,
    model_validator,
)
from pydantic_core import PydanticCustomError

from .fields import Integer, SectionModel, String, as_integer, as_number, choice
from .messages import describe, did_you_mean, fail, fmt

#: Most scenarios in one study: each is a full Monte Carlo run.
MAX_SCENARIOS = 10_000
#: Most inputs varied in one study.
MAX_VARIED = 50


class Range(SectionModel):
    """A continuous range of a numeric input: ``{range: [lo, hi], levels: N}``."""

    range: tuple[float, float] = Field(description="Lowest and highest value [lo, hi], lo < hi.")
    levels: Annotated[Integer, Field(ge=2, le=MAX_SCENARIOS)] | None = Field(
        None,
        description="Evenly spaced values from lo to hi, both included, for a grid; a "
        "sampled study draws from the whole range and ignores it.",
    )

    @model_validator(mode="before")
    @classmethod
    def _check_range(cls, data: Any) -> Any:
        if isinstance(data, dict) and "range" in data:
            value = data["range"]
            if not isinstance(value, list | tuple) or len(value) != 2:
                raise fail(f"expected [lo, hi], got {describe(value)}", ("range",))
            lo = as_number(value[0], ("range", 0))
            hi = as_number(value[1], ("range", 1))
            if not lo < hi:
                raise fail(
                    f"expected [lo, hi] with lo < hi, got [{fmt(lo)}, {fmt(hi)}]", ("range",)
                )
            data = {**data, "range": (lo, hi)}
        return data

    def grid_values(self) -> list[float]:
        """The ``levels`` evenly spaced values of a grid, lo and hi included."""
        assert self.levels is not None
        lo, hi = self.range
        step = (hi - lo) / (self.levels - 1)
        # lo + i * step rather than numpy's linspace: plain floats, hi exactly hi
        return [lo + i * step if i < self.levels - 1 else hi for i in range(self.levels)]


def _parse_levels(value: Any) -> Any:
    """A list of values (kept as written) or a ``{range: ...}`` mapping."""
    if isinstance(value, list | tuple):
        if not value:
            raise fail("expected at least one value, got an empty list")
        seen: list[Any] = []
        for i, item in enumerate(value):
            if isinstance(item, float) and not math.isfinite(item):
                raise fail(f"must be finite, got {fmt(item)}", (i,))
            if any(type(item) is type(s) and item == s for s in seen):
                raise fail(f"value {fmt(item)} is listed twice", (i,))
            seen.append(item)
        return list(value)
    if isinstance(value, dict):
        if "range" not in value:
            raise fail(
                "expected a list of values or {range: [lo, hi]}, got a mapping without 'range'"
            )
        return Range.model_validate(value)
    raise fail(f"expected a list of values or {{range: [lo, hi]}}, got {describe(value)}")


Levels = Annotated[list[Any] | Range, BeforeValidator(_parse_levels)]


class Sample(SectionModel):
    """A sampled study: ``{sample: latin_hypercube, n: 50, seed: 3}``."""

    sample: Annotated[Literal["latin_hypercube"], BeforeValidator(choice("latin_hypercube"))] = (
        Field(description="Sampling design: latin_hypercube (scipy.stats.qmc.LatinHypercube).")
    )
    n: Annotated[Integer, Field(ge=2, le=MAX_SCENARIOS)] = Field(
        description="Number of scenarios drawn."
    )
    seed: Annotated[Integer, Field(ge=0)] = Field(
        0, description="Seed of the sample (the scenarios' values; not the rocks)."
    )


_SCENARIOS = "grid or {sample: latin_hypercube, n: N, seed: S}"


def _parse_scenarios(value: Any) -> Any:
    """``grid`` or a :class:`Sample`, each problem one message at its key.

    Validated here rather than as a pydantic union, which would report a
    mapping's problems twice (once per alternative).
    """
    if isinstance(value, Sample) or (value == "grid" and isinstance(value, str)):
        return value
    if not isinstance(value, dict):
        raise fail(f"expected {_SCENARIOS}, got {describe(value)}")
    for key in value:
        if key not in Sample.model_fields:
            hint = did_you_mean(str(key), list(Sample.model_fields)) or (
                f"; expected one of {', '.join(Sample.model_fields)}")
            raise fail(f"unknown key {key!r}{hint}", (key,))
    if "sample" not in value:
        raise fail(f"expected {_SCENARIOS}: 'sample' is missing")
    if value["sample"] != "latin_hypercube" or not isinstance(value["sample"], str):
        raise fail(
            f"expected latin_hypercube, got {describe(value['sample'])}", ("sample",)
        )
    if "n" not in value:
        raise fail("required key is missing (the number of scenarios drawn)", ("n",))
    limits = {"n": (2, MAX_SCENARIOS), "seed": (0, None)}
    numbers = {}
    for key, (low, high) in limits.items():
        if key not in value:
            continue
        number = _as_integer_at(value[key], key)
        if number < low or (high is not None and number > high):
            bound = f">= {low}" if number < low else f"<= {high:,}"
            raise fail(f"expected an integer {bound}, got {number}", (key,))
        numbers[key] = number
    return Sample(sample="latin_hypercube", **numbers)


def _as_integer_at(value: Any, key: str) -> int:
    try:
        return as_integer(value)
    except PydanticCustomError as exc:
        raise fail(exc.message(), (key,)) from None


class StudySpec(SectionModel):
    """The ``study:`` section: which inputs vary, and which scenarios are run."""

    vary: Annotated[dict[String, Levels], Field(min_length=1, max_length=MAX_VARIED)] = Field(
        description="Input path -> a list of values or {range: [lo, hi], levels: N}."
    )
    scenarios: Annotated[
        Literal["grid"] | Sample,
        PlainValidator(_parse_scenarios),
        PlainSerializer(lambda v: v if isinstance(v, str) else v.model_dump(mode="json")),
        WithJsonSchema({"anyOf": [{"const": "grid"}, Sample.model_json_schema()]}),
    ] = Field(
        "grid",
        description="grid (every combination of the values) or {sample: latin_hypercube, "
        "n: N, seed: S}.",
    )

    seeds: Annotated[
        Literal["independent", "common"], BeforeValidator(choice("independent", "common"))
    ] = Field(
        "independent",
        description="independent: each scenario draws its own rocks (its seed derived from "
        "the run's seed and its index); common: every scenario runs the same rocks (the "
        "run's seed), so that differences between scenarios come from the inputs alone.",
    )

    @model_validator(mode="after")
    def _check_study(self) -> "StudySpec":
        if self.scenarios == "grid":
            total = 1
            for path, levels in self.vary.items():
                if isinstance(levels, Range):
                    if levels.levels is None:
                        raise fail(
                            "a range in a grid needs levels: N (how many evenly spaced "
                            "values to try), or give the values as a list",
                            ("vary", path),
                        )
                    total *= levels.levels
                else:
                    total *= len(levels)
            if total > MAX_SCENARIOS:
                raise fail(
                    f"the grid has {total:,} scenarios, more than {MAX_SCENARIOS:,}: use fewer "
                    "values or a sample ({sample: latin_hypercube, n: N})",
                    ("scenarios",),
                )
        return self

    @property
    def sampled(self) -> bool:
        """True for a sampled (latin hypercube) study, False for a grid."""
        return isinstance(self.scenarios, Sample)


def values_text(values: Mapping[str, Any]) -> str:
    """A scenario's values as one line (``path = value, ...``), or "as written".

    Here, beside the study's keys, so that the studies, the report and the
    command line word a scenario alike without the studies loading the
    report (and pandas with it) for one line of text.
    """
    return ", ".join(f"{k} = {v}" for k, v in values.items()) or "as written"

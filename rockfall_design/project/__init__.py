"""The project file: ``project.yaml`` -> a validated, normalised :class:`Project`.

Loading is strict and reports the first problem as one line,
``file:line: key.path: message`` (a :class:`~rockfall_design.errors.ProjectError`):

- every section forbids unknown keys, with "did you mean" for near misses;
- numbers must be finite YAML numbers: booleans, strings such as ``"0.5"``,
  ``.nan`` and ``.inf`` are rejected;
- duplicate keys in a mapping are an error (plain YAML keeps the last one);
- cross-field rules (materials used by the slope are defined, release zones,
  stations and the protection lie on the section, ...) name the key involved.

The plugin sections ``measures:`` (a list of mappings, each with a string
``type``) and ``safety:`` (a mapping with a string ``concept``, default
``spang``) are kept raw, as plain data with finite numbers: the plugins that
own them are loaded later, and their parameters are validated then with
:meth:`Project.validate_params`, which locates problems in the file as the
core sections do (:meth:`Project.error_at`, :meth:`Project.unknown_name`).

Normalisation (what the models hold, whatever short form the file used):

- ``slope.materials`` is always a list with one material name per segment;
- ``rocks.release`` is always a list of :class:`ReleaseZone`;
- ``ReleaseZone.x`` is always a ``(min, max)`` tuple in m;
- ``rocks.radius`` / ``rocks.volume`` / ``rocks.mass`` hold a :class:`SizeSpec`
  (exactly one of them is set); :attr:`Rocks.size` and
  :attr:`Rocks.size_quantity` give the one that is set.

:meth:`Project.resolved_dict` writes the normalised project back in the
file's own syntax with every default filled in, so it is itself a valid
project file; :meth:`Project.resolved_hash` is the sha256 of its canonical JSON.

Units are SI throughout: m, m/s, rad/s, kg, m3, kg/m3; angles in degrees
where the key says ``_deg``.
"""

import contextlib
import contextvars
import copy
import difflib
import hashlib
import json
import math
import os
import re
import sys
import types
import typing
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Annotated, Any, Literal, Union

import yaml
from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    PlainValidator,
    PrivateAttr,
    ValidationError,
    WithJsonSchema,
    field_serializer,
    model_validator,
)
from pydantic_core import PydanticCustomError

from ..errors import Interrupted, PluginError, ProjectError
from ..inputs import read_text

__all__ = [
    "dump_yaml",
    "Analysis",
    "Design",
    "DesignCosts",
    "Locator",
    "ResidualFraction",
    "Site",
    "params_problem",
    "EngineConfig",
    "Material",
    "Project",
    "Protect",
    "ReleaseZone",
    "Rocks",
    "Scatter",
    "SizeSpec",
    "Slope",
    "load_project",
    "load_project_text",
]

# --------------------------------------------------------------------------------------
# Validation helpers: strict scalars with one-line messages
# --------------------------------------------------------------------------------------

_ERROR_TYPE = "rockfall_project"


def _fail(message: str, subpath: tuple = ()) -> PydanticCustomError:
    """An error to raise from a validator.

    ``subpath`` is appended to the location pydantic reports, so a model-level
    check can point at the field (or list item) it is about.
    """
    return PydanticCustomError(_ERROR_TYPE, "{message}", {"message": message, "subpath": subpath})


def _fmt(value: Any) -> str:
    """A number as the user would write it (``1`` rather than ``1.0``)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value):
            return ".nan"
        if math.isinf(value):
            return ".inf" if value > 0 else "-.inf"
        return format(value, ".12g")
    return str(value)


#: False while data from a file that the project names (a catalogue, a price
#: file) is checked: the path may point at any file, so its values are not
#: repeated in messages, only its file, line and key path.
_QUOTE_VALUES: contextvars.ContextVar[bool] = contextvars.ContextVar("quote", default=True)


@contextlib.contextmanager
def _unquoted() -> Iterator[None]:
    """Within the block, :func:`_describe` names a value's type, never the value."""
    token = _QUOTE_VALUES.set(False)
    try:
        yield
    finally:
        _QUOTE_VALUES.reset(token)


def _describe(value: Any) -> str:
    """A short, one-line description of a YAML value for "got ..." messages."""
    if value is None:
        return "null"
    if not _QUOTE_VALUES.get() and isinstance(value, bool | int | float | str):
        return "a boolean" if isinstance(value, bool) else (
            "a string" if isinstance(value, str) else "a number")
    if isinstance(value, bool):
        return f"{_fmt(value)} (a boolean)"
    if isinstance(value, int | float):
        return _fmt(value)
    if isinstance(value, str):
        text = value if len(value) <= 40 else value[:37] + "..."
        return f"string {text!r}"
    if isinstance(value, list | tuple):
        return f"a list of {len(value)} item{'s' if len(value) != 1 else ''}"
    if isinstance(value, dict):
        return "a mapping"
    return f"a value of type {type(value).__name__}"


def _as_number(value: Any, subpath: tuple = ()) -> float:
    """``value`` as a finite float; bools, strings and None are rejected."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise _fail(f"expected a number, got {_describe(value)}", subpath)
    try:
        number = float(value)
    except OverflowError:
        raise _fail("number is too large", subpath) from None
    if not math.isfinite(number):
        raise _fail(f"must be finite, got {_fmt(number)}", subpath)
    return number


def _as_integer(value: Any) -> int:
    """``value`` as an int; integral floats (``1000.0``) are accepted, bools are not."""
    if isinstance(value, float) and not isinstance(value, bool):
        if not math.isfinite(value):
            raise _fail(f"must be finite, got {_fmt(value)}")
        if value.is_integer():
            return int(value)
    if isinstance(value, bool) or not isinstance(value, int):
        raise _fail(f"expected an integer, got {_describe(value)}")
    return value


def _as_string(value: Any) -> str:
    if not isinstance(value, str):
        raise _fail(f"expected a string, got {_describe(value)}")
    return value


def _as_bool(value: Any) -> bool:
    if not isinstance(value, bool):
        raise _fail(f"expected true or false, got {_describe(value)}")
    return value


def _as_list(value: Any) -> list:
    if isinstance(value, tuple):
        return list(value)
    if not isinstance(value, list):
        raise _fail(f"expected a list, got {_describe(value)}")
    return value


def _pair(what: str) -> Callable[[Any], tuple[float, float]]:
    """Validator for a ``[a, b]`` pair of finite numbers, ``what`` naming it in messages."""

    def check(value: Any) -> tuple[float, float]:
        if not isinstance(value, list | tuple) or len(value) != 2:
            raise _fail(f"expected a pair {what}, got {_describe(value)}")
        return (_as_number(value[0], (0,)), _as_number(value[1], (1,)))

    return check


def _choice(*options: str) -> Callable[[Any], str]:
    def check(value: Any) -> str:
        if value not in options or not isinstance(value, str):
            hint = _did_you_mean(value, options) if isinstance(value, str) else ""
            raise _fail(f"expected one of {', '.join(options)}, got {_describe(value)}{hint}")
        return value

    return check


def _did_you_mean(word: str, candidates: Any) -> str:
    matches = difflib.get_close_matches(word, [str(c) for c in candidates], n=1)
    return f"; did you mean {matches[0]!r}?" if matches else ""


def _none_as_empty(value: Any) -> Any:
    """An empty section (``analysis:`` with nothing under it) means "all defaults"."""
    return {} if value is None else value


Number = Annotated[float, BeforeValidator(_as_number)]
Integer = Annotated[int, BeforeValidator(_as_integer)]
String = Annotated[str, BeforeValidator(_as_string)]
Boolean = Annotated[bool, BeforeValidator(_as_bool)]
Fraction = Annotated[Number, Field(ge=0.0, le=1.0)]
NonNegative = Annotated[Number, Field(ge=0.0)]
Positive = Annotated[Number, Field(gt=0.0)]


class _Model(BaseModel):
    """Base of every section: unknown keys are rejected with "did you mean"."""

    model_config = ConfigDict(extra="forbid", validate_default=False)

    @model_validator(mode="before")
    @classmethod
    def _check_mapping_and_keys(cls, data: Any) -> Any:
        if isinstance(data, cls):
            return data
        if not isinstance(data, dict):
            raise _fail(f"expected a mapping of key: value, got {_describe(data)}")
        fields = list(cls.model_fields)
        for key in data:
            if key not in cls.model_fields:
                if isinstance(key, str):
                    hint = _did_you_mean(key, fields) or f"; expected one of {', '.join(fields)}"
                else:
                    hint = f"; keys must be names, expected one of {', '.join(fields)}"
                raise _fail(f"unknown key {key!r}{hint}", (key,))
        return data


# --------------------------------------------------------------------------------------
# Sections
# --------------------------------------------------------------------------------------


class Scatter(_Model):
    """Standard deviations of the material parameters, drawn per impact (default 0)."""

    restitution: NonNegative = Field(
        0.0, description="Standard deviation of the restitution coefficient (-)."
    )
    friction: NonNegative = Field(0.0, description="Standard deviation of the friction mu (-).")
    rolling_resistance: NonNegative = Field(
        0.0, description="Standard deviation of the rolling resistance mu_r (-)."
    )


class Material(_Model):
    """Ground material of slope segments: impact and contact parameters."""

    impact_model: Annotated[
        Literal["spang", "rn_rt"], BeforeValidator(_choice("spang", "rn_rt"))
    ] = Field(
        "spang",
        description="Impact model: 'spang' (one restitution e) or 'rn_rt' "
        "(normal Rn and tangential Rt restitution).",
    )
    restitution: Fraction = Field(
        description="Restitution (-): e for impact_model spang, Rn for rn_rt; 0..1."
    )
    tangential_restitution: Fraction | None = Field(
        None, description="Tangential restitution Rt (-), 0..1; only (and required) for rn_rt."
    )
    friction: Annotated[NonNegative, Field(le=10.0)] = Field(
        description="Coulomb friction coefficient mu (-) for sliding and impacts; 0..10."
    )
    rolling_resistance: NonNegative = Field(
        0.0, description="Rolling resistance coefficient mu_r (-)."
    )
    velocity_scaling: Boolean = Field(
        False,
        description="Scale the restitution with the impact velocity (Pfeiffer & Bowen 1989).",
    )
    velocity_scaling_k: Positive = Field(
        9.144, description="Velocity scaling constant K (m/s) of Pfeiffer & Bowen."
    )
    roughness_deg: Annotated[NonNegative, Field(lt=45.0)] = Field(
        0.0,
        description="Slope roughness: standard deviation of the random tilt of the impact "
        "normal (deg), drawn per impact.",
    )
    roughness_height_m: Annotated[NonNegative, Field(le=25.0)] = Field(
        0.0,
        description="Slope roughness as a height h_r (m), for values calibrated in PlatRock "
        "or PyRockfall: per impact the normal tilts against the motion by an angle drawn "
        "uniformly in [0, atan(h_r / r)], r the rock radius; 0..25.",
    )
    scatter: Annotated[Scatter, BeforeValidator(_none_as_empty)] = Field(
        default_factory=Scatter, description="Standard deviations of the parameters."
    )

    @model_validator(mode="after")
    def _check_impact_model(self) -> "Material":
        if self.impact_model == "rn_rt" and self.tangential_restitution is None:
            raise _fail(
                "required for impact_model rn_rt (tangential restitution Rt, 0..1)",
                ("tangential_restitution",),
            )
        if self.impact_model == "spang" and self.tangential_restitution is not None:
            raise _fail(
                "only for impact_model rn_rt; remove it or set impact_model: rn_rt",
                ("tangential_restitution",),
            )
        return self


#: Largest coordinate (m) of a slope point. Far from the origin a float64 keeps
#: too few digits for the contact geometry of a small rock: with coordinates
#: near 1e7 m the same rocks already take measurably different paths.
MAX_COORDINATE_M = 1e6
#: Largest rock radius (m). A sphere of 25 m radius holds 65,000 m3: a rock
#: avalanche, far beyond the blocks this model is for. Size distributions are
#: truncated here, so that no draw from a long tail overflows the energies.
MAX_RADIUS_M = 25.0
#: Smallest rock radius (m): 1 cm, gravel. Below it the model is no longer one
#: of rockfall, and far below (1e-300 m) mass and spin leave float64's range.
#: Size distributions are cut off here too (draws below are raised to it).
MIN_RADIUS_M = 0.01
#: Largest rock density (kg/m3), above any rock's (ores reach about 5,000).
MAX_DENSITY = 20_000.0
#: Smallest rock density (kg/m3), below any rock's (pumice is about 250).
MIN_DENSITY = 100.0
#: Most rocks in one run (rocks.count, --rocks, design.fresh_rocks): a streamed
#: run of a billion rocks takes about six hours on one core.
MAX_ROCKS = 1_000_000_000
#: Most analysis stations: each adds a column per rock and its histograms.
MAX_STATIONS = 1_000
#: Most percentiles of the envelopes.
MAX_PERCENTILES = 100
#: Most envelope points: each adds two values per rock (or two histograms).
MAX_ENVELOPE_POINTS = 10_000
#: Smallest chord angle (deg) of the centre path's arcs: every convex vertex
#: becomes up to 180 / max_chord_deg edges, for every rock size.
MIN_CHORD_DEG = 0.5
#: Most measures in one design of the optimiser.
MAX_DESIGN_MEASURES = 10
#: Most families (multisets of candidates) the optimiser searches: at about
#: four seconds a family on 10,000 rocks, an hour's work.
MAX_FAMILIES = 1_000
#: Largest release speed (m/s) in x or y: a free fall of 500 m ends at 99 m/s.
MAX_RELEASE_SPEED = 100.0
#: Largest release spin (rad/s).
MAX_RELEASE_SPIN = 1000.0
#: Largest release clearance above the ground (m).
MAX_RELEASE_HEIGHT_M = 10_000.0


class Slope(_Model):
    """The 2-D slope section: a polyline of ground points and a material per segment."""

    points: Annotated[
        list[Annotated[tuple[float, float], BeforeValidator(_pair("[x, y]"))]],
        BeforeValidator(_as_list),
    ] = Field(description="Ground points [x, y] (m), x strictly increasing downslope; at least 2.")
    materials: Annotated[list[String], BeforeValidator(_as_list)] = Field(
        description="Material name for all segments, or a list with one name per segment "
        "(len(points) - 1). Always stored as the per-segment list."
    )

    @model_validator(mode="before")
    @classmethod
    def _broadcast_material(cls, data: Any) -> Any:
        if isinstance(data, dict) and isinstance(data.get("materials"), str):
            points = data.get("points")
            n_segments = max(len(points) - 1, 1) if isinstance(points, list | tuple) else 1
            data = {**data, "materials": [data["materials"]] * n_segments}
        return data

    @model_validator(mode="after")
    def _check_geometry(self) -> "Slope":
        if len(self.points) < 2:
            raise _fail(f"expected at least 2 points, got {len(self.points)}", ("points",))
        for i, point in enumerate(self.points):
            for k, value in enumerate(point):
                if abs(value) > MAX_COORDINATE_M:
                    raise _fail(
                        f"{'xy'[k]} = {_fmt(value)} m is farther than {MAX_COORDINATE_M:,.0f} m "
                        "from the origin: give the section in metres, x measured along it "
                        "(from its top, say) and y as height",
                        ("points", i, k),
                    )
        for i in range(1, len(self.points)):
            if self.points[i][0] <= self.points[i - 1][0]:
                raise _fail(
                    f"x must increase strictly along the slope: x = {_fmt(self.points[i][0])} "
                    f"follows x = {_fmt(self.points[i - 1][0])}",
                    ("points", i),
                )
        if len(self.materials) != self.n_segments:
            raise _fail(
                f"expected one material name per segment ({self.n_segments}), "
                f"got {len(self.materials)}; or give a single name for all",
                ("materials",),
            )
        return self

    @property
    def n_segments(self) -> int:
        """Number of segments (``len(points) - 1``)."""
        return len(self.points) - 1

    @property
    def x_range(self) -> tuple[float, float]:
        """(first x, last x) of the section (m)."""
        return (self.points[0][0], self.points[-1][0])


class SizeSpec(_Model):
    """A rock size distribution, in the quantity given by :attr:`Rocks.size_quantity`.

    ``kind`` and the meaning of ``a`` and ``b``:

    - ``fixed``: every rock has size ``a`` (= ``b``);
    - ``uniform``: uniform on [a, b], 0 < a <= b;
    - ``normal``: mean a > 0, standard deviation b >= 0;
    - ``lognormal``: median a > 0, sigma b >= 0 of the underlying normal (log) distribution.

    In the project file this is written as a number (fixed) or as a one-key
    mapping ``{uniform: [a, b]}``, ``{normal: [mean, sd]}`` or
    ``{lognormal: [median, sigma]}``; :meth:`Project.resolved_dict` writes it
    back the same way.
    """

    kind: Literal["fixed", "uniform", "normal", "lognormal"] = Field(
        description="Distribution kind."
    )
    a: Number = Field(description="Fixed value, minimum, mean or median (m, m3 or kg).")
    b: Number = Field(description="Fixed value, maximum, standard deviation or sigma.")

    @model_validator(mode="after")
    def _check_parameters(self) -> "SizeSpec":
        problem = _size_problem(self.kind, self.a, self.b)
        if problem:
            raise _fail(problem)
        return self

    def to_yaml(self) -> float | dict[str, list[float]]:
        """The project-file form: a number, or ``{kind: [a, b]}``."""
        if self.kind == "fixed":
            return self.a
        return {self.kind: [self.a, self.b]}


_SIZE_KINDS = {
    "uniform": "[min, max]",
    "normal": "[mean, sd]",
    "lognormal": "[median, sigma]",
}


def _size_problem(kind: str, a: float, b: float) -> str:
    if kind == "fixed":
        if a <= 0:
            return f"expected a number > 0, got {_fmt(a)}"
        if a != b:
            return "a fixed size needs a == b"
    elif kind == "uniform":
        if not 0 < a <= b:
            return f"uniform [min, max] needs 0 < min <= max, got [{_fmt(a)}, {_fmt(b)}]"
    elif a <= 0 or b < 0:
        first, second = _SIZE_KINDS[kind][1:-1].split(", ")
        return (
            f"{kind} {_SIZE_KINDS[kind]} needs {first} > 0 and {second} >= 0, "
            f"got [{_fmt(a)}, {_fmt(b)}]"
        )
    return ""


def _parse_size(value: Any) -> Any:
    """Project-file size (number or ``{kind: [a, b]}``) -> :class:`SizeSpec` data."""
    if value is None or isinstance(value, SizeSpec):
        return value
    forms = "a number > 0 or one of " + ", ".join(
        f"{{{kind}: {what}}}" for kind, what in _SIZE_KINDS.items()
    )
    if isinstance(value, dict):
        if len(value) != 1:
            raise _fail(f"expected {forms}, got a mapping with {len(value)} keys")
        ((kind, params),) = value.items()
        if kind not in _SIZE_KINDS:
            hint = _did_you_mean(kind, _SIZE_KINDS) if isinstance(kind, str) else ""
            raise _fail(
                f"unknown distribution {kind!r}{hint}; expected {', '.join(_SIZE_KINDS)}",
                (kind,),
            )
        if not isinstance(params, list | tuple) or len(params) != 2:
            raise _fail(f"expected {_SIZE_KINDS[kind]}, got {_describe(params)}", (kind,))
        a = _as_number(params[0], (kind, 0))
        b = _as_number(params[1], (kind, 1))
        problem = _size_problem(kind, a, b)
        if problem:
            raise _fail(problem, (kind,))
        return SizeSpec(kind=kind, a=a, b=b)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise _fail(f"expected {forms}, got {_describe(value)}")
    number = _as_number(value)
    if number <= 0:
        raise _fail(f"expected a number > 0, got {_fmt(number)}")
    return SizeSpec(kind="fixed", a=number, b=number)


_SIZE_SCHEMA = {
    "anyOf": [
        {"type": "number", "exclusiveMinimum": 0},
        *(
            {
                "type": "object",
                "properties": {
                    kind: {
                        "type": "array",
                        "items": {"type": "number"},
                        "minItems": 2,
                        "maxItems": 2,
                    }
                },
                "required": [kind],
                "additionalProperties": False,
            }
            for kind in _SIZE_KINDS
        ),
        {"type": "null"},
    ]
}

SizeField = Annotated[SizeSpec | None, BeforeValidator(_parse_size), WithJsonSchema(_SIZE_SCHEMA)]


def _parse_x_range(value: Any) -> tuple[float, float]:
    if isinstance(value, list | tuple):
        low, high = _pair("[min, max]")(value)
        if low > high:
            raise _fail(f"expected [min, max] with min <= max, got [{_fmt(low)}, {_fmt(high)}]")
        return (low, high)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise _fail(f"expected a number or [min, max], got {_describe(value)}")
    x = _as_number(value)
    return (x, x)


def _parse_spin(value: Any) -> float | str:
    if value == "rolling" and isinstance(value, str):
        return "rolling"
    if isinstance(value, str):
        raise _fail(f"expected a number (rad/s) or 'rolling', got {_describe(value)}")
    spin = _as_number(value)
    if abs(spin) > MAX_RELEASE_SPIN:
        raise _fail(f"expected a spin within +-{MAX_RELEASE_SPIN:g} rad/s, got {_fmt(spin)}")
    return spin


def _release_velocity(value: Any) -> tuple[float, float]:
    """A release ``velocity`` [vx, vy] (m/s), each component within MAX_RELEASE_SPEED."""
    velocity = _pair("[vx, vy]")(value)
    for k, v in enumerate(velocity):
        if abs(v) > MAX_RELEASE_SPEED:
            raise _fail(
                f"expected a speed within +-{MAX_RELEASE_SPEED:g} m/s, got {_fmt(v)}", (k,)
            )
    return velocity


def _clearance(value: Any) -> float:
    """A release ``height``: the clearance (m) above the ground, so never negative."""
    height = _as_number(value)
    if height > MAX_RELEASE_HEIGHT_M:
        raise _fail(f"expected a clearance <= {MAX_RELEASE_HEIGHT_M:,.0f} m, got {_fmt(height)}")
    if height < 0:
        raise _fail(
            f"expected a clearance >= 0 (m), got {_fmt(height)}: the release would start "
            "the rock below the ground (height is measured from the ground up; "
            "0 = resting on it)"
        )
    return height


class ReleaseZone(_Model):
    """A release zone: where and how rocks start."""

    x: Annotated[
        tuple[float, float],
        BeforeValidator(_parse_x_range),
        WithJsonSchema(
            {
                "anyOf": [
                    {"type": "number"},
                    {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2},
                ]
            }
        ),
    ] = Field(
        description="Release x (m): a number or a range [min, max] sampled uniformly. "
        "Always stored as (min, max)."
    )
    height: Annotated[float, BeforeValidator(_clearance)] = Field(
        0.0, description="Initial clearance between the rock and the ground (m), >= 0."
    )
    velocity: Annotated[tuple[float, float], BeforeValidator(_release_velocity)] = Field(
        (0.0, 0.0), description="Initial velocity [vx, vy] (m/s), each within +-100 m/s."
    )
    spin: Annotated[
        float | Literal["rolling"],
        PlainValidator(_parse_spin),
        WithJsonSchema({"anyOf": [{"type": "number"}, {"const": "rolling"}]}),
    ] = Field(
        0.0,
        description="Initial angular velocity (rad/s), or 'rolling' for the spin matching "
        "rolling without slip.",
    )
    weight: Positive = Field(1.0, description="Relative weight of this zone (-).")


def _zones(value: Any) -> Any:
    """One zone (a mapping) or a list of zones -> a list of zones."""
    if isinstance(value, dict | ReleaseZone):
        return [value]
    if isinstance(value, list | tuple):
        if not value:
            raise _fail("expected at least one release zone, got an empty list")
        return list(value)
    raise _fail(f"expected a release zone (mapping) or a list of zones, got {_describe(value)}")


class Rocks(_Model):
    """The rock ensemble: how many, what size, where they are released.

    Exactly one of ``radius``, ``volume`` and ``mass`` is set; :attr:`size`
    and :attr:`size_quantity` give it without looking at all three.
    """

    count: Annotated[Integer, Field(ge=1, le=MAX_ROCKS)] = Field(
        1000, description="Number of rocks, at most 1,000,000,000."
    )
    seed: Annotated[Integer, Field(ge=0)] = Field(0, description="Random seed (reproducible).")
    density: Annotated[Number, Field(ge=MIN_DENSITY, le=MAX_DENSITY)] = Field(
        2650.0, description="Rock density (kg/m3), 100..20,000."
    )
    radius: SizeField = Field(None, description="Rock radius (m): a number or a distribution.")
    volume: SizeField = Field(None, description="Rock volume (m3): a number or a distribution.")
    mass: SizeField = Field(None, description="Rock mass (kg): a number or a distribution.")
    release: Annotated[list[ReleaseZone], BeforeValidator(_zones)] = Field(
        description="One release zone or a list of zones. Always stored as a list."
    )

    @model_validator(mode="after")
    def _check_size(self) -> "Rocks":
        given = [name for name in ("radius", "volume", "mass") if getattr(self, name) is not None]
        if not given:
            raise _fail(
                "give the rock size as one of radius (m), volume (m3) or mass (kg)", ("radius",)
            )
        if len(given) > 1:
            raise _fail(
                f"give only one of radius, volume, mass; got {' and '.join(given)}",
                (given[1],),
            )
        spec, top, bottom = self.size, self.max_size, self.min_size
        unit = {"radius": "m", "volume": "m3", "mass": "kg"}[self.size_quantity]
        # The smallest size the distribution must be able to exceed: its fixed
        # value, its maximum, or its mean or median (a tail beyond is cut off).
        least = spec.b if spec.kind == "uniform" else spec.a
        if least > top:
            raise _fail(
                f"expected sizes up to {_fmt(float(f'{top:.6g}'))} {unit} (a sphere of "
                f"{MAX_RADIUS_M:g} m radius), got {_fmt(least)}",
                (self.size_quantity,),
            )
        # And the size it must reach at least: its fixed value, its minimum,
        # its mean or median (a tail below is cut off).
        if spec.a < bottom:
            raise _fail(
                f"expected sizes of at least {_fmt(float(f'{bottom:.6g}'))} {unit} (a sphere "
                f"of {MIN_RADIUS_M:g} m radius), got {_fmt(spec.a)}",
                (self.size_quantity,),
            )
        return self

    @property
    def min_size(self) -> float:
        """The smallest size a rock may have, in the units of :attr:`size_quantity`.

        A sphere of :data:`MIN_RADIUS_M`; draws below it are raised to it.
        """
        volume = 4.0 / 3.0 * math.pi * MIN_RADIUS_M**3
        return {"radius": MIN_RADIUS_M, "volume": volume,
                "mass": volume * self.density}[self.size_quantity]

    @property
    def max_size(self) -> float:
        """The largest size a rock may have, in the units of :attr:`size_quantity`.

        A sphere of :data:`MAX_RADIUS_M`; draws beyond it are cut off (the
        distribution is truncated there).
        """
        volume = 4.0 / 3.0 * math.pi * MAX_RADIUS_M**3
        return {"radius": MAX_RADIUS_M, "volume": volume,
                "mass": volume * self.density}[self.size_quantity]

    @field_serializer("radius", "volume", "mass")
    def _size_to_yaml(self, value: SizeSpec | None) -> Any:
        return None if value is None else value.to_yaml()

    @property
    def size_quantity(self) -> Literal["radius", "volume", "mass"]:
        """Which of radius (m), volume (m3) or mass (kg) the size is given as."""
        for name in ("radius", "volume", "mass"):
            if getattr(self, name) is not None:
                return name  # type: ignore[return-value]
        raise ValueError("no rock size given")  # unreachable for a validated model

    @property
    def size(self) -> SizeSpec:
        """The size distribution, in the units of :attr:`size_quantity`."""
        return getattr(self, self.size_quantity)


class Analysis(_Model):
    """What to evaluate along the section."""

    stations: Annotated[
        list[Number], Field(max_length=MAX_STATIONS), BeforeValidator(_as_list)
    ] = Field(
        default_factory=list,
        description="Stations x (m) where crossings are recorded; at most 1,000.",
    )
    percentiles: Annotated[
        list[Annotated[Number, Field(gt=0.0, lt=100.0)]],
        Field(max_length=MAX_PERCENTILES),
        BeforeValidator(_as_list),
    ] = Field(
        default_factory=lambda: [50.0, 95.0, 99.0],
        description="Percentiles (%) of height and energy reported, each in (0, 100).",
    )
    envelope_points: Annotated[Integer, Field(ge=2, le=MAX_ENVELOPE_POINTS)] = Field(
        201, description="Number of envelope stations spread along the section, 2..10,000."
    )
    min_rocks_envelope: Annotated[Integer, Field(ge=1)] = Field(
        30,
        description="Fewest rocks that must pass a point of the section for the figures to "
        "draw the envelopes there (a percentile of a handful of rocks says little).",
    )


class Protect(_Model):
    """Where the protection is to be placed."""

    x: Number = Field(description="Position of the protective measure along the section (m).")
    allowed_fraction: Fraction = Field(
        0.0,
        description="Fraction of the rocks allowed to reach the protected zone (-), 0..1.",
    )


class EngineConfig(_Model):
    """Advanced numerical parameters of the trajectory engine."""

    v_contact: Positive = Field(
        0.5, description="Below this outgoing normal speed (m/s) the rock stays in contact."
    )
    v_stop: Positive = Field(0.05, description="Below this speed (m/s) the rock stops.")
    max_events: Annotated[Integer, Field(ge=10, le=10_000_000)] = Field(
        10000, description="Maximum number of events (impacts, phase changes) per rock, "
        "10..10,000,000."
    )
    max_chord_deg: Annotated[Number, Field(ge=MIN_CHORD_DEG, le=30.0)] = Field(
        5.0, description="Maximum angle (deg) between trajectory chords and the arc, 0.5..30."
    )


# --------------------------------------------------------------------------------------
# Plugin sections: measures and safety, kept raw until the plugins are loaded
# --------------------------------------------------------------------------------------


def _raw(value: Any, subpath: tuple = (), *, number_keys: bool = False) -> Any:
    """Plain YAML data for a plugin, checked and copied.

    Accepts null, booleans, strings, integers, finite floats, lists and
    mappings with string keys (recursively); NaN and infinities, non-string
    keys and other YAML types (``!!binary``, ``!!set``) are rejected at the
    offending node. With ``number_keys``, finite numbers are accepted as keys
    too (a price table by height, ``{2: 350, 3: 420}``).
    """
    if value is None or isinstance(value, bool | str | int):
        return value
    if isinstance(value, float):
        if not math.isfinite(value):
            raise _fail(f"must be finite, got {_fmt(value)}", subpath)
        return value
    if isinstance(value, list | tuple):
        return [_raw(item, subpath + (i,), number_keys=number_keys) for i, item in enumerate(value)]
    if isinstance(value, dict):
        copied = {}
        for key, item in value.items():
            number = isinstance(key, int | float) and not isinstance(key, bool)
            if number and number_keys:
                if not math.isfinite(key):
                    raise _fail(f"keys must be finite, got {_fmt(key)}", subpath + (key,))
            elif not isinstance(key, str):
                raise _fail(f"keys must be names, got {_describe(key)}", subpath + (key,))
            copied[key] = _raw(item, subpath + (key,), number_keys=number_keys)
        return copied
    raise _fail(f"unsupported value: {_describe(value)}", subpath)



def _check_typed_item(item: Any, i: int, expected: str) -> None:
    """An entry of ``measures:`` or ``design.candidates``: a mapping with a string ``type``."""
    if not isinstance(item, dict):
        raise _fail(f"expected {expected}, got {_describe(item)}", (i,))
    if "type" not in item:
        raise _fail("required key 'type' is missing (the kind of measure, e.g. fence)", (i,))
    kind = item["type"]
    if not isinstance(kind, str):
        raise _fail(f"expected the name of a measure type, got {_describe(kind)}", (i, "type"))
    if not kind.strip():
        raise _fail("must not be empty (the kind of measure, e.g. fence)", (i, "type"))

def _parse_measures(value: Any) -> list[dict[str, Any]]:
    """``measures:``: a list of mappings, each with a non-empty string ``type``."""
    if value is None:
        return []
    if not isinstance(value, list | tuple):
        raise _fail(f"expected a list of measures (mappings with a type), got {_describe(value)}")
    measures = []
    for i, item in enumerate(value):
        _check_typed_item(item, i, "a measure (a mapping such as {type: fence, x: 70, ...})")
        measures.append(_raw(item, (i,)))
    return measures


_DEFAULT_CONCEPT = "spang"


def _parse_safety(value: Any) -> dict[str, Any]:
    """``safety:``: a mapping with a string ``concept`` (default spang), listed first."""
    if value is None:
        return {"concept": _DEFAULT_CONCEPT}
    if not isinstance(value, dict):
        raise _fail(
            f"expected a mapping (concept: NAME and its parameters), got {_describe(value)}"
        )
    concept = value.get("concept", _DEFAULT_CONCEPT)
    if not isinstance(concept, str):
        raise _fail(
            f"expected the name of a safety concept, got {_describe(concept)}", ("concept",)
        )
    if not concept.strip():
        raise _fail("must not be empty (the name of a safety concept, e.g. spang)", ("concept",))
    rest = _raw({k: v for k, v in value.items() if k != "concept"})
    return {"concept": concept, **rest}


def _plain_copy(value: Any, what: str) -> Any:
    """:func:`_raw` for data a program passes in: problems are a ValueError (a bug)."""
    try:
        return _raw(value)
    except PydanticCustomError as exc:
        where = "".join(f"[{p!r}]" for p in (exc.context or {}).get("subpath", ()))
        raise ValueError(f"{what}{where}: {exc.message()}") from None


# --------------------------------------------------------------------------------------
# The design section (least-cost optimiser): shapes checked here, plugins resolve it later
# --------------------------------------------------------------------------------------


class ResidualFraction(_Model):
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
                hint = _did_you_mean(key, ["fraction"]) if isinstance(key, str) else ""
                raise _fail(f"unknown key {key!r}{hint}; expected {forms}", (key,))
        if "fraction" not in value:
            raise _fail(f"required key 'fraction' is missing; expected {forms}")
        fraction = _as_number(value["fraction"], ("fraction",))
        if not 0.0 <= fraction <= 1.0:
            raise _fail(f"expected a number in 0..1, got {_fmt(fraction)}", ("fraction",))
        return ResidualFraction(fraction=fraction)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise _fail(f"expected {forms}, got {_describe(value)}")
    if isinstance(value, float) and not (math.isfinite(value) and value.is_integer()):
        raise _fail(f"expected {forms}, got {_describe(value)}")
    if value < 0:
        raise _fail(f"expected {forms}, got {_fmt(value)}")
    return int(value)


class Site(_Model):
    """The site: how much slope the measures span."""

    length_m: Annotated[Positive, Field(le=MAX_COORDINATE_M)] = Field(
        description="Length of slope to protect, along the contour (m): what the measures "
        "span; at most 1,000 km (costs scale with it; 1e300 overflowed the optimiser)."
    )


_CATALOGUE_FORM = "measure type -> product name -> {capacity_kj: E, heights: [h, ...]}"


def _check_products(value: Any) -> dict[str, dict[str, dict[str, Any]]]:
    """A product catalogue, normalised: ``{kind: {name: {capacity_kj, heights, ...}}}``.

    ``capacity_kj`` (kJ) is a number > 0, ``heights`` (m) a non-empty list of
    distinct numbers > 0; other keys of a product are kept as plain data.
    """
    if not isinstance(value, dict):
        raise _fail(f"expected a mapping {_CATALOGUE_FORM}, got {_describe(value)}")
    catalogue: dict[str, dict[str, dict[str, Any]]] = {}
    for kind, table in value.items():
        if not isinstance(kind, str) or not kind.strip():
            raise _fail(f"expected the name of a measure type, got {_describe(kind)}", (kind,))
        if not isinstance(table, dict):
            raise _fail(
                f"expected a mapping of product name -> {{capacity_kj: E, heights: [h, ...]}}, "
                f"got {_describe(table)}",
                (kind,),
            )
        products: dict[str, dict[str, Any]] = {}
        for name, entry in table.items():
            where = (kind, name)
            if not isinstance(name, str) or not name.strip():
                raise _fail(
                    f"expected a product name, got {_describe(name)} (quote names such as '100')",
                    where,
                )
            if not isinstance(entry, dict):
                raise _fail(
                    f"expected a mapping {{capacity_kj: E, heights: [h, ...]}}, "
                    f"got {_describe(entry)}",
                    where,
                )
            for key in ("capacity_kj", "heights"):
                if key not in entry:
                    what = "energy class (kJ)" if key == "capacity_kj" else "heights (m)"
                    raise _fail(f"required key {key!r} is missing (the product's {what})", where)
            capacity = _as_number(entry["capacity_kj"], where + ("capacity_kj",))
            if capacity <= 0:
                raise _fail(
                    f"expected a number > 0, got {_fmt(capacity)}", where + ("capacity_kj",)
                )
            heights_raw = entry["heights"]
            if not isinstance(heights_raw, list | tuple) or not heights_raw:
                raise _fail(
                    f"expected a non-empty list of heights (m), got {_describe(heights_raw)}",
                    where + ("heights",),
                )
            heights: list[float] = []
            for j, item in enumerate(heights_raw):
                h = _as_number(item, where + ("heights", j))
                if h <= 0:
                    raise _fail(f"expected a number > 0, got {_fmt(h)}", where + ("heights", j))
                if h in heights:
                    raise _fail(f"height {_fmt(h)} is listed twice", where + ("heights", j))
                heights.append(h)
            rest = {k: v for k, v in entry.items() if k not in ("capacity_kj", "heights")}
            products[name] = {
                "capacity_kj": capacity,
                "heights": heights,
                **_raw(rest, where),
            }
        catalogue[kind] = products
    return catalogue


def _parse_products(value: Any) -> Any:
    """``design.products``: a catalogue file (a path) or an inline catalogue."""
    if value is None:
        return None
    if isinstance(value, str):
        if not value.strip():
            raise _fail("must not be empty (a catalogue file, e.g. catalogue_products.yaml)")
        return value
    if not isinstance(value, dict):
        raise _fail(
            f"expected a catalogue file (a path) or a mapping {_CATALOGUE_FORM}, "
            f"got {_describe(value)}"
        )
    return _check_products(value)


def _parse_cost_params(value: Any) -> Any:
    if value is None:
        return None
    if not isinstance(value, dict):
        raise _fail(f"expected a mapping of the cost model's parameters, got {_describe(value)}")
    return _raw(value, number_keys=True)


class DesignCosts(_Model):
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
            raise _fail(
                "give the cost model's parameters: file: PATH (a YAML file) or params: {...}"
            )
        if self.file is not None and self.params is not None:
            raise _fail("give only one of file and params", ("params",))
        return self


_VALUE_FORMS = "a value (fixed), a range [min, max] or {options: [a, b, ...]}"


def _check_options(value: Any, subpath: tuple) -> list:
    if set(value) != {"options"}:
        extra = next((k for k in value if k != "options"), None)
        if extra is not None:
            hint = _did_you_mean(extra, ["options"]) if isinstance(extra, str) else ""
            raise _fail(
                f"unknown key {extra!r}{hint}; expected {{options: [...]}}", subpath + (extra,)
            )
        raise _fail("required key 'options' is missing: expected {options: [...]}", subpath)
    options = value["options"]
    where = subpath + ("options",)
    if not isinstance(options, list | tuple) or not options:
        raise _fail(f"expected a non-empty list of options, got {_describe(options)}", where)
    seen: list = []
    for k, item in enumerate(options):
        if item is None or not isinstance(item, bool | int | float | str):
            raise _fail(
                f"expected a number, string or boolean, got {_describe(item)}", where + (k,)
            )
        _raw(item, where + (k,))
        if any(type(item) is type(s) and item == s for s in seen):
            raise _fail(f"option {_fmt(item)} is listed twice", where + (k,))
        seen.append(item)
    return list(options)


def _check_candidate_value(value: Any, subpath: tuple) -> Any:
    """A candidate parameter: a fixed value, a range [min, max] or {options: [...]}."""
    if isinstance(value, list | tuple):
        if len(value) != 2:
            raise _fail(
                f"expected a range [min, max] of two numbers, got {_describe(value)}; "
                "for a choice write {options: [...]}",
                subpath,
            )
        for k, item in enumerate(value):
            if isinstance(item, bool) or not isinstance(item, int | float):
                raise _fail(
                    f"a range [min, max] needs numbers, got {_describe(item)}; "
                    "for a choice write {options: [...]}",
                    subpath + (k,),
                )
        low, high = _as_number(value[0], subpath + (0,)), _as_number(value[1], subpath + (1,))
        if not low < high:
            raise _fail(
                f"expected a range [min, max] with min < max, got [{_fmt(low)}, {_fmt(high)}]; "
                "for a fixed value give the number",
                subpath,
            )
        return list(value)
    if isinstance(value, dict):
        return {"options": _check_options(value, subpath)}
    if value is None or not isinstance(value, bool | int | float | str):
        raise _fail(f"expected {_VALUE_FORMS}, got {_describe(value)}", subpath)
    return _raw(value, subpath)


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
        raise _fail(
            f"expected a product name or a non-empty list of names, got {_describe(value)}",
            subpath,
        )
    for k, name in enumerate(names):
        at = where if isinstance(value, str) else where + (k,)
        if not isinstance(name, str) or not name.strip():
            raise _fail(f"expected a product name, got {_describe(name)}", at)
        if name in names[:k]:
            raise _fail(f"product {name!r} is listed twice", at)
    return _raw(value, subpath)


def _parse_candidates(value: Any) -> list[dict[str, Any]]:
    """``design.candidates``: a non-empty list of mappings with ``type`` and ``x: [min, max]``."""
    if not isinstance(value, list | tuple) or not value:
        raise _fail(
            "expected a non-empty list of candidate measures (mappings such as "
            f"{{type: fence, x: [60, 110]}}), got {_describe(value)}"
        )
    candidates = []
    for i, item in enumerate(value):
        _check_typed_item(
            item, i, "a candidate measure (a mapping such as {type: fence, x: [60, 110]})"
        )
        if "x" not in item:
            raise _fail(
                "required key 'x' is missing (the station range [min, max] (m) where the "
                "optimiser may place the measure)",
                (i,),
            )
        x = item["x"]
        if not isinstance(x, list | tuple) or len(x) != 2:
            raise _fail(
                f"expected a station range [min, max] (m), got {_describe(x)}; the optimiser "
                "places the measure within it",
                (i, "x"),
            )
        low, high = _as_number(x[0], (i, "x", 0)), _as_number(x[1], (i, "x", 1))
        if not low < high:
            raise _fail(
                f"expected a station range [min, max] with min < max, "
                f"got [{_fmt(low)}, {_fmt(high)}]",
                (i, "x"),
            )
        candidate: dict[str, Any] = {"type": item["type"], "x": [x[0], x[1]]}
        for key, item_value in item.items():
            if key in ("type", "x"):
                continue
            if not isinstance(key, str):
                raise _fail(f"keys must be names, got {_describe(key)}", (i, key))
            if key == "product":
                candidate[key] = _check_product_choice(item_value, (i, key))
            else:
                candidate[key] = _check_candidate_value(item_value, (i, key))
        candidates.append(candidate)
    return candidates


class Design(_Model):
    """``design:``, what the least-cost optimiser may build and how it checks a design.

    Candidate parameters are kept raw (the measure plugins are loaded later,
    see :func:`rockfall_design.design.resolve_design`), their shapes checked:
    ``x`` is a station range ``[min, max]`` (m) inside the section; any other
    value is fixed (a number, string or boolean), a range ``[a, b]`` of
    numbers with a < b (a continuous design variable) or ``{options: [...]}``
    (a discrete one); ``product`` is a catalogue name or a list of names.

    The product catalogue and the cost model's parameters may come from files
    (paths relative to the project file); :func:`load_project` reads them and
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
        50_000,
        description="Most rocks a design near a limit is decided with: while it holds on the "
        "point values but not with the confidence bounds, its rocks are doubled up to this.",
    )
    fresh_seed: Annotated[Integer, Field(ge=0)] | None = Field(
        None, description="Seed of the re-check; default: the run's seed + 1000003."
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
            raise _fail(
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


class Project(_Model):
    """A validated, normalised project file.

    Load one with :func:`load_project` or :func:`load_project_text`; the file
    it came from is :attr:`source`.
    """

    name: Annotated[String, Field(min_length=1)] = Field(description="Project name.")
    description: Annotated[String, BeforeValidator(lambda v: "" if v is None else v)] = Field(
        "", description="Free text."
    )
    slope: Slope = Field(description="The slope section.")
    materials: Annotated[dict[String, Material], Field(min_length=1)] = Field(
        description="Ground materials by name."
    )
    rocks: Rocks = Field(description="The rock ensemble.")
    analysis: Annotated[Analysis, BeforeValidator(_none_as_empty)] = Field(
        default_factory=Analysis, description="What to evaluate."
    )
    protect: Protect | None = Field(None, description="Protection position; none if absent.")
    engine: Annotated[EngineConfig, BeforeValidator(_none_as_empty)] = Field(
        default_factory=EngineConfig, description="Advanced numerical parameters."
    )
    measures: Annotated[list[dict[str, Any]], BeforeValidator(_parse_measures)] = Field(
        default_factory=list,
        description="Protective measures: mappings with a 'type' (the measure plugin's kind) "
        "and that plugin's parameters. Kept raw here; each plugin validates its own "
        "(see Project.validate_params).",
    )
    safety: Annotated[dict[str, Any], BeforeValidator(_parse_safety)] = Field(
        default_factory=lambda: {"concept": _DEFAULT_CONCEPT},
        description="Safety concept: 'concept' (a name, default spang) and that concept's "
        "parameters. Kept raw here; the concept plugin validates them.",
    )
    design: Design | None = Field(
        None, description="What the least-cost optimiser may build; none if absent."
    )

    _source: str = PrivateAttr(default="<string>")
    #: key path -> (line, node kind) of the file the project was loaded from
    _lines: dict = PrivateAttr(default_factory=dict)
    #: (measures, safety) as resolved by the plugins, for resolved_dict
    _resolved_plugins: tuple | None = PrivateAttr(default=None)

    @property
    def source(self) -> str:
        """The file the project was loaded from (``"<string>"`` for text)."""
        return self._source

    @model_validator(mode="after")
    def _check_references(self) -> "Project":
        for i, name in enumerate(self.slope.materials):
            if name not in self.materials:
                hint = _did_you_mean(name, self.materials) or (
                    f"; defined: {', '.join(map(str, self.materials))}"
                )
                raise _fail(f"undefined material {name!r}{hint}", ("slope", "materials", i))
        first, last = self.slope.x_range
        section = f"[{_fmt(first)}, {_fmt(last)}] m"
        for i, zone in enumerate(self.rocks.release):
            low, high = zone.x
            if low < first or high > last:
                shown = _fmt(low) if low == high else f"[{_fmt(low)}, {_fmt(high)}]"
                raise _fail(
                    f"release x {shown} is outside the slope section {section}",
                    ("rocks", "release", i, "x"),
                )
        for i, x in enumerate(self.analysis.stations):
            if not first <= x <= last:
                raise _fail(
                    f"station x {_fmt(x)} is outside the slope section {section}",
                    ("analysis", "stations", i),
                )
        if self.protect is not None and not first <= self.protect.x <= last:
            raise _fail(
                f"x {_fmt(self.protect.x)} is outside the slope section {section}",
                ("protect", "x"),
            )
        if self.design is not None:
            if self.protect is None:
                raise _fail(
                    "the design needs protect: (the station x of the protected zone, which the "
                    "residual rocks are counted at)",
                    ("design",),
                )
            for i, candidate in enumerate(self.design.candidates):
                low, high = candidate["x"]
                if low < first or high > last:
                    raise _fail(
                        f"station range [{_fmt(low)}, {_fmt(high)}] is outside the slope "
                        f"section {section}",
                        ("design", "candidates", i, "x"),
                    )
        return self

    def resolved_dict(self) -> dict[str, Any]:
        """The project with every default filled in, as plain JSON-serialisable data.

        Written in the project file's own syntax (sizes as a number or
        ``{kind: [a, b]}``, the release as a list of zones, ``x`` as
        ``[min, max]``, materials per segment), so that dumping it as YAML
        gives a valid project file that loads to the same resolved dict.
        Unset optional values (``protect``, the two unused of
        radius/volume/mass, ``tangential_restitution`` for spang) are ``None``.

        ``measures`` and ``safety`` are as given in the file (``safety`` with
        its ``concept`` filled in), or, on a project returned by
        :meth:`with_resolved_plugins`, the plugin-validated values passed there.

        In ``design``, the product catalogue and the cost parameters are
        written inline (``products: {...}``, ``costs: {model, file: null,
        params: {...}}``) even when the file named catalogue files, so the
        record is self-contained and its hash changes with any price or product.
        Numeric keys (heights in a price table) become strings, as in JSON.
        """
        data = self.model_dump(mode="json")
        if self.design is not None and data.get("design") is not None:
            # the catalogues inline, so the record (and its hash) holds the figures used
            design = data["design"]
            try:
                design["products"] = _json_copy(self.design.catalogue)
                design["costs"] = {
                    "model": self.design.costs.model,
                    "file": None,
                    "params": _json_copy(self.design.cost_params),
                }
            except RuntimeError:  # not loaded from a file: keep the paths as given
                pass
        if self._resolved_plugins is not None:
            measures, safety = self._resolved_plugins
            data["measures"] = copy.deepcopy(measures)
            data["safety"] = copy.deepcopy(safety)
        return data

    def resolved_hash(self) -> str:
        """sha256 (hex) of the canonical JSON of :meth:`resolved_dict` (sorted keys)."""
        text = json.dumps(
            self.resolved_dict(),
            sort_keys=True,
            separators=(",", ":"),
            ensure_ascii=False,
            allow_nan=False,
        )
        return hashlib.sha256(text.encode("utf-8")).hexdigest()

    def with_resolved_plugins(
        self, measures: Sequence[Mapping[str, Any]], safety: Mapping[str, Any]
    ) -> "Project":
        """A copy whose :meth:`resolved_dict` (and hash) hold the plugin-resolved values.

        The evaluator calls this once the plugins have validated the raw
        ``measures`` and ``safety`` sections, so the reproducibility record
        shows every plugin default too. The copy's :attr:`measures` and
        :attr:`safety` stay as given in the file (and its error locations
        those of the file).

        Parameters
        ----------
        measures
            One mapping per measure, in the order of :attr:`measures`, each
            with its ``type`` and every parameter (defaults included).
        safety
            The safety section with its ``concept`` and every parameter.

        Raises
        ------
        ValueError
            If the data is not plain JSON-like data with finite numbers, a
            measure has no string ``type`` or the safety section no string
            ``concept`` (a bug of the caller, not a user error).
        """
        resolved_measures = _plain_copy(list(measures), "measures")
        if len(resolved_measures) != len(self.measures):
            raise ValueError(
                f"expected {len(self.measures)} resolved measure(s), got {len(resolved_measures)}"
            )
        for i, item in enumerate(resolved_measures):
            if not isinstance(item, dict) or not isinstance(item.get("type"), str):
                raise ValueError(f"measures[{i}]: expected a mapping with a string 'type'")
        resolved_safety = _plain_copy(dict(safety), "safety")
        if not isinstance(resolved_safety.get("concept"), str):
            raise ValueError("safety: expected a mapping with a string 'concept'")
        resolved_safety = {"concept": resolved_safety.pop("concept"), **resolved_safety}
        project = self.model_copy()
        project._resolved_plugins = (resolved_measures, resolved_safety)
        return project

    # ----------------------------------------------------------------------------------
    # Errors located in the file, for the code that validates the plugin sections
    # ----------------------------------------------------------------------------------

    def error_at(self, path: Sequence[str | int], message: str) -> ProjectError:
        """A :class:`ProjectError` located at a key path of the project file.

        Parameters
        ----------
        path
            Key path as in the data, e.g. ``("measures", 1, "width")``.
        message
            What is wrong (one line; newlines are collapsed).

        Returns
        -------
        ProjectError
            ``file:line: measures[1].width: message``, with the line of that
            node or, if it is not in the file (a missing key), of its nearest
            existing ancestor. The line is None for a project not loaded from
            text.
        """
        return self.locator.error_at(path, message)

    @property
    def locator(self) -> "Locator":
        """Where the nodes of the project file are (see :class:`Locator`)."""
        return Locator(self._source, self._lines)

    def unknown_name(
        self, path: Sequence[str | int], name: Any, candidates: Iterable[str], what: str
    ) -> ProjectError:
        """A :class:`ProjectError` for an unknown plugin name, with "did you mean".

        Parameters
        ----------
        path
            Key path of the name, e.g. ``("measures", 2, "type")``.
        name
            The name given.
        candidates
            The names available, listed in the given order.
        what
            What the name is, e.g. ``"measure type"`` or ``"safety concept"``.

        Returns
        -------
        ProjectError
            e.g. ``p.yaml:12: measures[2].type: unknown measure type 'fense';
            did you mean 'fence'? (available: berm, ditch, fence, wall, boulder_row)``.
        """
        return self.locator.unknown_name(path, name, candidates, what)

    def validate_params(
        self,
        path: Sequence[str | int],
        model: type[BaseModel],
        data: Any,
        *,
        drop: Iterable[str] = (),
    ) -> BaseModel:
        """Validate a plugin's raw parameters with its model, errors located in the file.

        Parameters
        ----------
        path
            Key path of the parameters in the file, e.g. ``("measures", 1)``
            or ``("safety",)``.
        model
            The plugin's pydantic model (``extra="forbid"`` is expected, so
            misspelt keys are caught).
        data
            The raw mapping, e.g. ``project.measures[1]``.
        drop
            Keys consumed by the program rather than the model, e.g.
            ``("type",)`` or ``("concept",)``.

        Returns
        -------
        BaseModel
            The validated ``model`` instance.

        Raises
        ------
        ProjectError
            For the problem earliest in the file, one line at the offending
            key: unknown key (with "did you mean" against the model's
            fields), missing required key, wrong type ("expected a number"),
            out of range (with the bound), or a plugin validator's message.

        Notes
        -----
        Plugin models declare plain ``float``, ``int``, ``bool``, ``str`` and
        ``Literal`` fields, which pydantic validates leniently (``"5"`` or
        ``true`` for a float, ``.nan``). Strictness is added here, uniformly
        for every plugin, by walking the data along the model's annotations
        (nested models, lists, tuples, dicts and optional/union types
        included) before validating: booleans and strings are rejected where
        only a number is accepted, numbers and strings where only a boolean
        is, and NaN or infinity anywhere. Pydantic's strict mode is not used:
        it would also reject YAML lists for tuple fields.
        """
        return self.locator.validate_params(path, model, data, drop=drop)


def _json_copy(value: Any) -> Any:
    """Plain data as JSON has it: mapping keys become strings."""
    if isinstance(value, dict):
        return {
            (key if isinstance(key, str) else _fmt(key)): _json_copy(item)
            for key, item in value.items()
        }
    if isinstance(value, list | tuple):
        return [_json_copy(item) for item in value]
    return value


class Locator:
    """Where the nodes of some YAML data are: a file, its line map and a key prefix.

    The project file has one (:attr:`Project.locator`); so has each part of
    the design section that may come from another file: the product
    catalogue (:attr:`Design.products_locator`) and the cost model's
    parameters (:attr:`Design.costs_locator`). Key paths given to the methods
    are relative to the data's root; the prefix locates that root in its
    file (``("design", "products")`` for an inline catalogue, ``()`` for a
    catalogue file). Errors read ``file:line: key.path: message``.

    Parameters
    ----------
    source
        The file as the user named it.
    lines
        Key path -> (line, node kind), from the YAML loader.
    prefix
        Key path of the data's root in that file.
    """

    def __init__(
        self, source: str, lines: dict, prefix: Sequence[str | int] = (), *, quote: bool = True
    ) -> None:
        self.source = source
        self._lines = lines
        self.prefix = tuple(prefix)
        #: False for a file the project names: its values are not quoted in messages.
        self.quote = quote

    def __repr__(self) -> str:
        return f"Locator({self.source!r}, prefix={self.prefix!r})"

    def line(self, path: Sequence[str | int]) -> int | None:
        """Line of ``path`` (or of its nearest existing ancestor); None if unknown."""
        return _line_of(_yaml_path(self.prefix + tuple(path), self._lines), self._lines)

    def error_at(self, path: Sequence[str | int], message: str) -> ProjectError:
        """A :class:`ProjectError` at ``path`` (see :meth:`Project.error_at`)."""
        full = _yaml_path(self.prefix + tuple(path), self._lines)
        return ProjectError(
            self.source, _line_of(full, self._lines), _key_text(full, self._lines), message
        )

    def unknown_name(
        self, path: Sequence[str | int], name: Any, candidates: Iterable[str], what: str
    ) -> ProjectError:
        """An unknown name with "did you mean" (see :meth:`Project.unknown_name`)."""
        names = [str(c) for c in candidates]
        hint = _did_you_mean(name, names) if isinstance(name, str) else ""
        available = f" (available: {', '.join(names)})" if names else " (none available)"
        return self.error_at(path, f"unknown {what} {name!r}{hint}{available}")

    def validate_params(
        self,
        path: Sequence[str | int],
        model: type[BaseModel],
        data: Any,
        *,
        drop: Iterable[str] = (),
    ) -> BaseModel:
        """Validate plugin parameters at ``path`` (see :meth:`Project.validate_params`)."""
        path = tuple(path)
        if not isinstance(data, Mapping):
            raise self.error_at(path, f"expected a mapping of key: value, got {_describe(data)}")
        dropped = set(drop)
        data = {key: value for key, value in data.items() if key not in dropped}
        with contextlib.nullcontext() if self.quote else _unquoted():
            instance, problems = _check_params(model, data)
        if instance is not None:
            return instance
        # unknown keys first (a misspelt key also makes a required one "missing"),
        # then the problem earliest in the file
        located = []
        for order, (loc, message, rank) in enumerate(problems):
            full = _yaml_path(self.prefix + path + loc, self._lines)
            line = _line_of(full, self._lines)
            located.append((rank, line if line is not None else 0, order, full, message))
        *_, full, message = min(located, key=lambda item: item[:3])
        raise ProjectError(
            self.source, _line_of(full, self._lines), _key_text(full, self._lines), message
        )


def _check_params(
    model: type[BaseModel], data: Mapping[str, Any]
) -> tuple[BaseModel | None, list[tuple[tuple, str, int]]]:
    """``(instance, [])`` if ``data`` is valid for ``model``, else ``(None, problems)``."""
    problems: list[tuple[tuple, str, int]] = []  # (location, message, rank)
    _strict_problems(model, data, (), problems)
    try:
        # A plugin's validators are plugin code: what they print goes to stderr.
        with contextlib.redirect_stdout(sys.stderr):
            instance = model.model_validate(data)
    except ValidationError as exc:
        problems.extend(_param_problems(model, exc.errors()))
    except BaseException as exc:
        # pydantic turns a validator's ValueError or AssertionError into a
        # validation error; anything else is a bug in the plugin's model
        # (SystemExit too), unless it is a real Ctrl-C.
        if isinstance(exc, Interrupted):
            raise
        raise PluginError(
            f"the parameter model {model.__module__}.{model.__qualname__} failed while "
            f"validating: {type(exc).__name__}: {exc}; this is a bug in the plugin, "
            "not in the project"
        ) from exc
    else:
        if not problems:
            return instance, []
    return None, problems


def params_problem(model: type[BaseModel], data: Mapping[str, Any]) -> tuple[tuple, str] | None:
    """The first problem of plugin parameters ``data`` for ``model``, or None if valid.

    The same strict checks and one-line messages as
    :meth:`Project.validate_params`, for data that is not in a file (the
    optimiser's candidates): unknown keys first, then pydantic's order.

    Returns
    -------
    tuple of (key path, message) or None
        e.g. ``(("width",), "expected a number > 0, got -1")``.
    """
    _, problems = _check_params(model, dict(data))
    if not problems:
        return None
    loc, message, _ = min(problems, key=lambda item: item[2])
    return loc, message


# --------------------------------------------------------------------------------------
# YAML with line numbers
# --------------------------------------------------------------------------------------

_MERGE_TAG = "tag:yaml.org,2002:merge"
_MAX_NODES = 200_000  # guards against alias bombs ("billion laughs")
_MAX_MERGED = 10_000  # entries that merge keys (<<) may copy, in the whole file


class _Loader(yaml.SafeLoader):
    """SafeLoader with project-friendly scalars.

    - ``1e3`` is a number (as in YAML 1.2; PyYAML's YAML 1.1 reads it as a string);
    - dates stay strings (a name like ``2024-05-01`` is text, not a date);
    - scalar conversion errors (``!!int abc``) become YAML errors with a mark.
    """

    def construct_object(self, node: yaml.Node, deep: bool = False) -> Any:
        try:
            return super().construct_object(node, deep=deep)
        except yaml.YAMLError:
            raise
        except (ValueError, TypeError, OverflowError) as exc:
            raise yaml.constructor.ConstructorError(
                None, None, f"invalid value: {exc}", node.start_mark
            ) from exc

    def compose_node(self, parent: Any, index: Any) -> Any:
        # Counted as they are composed: a large file of small values is
        # refused after _MAX_NODES of them, not after building them all.
        self._composed = getattr(self, "_composed", 0) + 1
        if self._composed > _MAX_NODES:
            raise _TooManyValues(self.peek_event().start_mark)
        return super().compose_node(parent, index)


class _TooManyValues(yaml.YAMLError):
    """More than _MAX_NODES values in a file, found while it is read (at ``mark``)."""

    def __init__(self, mark: Any) -> None:
        super().__init__(f"more than {_MAX_NODES} values")
        self.mark = mark


#: Above this size (characters) a file is parsed by libyaml, where PyYAML has
#: it: the pure-Python scanner takes about half a second per megabyte, so a
#: file near the size limit (RF_MAX_FILE_MB) would take minutes.
_LIBYAML_FROM = 1_000_000

if getattr(yaml, "__with_libyaml__", False):
    from yaml.cyaml import CParser

    class _CLoader(CParser, _Loader):  # type: ignore[misc]
        """:class:`_Loader` with libyaml's parser and composer (same constructors, resolvers)."""

        def __init__(self, stream: str) -> None:
            CParser.__init__(self, stream)
            yaml.constructor.SafeConstructor.__init__(self)
            yaml.resolver.Resolver.__init__(self)

else:  # pragma: no cover - PyYAML without libyaml
    _CLoader = None


def _count_values(text: str) -> None:
    """Refuse a file of more than _MAX_NODES values before libyaml composes them all.

    libyaml's composer builds every node before the line map can count
    them; its events are counted here first, one at a time.
    """
    parser = CParser(text)
    try:
        count = 0
        while parser.check_event():
            event = parser.get_event()
            if isinstance(event, yaml.NodeEvent):
                count += 1
                if count > _MAX_NODES:
                    raise _TooManyValues(event.start_mark)
    finally:
        parser.dispose()


_Loader.add_constructor("tag:yaml.org,2002:timestamp", yaml.SafeLoader.construct_yaml_str)
# ``1e3`` is a float (YAML 1.2), not a string as in PyYAML's YAML 1.1: the
# loader reads it so, and the dumper (below) must quote a string spelt so.
_YAML12_FLOAT = ("tag:yaml.org,2002:float",
                 re.compile(r"^[-+]?[0-9][0-9_]*(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
                 list("-+0123456789"))
_Loader.add_implicit_resolver(*_YAML12_FLOAT)



class _Dumper(yaml.SafeDumper):
    """SafeDumper that quotes every string the project loader would read as something else.

    The dumper decides whether a string may be written plain by asking its own
    resolvers what the plain scalar would be read as; giving it the loader's
    extra resolver makes it quote a product or material named ``1e3``, which
    :class:`_Loader` would otherwise read back as the number 1000.
    """

    def represent_str(self, data: str) -> yaml.ScalarNode:
        # YAML 1.1 folds the line breaks NEL, LS and PS inside plain and single-
        # quoted scalars; only double quotes keep them (escaped).
        if any(ch in data for ch in "\x85\u2028\u2029"):
            return self.represent_scalar("tag:yaml.org,2002:str", data, style='"')
        return super().represent_str(data)


_Dumper.add_representer(str, _Dumper.represent_str)
_Dumper.add_implicit_resolver(*_YAML12_FLOAT)


def dump_yaml(data: Any) -> str:
    """``data`` as YAML that :func:`load_project_text` reads back to the same values.

    Keys keep their order; non-ASCII text is written as it is.
    """
    return yaml.dump(data, Dumper=_Dumper, sort_keys=False, allow_unicode=True)


#: key path -> (1-based line, node kind: "map" | "seq" | "scalar")
_Lines = dict[tuple, tuple[int, str]]


def _key_text(path: tuple, lines: _Lines) -> str:
    """Dotted key path as the user sees it: ``rocks.release[1].x``."""
    text = ""
    prefix: tuple = ()
    for element in path:
        parent = lines.get(prefix)
        if parent is not None and parent[1] == "seq" and isinstance(element, int):
            text += f"[{element}]"
        elif parent is None and isinstance(element, int) and not isinstance(element, bool):
            text += f"[{element}]"
        else:
            text += f".{element}" if text else str(element)
        prefix += (element,)
    return text


def _yaml_path(loc: tuple, lines: _Lines) -> tuple:
    """Drop list indices that normalisation added (a single zone or material name
    stored as a list): an int under a YAML mapping or scalar that is not one of its keys."""
    path: tuple = ()
    for element in loc:
        parent = lines.get(path)
        if (
            isinstance(element, int)
            and not isinstance(element, bool)
            and parent is not None
            and parent[1] in ("map", "scalar")
            and path + (element,) not in lines
        ):
            continue
        path += (element,)
    return path


def _line_of(path: tuple, lines: _Lines) -> int | None:
    """Line of ``path`` or of its nearest ancestor present in the file."""
    for end in range(len(path), -1, -1):
        hit = lines.get(path[:end])
        if hit is not None:
            return hit[0]
    return None


def _check_merges(root: yaml.Node, source: str) -> None:
    """Refuse merge keys (``<<``) that would expand to more than :data:`_MAX_MERGED` entries.

    PyYAML flattens a merge by copying the merged mapping's entries, merges
    within it included, once per reference: ten levels of mappings merging
    ten aliases of the level above fit in a kilobyte and expand to 10**10
    entries (a "billion laughs" made of merge keys; the loader would hang).
    The count here is what that flattening copies, with every mapping's
    flattened size computed once, so it costs time in proportion to the file.
    """
    sizes: dict[int, int] = {}  # id(mapping node) -> entries once flattened
    total = [0]

    def flattened(node: yaml.MappingNode, busy: frozenset) -> int:
        if id(node) in sizes:
            return sizes[id(node)]
        if id(node) in busy:
            raise ProjectError(source, node.start_mark.line + 1, "",
                               "recursive alias: a value contains itself")
        size = 0
        for key_node, value_node in node.value:
            if key_node.tag != _MERGE_TAG:
                size += 1
                continue
            merged = value_node.value if isinstance(value_node, yaml.SequenceNode) else [value_node]
            for item in merged:
                if isinstance(item, yaml.MappingNode):
                    n = flattened(item, busy | {id(node)})
                    size += n
                    total[0] += n
                    if total[0] > _MAX_MERGED:
                        raise ProjectError(
                            source, key_node.start_mark.line + 1, "",
                            f"merge keys (<<) would copy more than {_MAX_MERGED:,} entries "
                            "(an alias bomb?); write the values out or merge less",
                        )
        sizes[id(node)] = size
        return size

    seen: set[int] = set()
    stack = [root]
    while stack:  # every node once, aliases included, without recursion
        node = stack.pop()
        if id(node) in seen:
            continue
        seen.add(id(node))
        if isinstance(node, yaml.MappingNode):
            flattened(node, frozenset())
            for key_node, value_node in node.value:
                stack.extend((key_node, value_node))
        elif isinstance(node, yaml.SequenceNode):
            stack.extend(node.value)


def _map_lines(loader: _Loader, root: yaml.Node, source: str) -> _Lines:
    """Walk the node tree: key path -> line, rejecting duplicate and non-scalar keys."""
    _check_merges(root, source)
    lines: _Lines = {}
    budget = [_MAX_NODES]

    def error(node: yaml.Node, path: tuple, message: str) -> ProjectError:
        return ProjectError(source, node.start_mark.line + 1, _key_text(path, lines), message)

    def key_of(key_node: yaml.Node, path: tuple) -> Any:
        if not isinstance(key_node, yaml.ScalarNode):
            raise error(key_node, path, "keys must be plain names, not lists or mappings")
        key = loader.construct_object(key_node)
        try:
            hash(key)
        except TypeError:
            key = key_node.value
        return key

    def visit(node: yaml.Node, path: tuple, line: int, ancestors: frozenset) -> None:
        budget[0] -= 1
        if budget[0] < 0:
            raise error(
                node, path, f"the file has more than {_MAX_NODES} values (alias expansion?)"
            )
        if id(node) in ancestors:
            raise error(node, path, "recursive alias: a value contains itself")
        if isinstance(node, yaml.MappingNode):
            lines.setdefault(path, (line, "map"))
            inner = ancestors | {id(node)}
            seen: dict[Any, int] = {}
            merges = []
            for key_node, value_node in node.value:
                if key_node.tag == _MERGE_TAG:
                    merges.append(value_node)
                    continue
                key = key_of(key_node, path)
                key_line = key_node.start_mark.line + 1
                if key in seen:
                    raise error(
                        key_node,
                        path + (key,),
                        f"duplicate key {key!r} (first given on line {seen[key]})",
                    )
                seen[key] = key_line
                visit(value_node, path + (key,), key_line, inner)
            pending = list(merges)
            while pending:  # merged keys ("<<: *base") that the mapping does not override
                source_node = pending.pop(0)
                if id(source_node) in inner:
                    raise error(source_node, path, "recursive alias: a value contains itself")
                if isinstance(source_node, yaml.SequenceNode):
                    pending[:0] = source_node.value
                    continue
                if not isinstance(source_node, yaml.MappingNode):
                    continue  # the constructor reports the bad merge
                for key_node, value_node in source_node.value:
                    if key_node.tag == _MERGE_TAG:
                        pending.append(value_node)
                        continue
                    key = key_of(key_node, path)
                    if key not in seen:
                        seen[key] = key_node.start_mark.line + 1
                        visit(value_node, path + (key,), seen[key], inner)
        elif isinstance(node, yaml.SequenceNode):
            lines.setdefault(path, (line, "seq"))
            inner = ancestors | {id(node)}
            for i, item in enumerate(node.value):
                visit(item, path + (i,), item.start_mark.line + 1, inner)
        else:
            lines.setdefault(path, (line, "scalar"))

    visit(root, (), root.start_mark.line + 1, frozenset())
    return lines


def _parse_yaml(text: str, source: str) -> tuple[Any, _Lines]:
    try:
        if _CLoader is not None and len(text) > _LIBYAML_FROM:
            _count_values(text)
            loader = _CLoader(text)
        else:
            loader = _Loader(text)
        try:
            root = loader.get_single_node()
            if root is None:
                return None, {}
            lines = _map_lines(loader, root, source)
            data = loader.construct_document(root)
        finally:
            loader.dispose()
    except _TooManyValues as exc:
        raise ProjectError(
            source, exc.mark.line + 1 if exc.mark is not None else None, "",
            f"the file has more than {_MAX_NODES} values",
        ) from None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        problem = " ".join(p for p in (exc.context, exc.problem) if p) or "invalid YAML"
        if mark is None:
            raise ProjectError(source, None, "", f"invalid YAML: {problem}") from exc
        raise ProjectError(
            source, mark.line + 1, "", f"invalid YAML: {problem} (column {mark.column + 1})"
        ) from exc
    except yaml.reader.ReaderError as exc:  # a character YAML does not allow
        line = text.count("\n", 0, exc.position) + 1 if isinstance(text, str) else None
        raise ProjectError(
            source, line, "", f"invalid YAML: character #x{exc.character:04x} is not allowed"
        ) from exc
    except yaml.YAMLError as exc:
        raise ProjectError(source, None, "", f"invalid YAML: {exc}") from exc
    except RecursionError as exc:
        raise ProjectError(source, None, "", "the file is nested too deeply") from exc
    return data, lines


# --------------------------------------------------------------------------------------
# pydantic errors -> one line
# --------------------------------------------------------------------------------------

_BOUNDS = {
    "greater_than": (">", "gt"),
    "greater_than_equal": (">=", "ge"),
    "less_than": ("<", "lt"),
    "less_than_equal": ("<=", "le"),
}


def _message(error: dict) -> str:
    kind = error["type"]
    ctx = error.get("ctx") or {}
    value = error.get("input")
    if kind == _ERROR_TYPE:
        return str(ctx["message"])
    if kind == "missing":
        return "required key is missing"
    if kind == "extra_forbidden":
        return "unknown key"
    if kind in _BOUNDS:
        op, name = _BOUNDS[kind]
        # integer fields carry integer bounds (ge=1), float fields float bounds (gt=0.0)
        bound = ctx[name]
        noun = (
            "an integer" if isinstance(bound, int) and not isinstance(bound, bool) else "a number"
        )
        # (In a file the project names, the value is not repeated.)
        got = f", got {_describe(value)}" if _QUOTE_VALUES.get() else ""
        return f"expected {noun} {op} {_fmt(ctx[name])}{got}"
    if kind == "too_short":
        if isinstance(value, str):
            return "must not be empty"
        return f"expected at least {ctx.get('min_length')} item(s), got {ctx.get('actual_length')}"
    if kind == "too_long":
        return f"expected at most {ctx.get('max_length')} item(s), got {ctx.get('actual_length')}"
    if kind in ("dict_type", "model_type", "model_attributes_type"):
        return f"expected a mapping of key: value, got {_describe(value)}"
    if kind in ("list_type", "tuple_type"):
        return f"expected a list, got {_describe(value)}"
    return str(error.get("msg", kind))


def _to_project_error(
    exc: ValidationError, source: str, lines: _Lines, model: type[BaseModel]
) -> ProjectError:
    located = []
    for order, error in enumerate(exc.errors()):
        loc = tuple(error["loc"])
        ctx = error.get("ctx") or {}
        if error["type"] == _ERROR_TYPE:
            loc += tuple(ctx.get("subpath", ()))
        prefix = ""
        if loc and loc[-1] == "[key]":  # a bad mapping key, e.g. a material named 1
            loc = loc[:-1]
            prefix = "invalid key: "
        path = _yaml_path(loc, lines)
        line = _line_of(path, lines)
        if error["type"] == "missing":
            message = _missing_message(_navigate(model, loc)[1], loc)
        else:
            message = prefix + _message(error)
        located.append((line if line is not None else 0, order, path, line, message))
    _, _, path, line, message = min(located, key=lambda item: item[:2])
    return ProjectError(source, line, _key_text(path, lines), message)


# --------------------------------------------------------------------------------------
# Plugin parameters: strictness by annotation, and pydantic errors -> one line
# --------------------------------------------------------------------------------------

_UNION_ORIGINS = (Union, types.UnionType)
_SEQUENCE_ORIGINS = (list, tuple, set, frozenset, Sequence)
_MAPPING_ORIGINS = (dict, Mapping)


def _options(annotation: Any) -> list[Any]:
    """The alternatives of an annotation: ``Annotated`` unwrapped, unions flattened."""
    origin = typing.get_origin(annotation)
    if origin is Annotated:
        return _options(typing.get_args(annotation)[0])
    if origin in _UNION_ORIGINS:
        return [option for arg in typing.get_args(annotation) for option in _options(arg)]
    return [annotation]


def _is_model(option: Any) -> bool:
    return isinstance(option, type) and issubclass(option, BaseModel)


def _accepts(options: list[Any]) -> set[str]:
    """Which plain YAML kinds the alternatives accept: any, bool, number, str."""
    kinds = set()
    for option in options:
        origin = typing.get_origin(option)
        if option is bool:
            kinds.add("bool")
        elif option in (int, float):
            kinds.add("number")
        elif option is str:
            kinds.add("str")
        elif origin is Literal:
            for value in typing.get_args(option):
                kinds.add(
                    "bool"
                    if isinstance(value, bool)
                    else "str"
                    if isinstance(value, str)
                    else "number"
                )
        elif option is type(None) or _is_model(option):
            continue
        elif origin in _SEQUENCE_ORIGINS or origin in _MAPPING_ORIGINS:
            continue
        elif option in (list, tuple, dict, set, frozenset):
            continue
        else:  # Any, enums, custom types: left to pydantic
            kinds.add("any")
    return kinds


def _field_of(model: type[BaseModel], key: Any) -> Any:
    """The FieldInfo of ``key`` (a field name or alias) in ``model``, or None."""
    for name, info in model.model_fields.items():
        if key == name or (info.alias is not None and key == info.alias):
            return info
    return None


def _strict_problems(annotation: Any, value: Any, loc: tuple, problems: list) -> None:
    """Append ``(loc, message, 1)`` for values pydantic's lax mode would wrongly accept."""
    if isinstance(value, float) and not math.isfinite(value):
        problems.append((loc, f"must be finite, got {_fmt(value)}", 1))
        return
    options = _options(annotation)
    kinds = _accepts(options)
    if isinstance(value, bool):
        if "number" in kinds and not kinds & {"bool", "any"}:
            problems.append((loc, f"expected a number, got {_describe(value)}", 1))
        return
    if isinstance(value, str):
        if not kinds & {"str", "any"}:
            if "number" in kinds:
                problems.append((loc, f"expected a number, got {_describe(value)}", 1))
            elif "bool" in kinds:
                problems.append((loc, f"expected true or false, got {_describe(value)}", 1))
        return
    if isinstance(value, int | float):
        if "bool" in kinds and not kinds & {"number", "any", "str"}:
            problems.append((loc, f"expected true or false, got {_describe(value)}", 1))
        return
    if isinstance(value, Mapping):
        model = next((o for o in options if _is_model(o)), None)
        mapping = next((o for o in options if typing.get_origin(o) in _MAPPING_ORIGINS), None)
        for key, item in value.items():
            if model is not None:
                info = _field_of(model, key)
                inner = Any if info is None else info.annotation
            elif mapping is not None:
                inner = (typing.get_args(mapping) or (Any, Any))[-1]
            else:
                inner = Any
            _strict_problems(inner, item, loc + (key,), problems)
        return
    if isinstance(value, list | tuple):
        sequence = next((o for o in options if typing.get_origin(o) in _SEQUENCE_ORIGINS), None)
        args = typing.get_args(sequence) if sequence is not None else ()
        for i, item in enumerate(value):
            if typing.get_origin(sequence) is tuple and args and args[-1] is not Ellipsis:
                inner = args[i] if i < len(args) else Any
            else:
                inner = args[0] if args else Any
            _strict_problems(inner, item, loc + (i,), problems)


def _navigate(model: type[BaseModel], loc: tuple) -> tuple[tuple, Any, Any]:
    """Follow a pydantic error location through the model's annotations.

    Returns the location without union tags (``'float'``,
    ``"literal['a']"``), the model owning the last key (or None) and the
    annotation at the location (``Any`` where it cannot be followed).
    """
    clean: tuple = ()
    annotation: Any = model
    owner: Any = None
    for element in loc:
        options = _options(annotation)
        model_option = next((o for o in options if _is_model(o)), None)
        mapping = next((o for o in options if typing.get_origin(o) in _MAPPING_ORIGINS), None)
        sequence = next((o for o in options if typing.get_origin(o) in _SEQUENCE_ORIGINS), None)
        if isinstance(element, str) and model_option is not None:
            owner = model_option
            info = _field_of(model_option, element)
            annotation = Any if info is None else info.annotation
            clean += (element,)
        elif mapping is not None:
            annotation = (typing.get_args(mapping) or (Any, Any))[-1]
            owner = None
            clean += (element,)
        elif isinstance(element, int) and sequence is not None:
            args = typing.get_args(sequence)
            if typing.get_origin(sequence) is tuple and args and args[-1] is not Ellipsis:
                annotation = args[element] if element < len(args) else Any
            else:
                annotation = args[0] if args else Any
            owner = None
            clean += (element,)
        elif len(options) > 1 and isinstance(element, str):
            continue  # a union member's tag, e.g. ('spin', 'float')
        else:
            annotation = Any
            owner = None
            clean += (element,)
    return clean, owner, annotation


_NUMBER_ERRORS = {"float_type", "float_parsing", "int_type", "int_parsing"}


def _param_problems(model: type[BaseModel], errors: list[Any]) -> list[tuple[tuple, str, int]]:
    """Pydantic errors of a plugin model -> (location, one-line message, rank).

    The rank is 0 for an unknown key, reported before anything else, 1
    otherwise. A value that fits no member of a union (pydantic reports one
    error per member) gives one message naming every alternative.
    """
    problems = []
    done: set[tuple] = set()
    for error in errors:
        if error["loc"] and error["loc"][-1] == "[key]":  # e.g. a height key 'abc'
            key_loc, _, _ = _navigate(model, tuple(error["loc"][:-1]))
            problems.append((key_loc, "invalid key: " + _param_message(model, error)[1], 1))
            continue
        loc, owner, annotation = _navigate(model, tuple(error["loc"]))
        options = _options(annotation)
        if len(options) > 1 and len(error["loc"]) > len(loc):  # an error of a union member
            if loc in done:
                continue
            done.add(loc)
            problems.append((loc, _union_message(options, error.get("input")), 1))
            continue
        loc, message = _param_message(model, error)
        problems.append((loc, message, 0 if error["type"] == "extra_forbidden" else 1))
    return problems


def _union_message(options: list[Any], value: Any) -> str:
    """ "expected a number or one of rolling, got ..." for a value that fits no alternative."""
    wanted: list[str] = []
    choices: list[Any] = []
    for option in options:
        origin = typing.get_origin(option)
        if origin is Literal:
            choices.extend(typing.get_args(option))
            continue
        if option in (int, float):
            text = "a number"
        elif option is bool:
            text = "true or false"
        elif option is str:
            text = "a string"
        elif option is type(None):
            text = "null"
        elif _is_model(option) or origin in _MAPPING_ORIGINS or option is dict:
            text = "a mapping"
        elif origin in _SEQUENCE_ORIGINS or option in (list, tuple):
            text = "a list"
        else:
            text = getattr(option, "__name__", str(option))
        if text not in wanted:
            wanted.append(text)
    if choices:
        wanted.append("one of " + ", ".join(_fmt(c) for c in choices))
    hint = _did_you_mean(value, choices) if isinstance(value, str) and choices else ""
    return f"expected {' or '.join(wanted)}, got {_describe(value)}{hint}"


def _missing_message(owner: Any, loc: tuple) -> str:
    """"required key is missing", with what the key holds (its field's description)."""
    info = _field_of(owner, loc[-1]) if owner is not None and loc else None
    about = ""
    if info is not None and info.description:
        about = f" ({info.description.split('. ')[0].strip().rstrip('.')})"
    return f"required key is missing{about}"


def _param_message(model: type[BaseModel], error: Any) -> tuple[tuple, str]:
    kind = error["type"]
    value = error.get("input")
    loc, owner, annotation = _navigate(model, tuple(error["loc"]))
    if kind == "extra_forbidden" and loc:
        key = loc[-1]
        fields = list(owner.model_fields) if owner is not None else []
        listing = f"; expected one of {', '.join(fields)}" if fields else ""
        hint = (_did_you_mean(key, fields) if isinstance(key, str) else "") or listing
        return loc, f"unknown key {key!r}{hint}"
    if kind == "missing":
        if loc and isinstance(loc[-1], int):
            return loc[:-1], f"expected more items: item {loc[-1]} is missing"
        return loc, _missing_message(owner, loc)
    if kind == "finite_number":
        return loc, f"must be finite, got {_describe(value)}"
    if kind in _NUMBER_ERRORS or kind == "int_from_float":
        noun = "an integer" if kind.startswith("int") else "a number"
        return loc, f"expected {noun}, got {_describe(value)}"
    if kind in ("bool_type", "bool_parsing"):
        return loc, f"expected true or false, got {_describe(value)}"
    if kind in ("string_type", "string_sub_type"):
        return loc, f"expected a string, got {_describe(value)}"
    if kind == "literal_error":
        choices = [
            v
            for o in _options(annotation)
            if typing.get_origin(o) is Literal
            for v in typing.get_args(o)
        ]
        if choices:
            hint = _did_you_mean(value, choices) if isinstance(value, str) else ""
            listing = ", ".join(_fmt(c) for c in choices)
            return loc, f"expected one of {listing}, got {_describe(value)}{hint}"
        return loc, f"expected {error['ctx']['expected']}, got {_describe(value)}"
    if kind in ("value_error", "assertion_error"):
        message = str(error.get("msg", ""))
        for prefix in ("Value error, ", "Assertion failed, "):
            message = message.removeprefix(prefix)
        return loc, message
    return loc, _message(error)


# --------------------------------------------------------------------------------------
# Public entry points
# --------------------------------------------------------------------------------------


def load_project_text(
    text: str, source: str = "<string>", *, base_dir: str | os.PathLike[str] | None = None
) -> Project:
    """Parse and validate a project from YAML text.

    Parameters
    ----------
    text
        The YAML document.
    source
        Name used in error messages and stored as :attr:`Project.source`.
    base_dir
        Directory that catalogue files of ``design:``, a survey file of
        ``slope:`` and a materials library are relative to; by
        default the directory of ``source`` (the current directory for
        ``"<string>"``).

    Returns
    -------
    Project
        The validated, normalised project.

    Raises
    ------
    ProjectError
        For any problem (the one earliest in the file), as one line
        ``source:line: key.path: message``.
    """
    data, lines = _parse_yaml(text, source)
    if data is None:
        raise ProjectError(source, 1, "", "the project file is empty")
    if not isinstance(data, dict):
        with _unquoted():  # not a project file at all: its content is not repeated
            got = _describe(data)
        raise ProjectError(
            source,
            _line_of((), lines),
            "",
            f"expected a mapping of top-level keys (name, slope, materials, rocks, ...), "
            f"got {got}",
        )
    base = Path(source).parent if base_dir is None else Path(base_dir)
    # A slope from a survey file and materials from a library become inline data here.
    from ..sources import resolve_inputs

    data = resolve_inputs(data, lines, source, base)
    try:
        project = Project.model_validate(data)
    except ValidationError as exc:
        raise _to_project_error(exc, source, lines, Project) from exc
    except RecursionError as exc:
        raise ProjectError(source, None, "", "the file is nested too deeply") from exc
    project._source = source
    project._lines = lines
    if project.design is not None:
        _attach_catalogues(project, base)
    return project


def _catalogue_file(
    project: Project, relative: str, base_dir: Path, at: tuple, what: str
) -> tuple[str, Any, _Lines]:
    """Read and parse a catalogue file named in the project: (shown name, data, lines)."""
    path = Path(relative)
    if not path.is_absolute():
        path = base_dir / path
    shown = os.fspath(path)
    try:
        text = read_text(path)
    except UnicodeDecodeError as exc:
        raise project.error_at(
            at, f"cannot read the {what} {shown}: not UTF-8 text ({exc.reason})"
        ) from exc
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise project.error_at(at, f"cannot read the {what} {shown}: {reason}") from exc
    data, lines = _parse_yaml(text, shown)
    if data is None:
        raise ProjectError(shown, 1, "", f"the {what} is empty")
    return shown, data, lines


def _custom_error(exc: PydanticCustomError, source: str, lines: _Lines) -> ProjectError:
    """A ``_fail`` raised outside a model -> a ProjectError located by its subpath."""
    path = _yaml_path(tuple((exc.context or {}).get("subpath", ())), lines)
    return ProjectError(source, _line_of(path, lines), _key_text(path, lines), exc.message())


def _attach_catalogues(project: Project, base_dir: Path) -> None:
    """Read the design's catalogue files (or take the inline ones), keeping their lines."""
    design = project.design
    assert design is not None
    if isinstance(design.products, str):
        shown, data, lines = _catalogue_file(
            project, design.products, base_dir, ("design", "products"), "product catalogue"
        )
        try:
            with _unquoted():
                design._catalogue = _check_products(data)
        except PydanticCustomError as exc:
            raise _custom_error(exc, shown, lines) from None
        design._products_locator = Locator(shown, lines, quote=False)
    else:
        design._catalogue = design.products or {}
        design._products_locator = Locator(project.source, project._lines, ("design", "products"))
    if design.costs.file is not None:
        shown, data, lines = _catalogue_file(
            project, design.costs.file, base_dir, ("design", "costs", "file"), "cost file"
        )
        try:
            with _unquoted():
                if not isinstance(data, dict):
                    raise _fail(
                        f"expected a mapping of the cost model's parameters, got {_describe(data)}"
                    )
                design._cost_params = _raw(data, number_keys=True)
        except PydanticCustomError as exc:
            raise _custom_error(exc, shown, lines) from None
        design._costs_locator = Locator(shown, lines, quote=False)
    else:
        design._cost_params = design.costs.params
        design._costs_locator = Locator(
            project.source, project._lines, ("design", "costs", "params")
        )


def load_project(path: str | os.PathLike[str]) -> Project:
    """Read, parse and validate a project file.

    Parameters
    ----------
    path
        Path of the YAML project file (UTF-8).

    Returns
    -------
    Project
        The validated, normalised project; :attr:`Project.source` is ``path``.

    Raises
    ------
    ProjectError
        If the file cannot be read or is not a valid project (one line,
        ``path:line: key.path: message``).
    """
    source = os.fspath(path)
    try:
        text = read_text(source)
    except UnicodeDecodeError as exc:
        raise ProjectError(
            source, None, "", f"cannot read file: not UTF-8 text ({exc.reason})"
        ) from exc
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise ProjectError(source, None, "", f"cannot read file: {reason}") from exc
    return load_project_text(text, source, base_dir=Path(source).parent)

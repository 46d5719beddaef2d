"""Schema: the pydantic models of the project's core sections.

``slope``, ``materials``, ``rocks`` (sizes, release zones), ``analysis``,
``protect`` and ``engine``, with the limits that keep a file from asking for
more than a run can hold. The whole file is :class:`~.model.Project`.
"""

import math
from typing import Annotated, Any, Literal

from pydantic import (
    BeforeValidator,
    Field,
    PlainValidator,
    WithJsonSchema,
    field_serializer,
    model_validator,
)

from ..limits import MAX_ROCKS as _LIMIT_MAX_ROCKS
from .design_block import DesignBlockSpec
from .fields import (
    Boolean,
    Fraction,
    Integer,
    NonNegative,
    Number,
    Positive,
    SectionModel,
    String,
    as_list,
    as_number,
    choice,
    none_as_empty,
    number_pair,
)
from .messages import describe, did_you_mean, fail, fmt

# --------------------------------------------------------------------------------------
# Sections
# --------------------------------------------------------------------------------------


class Scatter(SectionModel):
    """Standard deviations of the material parameters, drawn per impact (default 0)."""

    restitution: NonNegative = Field(
        0.0, description="Standard deviation of the restitution coefficient (-)."
    )
    friction: NonNegative = Field(0.0, description="Standard deviation of the friction mu (-).")
    rolling_resistance: NonNegative = Field(
        0.0, description="Standard deviation of the rolling resistance mu_r (-)."
    )


#: Default height (m) up to which a passing rock's centre meets a stem.
#: ILLUSTRATIVE. Stems taper, and Dorren & Berger's (2006) energy law was
#: measured with impacts in the lower stem, where the diameter is near the
#: DBH: counting only impacts in the lowest 5 m errs towards less protection
#: than a stand of 20 to 30 m trees gives. Give the stand's own value where
#: rocks are seen to hit higher (scars on the stems).
DEFAULT_TREE_HEIGHT_M = 5.0
#: Most stems per hectare: 20,000 (a stem per 0.5 m^2, a young thicket).
MAX_STEMS_PER_HA = 20_000.0


class Forest(SectionModel):
    """A stand of trees on a material's ground (engine/forest.py, docs/materials.md)."""

    stems_per_ha: Annotated[Positive, Field(le=MAX_STEMS_PER_HA)] = Field(
        description="Stem density (stems per hectare of map area); 0 < N <= 20,000."
    )
    dbh_mean_cm: Annotated[Positive, Field(le=300.0)] = Field(
        description="Mean stem diameter at breast height, DBH (cm); 0 < DBH <= 300."
    )
    dbh_sd_cm: NonNegative = Field(
        0.0, description="Standard deviation of the DBH (cm), at most the mean; the DBH is "
        "drawn from a normal distribution truncated to [0, 2 x mean]."
    )
    tree_height_m: Annotated[Positive, Field(le=100.0)] = Field(
        DEFAULT_TREE_HEIGHT_M,
        description="Height above the ground (m) up to which a passing rock's centre meets "
        "a stem (default 5, ILLUSTRATIVE: the lower stem, where the diameter is near the DBH).",
    )

    @model_validator(mode="after")
    def _check_spread(self) -> "Forest":
        if self.dbh_sd_cm > self.dbh_mean_cm:
            raise fail(f"must be at most dbh_mean_cm ({self.dbh_mean_cm:g}); the DBH is "
                        "drawn within [0, 2 x mean]", ("dbh_sd_cm",))
        return self


#: Parameters of a material that may carry a published range (``ranges:``).
RANGED_KEYS = ("restitution", "tangential_restitution", "friction", "rolling_resistance",
               "velocity_scaling_k", "roughness_deg", "roughness_height_m",
               "obstacle_height_m", "drag_speed_ms")


class Material(SectionModel):
    """Ground material of slope segments: impact and contact parameters."""

    impact_model: Annotated[
        Literal["spang", "rn_rt", "rough_soft"],
        BeforeValidator(choice("spang", "rn_rt", "rough_soft")),
    ] = Field(
        "spang",
        description="Impact model: 'spang' (one restitution e), 'rn_rt' "
        "(normal Rn and tangential Rt restitution) or 'rough_soft' (spang's impact with "
        "a resistance from the block's radius against the ground's obstacles and from its "
        "softness, growing with the speed; docs/PHYSICS.md).",
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
    obstacle_height_m: Annotated[NonNegative, Field(le=25.0)] = Field(
        0.0,
        description="rough_soft: mean obstacle height h_o of the ground (m), Rockyfor3D's "
        "MOH; a block of radius r adds h_o / (h_o + r) to the resistance; 0..25.",
    )
    drag_speed_ms: Positive | None = Field(
        None,
        description="rough_soft: speed V_s (m/s) at which the ground's resistance has "
        "doubled, mu = mu_0 (1 + (v / V_s)^2); none for a resistance that does not grow.",
    )
    scatter: Annotated[Scatter, BeforeValidator(none_as_empty)] = Field(
        default_factory=Scatter, description="Standard deviations of the parameters."
    )
    forest: Forest | None = Field(
        None,
        description="Trees on this ground: stems_per_ha, dbh_mean_cm, dbh_sd_cm, "
        "tree_height_m; a rock meets stems and loses the energy they take (docs/materials.md).",
    )
    ranges: dict[str, tuple[Number, Number]] | None = Field(
        None,
        description="The range [low, high] the material's source gives for each of its "
        "numeric parameters (a library entry's published range): calibrate's prior range. "
        "The simulation uses the values, never the ranges.",
    )

    @model_validator(mode="after")
    def _check_impact_model(self) -> "Material":
        if self.impact_model == "rn_rt" and self.tangential_restitution is None:
            raise fail(
                "required for impact_model rn_rt (tangential restitution Rt, 0..1)",
                ("tangential_restitution",),
            )
        if self.impact_model != "rn_rt" and self.tangential_restitution is not None:
            raise fail(
                "only for impact_model rn_rt; remove it or set impact_model: rn_rt",
                ("tangential_restitution",),
            )
        for key, (low, high) in (self.ranges or {}).items():
            value = getattr(self, key, None) if key in RANGED_KEYS else None
            if value is None:
                raise fail(f"{key!r} is not a numeric parameter of this material (one of "
                            f"{', '.join(RANGED_KEYS)})", ("ranges", key))
            if not low <= value <= high:
                raise fail(f"the range [{low:g}, {high:g}] must hold the value {value:g}",
                            ("ranges", key))
        if self.impact_model != "rough_soft":
            # By value, not by the keys given: a study or a calibration writes
            # every default back (0 and none) before it validates again.
            for key in ("obstacle_height_m", "drag_speed_ms"):
                if getattr(self, key):
                    raise fail(
                        "only for impact_model rough_soft; remove it or set "
                        "impact_model: rough_soft", (key,),
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
#: Sections of more points than this are surveys: the engine makes the centre path
#: of a run's rock size once per run there, and rocks of varying size are rounded to
#: size classes (``rocks.size_step``) so that rocks of one class share one path. The
#: engine's ``ensemble.SHARED_PATH_VERTICES`` (the project does not load the engine;
#: tests/run/test_size_classes.py checks they agree).
SURVEY_POINTS = 256
#: Relative step of the geometric grid of radii rocks of varying size are rounded
#: to on a survey (``rocks.size_step``, default): 0.5 %, so that a radius moves by
#: at most 0.25 % and a mass by 0.751 %, far inside what any survey of block sizes
#: knows (a decision of the project, not a published value).
DEFAULT_SIZE_STEP = 0.005
#: Largest ``rocks.size_step``: 5 % (radii within 2.5 %, masses within 7.6 %).
#: ILLUSTRATIVE: a bound against a step given as a per cent (0.5 for 0.5 %).
MAX_SIZE_STEP = 0.05
#: Largest rock density (kg/m3), above any rock's (ores reach about 5,000).
MAX_DENSITY = 20_000.0
#: Smallest rock density (kg/m3), below any rock's (pumice is about 250).
MIN_DENSITY = 100.0
#: Most rocks in one run (rocks.count, --rocks, rocks=, design.fresh_rocks): a
#: streamed run of a billion rocks takes about six hours on one core. One
#: value for the project file, the command line and the API.
MAX_ROCKS = _LIMIT_MAX_ROCKS
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

#: ``design.checker_power`` by default: the chance with which a checker's check of
#: twice the deciding rocks confirms the chosen design (rockfall_design.judge.margin).
DEFAULT_CHECKER_POWER = 0.9
#: ``design.max_rocks`` by default: the rocks of the last look of every sequential
#: decision (rockfall_design.judge.sequential). A budget of rocks, not of time, so
#: that the chosen design depends on the project and the seed only, never on the
#: machine or its load. Set from benchmarks/optimise.py at seeds 11-15 on the
#: bundled design projects (docs/speed.md, "The default rock budget"): the least
#: budget tried (50,000, 100,000, 200,000, 400,000) under which design_quarry and
#: design_ditch_or_fence choose one design at every seed (at 50,000 they spread
#: by 32 % and 4 %); design_two_zones still spreads there, for its checker's
#: margin, not its budget.
DEFAULT_MAX_ROCKS = 400_000
#: Most families (multisets of candidates) the optimiser searches: at about
#: four seconds a family on 10,000 rocks, an hour's work.
MAX_FAMILIES = 1_000
#: Largest release speed (m/s) in x or y: a free fall of 500 m ends at 99 m/s.
MAX_RELEASE_SPEED = 100.0
#: Largest release spin (rad/s).
MAX_RELEASE_SPIN = 1000.0
#: Largest release clearance above the ground (m).
MAX_RELEASE_HEIGHT_M = 10_000.0


class Slope(SectionModel):
    """The 2-D slope section: a polyline of ground points and a material per segment."""

    points: Annotated[
        list[Annotated[tuple[float, float], BeforeValidator(number_pair("[x, y]"))]],
        BeforeValidator(as_list),
    ] = Field(description="Ground points [x, y] (m), x strictly increasing downslope; at least 2.")
    materials: Annotated[list[String], BeforeValidator(as_list)] = Field(
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
            raise fail(f"expected at least 2 points, got {len(self.points)}", ("points",))
        for i, point in enumerate(self.points):
            for k, value in enumerate(point):
                if abs(value) > MAX_COORDINATE_M:
                    raise fail(
                        f"{'xy'[k]} = {fmt(value)} m is farther than {MAX_COORDINATE_M:,.0f} m "
                        "from the origin: give the section in metres, x measured along it "
                        "(from its top, say) and y as height",
                        ("points", i, k),
                    )
        for i in range(1, len(self.points)):
            if self.points[i][0] <= self.points[i - 1][0]:
                raise fail(
                    f"x must increase strictly along the slope: x = {fmt(self.points[i][0])} "
                    f"follows x = {fmt(self.points[i - 1][0])}",
                    ("points", i),
                )
        if len(self.materials) != self.n_segments:
            raise fail(
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


class SizeSpec(SectionModel):
    """A rock size distribution, in the quantity given by :attr:`Rocks.size_quantity`.

    ``kind`` and the meaning of ``a`` and ``b``:

    - ``fixed``: every rock has size ``a`` (= ``b``);
    - ``uniform``: uniform on [a, b], 0 < a <= b;
    - ``normal``: mean a > 0, standard deviation b >= 0;
    - ``lognormal``: median a > 0, sigma b >= 0 of the underlying normal (log) distribution.

    In the project file this is written as a number (fixed) or as a one-key
    mapping ``{uniform: [a, b]}``, ``{normal: [mean, sd]}`` or
    ``{lognormal: [median, sigma]}``; :meth:`.Project.resolved_dict` writes it
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
            raise fail(problem)
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
            return f"expected a number > 0, got {fmt(a)}"
        if a != b:
            return "a fixed size needs a == b"
    elif kind == "uniform":
        if not 0 < a <= b:
            return f"uniform [min, max] needs 0 < min <= max, got [{fmt(a)}, {fmt(b)}]"
    elif a <= 0 or b < 0:
        first, second = _SIZE_KINDS[kind][1:-1].split(", ")
        return (
            f"{kind} {_SIZE_KINDS[kind]} needs {first} > 0 and {second} >= 0, "
            f"got [{fmt(a)}, {fmt(b)}]"
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
            raise fail(f"expected {forms}, got a mapping with {len(value)} keys")
        ((kind, params),) = value.items()
        if kind not in _SIZE_KINDS:
            hint = did_you_mean(kind, _SIZE_KINDS) if isinstance(kind, str) else ""
            raise fail(
                f"unknown distribution {kind!r}{hint}; expected {', '.join(_SIZE_KINDS)}",
                (kind,),
            )
        if not isinstance(params, list | tuple) or len(params) != 2:
            raise fail(f"expected {_SIZE_KINDS[kind]}, got {describe(params)}", (kind,))
        a = as_number(params[0], (kind, 0))
        b = as_number(params[1], (kind, 1))
        problem = _size_problem(kind, a, b)
        if problem:
            raise fail(problem, (kind,))
        return SizeSpec(kind=kind, a=a, b=b)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise fail(f"expected {forms}, got {describe(value)}")
    number = as_number(value)
    if number <= 0:
        raise fail(f"expected a number > 0, got {fmt(number)}")
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
        low, high = number_pair("[min, max]")(value)
        if low > high:
            raise fail(f"expected [min, max] with min <= max, got [{fmt(low)}, {fmt(high)}]")
        return (low, high)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise fail(f"expected a number or [min, max], got {describe(value)}")
    x = as_number(value)
    return (x, x)


def _parse_spin(value: Any) -> float | str:
    if value == "rolling" and isinstance(value, str):
        return "rolling"
    if isinstance(value, str):
        raise fail(f"expected a number (rad/s) or 'rolling', got {describe(value)}")
    spin = as_number(value)
    if abs(spin) > MAX_RELEASE_SPIN:
        raise fail(f"expected a spin within +-{MAX_RELEASE_SPIN:g} rad/s, got {fmt(spin)}")
    return spin


def _release_velocity(value: Any) -> tuple[float, float]:
    """A release ``velocity`` [vx, vy] (m/s), each component within MAX_RELEASE_SPEED."""
    velocity = number_pair("[vx, vy]")(value)
    for k, v in enumerate(velocity):
        if abs(v) > MAX_RELEASE_SPEED:
            raise fail(
                f"expected a speed within +-{MAX_RELEASE_SPEED:g} m/s, got {fmt(v)}", (k,)
            )
    return velocity


def _clearance(value: Any) -> float:
    """A release ``height``: the clearance (m) above the ground, so never negative."""
    height = as_number(value)
    if height > MAX_RELEASE_HEIGHT_M:
        raise fail(f"expected a clearance <= {MAX_RELEASE_HEIGHT_M:,.0f} m, got {fmt(height)}")
    if height < 0:
        raise fail(
            f"expected a clearance >= 0 (m), got {fmt(height)}: the release would start "
            "the rock below the ground (height is measured from the ground up; "
            "0 = resting on it)"
        )
    return height


class ReleaseZone(SectionModel):
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
            raise fail("expected at least one release zone, got an empty list")
        return list(value)
    raise fail(f"expected a release zone (mapping) or a list of zones, got {describe(value)}")


class Rocks(SectionModel):
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
    size_step: Annotated[NonNegative, Field(le=MAX_SIZE_STEP)] | None = Field(
        None,
        description="Relative step (-) of the geometric grid of radii that rocks of varying "
        "size are rounded to on a survey (a slope of more than 256 points), so that rocks "
        "of one size class share one centre path: 0.005 (0.5 %) if not given, 0 keeps "
        "every size exact; at most 0.05. No effect on a section of fewer points or on "
        "rocks of one size.",
    )
    design_block: DesignBlockSpec | None = Field(
        None,
        description="The design block of the concepts that design on one block (uni11211, "
        "onr24810): {survey: blocks.csv, percentile: 98} or {return_period_years: 100, "
        "frequency: {a, b}}; none: the simulated rocks' masses.",
    )

    @model_validator(mode="after")
    def _check_size(self) -> "Rocks":
        given = [name for name in ("radius", "volume", "mass") if getattr(self, name) is not None]
        if not given:
            raise fail(
                "give the rock size as one of radius (m), volume (m3) or mass (kg)", ("radius",)
            )
        if len(given) > 1:
            raise fail(
                f"give only one of radius, volume, mass; got {' and '.join(given)}",
                (given[1],),
            )
        spec, top, bottom = self.size, self.max_size, self.min_size
        unit = {"radius": "m", "volume": "m3", "mass": "kg"}[self.size_quantity]
        # The smallest size the distribution must be able to exceed: its fixed
        # value, its maximum, or its mean or median (a tail beyond is cut off).
        least = spec.b if spec.kind == "uniform" else spec.a
        if least > top:
            raise fail(
                f"expected sizes up to {fmt(float(f'{top:.6g}'))} {unit} (a sphere of "
                f"{MAX_RADIUS_M:g} m radius), got {fmt(least)}",
                (self.size_quantity,),
            )
        # And the size it must reach at least: its fixed value, its minimum,
        # its mean or median (a tail below is cut off).
        if spec.a < bottom:
            raise fail(
                f"expected sizes of at least {fmt(float(f'{bottom:.6g}'))} {unit} (a sphere "
                f"of {MIN_RADIUS_M:g} m radius), got {fmt(spec.a)}",
                (self.size_quantity,),
            )
        return self

    @property
    def sizes_vary(self) -> bool:
        """Whether the rocks' sizes are drawn from a distribution of more than one value."""
        spec = self.size
        if spec.kind == "fixed":
            return False
        if spec.kind == "uniform":
            return spec.b > spec.a
        return spec.b > 0.0  # normal and lognormal: a spread of 0 is one size

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


class Analysis(SectionModel):
    """What to evaluate along the section."""

    stations: Annotated[
        list[Number], Field(max_length=MAX_STATIONS), BeforeValidator(as_list)
    ] = Field(
        default_factory=list,
        description="Stations x (m) where crossings are recorded; at most 1,000.",
    )
    percentiles: Annotated[
        list[Annotated[Number, Field(gt=0.0, lt=100.0)]],
        Field(max_length=MAX_PERCENTILES),
        BeforeValidator(as_list),
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


class Protect(SectionModel):
    """Where the protection is to be placed."""

    x: Number = Field(description="Position of the protective measure along the section (m).")
    allowed_fraction: Fraction = Field(
        0.0,
        description="Fraction of the rocks allowed to reach the protected zone (-), 0..1.",
    )


class EngineConfig(SectionModel):
    """Advanced numerical parameters of the trajectory engine."""

    v_contact: Positive = Field(
        0.05, description="Below this outgoing normal speed (m/s) the rock stays in contact: "
        "a numerical floor, not a property of the ground (docs/PHYSICS.md, 'The transition "
        "to contact'); below the hop criterion it no longer moves the answer."
    )
    # The default is rockfall_design.engine.columns.CONTACT_HOP_RATIO (ILLUSTRATIVE,
    # its source there); tests/project/test_project.py checks they agree.
    contact_hop_ratio: Annotated[NonNegative, Field(le=10.0)] = Field(
        0.1, description="kappa (-): a rebound whose hop above the ground is lower than "
        "max(roughness_height_m, kappa x radius) continues rolling or sliding; "
        "ILLUSTRATIVE; 0 leaves the decision to v_contact alone; 0..10."
    )
    v_stop: Positive = Field(0.05, description="Below this speed (m/s) the rock stops.")
    max_events: Annotated[Integer, Field(ge=10, le=10_000_000)] = Field(
        10000, description="Maximum number of events (impacts, phase changes) per rock, "
        "10..10,000,000."
    )
    max_chord_deg: Annotated[Number, Field(ge=MIN_CHORD_DEG, le=30.0)] = Field(
        5.0, description="Maximum angle (deg) between trajectory chords and the arc, 0.5..30."
    )

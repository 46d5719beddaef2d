"""Model: :class:`Project`, the whole project file.

The sections tied together (materials used by the slope are defined,
release zones, stations, the protection and the design's candidates lie on
the section), the resolved dict and its hash, and errors located in the file
for the code that validates the plugin sections.
"""

import copy
import hashlib
import json
from collections.abc import Iterable, Mapping, Sequence
from typing import Annotated, Any

from pydantic import BaseModel, BeforeValidator, Field, PrivateAttr, model_validator

from ..errors import ProjectError
from .calibrate import AUTO_FIT, CalibrateSpec, auto_fit_ranges
from .design import Design
from .fields import (
    DEFAULT_CONCEPT,
    Prose,
    SectionModel,
    String,
    Title,
    none_as_empty,
    parse_measures,
    parse_safety,
    plain_copy,
)
from .locator import Locator
from .messages import did_you_mean, fail, fmt
from .schema import (
    DEFAULT_SIZE_STEP,
    SURVEY_POINTS,
    Analysis,
    EngineConfig,
    Material,
    Protect,
    Rocks,
    Slope,
)
from .study import StudySpec


class Project(SectionModel):
    """A validated, normalised project file.

    Load one with :func:`.load_project` or :func:`.load_project_text`; the file
    it came from is :attr:`source`.
    """

    name: Annotated[Title, Field(min_length=1)] = Field(description="Project name.")
    description: Annotated[Prose, BeforeValidator(lambda v: "" if v is None else v)] = Field(
        "", description="Free text."
    )
    slope: Slope = Field(description="The slope section.")
    materials: Annotated[dict[String, Material], Field(min_length=1)] = Field(
        description="Ground materials by name."
    )
    rocks: Rocks = Field(description="The rock ensemble.")
    analysis: Annotated[Analysis, BeforeValidator(none_as_empty)] = Field(
        default_factory=Analysis, description="What to evaluate."
    )
    protect: Protect | None = Field(None, description="Protection position; none if absent.")
    engine: Annotated[EngineConfig, BeforeValidator(none_as_empty)] = Field(
        default_factory=EngineConfig, description="Advanced numerical parameters."
    )
    measures: Annotated[list[dict[str, Any]], BeforeValidator(parse_measures)] = Field(
        default_factory=list,
        description="Protective measures: mappings with a 'type' (the measure plugin's kind) "
        "and that plugin's parameters. Kept raw here; each plugin validates its own "
        "(see Project.validate_params).",
    )
    safety: Annotated[dict[str, Any], BeforeValidator(parse_safety)] = Field(
        default_factory=lambda: {"concept": DEFAULT_CONCEPT},
        description="Safety concept: 'concept' (a name, default spang) and that concept's "
        "parameters. Kept raw here; the concept plugin validates them.",
    )
    design: Design | None = Field(
        None, description="What the least-cost optimiser may build; none if absent."
    )
    study: StudySpec | None = Field(
        None,
        description="A parametric study (rockfall-design study): inputs to vary by their "
        "path in this file, and the scenarios to run; none if absent.",
    )
    calibrate: CalibrateSpec | None = Field(
        None,
        description="A back-analysis (rockfall-design calibrate): observed stop positions "
        "and the inputs fitted to them, by their path in this file; none if absent.",
    )

    _source: str = PrivateAttr(default="<string>")
    #: key path -> (line, node kind) of the file the project was loaded from
    _lines: dict = PrivateAttr(default_factory=dict)
    #: (measures, safety) as resolved by the plugins, for resolved_dict
    _resolved_plugins: tuple | None = PrivateAttr(default=None)
    #: the plan resolved against the plugins (rockfall_design.judge.plan.plan_for)
    _plan: Any = PrivateAttr(default=None)

    @property
    def size_step(self) -> float:
        """The relative step of the size classes the rocks are rounded to (0: none).

        On a survey (a slope of more than :data:`~.schema.SURVEY_POINTS`
        points) with rocks of varying size, ``rocks.size_step`` or its
        default :data:`~.schema.DEFAULT_SIZE_STEP`; else 0 (every size as
        drawn). See ``run.releases.size_classes``.
        """
        if len(self.slope.points) <= SURVEY_POINTS or not self.rocks.sizes_vary:
            return 0.0
        step = self.rocks.size_step
        return DEFAULT_SIZE_STEP if step is None else float(step)

    @property
    def source(self) -> str:
        """The file the project was loaded from (``"<string>"`` for text)."""
        return self._source

    def _auto_fit(self) -> dict[str, tuple[float, float]]:
        """``calibrate.fit: auto``: each section material's calibrated parameters, its ranges."""
        try:
            return auto_fit_ranges(self.materials, self.slope.materials)
        except ValueError as exc:
            raise fail(str(exc), ("calibrate", "fit")) from None

    @model_validator(mode="after")
    def _check_references(self) -> "Project":
        for i, name in enumerate(self.slope.materials):
            if name not in self.materials:
                hint = did_you_mean(name, self.materials) or (
                    f"; defined: {', '.join(map(str, self.materials))}"
                )
                raise fail(f"undefined material {name!r}{hint}", ("slope", "materials", i))
        first, last = self.slope.x_range
        section = f"[{fmt(first)}, {fmt(last)}] m"
        for i, zone in enumerate(self.rocks.release):
            low, high = zone.x
            if low < first or high > last:
                shown = fmt(low) if low == high else f"[{fmt(low)}, {fmt(high)}]"
                raise fail(
                    f"release x {shown} is outside the slope section {section}",
                    ("rocks", "release", i, "x"),
                )
        for i, x in enumerate(self.analysis.stations):
            if not first <= x <= last:
                raise fail(
                    f"station x {fmt(x)} is outside the slope section {section}",
                    ("analysis", "stations", i),
                )
        if self.protect is not None and not first <= self.protect.x <= last:
            raise fail(
                f"x {fmt(self.protect.x)} is outside the slope section {section}",
                ("protect", "x"),
            )
        if self.calibrate is not None and AUTO_FIT in self.calibrate.fit:
            self.calibrate.fit = self._auto_fit()
            self.calibrate._auto = True
        for i, entry in enumerate(self.calibrate.observed if self.calibrate else []):
            if entry.profile is None and entry.x is not None and not first <= entry.x <= last:
                raise fail(f"station x {fmt(entry.x)} is outside the slope section {section}",
                            ("calibrate", "observed", i, "x"))
        if self.design is not None:
            if self.protect is None:
                raise fail(
                    "the design needs protect: (the station x of the protected zone, which the "
                    "residual rocks are counted at)",
                    ("design",),
                )
            if self.design.scenarios is not None and self.study is None:
                raise fail(
                    "the design's scenarios are those of a study: give a study: section "
                    "(see the README, 'Designs that hold across scenarios')",
                    ("design", "scenarios"),
                )
            for i, candidate in enumerate(self.design.candidates):
                low, high = candidate["x"]
                if low < first or high > last:
                    raise fail(
                        f"station range [{fmt(low)}, {fmt(high)}] is outside the slope "
                        f"section {section}",
                        ("design", "candidates", i, "x"),
                    )
                if low > self.protect.x:
                    # Rocks reach the zone before they reach such a measure.
                    raise fail(
                        f"station range [{fmt(low)}, {fmt(high)}] lies inside the protected "
                        f"zone (beyond protect.x = {fmt(self.protect.x)} m): a measure there "
                        "cannot keep rocks out of it; place the candidates upslope of it",
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
        if data.get("study") is None:
            # absent from files without a study, so their record and hash are as before
            data.pop("study", None)
        if data.get("calibrate") is None:
            # likewise: files without a calibration keep their record and hash
            data.pop("calibrate", None)
        elif not data["calibrate"].get("profiles"):
            # one section, as before profiles existed: the record and hash as before
            data["calibrate"].pop("profiles", None)
        if data["rocks"].get("size_step") is None:
            # the step in effect where sizes are rounded (a survey, sizes that vary);
            # elsewhere absent, so that those records and hashes are as before
            if self.size_step > 0.0:
                data["rocks"]["size_step"] = self.size_step
            else:
                data["rocks"].pop("size_step", None)
        for material in (data.get("materials") or {}).values():
            if isinstance(material, dict) and material.get("forest") is None:
                # a material without trees: absent, so the record and hash are as before
                material.pop("forest", None)
        if data["rocks"].get("design_block") is None:
            # absent unless given, so the record and hash of other projects are as before
            data["rocks"].pop("design_block", None)
        if self.design is not None and data.get("design") is not None:
            # the catalogues inline, so the record (and its hash) holds the figures used
            design = data["design"]
            if design.get("scenarios") is None:
                # absent unless given, so the record and hash of a design are as before
                design.pop("scenarios", None)
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
        resolved_measures = plain_copy(list(measures), "measures")
        if len(resolved_measures) != len(self.measures):
            raise ValueError(
                f"expected {len(self.measures)} resolved measure(s), got {len(resolved_measures)}"
            )
        for i, item in enumerate(resolved_measures):
            if not isinstance(item, dict) or not isinstance(item.get("type"), str):
                raise ValueError(f"measures[{i}]: expected a mapping with a string 'type'")
        resolved_safety = plain_copy(dict(safety), "safety")
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
            (key if isinstance(key, str) else fmt(key)): _json_copy(item)
            for key, item in value.items()
        }
    if isinstance(value, list | tuple):
        return [_json_copy(item) for item in value]
    return value

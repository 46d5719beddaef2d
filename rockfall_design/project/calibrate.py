"""Calibrate: the ``calibrate:`` section, a back-analysis of observed stop positions.

.. code-block:: yaml

    calibrate:
      observed: stops.csv            # one row per observed block: x (m); optional
                                     # volume_m3 or mass_kg
      fit:                           # paths as in study.vary, each with its range
        materials.soil.restitution: [0.05, 0.7]
        materials.soil.rolling_resistance: [0.05, 1.2]
      levels: {bench: [33, 41], floor: [41, 110]}   # optional stretches of x (m)
      rocks: 1000                    # simulated rocks per evaluation
      bootstrap: 50                  # replicates for the intervals
      confidence: 0.95
      distance: energy               # or wasserstein

``observed:`` may also be a list of observation sets, each of a ``kind``
(``stops``, ``passing_heights``, ``speeds``) from a ``file`` or inline
``values``, on the project's own section or on one of its ``profiles:``
(other project files of the same site, whose materials are the project's by
name), with a ``weight``::

    calibrate:
      profiles: {P2: site_P2.yaml}
      observed:
        - stops.csv                                   # kind stops, this section
        - {kind: passing_heights, x: 25, file: scars.csv, weight: 0.5}
        - {kind: stops, file: stops_P2.csv, profile: P2, levels: {bench: [40, 62]}}

This module checks the section's shape; whether each path names an input
of the project and each end of its range is valid there is checked against
the project itself by :mod:`rockfall_design.calibration`, as the study's
paths are (:func:`rockfall_design.studies.paths.with_values`).
"""

from collections.abc import Iterable, Mapping
from typing import Annotated, Any, Literal

from pydantic import BeforeValidator, Field, PrivateAttr, field_serializer, model_validator

from .fields import Integer, Label, Number, SectionModel, String, as_number, choice
from .messages import describe, fail, fmt

#: Most inputs fitted at once: every one costs evaluations, and a few dozen
#: observed stops cannot pin down more than a handful (the bootstrap says which
#: are not identified). 12 lets ``fit: auto`` run on a section of six spang
#: or rn_rt materials (two calibrated parameters each).
MAX_FITTED = 12
#: Most simulated rocks per evaluation (each replicate makes ~100 evaluations).
MAX_CALIBRATION_ROCKS = 200_000
#: Most bootstrap replicates.
MAX_BOOTSTRAP = 2_000


def _interval(value: Any) -> tuple[float, float]:
    """``[lo, hi]`` with lo < hi, both finite numbers."""
    if not isinstance(value, list | tuple) or len(value) != 2:
        raise fail(f"expected [lo, hi], got {describe(value)}")
    lo = as_number(value[0], (0,))
    hi = as_number(value[1], (1,))
    if not lo < hi:
        raise fail(f"expected [lo, hi] with lo < hi, got [{fmt(lo)}, {fmt(hi)}]")
    return (lo, hi)


Interval = Annotated[tuple[float, float], BeforeValidator(_interval)]


#: ``fit: auto`` until the project expands it (rockfall_design.project.model):
#: a key no input path can be, so that ``fit`` keeps one type and its errors
#: their plain locations.
AUTO_FIT = "*auto*"


def _auto_fit_marker(value: Any) -> Any:
    """``fit: auto`` as the one-entry mapping the project expands."""
    return {AUTO_FIT: (0.0, 1.0)} if value == "auto" else value


#: The kinds of observation a calibration fits, and what each is of.
OBSERVED_KINDS: dict[str, str] = {
    "stops": "the station x (m) where each block stopped",
    "passing_heights": "the height (m) of the block's centre above the ground where it "
                       "passed the station x (an impact mark on a tree, a scar)",
    "speeds": "the translational speed (m/s) of the block where it passed the station x "
              "(from video)",
}
#: Most observation sets one calibration fits (each costs nothing to run on a
#: profile already simulated, but every one is a term of the objective).
MAX_OBSERVED = 20
#: Most profiles besides the project's own section (each is simulated at
#: every evaluation).
MAX_PROFILES = 5


class ObservedSpec(SectionModel):
    """One observation set of ``calibrate.observed`` (the list form)."""

    kind: Annotated[Literal["stops", "passing_heights", "speeds"],
                    BeforeValidator(choice(*OBSERVED_KINDS))] = Field(
        "stops", description="What was observed: stops (where each block stopped), "
        "passing_heights (the centre's height above the ground at the station x) or "
        "speeds (the speed at the station x).")
    file: Annotated[String, Field(min_length=1)] | None = Field(
        None, description="CSV file of the observations (relative to the project file): "
        "stops as the single-file form (x, optionally volume_m3 or mass_kg); "
        "passing_heights a column height_m; speeds a column speed_ms.")
    values: Annotated[list[Number], Field(min_length=1)] | None = Field(
        None, description="The observations inline instead of a file: stop stations (m), "
        "heights (m) or speeds (m/s).")
    x: Number | None = Field(
        None, description="The station (m) of passing_heights and speeds, on the "
        "observation's profile.")
    profile: Label | None = Field(
        None, description="The name under calibrate.profiles of the section observed; "
        "none: the project's own.")
    weight: Annotated[Number, Field(gt=0.0, le=100.0)] = Field(
        1.0, description="Weight of this set's term in the objective (-).")
    measured: Annotated[Literal["vertical", "normal"],
                        BeforeValidator(choice("vertical", "normal"))] = Field(
        "vertical", description="passing_heights: the height measured vertically (a "
        "mark on a tree stem) or normal to the slope.")
    levels: dict[Label, Interval] | None = Field(
        None, description="stops: the levels of this set (default: calibrate.levels for "
        "the project's own section, none for a profile).")

    @model_validator(mode="after")
    def _check_entry(self) -> "ObservedSpec":
        if (self.file is None) == (self.values is None):
            raise fail("give either file: (a CSV) or values: (a list), and only one",
                        ("file",))
        passage = self.kind != "stops"
        if passage and self.x is None:
            raise fail(f"a {self.kind} observation needs x: the station (m) where the "
                        "blocks passed", ("x",))
        if not passage and self.x is not None:
            raise fail("stops have no station x: each block's stop position is the "
                        "observation", ("x",))
        if self.kind != "passing_heights" and "measured" in self.model_fields_set:
            raise fail("measured: is for passing_heights only", ("measured",))
        if passage and self.levels is not None:
            raise fail("levels: are for stops only", ("levels",))
        _check_overlaps(self.levels or {}, ("levels",))
        return self


def _observed(value: Any) -> Any:
    """The observation sets: a plain file name (alone or in the list) is a set of stops."""
    if isinstance(value, str):
        return [{"file": value}]
    if isinstance(value, list | tuple):
        return [{"file": v} if isinstance(v, str) else v for v in value]
    raise fail("expected the file of observed stops, or a list of observation sets (kind, "
                f"file or values, ...), got {describe(value)}")


def _check_overlaps(levels: dict[str, tuple[float, float]], at: tuple) -> None:
    """Levels that overlap: one line at the second of them."""
    spans = sorted((lo, hi, name) for name, (lo, hi) in levels.items())
    for (_, hi, first), (lo, _, second) in zip(spans, spans[1:], strict=False):
        if lo < hi:
            raise fail(f"level {second!r} overlaps level {first!r}: each stop belongs to "
                        "one level at most", (*at, second))


class CalibrateSpec(SectionModel):
    """The ``calibrate:`` section: observed stops, the inputs fitted and their ranges."""

    observed: Annotated[list[ObservedSpec], Field(min_length=1, max_length=MAX_OBSERVED),
                        BeforeValidator(_observed)] = Field(
        description="CSV file of the observed blocks (relative to the project file): a "
        "header row, then one row per block with x (its stop station, m) and optionally "
        "volume_m3 or mass_kg. Or a list of observation sets, each with kind (stops, "
        "passing_heights, speeds), file or values, x (the station of passing_heights and "
        "speeds), profile, weight (docs/calibration.md).",
    )
    profiles: Annotated[dict[Label, Annotated[String, Field(min_length=1)]],
                        Field(max_length=MAX_PROFILES)] = Field(
        default_factory=dict,
        description="Other sections of the same site fitted together with this one: name "
        "-> project file (relative to this one). Each profile runs its own slope, rocks "
        "and engine settings, with this project's materials by name, so that one set of "
        "ground values is fitted to every profile.",
    )
    fit: Annotated[dict[String, Interval], Field(min_length=1, max_length=MAX_FITTED),
                   BeforeValidator(_auto_fit_marker)] = Field(
        description="Input path (as in study.vary) -> [lo, hi], the range searched; or "
        "auto: for every material on the section the parameters its law calibrates "
        "(CALIBRATED), each over the material's ranges: (docs/calibration.md)."
    )
    levels: dict[Label, Interval] = Field(
        default_factory=dict,
        description="Named stretches of x [from, to) (m) whose shares of the stops are "
        "compared (and fitted) besides the stop positions.",
    )
    rocks: Annotated[Integer, Field(ge=20, le=MAX_CALIBRATION_ROCKS)] = Field(
        1000, description="Simulated rocks per evaluation of the distance (--rocks)."
    )
    bootstrap: Annotated[Integer, Field(ge=0, le=MAX_BOOTSTRAP)] = Field(
        50,
        description="Bootstrap replicates (each a refit on resampled observations with its "
        "own simulation seed) giving the intervals; 0: the best fit only.",
    )
    confidence: Annotated[float, Field(gt=0.5, lt=1.0)] = Field(
        0.95, description="Confidence of the parameters' intervals and the levels' shares."
    )
    distance: Annotated[
        Literal["energy", "wasserstein"], BeforeValidator(choice("energy", "wasserstein"))
    ] = Field(
        "energy",
        description="Distance between the observed and simulated stop positions: energy "
        "(Szekely & Rizzo) or wasserstein (Wasserstein-1).",
    )

    @model_validator(mode="after")
    def _check_levels(self) -> "CalibrateSpec":
        _check_overlaps(self.levels, ("levels",))
        used = set()
        for i, entry in enumerate(self.observed):
            if entry.profile is not None and entry.profile not in self.profiles:
                known = ", ".join(self.profiles) or "none"
                raise fail(f"no profile {entry.profile!r} under calibrate.profiles "
                            f"(given: {known})", ("observed", i, "profile"))
            used.add(entry.profile)
        if not any(e.kind == "stops" and e.profile is None for e in self.observed):
            raise fail("observed: needs a set of stops on the project's own section (kind "
                        "stops, no profile:): the other kinds and profiles add to it",
                        ("observed",))
        for name in self.profiles:
            if name not in used:
                raise fail(f"profile {name!r} has no observation: give it one under "
                            "observed: (with profile: " + name + ") or remove it",
                            ("profiles", name))
        return self

    #: Whether ``fit`` came from ``fit: auto`` (set by the project, which expands it):
    #: a calibration over profiles adds their sections' materials too.
    _auto: bool = PrivateAttr(default=False)

    @property
    def auto(self) -> bool:
        """Whether ``fit:`` was ``auto`` (expanded by the project)."""
        return self._auto

    @field_serializer("observed")
    def _dump_observed(self, entries: list[ObservedSpec]) -> Any:
        """One set of stops from a file, nothing else set, is written as the file alone.

        So a project of the single-file form keeps its resolved record (and
        its hash) as before the list form existed.
        """
        if len(entries) == 1 and entries[0].file is not None and \
                entries[0].model_fields_set <= {"file", "kind"} and entries[0].kind == "stops":
            return entries[0].file
        # Each set as it would be written: its kind, and what differs from the defaults.
        return [{"kind": e.kind, **e.model_dump(mode="json", exclude_defaults=True)}
                for e in entries]

    @property
    def entries(self) -> list[ObservedSpec]:
        """The observation sets (the single-file form is one set of stops)."""
        return list(self.observed)

    @property
    def single_file(self) -> str | None:
        """The file of the single-file form (one set of stops, nothing else), or None."""
        dumped = self._dump_observed(self.observed)
        return dumped if isinstance(dumped, str) else None


#: The parameters ``fit: auto`` calibrates, by impact law: the loss in contact
#: that a stop position depends on (rolling resistance, or R_t for the
#: lumped-mass law), and for spang and rn_rt the normal loss (restitution).
#: For rough_soft only the soil's rolling resistance mu_s: on Authume P1 the
#: restitution moves no level's share by more than 0.02 over its class's
#: range, and the obstacle height acts on a stop only through
#: mu_0 = mu_s + h_o / (h_o + r) with mu_s, so stops cannot tell the two apart
#: (fitted together, neither was identified in 10 of 10 refits); both stay at
#: their class's value, the obstacle height keeping the size effect
#: (docs/calibration.md, "Why P2 was not predicted"). Friction is left out:
#: stops hardly constrain it once rolling resistance is fitted.
CALIBRATED: dict[str, tuple[str, ...]] = {
    "spang": ("restitution", "rolling_resistance"),
    "rn_rt": ("restitution", "tangential_restitution"),
    "rough_soft": ("rolling_resistance",),
}



def auto_fit_ranges(materials: Mapping[str, Any], names: Iterable[str]
                    ) -> dict[str, tuple[float, float]]:
    """``fit: auto``: for each material named, the parameters its law calibrates, over its ranges.

    Parameters
    ----------
    materials
        Name -> material (with ``impact_model`` and ``ranges``).
    names
        The materials on the section(s) fitted, in order (repeats ignored).

    Raises
    ------
    ValueError
        A material without the range of a calibrated parameter, or more than
        :data:`MAX_FITTED` inputs (the message says what to give instead).
    """
    fit: dict[str, tuple[float, float]] = {}
    for name in dict.fromkeys(names):
        m = materials[name]
        for key in CALIBRATED[m.impact_model]:
            rng = (m.ranges or {}).get(key)
            if rng is None:
                raise ValueError(
                    f"fit: auto needs the range of materials.{name}.{key}: give the "
                    f"material ranges: {{{key}: [low, high]}} (the library's ground_ "
                    "entries carry them) or list the inputs under fit:")
            fit[f"materials.{name}.{key}"] = (float(rng[0]), float(rng[1]))
    if len(fit) > MAX_FITTED:
        raise ValueError(f"fit: auto gives {len(fit)} inputs, more than {MAX_FITTED}: list "
                         "the inputs under fit:")
    return fit


#: The choices of ``distance``, for the command line.
DISTANCES: tuple[str, ...] = ("energy", "wasserstein")

Distance = Literal["energy", "wasserstein"]

__all__ = ["AUTO_FIT", "CALIBRATED", "CalibrateSpec", "DISTANCES", "MAX_FITTED",
           "OBSERVED_KINDS", "Distance", "ObservedSpec", "auto_fit_ranges"]


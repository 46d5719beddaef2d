"""Helpers and pytest fixtures for testing a rockfall-design plugin.

In the spirit of pytest's ``pytester``: a plugin author tests a measure by
what it does to a rock, on a slope small enough to read, without writing a
project file.

>>> from rockfall_design.testing import assert_catches, assert_breaks_through
>>> net = {"type": "catch_net", "x": 40.0, "height": 2.0, "capacity_kj": 100.0}
>>> assert_catches(net, speed=5.0, height=1.0, registry=registry)           # doctest: +SKIP
>>> assert_breaks_through(net, speed=25.0, height=1.0, registry=registry)   # doctest: +SKIP

Helpers
-------
:func:`tiny_slope`
    A validated project: a 20 m incline onto a 40 m flat runout, one
    material, one rock, with the given measures.
:func:`run_one_rock`
    One rock that meets the first measure at a chosen speed (m/s) and
    passing height (m of its centre above the ground); returns what happened
    at every measure (:class:`RockRun`).
:func:`assert_outcome`, :func:`assert_catches`, :func:`assert_passes_over`,
:func:`assert_breaks_through`
    The same, as an assertion with a readable message.
:func:`make_registry`
    A fresh plugin registry with the installed plugins plus plugin modules
    or measure, safety-concept and cost-model classes registered inline.

Fixtures (registered with pytest through the ``pytest11`` entry point, so a
plugin's own tests need no conftest): ``rockfall_registry`` (the
:func:`make_registry` factory) and ``tiny_slope`` (the :func:`tiny_slope`
factory).

This module imports nothing of rockfall-design beyond the package itself
until a helper runs; nothing compiles until a rock runs (the first run
compiles the engine with numba, about 40 s once per machine; later runs use
the cache).
"""

from __future__ import annotations

import json
import math
import types
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from types import ModuleType
from typing import TYPE_CHECKING, Any

import pytest

from . import CostModel, ProtectiveMeasure, SafetyConcept, hookimpl
from .plugins import load_registry
from .project import load_project_text

if TYPE_CHECKING:  # pragma: no cover
    from .plugins import Registry
    from .project import Project

__all__ = [
    "MeasureOutcome",
    "RockRun",
    "TINY_SLOPE_POINTS",
    "assert_breaks_through",
    "assert_catches",
    "assert_outcome",
    "assert_passes_over",
    "make_registry",
    "run_one_rock",
    "tiny_slope",
]

#: Ground points [x, y] (m) of :func:`tiny_slope`: a 20 m incline (about
#: 27 degrees) onto a flat runout from x = 20 m to x = 60 m. Measures belong
#: on the runout (20 < x < 60), where :func:`run_one_rock` aims exactly.
TINY_SLOPE_POINTS: tuple[tuple[float, float], ...] = ((0.0, 10.0), (20.0, 0.0), (60.0, 0.0))

#: Gravity (m/s^2), as the engine's.
_G = 9.81

#: The outcome names of :class:`rockfall_design.Outcome`, lower case.
OUTCOMES = ("not_met", "caught", "passed_over", "broken_through", "rebounded",
            "passed_through_gap")


# ---------------------------------------------------------------------------
# registries



def _api() -> ModuleType:
    """The API module, imported on first use.

    pytest imports this module in every run of every project that has this
    package installed (its pytest11 entry point); the API imports the engine
    and numba (seconds), which a run that uses none of these fixtures must
    not pay. The one import of the package made inside a function here.
    """
    from . import api

    return api


def _plugin_for(classes: Sequence[type]) -> object:
    """A plugin object whose hooks return ``classes``, by their base class."""

    def hook(base: type) -> Any:
        chosen = [c for c in classes if isinstance(c, type) and issubclass(c, base)]
        return hookimpl(lambda: chosen)

    return types.SimpleNamespace(
        rockfall_design_measures=hook(ProtectiveMeasure),
        rockfall_design_safety_concepts=hook(SafetyConcept),
        rockfall_design_cost_models=hook(CostModel),
    )


def make_registry(*plugins: object, blocked: Iterable[str] = (),
                  installed: bool = True) -> Registry:
    """A fresh registry: the installed plugins plus ``plugins``, registered inline.

    Parameters
    ----------
    *plugins
        Plugin modules (or objects) with ``@hookimpl`` functions, and/or
        measure, safety-concept and cost-model classes (wrapped into one
        plugin named ``inline``). Modules are registered under their
        ``__name__``.
    blocked
        Entry-point or distribution names not to load.
    installed
        False: only ``plugins``, none of the installed ones (not even the
        built-ins).

    Returns
    -------
    Registry
        As :func:`rockfall_design.plugins.load_registry` builds it. A plugin
        of yours that fails to load is a failure listed in
        ``registry.failures``; this helper raises instead, so a test sees why.

    Raises
    ------
    AssertionError
        If one of ``plugins`` failed to load (the message gives the reason).
    """

    classes = [p for p in plugins if isinstance(p, type)]
    extra: list[tuple[str, object]] = []
    for i, p in enumerate(p for p in plugins if not isinstance(p, type)):
        extra.append((getattr(p, "__name__", None) or f"plugin{i}", p))
    if classes:
        extra.append(("inline", _plugin_for(classes)))
    registry = load_registry(blocked=blocked, extra_plugins=extra,
                             entry_points=None if installed else [])
    mine = {name for name, _ in extra}
    failed = [f for f in registry.failures if f.plugin in mine]
    if failed:
        raise AssertionError("; ".join(f"plugin {f.plugin!r}: {f.reason}" for f in failed))
    return registry


def _measure_dicts(measures: Any) -> tuple[list[dict[str, Any]], list[type]]:
    """(the measures as project entries, the classes of those given as objects)."""

    if measures is None:
        return [], []
    if isinstance(measures, Mapping | ProtectiveMeasure):
        measures = [measures]
    entries: list[dict[str, Any]] = []
    classes: list[type] = []
    for m in measures:
        if isinstance(m, ProtectiveMeasure):
            entries.append({"type": m.kind, **m.params.model_dump(mode="json")})
            classes.append(type(m))
        elif isinstance(m, Mapping):
            entries.append(dict(m))
        else:
            raise TypeError(f"expected a measure (a mapping with 'type', or a measure object), "
                            f"got {type(m).__name__}")
    return entries, classes


def _registry(registry: Registry | None, classes: Sequence[type]) -> Registry:
    """``registry``, or the installed plugins plus the classes of measure objects given."""
    if registry is not None:
        return registry
    if classes:
        known = _api().default_registry()
        missing = [c for c in dict.fromkeys(classes) if known.measures.get(c.kind) is not c]
        if missing:
            return make_registry(*missing)
        return known
    return _api().default_registry()


# ---------------------------------------------------------------------------
# the tiny slope


def tiny_slope(
    measures: Any = None,
    *,
    registry: Registry | None = None,
    safety: Mapping[str, Any] | None = None,
    radius: float = 0.25,
    protect_x: float | None = None,
) -> Project:
    """A small, validated project: a short incline, a flat runout, one material, one rock.

    Parameters
    ----------
    measures
        The measures: a mapping like a ``measures:`` entry (``{"type":
        "catch_net", "x": 40, ...}``), a measure object, or a list of these.
        Put them on the runout, 20 < x < 60 m.
    registry
        The plugins to validate the measures with; by default the installed
        ones plus the classes of measure objects given.
    safety
        The ``safety:`` section (default: the project default, ``spang``).
    radius
        Radius of the rock (m).
    protect_x
        Station of the protected zone (m), if any.

    Returns
    -------
    Project
        Validated as :func:`rockfall_design.load_project` validates a file:
        a bad measure raises :class:`~rockfall_design.errors.ProjectError`
        naming the key, e.g. ``<tiny_slope>:1: measures[0].height: ...``.
    """

    entries, classes = _measure_dicts(measures)
    data: dict[str, Any] = {
        "name": "tiny slope",
        "description": "rockfall_design.testing: a 20 m incline onto a 40 m flat runout",
        "slope": {"points": [list(p) for p in TINY_SLOPE_POINTS], "materials": "ground"},
        "materials": {"ground": {"restitution": 0.35, "friction": 0.6,
                                 "rolling_resistance": 0.3}},
        "rocks": {"count": 1, "seed": 0, "radius": radius,
                  "release": {"x": 1.0, "height": 0.0, "velocity": [1.0, 0.0]}},
        "measures": entries,
    }
    if safety is not None:
        data["safety"] = dict(safety)
    if protect_x is not None:
        data["protect"] = {"x": protect_x}
    # JSON is YAML: one line, so every message points at line 1.
    project = load_project_text(json.dumps(data), "<tiny_slope>")
    _api().validate_project(project, _registry(registry, classes))
    return project


# ---------------------------------------------------------------------------
# one rock


@dataclass(frozen=True)
class MeasureOutcome:
    """What one rock did at one measure (its first meeting).

    Attributes
    ----------
    index : int
        Position of the measure in ``measures:``.
    kind : str
        The measure's ``type``.
    outcome : str
        ``not_met``, ``caught``, ``passed_over``, ``broken_through``,
        ``rebounded`` or ``passed_through_gap``.
    held : bool
        Whether the measure counts as having stopped the rock (a rebound
        that stays upslope counts; for a ditch or berm: came to rest in it).
    passing_height_m : float
        Barriers: height of the rock's centre above the ground at the
        station (m); NaN if not met or for a profile edit.
    velocity_ms : float
        Barriers: speed there (m/s); NaN otherwise.
    energy_kj : float
        Barriers: total kinetic energy there (kJ); NaN otherwise.
    """

    index: int
    kind: str
    outcome: str
    held: bool
    passing_height_m: float
    velocity_ms: float
    energy_kj: float


@dataclass(frozen=True)
class RockRun:
    """One rock's run against the measures.

    Attributes
    ----------
    measures : list of MeasureOutcome
        One per measure, in project order.
    end : str
        How the path ended (``stopped``, ``caught``, ``exit_downslope``, ...).
    end_x_m : float
        Where its centre was then (m).
    release : dict
        The release the helper chose: ``x`` (m), ``height`` (clearance, m),
        ``velocity`` ([vx, vy], m/s), ``spin``.
    """

    measures: list[MeasureOutcome]
    end: str
    end_x_m: float
    release: dict[str, Any]

    @property
    def outcome(self) -> str:
        """The outcome at the only measure (ValueError with several)."""
        if len(self.measures) != 1:
            raise ValueError(f"{len(self.measures)} measures: use .measures[i].outcome")
        return self.measures[0].outcome

    @property
    def outcomes(self) -> list[str]:
        """The outcome at each measure, in project order."""
        return [m.outcome for m in self.measures]

    def describe(self) -> str:
        """One line per measure, for assertion messages."""
        lines = []
        for m in self.measures:
            met = (f" at {m.passing_height_m:.3g} m, {m.velocity_ms:.3g} m/s, "
                   f"{m.energy_kj:.4g} kJ" if math.isfinite(m.velocity_ms) else "")
            lines.append(f"measures[{m.index}] ({m.kind}): {m.outcome}{met}")
        lines.append(f"the rock ended {self.end} at x = {self.end_x_m:.4g} m")
        return "; ".join(lines)


def _ground(points: Sequence[Sequence[float]], x: float) -> tuple[float, float]:
    """(ground y (m), cos of the ground's slope) at ``x``."""
    xs = [float(p[0]) for p in points]
    ys = [float(p[1]) for p in points]
    for i in range(len(xs) - 1):
        if xs[i] <= x <= xs[i + 1] or i == len(xs) - 2:
            dx, dy = xs[i + 1] - xs[i], ys[i + 1] - ys[i]
            y = ys[i] + dy * (x - xs[i]) / dx
            return y, dx / math.hypot(dx, dy)
    raise ValueError("a section needs two points")  # pragma: no cover


def _release(project: Project, station: float, speed: float, height: float, radius: float,
             lead: float) -> dict[str, Any]:
    """A release from which the rock meets ``station`` at ``speed``, its centre ``height`` up.

    The rock flies on a parabola whose apex is at the station: it arrives
    moving horizontally at exactly ``speed``, ``height`` above the ground
    there. It is released ``lead`` m upslope, or closer where a release
    that far would start it below the ground. A rock asked for at its own
    radius (on the ground) is released rolling, ``lead`` m upslope, and
    arrives a little slower.
    """
    points = project.slope.points
    y_station, _ = _ground(points, station)
    on_ground = height <= radius * (1 + 1e-9)
    d = lead
    for _ in range(60):
        x0 = station - d
        y0_ground, cos0 = _ground(points, x0)
        centre_path = y0_ground + radius / cos0
        if on_ground:
            slope_dy = (y_station - y0_ground) / d
            norm = math.hypot(1.0, slope_dy)
            return {"x": x0, "height": 0.0, "velocity": [speed / norm, speed * slope_dy / norm],
                    "spin": "rolling"}
        t = d / speed
        clearance = y_station + height - 0.5 * _G * t * t - centre_path
        if clearance >= 0.0:
            return {"x": x0, "height": clearance, "velocity": [speed, _G * t], "spin": 0.0}
        d *= 0.5
    raise ValueError(f"cannot aim a rock of radius {radius:g} m at {height:g} m above the "
                     f"ground at x = {station:g} m")


def run_one_rock(
    target: Any,
    *,
    speed: float,
    height: float,
    radius: float = 0.25,
    density: float = 2650.0,
    lead: float = 1.0,
    at: float | None = None,
    registry: Registry | None = None,
    seed: int = 0,
) -> RockRun:
    """Run one rock against measures and say what happened at each.

    Parameters
    ----------
    target
        A project (e.g. from :func:`tiny_slope`), or measures as
        :func:`tiny_slope` takes them (then run on the tiny slope).
    speed
        Speed (m/s) at which the rock meets the first measure, > 0.
    height
        Passing height (m) of the rock's centre above the ground there;
        ``height <= radius`` sends the rock rolling along the ground.
    radius, density
        Of the rock (m, kg/m^3): mass = density * 4/3 pi radius^3.
    lead
        How far upslope of the station the rock is released (m), at most.
    at
        The station (m) to aim at; by default the smallest ``x`` of the
        measures (the first a rock running downslope meets).
    registry
        The plugins; by default the installed ones plus the classes of
        measure objects given.
    seed
        Random seed (the material's scatter and roughness, a boulder row's
        gaps).

    Returns
    -------
    RockRun
        ``.outcome`` (one measure) or ``.measures``, with the passing
        height, speed and energy the engine recorded.

    Notes
    -----
    The rock flies on a parabola whose apex is at the station, so it
    arrives moving horizontally at exactly ``speed`` and ``height``, with no
    spin: its energy there is ``0.5 * mass * speed**2``. On ground other
    than the tiny slope's flat runout, and for a rolling rock, the values
    are near those asked for; the run reports the engine's own.
    """
    if not speed > 0:
        raise ValueError(f"speed must be > 0 m/s, got {speed!r}")
    entries, classes = ([], []) if _is_project(target) else _measure_dicts(target)
    reg = _registry(registry, classes)
    project = target if _is_project(target) else tiny_slope(entries, registry=reg,
                                                             radius=radius)
    if at is None:
        xs = [float(m["x"]) for m in project.measures if "x" in m]
        if not xs:
            raise ValueError("no measure to aim at: give measures, or the station with at=")
        at = min(xs)
    release = _release(project, float(at), float(speed), float(height), radius, lead)
    rocks = type(project.rocks).model_validate(
        {"count": 1, "seed": seed, "density": density, "radius": radius, "release": release})
    project = project.model_copy(update={"rocks": rocks})


    result = _api().check(project, rocks=1, seed=seed, registry=reg, trajectories=0)
    return _rock_run(result, release)


def _rock_run(result: Any, release: Mapping[str, Any]) -> RockRun:
    """The one rock of a ``check`` as a :class:`RockRun`: what each measure did to it."""
    table = result.outcomes
    held_by = int(result.rocks["caught_by_measure"].iloc[0])
    rock = result.rocks.iloc[0]
    measures = [
        MeasureOutcome(
            index=int(row.measure),
            kind=str(row.type),
            outcome=str(row.outcome),
            held=int(row.measure) == held_by,
            passing_height_m=float(row.passing_height_m),
            velocity_ms=float(row.velocity_ms),
            energy_kj=float(row.energy_kj),
        )
        for row in table.itertuples()
    ]
    return RockRun(measures=measures, end=str(rock["end"]), end_x_m=float(rock["end_x_m"]),
                   release=release)


def _is_project(target: Any) -> bool:
    return hasattr(target, "slope") and hasattr(target, "rocks") and hasattr(target, "measures")


# ---------------------------------------------------------------------------
# assertions


def assert_outcome(target: Any, expected: str, *, measure: int = 0, speed: float,
                   height: float, **kwargs: Any) -> RockRun:
    """Assert that one rock at ``speed`` and ``height`` has outcome ``expected`` at a measure.

    Parameters
    ----------
    target
        As :func:`run_one_rock`.
    expected
        One of ``caught``, ``passed_over``, ``broken_through``,
        ``rebounded``, ``passed_through_gap``, ``not_met``.
    measure
        Index of the measure in ``measures:`` (default: the first).
    speed, height, **kwargs
        As :func:`run_one_rock`.

    Returns
    -------
    RockRun
        For further checks (``run.measures[0].energy_kj``, ...).

    Raises
    ------
    AssertionError
        With what happened at every measure.
    """
    if expected not in OUTCOMES:
        raise ValueError(f"unknown outcome {expected!r}; one of {', '.join(OUTCOMES)}")
    run = run_one_rock(target, speed=speed, height=height, **kwargs)
    got = run.measures[measure].outcome
    if got != expected:
        raise AssertionError(
            f"expected {expected} at measures[{measure}] for a rock at {speed:g} m/s, "
            f"{height:g} m, got {got}: {run.describe()}")
    return run


def assert_catches(target: Any, *, speed: float, height: float, **kwargs: Any) -> RockRun:
    """Assert that the measure catches one rock at ``speed`` (m/s) and ``height`` (m)."""
    return assert_outcome(target, "caught", speed=speed, height=height, **kwargs)


def assert_passes_over(target: Any, *, speed: float, height: float, **kwargs: Any) -> RockRun:
    """Assert that one rock at ``speed`` (m/s) and ``height`` (m) passes over the measure."""
    return assert_outcome(target, "passed_over", speed=speed, height=height, **kwargs)


def assert_breaks_through(target: Any, *, speed: float, height: float,
                          **kwargs: Any) -> RockRun:
    """Assert that one rock at ``speed`` (m/s) and ``height`` (m) breaks through the measure."""
    return assert_outcome(target, "broken_through", speed=speed, height=height, **kwargs)


# ---------------------------------------------------------------------------
# pytest fixtures (the module is a pytest plugin through the pytest11 entry point)


@pytest.fixture(name="rockfall_registry")
def _rockfall_registry_fixture() -> Any:
    """Factory of fresh registries: ``rockfall_registry(my_plugin_module_or_classes)``.

    See :func:`make_registry`.
    """
    return make_registry


@pytest.fixture(name="tiny_slope")
def _tiny_slope_fixture() -> Any:
    """Factory of small projects: ``tiny_slope(measures, registry=...)``.

    See :func:`tiny_slope`.
    """
    return tiny_slope

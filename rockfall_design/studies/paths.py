"""Paths: set inputs of a project by their path in the project file.

A path names an input as the project file writes it: keys joined by dots,
list items as ``[i]`` or ``.i``::

    materials.talus.restitution          a material's parameter
    rocks.volume.lognormal.0             the median of a lognormal size
    rocks.release[0].x                   the x of the first release zone
    release[0].x                         the same (``release`` is short for
                                         ``rocks.release``, see ALIASES)

The path refers to the project as it is resolved (every default filled in,
short forms written out: the release is always a list of zones, a zone's
``x`` always ``[min, max]``, ``slope.materials`` one name per segment), so
``rocks.release[0]`` exists whether the file wrote one zone or a list.

:func:`with_values` sets the values in that data and validates the whole
project again, so every rule of the schema applies to a varied value. Keys
of names (a material called ``a.b``) cannot contain dots or brackets here.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from pydantic import ValidationError

from ..errors import ProjectError
from ..judge.plan import validate_plugin_sections
from ..project import Project
from ..project.loading import attach_catalogues
from ..project.messages import describe, did_you_mean, to_project_error
from ..project.study import Range

if TYPE_CHECKING:  # pragma: no cover
    from ..project import Project

__all__ = ["ALIASES", "NOT_VARIED", "PathError", "check_study", "parse_path", "set_input",
           "with_values"]

# one key: anything but dots and brackets, then any number of [i]
_SEGMENT = re.compile(r"([^.\[\]]+)((?:\[\d+\])*)")
_INDEX = re.compile(r"\[(\d+)\]")

#: Sections whose entries are kept raw until their plugins are loaded: a key
#: not written in the file is left for the plugin to accept or refuse.
_PLUGIN_SECTIONS = ("measures", "safety")


class PathError(ValueError):
    """A path that is not well formed or does not name an input of the project."""


def parse_path(path: str) -> tuple[str | int, ...]:
    """Split a path into keys (str) and list indices (int).

    Parameters
    ----------
    path
        E.g. ``"rocks.release[0].x"`` or ``"rocks.volume.lognormal.0"``.

    Returns
    -------
    tuple
        E.g. ``("rocks", "release", 0, "x")``. A key of digits only becomes
        an int (an index into a list, or a key spelt so, see :func:`_step`).

    Raises
    ------
    PathError
        If the path is empty or has an empty key (``a..b``) or a stray bracket.
    """
    if not isinstance(path, str) or not path.strip():
        raise PathError("expected a path such as materials.talus.restitution")
    keys: list[str | int] = []
    for part in path.split("."):
        match = _SEGMENT.fullmatch(part)
        if match is None:
            raise PathError(
                f"{path!r} is not a path: expected keys joined by dots, list items as [i] "
                "(e.g. rocks.release[0].x)"
            )
        name, indices = match.groups()
        keys.append(int(name) if name.isdigit() else name)
        keys.extend(int(i) for i in _INDEX.findall(indices))
    return tuple(keys)


def shown(keys: tuple) -> str:
    """Keys back as a path: ``rocks.release[0].x``."""
    text = ""
    for key in keys:
        text += f"[{key}]" if isinstance(key, int) else (f".{key}" if text else str(key))
    return text


#: Short paths the README and users write: first key -> the keys it stands for.
ALIASES: dict[str, tuple[str, ...]] = {"release": ("rocks", "release")}


def _absolute(keys: tuple, data: Mapping[str, Any]) -> tuple:
    """The keys from the top of the file: ``release[0].x`` is ``rocks.release[0].x``."""
    first = keys[0]
    if first in data:
        return keys
    if first in ALIASES:
        return (*ALIASES[first], *keys[1:])
    sections = [k for k in data if isinstance(k, str)]
    hint = did_you_mean(str(first), sections) or f"; the sections are {', '.join(sections)}"
    raise PathError(f"no section {first!r} in the project{hint}")


def _step(container: Any, key: str | int, done: tuple) -> Any:
    """The key of ``container`` that ``key`` names (an index of a list, a key of a mapping)."""
    where = shown(done)
    if isinstance(container, list):
        if not isinstance(key, int):
            raise PathError(f"{where} is a list: expected an index such as {where}[0], got {key!r}")
        if key >= len(container):
            raise PathError(
                f"{where} has {len(container)} item(s): index {key} is out of range"
            )
        return key
    if isinstance(container, Mapping):
        if key in container:
            return key
        if isinstance(key, int) and str(key) in container:  # a key written as digits
            return str(key)
        if done and done[0] in _PLUGIN_SECTIONS:
            return str(key) if isinstance(key, int) else key  # the plugin validates it
        keys = [k for k in container if isinstance(k, str)]
        hint = did_you_mean(str(key), keys) or (
            f"; expected one of {', '.join(keys)}" if keys else ""
        )
        raise PathError(f"no key {key!r} in {where}{hint}")
    raise PathError(f"{where} is a single value ({describe(container)}), not a mapping or list")


#: Inputs a study may not vary, by their keys from the top of the file, and why.
#: ``name`` and ``description`` cannot change a scenario's result (its
#: "effect" would be noise); the study sets each scenario's seed itself (see
#: study.seeds) and runs every scenario with the run's rock count (--rocks),
#: so a varied seed or count would be recorded but not applied.
NOT_VARIED: dict[tuple[str, ...], str] = {
    ("name",): "the project's name cannot change a scenario's result",
    ("description",): "the project's description cannot change a scenario's result",
    ("rocks", "seed"): "the study sets each scenario's seed itself (study.seeds: "
    "independent or common; the run's seed is --seed or rocks.seed)",
    ("rocks", "count"): "every scenario runs the run's number of rocks (--rocks or "
    "rocks.count); to compare rock counts, run the study once per count",
}


def _refused(path: str, data: Mapping[str, Any]) -> str | None:
    """Why ``path`` may not be varied by a study, or None if it may."""
    keys = _absolute(parse_path(path), data)
    return NOT_VARIED.get(tuple(str(k) for k in keys))


def _set(data: dict[str, Any], path: str, value: Any) -> None:
    """Set the input at ``path`` in the resolved project data ``data`` (in place)."""
    keys = _absolute(parse_path(path), data)
    container: Any = data
    for depth, key in enumerate(keys):
        step = _step(container, key, keys[:depth])
        if depth == len(keys) - 1:
            container[step] = value
        else:
            container = container[step]


def set_input(data: dict[str, Any], path: str, value: Any) -> None:
    """Set the input at ``path`` in resolved project data ``data`` (in place).

    Raises
    ------
    PathError
        If the path names no input of ``data``.
    """
    _set(data, path, value)


def _validate(project: Project, data: dict[str, Any]) -> Project:
    """``data`` as a validated Project that reports later problems in ``project``'s file."""
    new = Project.model_validate(data)
    new._source = project._source
    new._lines = project._lines  # plugin problems are then located in the same file
    if new.design is not None:
        # the catalogues are inline in the resolved data: nothing is read again
        attach_catalogues(new, ".")
    return new


def _problem(exc: ValidationError) -> str:
    """A validation error of resolved data as ``key.path: message``."""
    err = to_project_error(exc, "", {}, Project)
    return f"{err.key}: {err.message}" if err.key else err.message


def scenario_base(project: Project) -> dict[str, Any]:
    """The data every scenario of ``project`` starts from (:func:`with_values`'s ``base``).

    The project's resolved data without its ``study:`` section and without
    ``design.scenarios``: one scenario has neither.
    """
    base = project.resolved_dict()
    base.pop("study", None)
    if isinstance(base.get("design"), dict):
        # design.scenarios names the study's scenarios: one scenario has none
        base["design"].pop("scenarios", None)
    return base


def with_values(project: Project, values: Mapping[str, Any], *,
                base: Mapping[str, Any] | None = None) -> Project:
    """A copy of ``project`` with the inputs at the given paths set, validated again.

    Parameters
    ----------
    project
        A validated project (from :func:`~rockfall_design.project.load_project`).
    values
        Path -> value, e.g. ``{"materials.talus.restitution": 0.3,
        "release[0].x": 5.0}``; values in the file's own syntax (a size may
        be ``{lognormal: [1.0, 0.4]}``). Values are copied, never shared.
    base
        :func:`scenario_base` of ``project``, if already at hand (a study
        sets each scenario's values on the same base; it is copied, never
        changed).

    Returns
    -------
    Project
        A new, fully validated project (the core sections; the plugin
        sections are checked when a command resolves its plugins). It has no
        ``study:`` section (it is one scenario of the study) and reports
        problems at the lines of ``project``'s file.

    Raises
    ------
    ProjectError
        If a path names no input, or a value is not valid there (exit code
        of bad input). The error is located at ``study.vary.<path>`` of the
        project file, names the value and says what is wrong, e.g.
        ``p.yaml:31: study.vary.materials.talus.restitution: value 1.2:
        materials.talus.restitution: expected a number <= 1``.
    """
    import copy

    if base is None:
        base = scenario_base(project)

    def located(path: str, message: str) -> ProjectError:
        return project.error_at(("study", "vary", path), message)

    data = copy.deepcopy(base)
    for path, value in values.items():
        try:
            why = _refused(path, data)
            if why is not None:
                raise located(path, f"cannot be varied: {why}")
            _set(data, path, copy.deepcopy(value))
        except PathError as exc:
            raise located(path, f"not an input of the project: {exc}") from None
    try:
        return _validate(project, data)
    except ValidationError as exc:
        combined = _problem(exc)
    if not values:  # the base itself is refused (say, sizes set in it): the whole project
        raise project.error_at((), combined)
    # Which value is to blame: each on its own, in the order given.
    for path, value in values.items():
        alone = copy.deepcopy(base)
        _set(alone, path, copy.deepcopy(value))
        try:
            Project.model_validate(alone)
        except ValidationError as exc:
            raise located(path, f"value {describe(value)}: {_problem(exc)}") from None
    given = ", ".join(f"{path} = {describe(value)}" for path, value in values.items())
    first = next(iter(values))
    raise located(first, f"the values {given} do not fit together: {combined}")


def check_study(project: Project, registry: Any = None) -> None:
    """Check every path and value of the project's ``study:`` section against the project.

    Each value of a list, and each end of a range (and each level of a grid
    range), is set alone with :func:`with_values`: an unknown path or a value
    that the schema refuses is reported before anything runs, by every
    command (as the rest of the file is). With the plugins (``registry``),
    the plugin sections of each such project are checked too (a fence's
    height varied to -1). Values that are valid alone but not together are
    reported when the study builds its scenarios.

    Raises
    ------
    ProjectError
        At ``study.vary.<path>``, as :func:`with_values` raises it.
    """
    spec = project.study
    if spec is None:
        return
    base = scenario_base(project)
    for path, levels in spec.vary.items():
        if isinstance(levels, Range):
            tried = list(levels.range)
            if levels.levels is not None and not spec.sampled:
                tried = levels.grid_values()
        else:
            tried = list(levels)
        for value in tried:
            varied = with_values(project, {path: value}, base=base)
            if registry is None:
                continue
            try:
                validate_plugin_sections(varied, registry)
            except ProjectError as exc:
                where = f"{exc.key}: " if exc.key else ""
                raise project.error_at(
                    ("study", "vary", path), f"value {describe(value)}: {where}{exc.message}"
                ) from None


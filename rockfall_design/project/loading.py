"""Loading: the entry points that read a project or a corridor file.

:func:`load_project` / :func:`load_project_text` read a project file (with
:mod:`.yaml_file`: line numbers and limits), validate it and attach the
catalogue files it names.
"""

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pydantic import ValidationError
from pydantic_core import PydanticCustomError

from ..errors import ProjectError
from .corridor import Corridor, CorridorSection, section_seed, split_sections
from .design import check_products
from .fields import lines_of_text, plugin_data
from .inputs import read_named_text, read_text, strip_controls
from .locator import Locator
from .messages import (
    Lines,
    describe,
    fail,
    key_text,
    line_of,
    to_project_error,
    unquoted,
    yaml_path,
)
from .model import Project
from .sources import resolve_inputs
from .terrain_corridor import terrain_corridor
from .yaml_file import parse_yaml

if TYPE_CHECKING:  # pragma: no cover
    from .corridor import Corridor





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
    data, lines = _parse_top(text, source)
    for key in ("sections", "corridor"):
        if key not in data:
            continue
        raise ProjectError(
            source, line_of((key,), lines), key,
            "this file lists sections (a corridor): load it with load_corridor; simulate, "
            "check, optimise and study run every section",
        )
    base = Path(source).parent if base_dir is None else Path(base_dir)
    return _validated(data, lines, source, base)


def _parse_top(text: str, source: str) -> tuple[dict, Lines]:
    """The YAML of a project file: a mapping of its top-level keys, and its line map."""
    data, lines = parse_yaml(text, source)
    if data is None:
        raise ProjectError(source, 1, "", "the project file is empty")
    if not isinstance(data, dict):
        with unquoted():  # not a project file at all: its content is not repeated
            got = describe(data)
        raise ProjectError(
            source,
            line_of((), lines),
            "",
            f"expected a mapping of top-level keys (name, slope, materials, rocks, ...), "
            f"got {got}",
        )
    return data, lines


def _validated(data: dict, lines: Lines, source: str, base: Path) -> Project:
    """A project from parsed data and its line map: files resolved, validated, catalogues."""
    # A slope from a survey file and materials from a library become inline data here.
    data = resolve_inputs(data, lines, source, base)
    try:
        project = Project.model_validate(data)
    except ValidationError as exc:
        raise to_project_error(exc, source, lines, Project) from exc
    except RecursionError as exc:
        raise ProjectError(source, None, "", "the file is nested too deeply") from exc
    project._source = source
    project._lines = lines
    if project.design is not None:
        attach_catalogues(project, base)
    return project


def _catalogue_file(
    project: Project, relative: str, base_dir: Path, at: tuple, what: str
) -> tuple[str, Any, Lines]:
    """Read and parse a catalogue file named in the project: (shown name, data, lines)."""
    path = Path(relative)
    if not path.is_absolute():
        path = base_dir / path
    shown = os.fspath(path)
    try:
        text = read_named_text(path, what)
    except ValueError as exc:
        raise project.error_at(at, str(exc)) from None
    data, lines = parse_yaml(text, shown)
    if data is None:
        raise ProjectError(shown, 1, "", f"the {what} is empty")
    return shown, data, lines


def _custom_error(exc: PydanticCustomError, source: str, lines: Lines) -> ProjectError:
    """A ``fail`` raised outside a model -> a ProjectError located by its subpath."""
    path = yaml_path(tuple((exc.context or {}).get("subpath", ())), lines)
    return ProjectError(source, line_of(path, lines), key_text(path, lines), exc.message())


def attach_catalogues(project: Project, base_dir: Path) -> None:
    """Read the design's catalogue files (or take the inline ones), keeping their lines."""
    design = project.design
    assert design is not None
    if isinstance(design.products, str):
        shown, data, lines = _catalogue_file(
            project, design.products, base_dir, ("design", "products"), "product catalogue"
        )
        try:
            with unquoted():
                design._catalogue = check_products(data)
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
            with unquoted():
                if not isinstance(data, dict):
                    raise fail(
                        f"expected a mapping of the cost model's parameters, got {describe(data)}"
                    )
                lines_of_text(data)  # a currency or product name of one line, no control characters
                design._cost_params = plugin_data(data, number_keys=True)
        except PydanticCustomError as exc:
            raise _custom_error(exc, shown, lines) from None
        design._costs_locator = Locator(shown, lines, quote=False)
    else:
        design._cost_params = design.costs.params
        design._costs_locator = Locator(
            project.source, project._lines, ("design", "costs", "params")
        )


def load_corridor_text(
    text: str, source: str = "<string>", *, base_dir: str | os.PathLike[str] | None = None
) -> "Corridor | Project":
    """Parse and validate a project file that may list ``sections:`` (a corridor).

    Parameters are those of :func:`load_project_text`.

    Returns
    -------
    Corridor or Project
        A :class:`~.corridor.Corridor` (one complete :class:`Project` per
        section, see :mod:`.corridor`) for a file with ``sections:``;
        otherwise the :class:`Project`, exactly as :func:`load_project_text`
        gives it.

    Raises
    ------
    ProjectError
        For the first problem, located in the file (``sections[1].slope...``).
    """
    data, lines = _parse_top(text, source)
    base = Path(source).parent if base_dir is None else Path(base_dir)
    where = None
    if "corridor" in data:
        # Sections along a road, cut from a DEM (the terrain extra).
        def error(path: Any, message: str) -> ProjectError:
            full = yaml_path(tuple(path), lines)
            return ProjectError(source, line_of(full, lines), key_text(full, lines), message)

        data, where = terrain_corridor(data, error, base)
    if "sections" not in data:
        return _validated(data, lines, source, base)
    sections = []
    run_seed = 0
    for index, (name, section_data, section_lines) in enumerate(
            split_sections(data, lines, source)):
        project = _validated(section_data, section_lines, source, base)
        # Each section its own random numbers, derived from the corridor's seed
        # (the top level's rocks.seed: a section may not set its own).
        run_seed = int(project.rocks.seed)
        seed = section_seed(run_seed, index)
        project = project.model_copy(
            update={"rocks": project.rocks.model_copy(update={"seed": seed})})
        sections.append(CorridorSection(name=strip_controls(str(name)), index=index,
                                        project=project))
    description = data.get("description")
    return Corridor(name=strip_controls(str(data.get("name", ""))),
                    description=(strip_controls(description, lines=True)
                                 if isinstance(description, str) else ""),
                    source=source, seed=run_seed, sections=tuple(sections), map=where)


def load_corridor(path: str | os.PathLike[str]) -> "Corridor | Project":
    """Read a project file that may list ``sections:``; see :func:`load_corridor_text`."""
    source = os.fspath(path)
    return load_corridor_text(_read_project(source), source, base_dir=Path(source).parent)


def _read_project(source: str) -> str:
    """The text of a project file; one located line when it cannot be read."""
    try:
        return read_text(source, "project file")
    except UnicodeDecodeError as exc:
        raise ProjectError(
            source, None, "", f"cannot read file: not UTF-8 text ({exc.reason})"
        ) from exc
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise ProjectError(source, None, "", f"cannot read file: {reason}") from exc


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
    return load_project_text(_read_project(source), source, base_dir=Path(source).parent)

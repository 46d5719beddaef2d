"""Loading: YAML with line numbers and limits, and the entry points.

:func:`load_project` / :func:`load_project_text` read a project file (a
SafeLoader with YAML 1.2 floats, duplicate keys refused, limits on values
and merge keys, libyaml for large files), map every key path to its line,
validate it and attach the catalogue files it names; :func:`dump_yaml`
writes data that loads back to the same values.
"""

import os
import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

import yaml
from pydantic import ValidationError
from pydantic_core import PydanticCustomError

from ..errors import ProjectError
from ..inputs import read_named_text, read_text, strip_controls
from .design import _check_products
from .fields import _raw
from .locator import Locator
from .messages import (
    _describe,
    _fail,
    _key_text,
    _line_of,
    _Lines,
    _to_project_error,
    _unquoted,
    _yaml_path,
)
from .model import Project

if TYPE_CHECKING:  # pragma: no cover
    from .corridor import Corridor

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
    if "sections" in data:
        raise ProjectError(
            source, _line_of(("sections",), lines), "sections",
            "this file lists sections (a corridor): load it with load_corridor; simulate, "
            "check, optimise and study run every section",
        )
    base = Path(source).parent if base_dir is None else Path(base_dir)
    return _validated(data, lines, source, base)


def _parse_top(text: str, source: str) -> tuple[dict, _Lines]:
    """The YAML of a project file: a mapping of its top-level keys, and its line map."""
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
    return data, lines


def _validated(data: dict, lines: _Lines, source: str, base: Path) -> Project:
    """A project from parsed data and its line map: files resolved, validated, catalogues."""
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
        text = read_named_text(path, what)
    except ValueError as exc:
        raise project.error_at(at, str(exc)) from None
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
    from .corridor import Corridor, CorridorSection, section_seed, split_sections

    data, lines = _parse_top(text, source)
    base = Path(source).parent if base_dir is None else Path(base_dir)
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
                    source=source, seed=run_seed, sections=tuple(sections))


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

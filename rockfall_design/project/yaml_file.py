"""YAML with line numbers and limits: how every project, catalogue and library file is read.

A SafeLoader with YAML 1.2 floats, duplicate keys refused, limits on the
number of values and on merge keys (alias bombs), parsed by libyaml where
PyYAML has it (a file libyaml refuses is read again by the pure-Python
parser, whose messages the project's are); every key path is mapped to its
line, so that messages can say
``file:line: key: ...``. :func:`dump_yaml` writes data that loads back to the
same values.
"""

import re
from typing import Any

import yaml

from ..errors import ProjectError
from .messages import Lines, key_text

_MERGE_TAG = "tag:yaml.org,2002:merge"
_MAX_NODES = 200_000  # guards against alias bombs ("billion laughs")
_MAX_MERGED = 10_000  # entries that merge keys (<<) may copy, in the whole file


class _Loader(yaml.SafeLoader):
    """SafeLoader with project-friendly scalars.

    - ``1e3`` is a number (as in YAML 1.2; PyYAML's YAML 1.1 reads it as a string);
    - dates stay strings (a name like ``2024-05-01`` is text, not a date);
    - scalar conversion errors (``!!int abc``, ``!!int`` on an empty value,
      ``!!bool x``) become YAML errors with a mark.
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
        except (IndexError, KeyError) as exc:  # "!!int" on an empty value, "!!bool x"
            kind = str(node.tag).rsplit(":", 1)[-1]
            raise yaml.constructor.ConstructorError(
                None, None, f"invalid value: !!{kind} {node.value!r}", node.start_mark
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


#: Above this size (characters) a file libyaml refuses is not read again by
#: the pure-Python parser for its message: that scanner takes about half a
#: second per megabyte, so a file near the size limit (RF_MAX_FILE_MB) would
#: take minutes. The message is then libyaml's.
LIBYAML_FROM = 1_000_000

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


class _ReadApart(Exception):
    """libyaml and PyYAML's pure-Python parser may read this file differently."""


#: Characters in a file that libyaml and PyYAML's pure-Python parser read
#: differently somewhere: libyaml takes a tab as a space between tokens
#: (PyYAML refuses it), and a byte-order mark inside the text.
_READ_APART_TEXT = ("\t", "\ufeff")


def _count_values(text: str, alike: bool = False) -> None:
    """Refuse a file of more than _MAX_NODES values before libyaml composes them all.

    libyaml's composer builds every node before the line map can count
    them; its events are counted here first, one at a time. With ``alike``,
    raise :class:`_ReadApart` at the first event the two parsers may read
    differently: a tag written out (libyaml reads ``!`` alone on an empty
    value as an empty string, PyYAML as null), a literal or folded block
    scalar (libyaml takes ``|#`` as a header, PyYAML refuses it), a
    directive (``%YAML``, ``%TAG``). Found by reading 100,000 random texts
    of YAML's characters with both (2026-11-28); a file without them was
    read to the same data and lines.
    """
    parser = CParser(text)
    try:
        count = 0
        while parser.check_event():
            event = parser.get_event()
            if alike and _read_apart(event):
                raise _ReadApart
            if isinstance(event, yaml.NodeEvent):
                count += 1
                if count > _MAX_NODES:
                    raise _TooManyValues(event.start_mark)
    finally:
        parser.dispose()


def _read_apart(event: yaml.Event) -> bool:
    """Whether libyaml and PyYAML's pure-Python parser may read ``event`` differently."""
    if isinstance(event, yaml.DocumentStartEvent):
        return bool(event.version or event.tags)
    if isinstance(event, yaml.ScalarEvent) and event.style in ("|", ">"):
        return True
    return getattr(event, "tag", None) is not None


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
    """``data`` as YAML that :func:`.load_project_text` reads back to the same values.

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


def _map_lines(loader: _Loader, root: yaml.Node, source: str) -> Lines:
    """Walk the node tree: key path -> line, rejecting duplicate and non-scalar keys."""
    _check_merges(root, source)
    lines: Lines = {}
    budget = [_MAX_NODES]

    def error(node: yaml.Node, path: tuple, message: str) -> ProjectError:
        return ProjectError(source, node.start_mark.line + 1, key_text(path, lines), message)

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


def parse_yaml(text: str, source: str, *, libyaml: bool = True) -> tuple[Any, Lines]:
    """``text`` as data, with the line of every key path.

    Parsed by libyaml where PyYAML has it: the bundled projects and
    catalogues load 4.7 times faster than with the pure-Python parser
    (0.71 s against 0.15 s for three reads of the 18 bundled YAML files,
    2026-11-28). The same constructors and resolvers build the data from
    either parser's nodes. A file the fast path refuses, for whatever reason,
    is read again by the pure-Python parser, so that a message (its wording,
    line and column) is the one it always was, and a file that parser reads
    is read; a file over :data:`LIBYAML_FROM` characters keeps libyaml's
    message instead.

    Parameters
    ----------
    text : str
        The file's text.
    source : str
        The file's name as messages show it.
    libyaml : bool
        False: PyYAML's pure-Python parser only, the reference the fast
        path is tested against.

    Returns
    -------
    data : object
        The document (None for an empty file).
    lines : dict
        Key path -> (line, kind), as :data:`.messages.Lines`.

    Raises
    ------
    ProjectError
        The file is not YAML, or breaks a limit (values, merges, nesting,
        duplicate keys), with its line where there is one.
    """
    large = len(text) > LIBYAML_FROM
    if libyaml and _CLoader is not None and (large or not any(c in text for c in _READ_APART_TEXT)):
        try:
            data, lines = _parse(text, source, fast=True, alike=not large)
        except _ReadApart:
            pass
        except Exception:  # noqa: BLE001 - whatever fails here, the reference parser decides
            if large:
                raise
        else:
            # An empty document: libyaml puts "---" alone a line lower.
            if data is not None or large:
                return data, lines
    # PyYAML's pure-Python parser: the reference, whose messages are the project's.
    return _parse(text, source, fast=False)


def _parse(text: str, source: str, fast: bool, alike: bool = False) -> tuple[Any, Lines]:
    """:func:`parse_yaml` by libyaml (``fast``) or by PyYAML's pure-Python parser.

    ``alike``: raise :class:`_ReadApart` if the two may read the file
    differently (:func:`_count_values`).
    """
    try:
        if fast:
            _count_values(text, alike)
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

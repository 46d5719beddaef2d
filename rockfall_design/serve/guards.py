"""What the app lets a page read and write: files inside the project's folder only.

:func:`inside` resolves a name the page sends against the project's folder
and refuses anything outside it (``..``, absolute paths, links out);
:func:`referenced_outside` finds a file a project text names outside the
served root. Uploads are limited in size and kind.
"""

from __future__ import annotations

import os
import re
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # pragma: no cover
    pass


#: Largest request body (bytes): a project file or a section to import.
MAX_BODY_BYTES = 1_000_000


#: Files that may be imported into a project's directory.
UPLOAD_SUFFIXES = (".csv", ".dxf", ".yaml", ".yml")


# A string in a project that names a file: no blanks, and a path separator
# or a file extension the project format reads.
_FILE_LIKE = re.compile(r"^[^\s]*(/|\\|\.(ya?ml|csv|dxf|json|txt))[^\s]*$", re.IGNORECASE)


class ServeError(Exception):
    """A request the app refuses: an HTTP status and one line saying why."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = int(status)
        self.message = message


def inside(base: Path, name: str) -> Path:
    """``name`` resolved against ``base``, refused unless it stays inside ``base``.

    Symbolic links are followed before the check, so a link that points out
    of the directory is refused as well.

    Raises
    ------
    ServeError
        403 if the path leaves ``base``; 400 if it is empty or malformed.
    """
    if not isinstance(name, str) or not name.strip() or "\x00" in name:
        raise ServeError(400, "path: expected a file name inside the project's directory")
    root = base.resolve()
    target = (root / name).resolve()
    if not target.is_relative_to(root):
        raise ServeError(403, f"path {name!r} lies outside the project's directory ({root})")
    return target


def referenced_outside(text: str, base: Path, root: Path) -> str | None:
    """The first string of a project's YAML that names a file outside ``root``, or None.

    A project names its survey section, materials library and catalogues as
    paths relative to its own directory ``base``; an edited project must not
    make the app read anything outside the project's directory ``root``.
    The YAML is composed, not constructed, and every node visited once, so
    that aliases cannot multiply the work (the loader's own limits come
    after this check).
    """
    import yaml

    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.YAMLError:
        return None  # the project loader says where and why
    seen: set[int] = set()
    todo = [node] if node is not None else []
    root = root.resolve()
    while todo:
        n = todo.pop()
        if id(n) in seen:
            continue
        seen.add(id(n))
        if isinstance(n, yaml.ScalarNode):
            value = n.value
            if isinstance(value, str) and _FILE_LIKE.match(value):
                target = (base / value).resolve()
                if not target.is_relative_to(root):
                    return value
        elif isinstance(n, yaml.SequenceNode):
            todo.extend(n.value)
        elif isinstance(n, yaml.MappingNode):
            for k, v in n.value:
                todo.extend((k, v))
    return None


def _library_comments(text: str) -> dict[str, str]:
    """Each library entry's ``# source:`` comment line (the bundled library's convention)."""
    out: dict[str, str] = {}
    source = ""
    for line in text.splitlines():
        m = re.match(r"#\s*source:\s*(.*)$", line)
        if m:
            source = m.group(1).strip()
            continue
        m = re.match(r"([A-Za-z0-9_][^:#\s]*)\s*:", line)
        if m:
            if source:
                out[m.group(1)] = source
            source = ""
    return out


def _write_atomically(target: Path, text: str) -> None:
    """Write ``text`` to ``target`` in one step: a reader sees the old file or the new one."""
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise

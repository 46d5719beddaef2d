"""What the app lets a page read and write: files inside the project's folder only.

:func:`inside` resolves a name the page sends against the project's folder
and refuses anything outside it (``..``, absolute paths, links out);
:func:`referenced_outside` finds a file a project text names outside the
served root. Uploads are limited in size and kind (:func:`file_kind`), and
never touch a dotfile or a dot-folder. :func:`request_problem` refuses a
request that changes something unless it comes from the app's own page
(its ``Origin``, or a same-origin ``Referer``) as JSON.
:func:`write_atomically` replaces a file in one step, keeping its mode, and
turns a full disk into a 507 with nothing written.
"""

from __future__ import annotations

import errno
import hashlib
import io
import math
import os
import re
import stat
from collections.abc import Mapping
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

from ..project.schema import Material
from ..report.temporaries import make, remove_stale

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


def library_comments(text: str) -> dict[str, str]:
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


#: What a full disk or a file-size limit raises: a 507 "Insufficient Storage".
_NO_ROOM = {errno.ENOSPC: "no space left on the device", errno.EFBIG: "the file is larger "
            "than this system allows", errno.EDQUOT: "the disk quota is exhausted"}


def write_bytes(fd: int, data: bytes) -> None:
    """Write all of ``data`` to the open file ``fd`` (os.write may write only part)."""
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]


def write_atomically(target: Path, text: str) -> None:
    """Write ``text`` to ``target`` in one step: a reader sees the old file or the new one.

    The new file keeps the mode of the file it replaces (a new file gets the
    mode the user's umask gives), not the 0600 of a temporary file. Nothing
    is left behind on failure: the temporary file is removed and ``target``
    is untouched.

    Raises
    ------
    ServeError
        507 when the disk is full or the file too large (ENOSPC, EFBIG,
        EDQUOT); other OS errors 500, one line each.
    """
    try:
        mode = stat.S_IMODE(target.stat().st_mode)
    except FileNotFoundError:
        umask = os.umask(0)
        os.umask(umask)
        mode = 0o666 & ~umask
    # Named by its owner, as the commands' temporaries are: a server killed
    # during a write leaves one that the next write here (or a run) removes.
    remove_stale(target.parent)
    fd, tmp = make(target.parent, target.name)
    try:
        try:
            write_bytes(fd, text.encode("utf-8"))
            os.fchmod(fd, mode)
            os.fsync(fd)  # a full disk shows here on some file systems, not at write
        finally:
            os.close(fd)
        os.replace(tmp, target)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        why = _NO_ROOM.get(exc.errno)
        if why is not None:
            raise ServeError(507, f"{target.name}: not written, {why} ({exc.strerror}); "
                             "the file is as it was") from None
        raise ServeError(500, f"{target.name}: not written: {exc.strerror or exc}; the file "
                         "is as it was") from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def version_of(path: Path) -> str:
    """The version of a file the page read: its size, mtime (ns) and SHA-256, as one string.

    Save sends it back; a file whose version differs changed since the page
    read it (an edit in another editor, another page). The hash decides even
    when a copy keeps the mtime; the mtime and size are there so that a
    reader sees at a glance what changed.
    """
    data = path.read_bytes()
    st = path.stat()
    return f"{st.st_size}-{st.st_mtime_ns}-{hashlib.sha256(data).hexdigest()[:32]}"


def same_version(path: Path, version: str) -> bool:
    """Whether ``path`` is still the file whose :func:`version_of` was ``version``.

    The content hash decides: a file rewritten with the same bytes (a new
    mtime) has not changed for the page.
    """
    current = version_of(path)
    return current.rsplit("-", 1)[-1] == str(version).rsplit("-", 1)[-1]


# ---- requests that change something: only the app's own page, as JSON -----------------

#: Methods that change nothing; every other one must come from the app's own page.
SAFE_METHODS = frozenset({"GET", "HEAD"})


def _origin_of(url: str) -> str | None:
    """``scheme://host[:port]`` of a URL, lower case, or None when it has none."""
    try:
        parts = urlsplit(url)
    except ValueError:
        return None
    if not parts.scheme or not parts.netloc:
        return None
    return f"{parts.scheme}://{parts.netloc}".lower()


def request_problem(method: str, scheme: str, headers: Mapping[str, str]) -> str | None:
    """Why a request may not change anything, or None when it may.

    A request that is not a GET or HEAD must name the app's own origin
    (``scheme://Host``) in its ``Origin`` header, or lacking one in a
    same-origin ``Referer``, and send ``Content-Type: application/json``.
    A form of another page (another port of 127.0.0.1 included: a port
    makes another origin, though not another site) sends its own origin and
    ``text/plain``, ``multipart/form-data`` or a urlencoded body: refused.

    Parameters
    ----------
    method
        The HTTP method.
    scheme
        ``http`` or ``https``, as the server sees the request.
    headers
        The request's headers, names in lower case.
    """
    if method.upper() in SAFE_METHODS:
        return None
    host = headers.get("host", "")
    own = f"{scheme}://{host}".lower()
    origin = headers.get("origin")
    if origin is not None:
        if origin.strip().lower() != own:
            return (f"Origin {origin.strip()[:80]!r} is not this app's {own}: only the app's "
                    "own page may change anything")
    else:
        referer = headers.get("referer")
        if referer is None or _origin_of(referer) != own:
            return (f"no Origin header and no Referer of this app's {own}: only the app's "
                    "own page may change anything")
    media = headers.get("content-type", "").split(";", 1)[0].strip().lower()
    if media != "application/json":
        return (f"Content-Type {media or 'none'!r}: a request that changes something sends "
                "application/json")
    return None


# ---- numbers in a request: finite only ------------------------------------------------


def non_finite_key(data: Any, where: str = "") -> str | None:
    """The key path of the first NaN or infinite number in a parsed JSON body, or None.

    Python's JSON reader takes ``NaN``, ``Infinity`` and ``-Infinity`` and
    turns a number too large for a float (``1e400``) into infinity: none of
    them is a value the app can use.
    """
    if isinstance(data, float):
        return None if math.isfinite(data) else (where or "body")
    if isinstance(data, dict):
        items: Any = ((f"{where}.{k}" if where else str(k), v) for k, v in data.items())
    elif isinstance(data, list):
        items = ((f"{where}[{i}]", v) for i, v in enumerate(data))
    else:
        return None
    for key, value in items:
        hit = non_finite_key(value, key)
        if hit is not None:
            return hit
    return None


# ---- what a file is: uploads replace only a file of their own kind ----------------------

SECTION_CSV = "surveyed section (CSV: x, y)"
STOPS_CSV = "observed stops (CSV: x)"
DXF = "DXF drawing"
LIBRARY = "materials library"
PROJECT = "project file"
#: The kinds of file an upload may write.
UPLOAD_KINDS = (SECTION_CSV, STOPS_CSV, DXF, LIBRARY)


def hidden_part(name: str) -> str | None:
    """The first part of a relative path that is a dotfile or dot-folder, or None."""
    for part in Path(name).parts:
        if part.startswith(".") and part not in (".", ".."):
            return part
    return None


def _csv_kind(text: str) -> str:
    import csv

    for row in csv.reader(io.StringIO(text.lstrip("\ufeff"))):
        cells = [c.strip().lower() for c in row]
        if not any(cells) or cells[0].startswith("#"):
            continue  # blank and comment lines before the header (a survey's notes)
        if "x" in cells and "y" in cells:
            return SECTION_CSV
        return STOPS_CSV if "x" in cells else "CSV of another kind"
    return "empty CSV"


def _yaml_kind(text: str) -> str:
    import yaml
    from pydantic import ValidationError


    try:
        # Composed, not constructed: an alias bomb is not expanded here.
        node = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.YAMLError:
        return "text that is not YAML"
    if not isinstance(node, yaml.MappingNode) or not node.value:
        return "YAML of another kind"
    keys = [k.value for k, _ in node.value if isinstance(k, yaml.ScalarNode)]
    if "slope" in keys:
        return PROJECT
    try:
        data = yaml.safe_load(text)
        for value in data.values():
            Material.model_validate(value)
    except (yaml.YAMLError, ValidationError, AttributeError, TypeError, RecursionError):
        return "YAML of another kind"
    return LIBRARY


def file_kind(name: str, text: str) -> str:
    """What the file ``name`` with content ``text`` is, in words (one of :data:`UPLOAD_KINDS`,
    :data:`PROJECT`, or a description of another kind).

    By its suffix and its first lines: a CSV with ``x`` and ``y`` columns is a
    surveyed section, one with ``x`` alone observed stops; a YAML file with a
    ``slope:`` key is a project, a mapping of valid materials a library; a DXF
    file begins with a ``0`` / ``SECTION`` group.
    """
    suffix = Path(name).suffix.lower()
    if suffix == ".csv":
        return _csv_kind(text)
    if suffix in (".yaml", ".yml"):
        return _yaml_kind(text)
    if suffix == ".dxf":
        head = [line.strip() for line in text.lstrip("\ufeff").splitlines()[:8]]
        return DXF if "SECTION" in head else "text that is not a DXF drawing"
    return f"a {suffix or 'suffix-less'} file"

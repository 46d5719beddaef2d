"""Project inputs kept in files of their own: surveyed sections and materials libraries.

A project may take its slope section from a survey instead of listing the
points inline, and its materials from a shared library file:

- ``slope: {csv: section.csv}``: a CSV file with a header row naming the
  columns ``x``, ``y`` and (optionally) ``material``;
- ``slope: {dxf: section.dxf, layer: NAME}``: the one 2-D polyline on that
  layer of a DXF drawing (read with ezdxf, the optional extra ``[dxf]``);
- ``materials: {library: materials.yaml, ...}``: named materials from a YAML
  library; materials written inline beside ``library`` add to it or replace
  the library's material of the same name (inline wins).

Paths are relative to the project file. :func:`resolve_inputs` reads these
files and replaces the references by the inline data that the project schema
(:mod:`rockfall_design.project`) validates as it does for any project, so the
rest of the program, the run record (``resolved_dict``) and ``design.yaml``
included, only ever sees inline points and materials.

Every problem is one line, located in the file that holds it:
``section.csv:7: y: expected a number, got string 'abc'``,
``materials.yaml:12: granite.restitution: expected a number <= 1, got 1.4``,
``section.dxf: layer SECTION, vertex 4: x must increase strictly ...``; a
file that cannot be read is reported at the key of the project that names it.
The checks of the points themselves (x strictly increasing, at least two
points, coordinates near the origin, one material per segment) are those of
:class:`~rockfall_design.project.Slope`, run on the file's points.
"""

from __future__ import annotations

import csv
import difflib
import io
import math
import os
import stat
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from ..errors import ProjectError
from .design_block import inline_survey
from .inputs import max_file_bytes, note_input, read_named_text
from .messages import (
    ERROR_TYPE,
    describe,
    did_you_mean,
    error_message,
    key_text,
    line_of,
    to_project_error,
    unquoted,
    yaml_path,
)
from .schema import Material, Slope
from .terrain_slope import is_terrain_slope, terrain_slope, terrain_zones
from .yaml_file import parse_yaml

__all__ = ["MAX_SURVEY_POINTS", "resolve_inputs"]

#: Most points a surveyed section may have. A section of a few kilometres
#: surveyed every 10 cm has tens of thousands; more is a point cloud, not a
#: section, and would only slow every rock down.
MAX_SURVEY_POINTS = 100_000

#: The columns a survey CSV may have, in the order they are reported.
CSV_COLUMNS = ("x", "y", "material")

_Lines = dict[tuple, tuple[int, str]]


class _Where:
    """Errors located in the project file (the keys that name the other files)."""

    def __init__(self, source: str, lines: _Lines) -> None:
        self.source = source
        self.lines = lines

    def error(self, path: Sequence[Any], message: str) -> ProjectError:
        full = yaml_path(tuple(path), self.lines)
        return ProjectError(
            self.source, line_of(full, self.lines), key_text(full, self.lines), message
        )


def resolve_inputs(data: dict[str, Any], lines: _Lines, source: str, base_dir: Path) -> dict:
    """Replace references to a materials library and a survey file by their data.

    Parameters
    ----------
    data
        The project file as parsed (a mapping); not modified.
    lines
        Key path -> (line, node kind) of the project file.
    source
        The project file as the user named it, for messages.
    base_dir
        Directory the referenced files are relative to.

    Returns
    -------
    dict
        ``data`` with ``materials`` merged from the library and ``slope`` as
        inline ``points`` and ``materials``; ``data`` itself when it refers to
        no other file.

    Raises
    ------
    ProjectError
        For a file that cannot be read or holds a problem, one line naming
        the file, the line (where a text file has one) and the key or column.
    """
    where = _Where(source, lines)
    out = dict(data)
    materials = data.get("materials")
    if isinstance(materials, dict) and "library" in materials:
        out["materials"] = _merge_library(materials, where, base_dir)
    slope = data.get("slope")
    if is_terrain_slope(slope):
        # A DEM or a point cloud (the terrain extra): cut here, as a survey is read.
        out["slope"], section, crs = terrain_slope(slope, where.error, base_dir)
        rocks = data.get("rocks")
        if isinstance(rocks, dict) and "release" in rocks:
            out["rocks"] = {**rocks, "release": terrain_zones(
                rocks["release"], section, crs, where.error, base_dir)}
    elif isinstance(slope, dict) and ("csv" in slope or "dxf" in slope):
        out["slope"] = _survey_slope(slope, out.get("materials"), where, base_dir)
    rocks = out.get("rocks")
    if isinstance(rocks, dict) and "design_block" in rocks:
        out["rocks"] = {**rocks, "design_block": _design_block(rocks["design_block"], where,
                                                               base_dir)}
    return out


def _design_block(block: Any, where: _Where, base_dir: Path) -> Any:
    """``rocks.design_block`` with its block survey read (see ``project.design_block``)."""
    at = ("rocks", "design_block", "survey")

    def read(name: Any) -> tuple[str, str]:
        relative = _file_name(name, where, at, "a block survey")
        path = _resolve(relative, base_dir)
        return _read_text(path, where, at, "block survey"), os.fspath(path)

    return inline_survey(block, read)


# ---- files named in the project ----------------------------------------------------


def _file_name(value: Any, where: _Where, at: tuple, what: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise where.error(at, f"expected the file name of {what}, got {describe(value)}")
    return value


def _resolve(relative: str, base_dir: Path) -> Path:
    path = Path(relative).expanduser()
    return path if path.is_absolute() else base_dir / path


def _check_file(path: Path, where: _Where, at: tuple, what: str) -> None:
    """A regular file within the size limit of every file read (``RF_MAX_FILE_MB``).

    Not a directory, a device or a pipe to read for ever. The DXF reader
    opens the file itself, so this is checked before it is handed over.
    """
    try:
        info = path.stat()
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise where.error(at, f"cannot read the {what} {os.fspath(path)}: {reason}") from None
    if not stat.S_ISREG(info.st_mode):
        raise where.error(at, f"cannot read the {what} {os.fspath(path)}: not a regular file")
    limit = max_file_bytes()
    if info.st_size > limit:
        raise where.error(
            at, f"the {what} {os.fspath(path)} is larger than {limit / 1e6:g} MB, the largest "
            "file read (set RF_MAX_FILE_MB to change it)"
        )


def _read_text(path: Path, where: _Where, at: tuple, what: str) -> str:
    """A referenced text file; a file that cannot be read is the project's error."""
    _check_file(path, where, at, what)
    try:
        # The one reader of every input file (size limit checked as it reads);
        # a BOM stripped: spreadsheet programs start their CSV exports with one.
        return read_named_text(path, what).removeprefix("\ufeff")
    except ValueError as exc:
        raise where.error(at, str(exc)) from None


# ---- materials library -------------------------------------------------------------


def _merge_library(materials: dict, where: _Where, base_dir: Path) -> dict[Any, Any]:
    """``materials:`` with its ``library`` file read: library first, inline on top."""
    inline = dict(materials)
    reference = inline.pop("library")
    if isinstance(reference, dict):
        # A material that happens to be called "library", as before libraries
        # existed: a file name is a string, a material is a mapping.
        return materials
    relative = _file_name(reference, where, ("materials", "library"), "a materials library")
    path = _resolve(relative, base_dir)
    shown = os.fspath(path)
    text = _read_text(path, where, ("materials", "library"), "materials library")
    data, lines = parse_yaml(text, shown)
    if data is None or data == {}:
        raise ProjectError(shown, 1, "", "the materials library is empty")
    # A library path may name any file (a key file, /etc/shadow): its
    # messages say what is wrong where, never what the file holds.
    with unquoted():
        if not isinstance(data, dict):
            raise ProjectError(
                shown,
                line_of((), lines),
                "",
                f"expected a mapping of material names to materials, got {describe(data)}",
            )
        for name, value in data.items():
            _check_library_material(name, value, shown, lines)
    # Inline materials replace library ones of the same name as a whole: a
    # project that redefines "talus" means its own talus, not a blend.
    return {**data, **inline}


def _check_library_material(name: Any, value: Any, shown: str, lines: _Lines) -> None:
    """Validate one library entry as an inline material is; errors name the library."""
    if not isinstance(name, str) or not name:
        raise ProjectError(
            shown, line_of((name,), lines), "",
            f"material names must be text, got {describe(name)}",
        )
    try:
        Material.model_validate(value)
    except ValidationError as exc:
        # Locate the problem within this material, then put its name in front.
        inner = {key[1:]: pos for key, pos in lines.items() if key[:1] == (name,)}
        err = to_project_error(exc, shown, inner, Material)
        key = f"{name}.{err.key}" if err.key else name
        raise ProjectError(shown, err.line, key, err.message) from None


# ---- surveyed slope section --------------------------------------------------------

_CSV_KEYS = ("csv", "materials")
_DXF_KEYS = ("dxf", "layer", "materials")


def _survey_slope(slope: dict, materials: Any, where: _Where, base_dir: Path) -> dict:
    """``slope: {csv: ...}`` or ``slope: {dxf: ..., layer: ...}`` -> points and materials."""
    if "csv" in slope and "dxf" in slope:
        raise where.error(("slope", "dxf"), "give the section as csv: or as dxf:, not both")
    kind = "csv" if "csv" in slope else "dxf"
    allowed = _CSV_KEYS if kind == "csv" else _DXF_KEYS
    for key in slope:
        if key == "points":
            raise where.error(
                ("slope", "points"),
                f"give the points inline (points:) or from a file ({kind}:), not both",
            )
        if key not in allowed:
            if isinstance(key, str):
                hint = did_you_mean(key, allowed) or f"; expected one of {', '.join(allowed)}"
            else:
                hint = f"; keys must be names, expected one of {', '.join(allowed)}"
            raise where.error(("slope", key), f"unknown key {key!r}{hint}")
    what = "survey section" if kind == "csv" else "drawing"
    relative = _file_name(slope[kind], where, ("slope", kind), f"a {what}")
    path = _resolve(relative, base_dir)
    if kind == "csv":
        section: _Section = _CsvSection(path, where)
    else:
        section = _DxfSection(path, slope, where)
    names = section.materials
    if names is not None:
        if "materials" in slope:
            raise where.error(
                ("slope", "materials"),
                f"{section.shown} has a material column: give the materials there or "
                "here, not both",
            )
        chosen: Any = names[:-1]  # the last point starts no segment
    elif "materials" in slope:
        chosen = slope["materials"]
    else:
        how = (
            "a material column in the CSV or slope.materials"
            if kind == "csv"
            else "slope.materials"
        )
        raise where.error(
            ("slope",),
            f"no materials for the section of {section.shown}: give {how} (one name for "
            "every segment, or a list with one name per segment)",
        )
    problems = []
    try:
        Slope.model_validate({"points": section.points, "materials": chosen})
    except ValidationError as exc:
        problems.append(_slope_error(exc, section, where, names is not None))
    if names is not None and isinstance(materials, dict):
        # Names from the file are checked here, where their lines are known
        # (the project's own check would point at slope: in the project file).
        for i, name in enumerate(chosen):
            if name not in materials:
                hint = did_you_mean(name, materials) or (
                    f"; defined: {', '.join(map(str, materials))}"
                )
                problems.append(section.error(i, "material", f"undefined material {name!r}{hint}"))
                break
    if problems:
        # The problem earliest in the file, as for a project file.
        raise min(problems, key=lambda e: (e.file != section.shown, e.line or 0)) from None
    return {"points": [list(p) for p in section.points], "materials": chosen}


def _slope_error(
    exc: ValidationError, section: _Section, where: _Where, file_materials: bool
) -> ProjectError:
    """The first problem :class:`Slope` found, located in the survey file or the project."""
    error = exc.errors()[0]
    loc = tuple(error["loc"])
    if error["type"] == ERROR_TYPE:
        loc += tuple((error.get("ctx") or {}).get("subpath", ()))
    message = error_message(error)
    if loc[:1] == ("points",) and len(loc) >= 2 and isinstance(loc[1], int):
        column = "xy"[loc[2]] if len(loc) >= 3 and loc[2] in (0, 1) else "x"
        return section.error(loc[1], column, message)
    if loc[:1] == ("points",):
        return ProjectError(section.shown, None, "", message)
    if file_materials and loc[:1] == ("materials",):
        index = loc[1] if len(loc) >= 2 and isinstance(loc[1], int) else 0
        return section.error(index, "material", message)
    return where.error(("slope",) + loc, message)


class _Section:
    """Points of a section read from a file, and how to name each one in a message."""

    shown: str
    points: list[tuple[float, float]]
    #: the material named at each point (the segment it starts), or None
    materials: list[str] | None

    def error(self, index: int, column: str, message: str) -> ProjectError:
        raise NotImplementedError


class _CsvSection(_Section):
    """A survey CSV: a header row, then one point per row (``#`` starts a comment row)."""

    def __init__(self, path: Path, where: _Where) -> None:
        self.shown = os.fspath(path)
        text = _read_text(path, where, ("slope", "csv"), "survey section")
        self.points = []
        self.row_lines: list[int] = []
        names: list[str] = []
        # strict: a stray quote is an error, not a value that swallows later rows.
        reader = csv.reader(io.StringIO(text, newline=""), strict=True)
        columns: list[str] | None = None
        while True:
            line = reader.line_num + 1  # where the next row starts
            try:
                row = next(reader)
            except StopIteration:
                break
            except csv.Error as exc:
                raise ProjectError(self.shown, line, "", f"invalid CSV: {exc}") from None
            cells = [cell.strip() for cell in row]
            if not any(cells) or cells[0].startswith("#"):
                continue
            if any("\n" in cell or "\r" in cell for cell in cells):
                raise ProjectError(self.shown, line, "", "invalid CSV: a value spans lines")
            if columns is None:
                columns = self._header(cells, line)
                continue
            if len(self.points) == MAX_SURVEY_POINTS:
                raise ProjectError(
                    self.shown, line, "",
                    f"more than {MAX_SURVEY_POINTS:,} points: thin the survey out",
                )
            point, name = self._row(cells, columns, line)
            self.points.append(point)
            self.row_lines.append(line)
            names.append(name)
        if columns is None:
            raise ProjectError(
                self.shown, None, "", "no header row: expected the columns x, y (and material)"
            )
        self.materials = names if "material" in columns else None
        for i, name in enumerate(names[:-1] if self.materials is not None else []):
            # The last point starts no segment, so its material may be left empty.
            if not name:
                raise self.error(
                    i, "material", "no value (the material of the segment from this point "
                    "to the next)"
                )

    def _header(self, cells: list[str], line: int) -> list[str]:
        # The survey path may name any file (a key file, /etc/passwd): a
        # header that is not one says where, never what the line holds.
        columns = [cell.lower() for cell in cells]
        if _is_number(cells[0]):
            raise ProjectError(
                self.shown, line, "",
                "expected a header row naming the columns x, y (and material), got a number",
            )
        for number, column in enumerate(columns, start=1):
            if column not in CSV_COLUMNS:
                hint = did_you_mean(column, CSV_COLUMNS) or (
                    f"; expected {', '.join(CSV_COLUMNS)}"
                )
                if ";" in column or "\t" in column:
                    hint = "; the columns must be separated by commas"
                raise ProjectError(self.shown, line, "",
                                   f"column {number} of the header is not a known column{hint}")
            if columns.count(column) > 1:
                raise ProjectError(self.shown, line, "", f"column {column!r} appears twice")
        for needed in ("x", "y"):
            if needed not in columns:
                raise ProjectError(self.shown, line, "", f"no column {needed!r} in the header")
        return columns

    def _row(
        self, cells: list[str], columns: list[str], line: int
    ) -> tuple[tuple[float, float], str]:
        if len(cells) != len(columns):
            raise ProjectError(
                self.shown, line, "",
                f"expected {len(columns)} values ({', '.join(columns)}), got {len(cells)}",
            )
        values = dict(zip(columns, cells, strict=True))
        xy = []
        for column in ("x", "y"):
            text = values[column]
            if not text:
                raise ProjectError(self.shown, line, column, "no value")
            if not _is_number(text):
                raise ProjectError(self.shown, line, column, "expected a number")
            number = float(text)
            if not math.isfinite(number):
                raise ProjectError(self.shown, line, column, f"must be finite, got {text}")
            xy.append(number)
        name = values.get("material", "")
        return (xy[0], xy[1]), name

    def error(self, index: int, column: str, message: str) -> ProjectError:
        line = self.row_lines[index] if 0 <= index < len(self.row_lines) else None
        return ProjectError(self.shown, line, column, message)


def _is_number(text: str) -> bool:
    # float() also reads "nan", "inf" and "1_000"; the first two are caught as
    # not finite, the last is a number as in the project file.
    try:
        float(text)
    except ValueError:
        return False
    return True


def _dxf_problem(exc: BaseException) -> str:
    """What is wrong with a DXF file ezdxf could not read, without quoting it.

    A file cut short ends ezdxf's tag iterator (StopIteration) or its
    stream; other failures are named by type and, where ezdxf says it, the
    line. The file's own text is never repeated (the path may name any file).
    """
    if isinstance(exc, StopIteration | EOFError) or "ENDSEC" in str(exc) or "EOF" in str(exc):
        return ("not a readable DXF drawing: the file ends before the drawing does "
                "(is it cut short?)")
    import re

    found = re.search(r"line (\d+)", str(exc))
    where = f" near line {found.group(1)}" if found else ""
    if "not a DXF file" in str(exc):
        return "not a readable DXF drawing: no DXF header"
    return f"not a readable DXF drawing: {type(exc).__name__}{where}"


class _DxfSection(_Section):
    """The one 2-D polyline on a layer of a DXF drawing, as section points."""

    def __init__(self, path: Path, slope: dict, where: _Where) -> None:
        self.shown = os.fspath(path)
        self.materials = None
        if "layer" not in slope:
            raise where.error(
                ("slope", "layer"),
                "required key is missing (the DXF layer that holds the section polyline)",
            )
        layer = slope["layer"]
        if not isinstance(layer, str) or not layer:
            raise where.error(
                ("slope", "layer"), f"expected a layer name, got {describe(layer)}"
            )
        self.layer = layer
        try:
            import ezdxf
        except ImportError:
            raise where.error(
                ("slope", "dxf"),
                "reading a DXF drawing needs ezdxf, the optional extra [dxf]: "
                "python -m pip install 'rockfall-design[dxf]' (or '.[dxf]' in the repository)",
            ) from None
        _check_file(path, where, ("slope", "dxf"), "drawing")

        note_input(path, "survey drawing")
        try:
            doc = ezdxf.readfile(path)
        except Exception as exc:  # noqa: BLE001 - the parser of an untrusted file
            # ezdxf raises many kinds of exception for a damaged or foreign
            # file; every one of them is a problem with the file, not a bug here.
            raise ProjectError(self.shown, None, "", _dxf_problem(exc)) from None
        units = doc.header.get("$INSUNITS", 0)
        if units not in (0, 6):  # unitless, metres
            name = ezdxf.units.unit_name(units)
            raise ProjectError(
                self.shown, None, "$INSUNITS",
                f"the drawing is in {name}; draw the section in metres (or unitless)",
            )
        polylines = []
        layers: set[str] = set()
        for entity in doc.modelspace():
            if entity.dxftype() not in ("LWPOLYLINE", "POLYLINE"):
                continue
            layers.add(entity.dxf.layer)
            if entity.dxf.layer.lower() == layer.lower():  # DXF layer names ignore case
                polylines.append(entity)
        if not polylines:
            found = sorted(layers)
            # DXF layer names ignore case, so the suggestion does too.
            by_lower = {name.lower(): name for name in found}
            match = difflib.get_close_matches(layer.lower(), list(by_lower), n=1)
            hint = (f"; did you mean {by_lower[match[0]]!r}?" if match else "") or (
                f"; layers with polylines: {', '.join(found)}" if found else
                "; the drawing has no polylines"
            )
            raise ProjectError(self.shown, None, "", f"no polyline on layer {layer!r}{hint}")
        if len(polylines) > 1:
            raise ProjectError(
                self.shown, None, f"layer {layer}",
                f"{len(polylines)} polylines; expected one, the section",
            )
        self.points, self.vertex_numbers = self._vertices(polylines[0])

    def _vertices(self, entity: Any) -> tuple[list[tuple[float, float]], list[int]]:
        where = f"layer {self.layer}"
        if entity.dxftype() == "LWPOLYLINE":
            closed = entity.closed
            bulges = [float(b) for (*_, b) in entity.get_points("xyb")]
            wcs = list(entity.vertices_in_wcs())
        else:
            if not (entity.is_2d_polyline or entity.is_3d_polyline):
                raise ProjectError(
                    self.shown, None, where, "the polyline is a mesh, not a section line"
                )
            closed = entity.is_closed
            bulges = [float(v.dxf.get("bulge", 0.0)) for v in entity.vertices]
            wcs = list(entity.points_in_wcs())
        if closed:
            raise ProjectError(
                self.shown, None, where, "the polyline is closed; a section is an open line"
            )
        for i, bulge in enumerate(bulges[:-1]):
            if bulge != 0.0:
                raise ProjectError(
                    self.shown, None, f"{where}, vertex {i + 1}",
                    "an arc segment (bulge); the section must be straight segments",
                )
        if wcs and any(not math.isclose(v.z, wcs[0].z, abs_tol=1e-9) for v in wcs):
            raise ProjectError(
                self.shown, None, where,
                "the polyline is not in the x-y plane (its z varies); draw the section "
                "with x along it and y as height",
            )
        points = [(float(v.x), float(v.y)) for v in wcs]
        numbers = list(range(1, len(points) + 1))  # as CAD programs number vertices
        xs = [p[0] for p in points]
        if len(xs) > 1 and all(b < a for a, b in zip(xs, xs[1:], strict=False)):
            # Drawn from the toe up: the same line, its vertices in x order.
            points.reverse()
            numbers.reverse()
        if len(points) > MAX_SURVEY_POINTS:
            raise ProjectError(
                self.shown, None, where,
                f"more than {MAX_SURVEY_POINTS:,} vertices: thin the section out",
            )
        return points, numbers

    def error(self, index: int, column: str, message: str) -> ProjectError:
        vertex = self.vertex_numbers[index] if 0 <= index < len(self.vertex_numbers) else "?"
        return ProjectError(self.shown, None, f"layer {self.layer}, vertex {vertex}", message)


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text or type(exc).__name__


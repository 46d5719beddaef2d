"""Observations: the observed stop positions of a calibration, read and checked.

The file is a CSV with a header row and one row per observed block::

    x,volume_m3
    35.2,0.31
    52.0,0.12

``x`` (the station where the block stopped, m) is required; ``volume_m3``
or ``mass_kg`` (one of them) may be given, and then the simulated rocks
take their sizes from the observed ones (a lognormal fitted to them, see
:func:`size_distribution`). Other columns (an id, a date, a note) are
ignored.

Every problem is one line naming the file, the line and the column,
``stops.csv:7: x: expected a number, got 'abc'``, raised as a
:class:`~rockfall_design.errors.ProjectError` (exit code 2).
"""

from __future__ import annotations

import csv
import dataclasses
import difflib
import io
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import ProjectError
from ..project import MAX_RADIUS_M, MIN_RADIUS_M
from ..project.inputs import read_named_text

if TYPE_CHECKING:  # pragma: no cover
    from ..project import Project

__all__ = ["MIN_OBSERVATIONS", "Observations", "observed_file", "read_observations",
           "size_distribution", "size_limits"]

#: Fewest observed blocks a calibration accepts: below it no distance between
#: distributions means anything (20 or more give useful intervals).
MIN_OBSERVATIONS = 5
#: The size columns an observation file may have, and the project key each sets.
SIZE_COLUMNS = {"volume_m3": "volume", "mass_kg": "mass"}


@dataclass(frozen=True)
class Observations:
    """Observed blocks: where each stopped, and its size if given.

    Attributes
    ----------
    x : ndarray
        Stop stations (m), in file order.
    size : ndarray or None
        Volume (m3) or mass (kg) of each block, per :attr:`size_key`.
    size_key : str or None
        ``"volume"`` or ``"mass"`` (the project's ``rocks`` key), or None.
    source : str
        The file, as shown in messages.
    path : Path or None
        The file read, absolute (None for text that came from no file).
    """

    x: np.ndarray
    size: np.ndarray | None = None
    size_key: str | None = None
    source: str = "<observations>"
    path: Path | None = None

    @property
    def n(self) -> int:
        """Number of observed blocks."""
        return int(self.x.size)


def _num(value: float) -> str:
    """A number as a message shows it (shortest form)."""
    return f"{value:g}"


def _number(text: str, source: str, line: int, column: str) -> float:
    """A finite number from a CSV cell, or the one-line error at its place."""
    cell = text.strip()
    try:
        value = float(cell)
    except ValueError:
        shown = repr(cell) if cell else "an empty cell"
        raise ProjectError(source, line, column, f"expected a number, got {shown}") from None
    if not math.isfinite(value):
        raise ProjectError(source, line, column, f"expected a finite number, got {cell}")
    return value


def _columns(header: list[str], source: str) -> tuple[int, int | None, str | None]:
    """Where x and the size column are in the header: (x, size or None, size key)."""
    names = [h.strip() for h in header]
    if "x" not in names:
        close = difflib.get_close_matches("x", [n.lower() for n in names], n=1, cutoff=0.5)
        hint = f"; did you mean {names[[n.lower() for n in names].index(close[0])]!r}?" if close \
            else ""
        raise ProjectError(source, 1, "x", f"no column 'x' (the stop station of each block, m) "
                           f"in the header row ({', '.join(names)}){hint}")
    sizes = [c for c in SIZE_COLUMNS if c in names]
    if len(sizes) > 1:
        raise ProjectError(source, 1, sizes[1], f"give only one of {' and '.join(sizes)}: "
                           "the simulated rocks take their sizes from one of them")
    if not sizes:
        return names.index("x"), None, None
    return names.index("x"), names.index(sizes[0]), sizes[0]


def size_limits(density: float) -> dict[str, tuple[float, float]]:
    """The sizes a rock of the project may have, per size column's key (``volume``, ``mass``).

    Spheres of :data:`~rockfall_design.project.MIN_RADIUS_M` to
    :data:`~rockfall_design.project.MAX_RADIUS_M` (the project file's own
    limits of a rock), in m3 and, at ``density`` (kg/m3), in kg.
    """
    small = 4.0 / 3.0 * math.pi * MIN_RADIUS_M**3
    large = 4.0 / 3.0 * math.pi * MAX_RADIUS_M**3
    return {"volume": (small, large), "mass": (small * density, large * density)}


def _check_size(size: float, limits: tuple[float, float] | None, source: str, line: int,
                column: str) -> None:
    """The one-line error at ``line`` for a size <= 0 or outside ``limits``."""
    if size <= 0:
        raise ProjectError(source, line, column, f"expected a size > 0, got {_num(size)}")
    if limits is None:
        return
    unit = column.rsplit("_", 1)[-1]
    low, high = limits
    if size < low:
        raise ProjectError(source, line, column, f"{_num(size)} {unit} is smaller than the "
                           f"smallest rock ({low:.3g} {unit}, a sphere of {MIN_RADIUS_M:g} m "
                           "radius at the project's density): is the column in other units?")
    if size > high:
        raise ProjectError(source, line, column, f"{_num(size)} {unit} is larger than the "
                           f"largest rock ({high:.3g} {unit}, a sphere of {MAX_RADIUS_M:g} m "
                           "radius at the project's density): is the column in other units?")


def parse_observations(text: str, source: str, x_range: tuple[float, float],
                       limits: dict[str, tuple[float, float]] | None = None) -> Observations:
    """Observed blocks from the CSV ``text`` of the file ``source``, checked.

    Parameters
    ----------
    text
        The file's content.
    source
        The file's name, as shown in messages.
    x_range
        (first, last) station of the slope section (m): every stop lies on it.
    limits
        The smallest and largest size of a rock per size key
        (:func:`size_limits`); None: any size > 0.

    Raises
    ------
    ProjectError
        Empty file, no ``x`` column, a cell that is not a finite number, a
        stop outside the section, a size <= 0 or outside ``limits``, fewer than
        :data:`MIN_OBSERVATIONS` blocks: ``file:line: column: message``.
    """
    # A UTF-8 byte order mark (Excel's "CSV UTF-8") is no part of the first name,
    # as the survey files read it (project.sources).
    rows = [r for r in csv.reader(io.StringIO(text.removeprefix("\ufeff")))]
    numbered = [(i + 1, r) for i, r in enumerate(rows) if any(c.strip() for c in r)]
    if not numbered:
        raise ProjectError(source, 1, "", "the file of observed stops is empty: expected a "
                           "header row with x (m), then one row per observed block")
    (_, header), body = numbered[0], numbered[1:]
    ix, isize, size_name = _columns(header, source)
    first, last = x_range
    xs: list[float] = []
    sizes: list[float] = []
    for line, row in body:
        if len(row) != len(header):
            raise ProjectError(source, line, "", f"expected {len(header)} cells as in the "
                               f"header row, got {len(row)}")
        x = _number(row[ix], source, line, "x")
        if not first <= x <= last:
            raise ProjectError(source, line, "x", f"stop x {_num(x)} is outside the slope "
                               f"section [{_num(first)}, {_num(last)}] m")
        xs.append(x)
        if isize is not None:
            assert size_name is not None
            size = _number(row[isize], source, line, size_name)
            _check_size(size, None if limits is None else limits[SIZE_COLUMNS[size_name]],
                        source, line, size_name)
            sizes.append(size)
    if len(xs) < MIN_OBSERVATIONS:
        line = body[-1][0] if body else numbered[0][0]
        raise ProjectError(source, line, "x", f"only {len(xs)} observed block(s): a "
                           f"calibration needs at least {MIN_OBSERVATIONS} (20 or more give "
                           "useful intervals)")
    return Observations(
        x=np.asarray(xs, dtype=float),
        size=np.asarray(sizes, dtype=float) if size_name else None,
        size_key=SIZE_COLUMNS[size_name] if size_name else None,
        source=source,
    )


def observed_file(project: Project) -> Path | None:
    """The observed-stops file of the project's ``calibrate:`` section (relative to the file).

    The file of the first set of stops on the project's own section; None
    when that set's stops are given inline (``values:``).
    """
    assert project.calibrate is not None
    entry = next(e for e in project.calibrate.entries if e.kind == "stops" and e.profile is None)
    if entry.file is None:
        return None
    path = Path(entry.file)
    if not path.is_absolute() and project.source != "<string>":
        path = Path(project.source).parent / path
    return path


def read_observations(path: str | os.PathLike[str], x_range: tuple[float, float],
                      limits: dict[str, tuple[float, float]] | None = None) -> Observations:
    """Read and check an observation file (see :func:`parse_observations`).

    Raises
    ------
    ProjectError
        As :func:`parse_observations`; or the file cannot be read (located
        at the file itself, line None).
    """
    shown = os.fspath(path)
    try:
        text = read_named_text(path, "file of observed stops")
    except ValueError as exc:
        raise ProjectError(shown, None, "", str(exc)) from None
    parsed = parse_observations(text, shown, x_range, limits)
    return dataclasses.replace(parsed, path=Path(os.path.abspath(path)))


def size_distribution(obs: Observations) -> dict[str, Any] | None:
    """The rock size the simulation draws from, fitted to the observed sizes.

    A lognormal with the median ``exp(mean(ln s))`` and ``sigma =
    std(ln s)`` of the observed sizes (maximum likelihood; a single size if
    every block had the same), as the project writes it:
    ``{"volume": {"lognormal": [median, sigma]}}``. None without sizes.

    Notes
    -----
    The block sizes of rockfall inventories are commonly described as
    lognormal or power-law; with 20 to 200 blocks a lognormal's two
    parameters are what the data can support.

    References
    ----------
    Dussauge, C., Grasso, J.-R., Helmstetter, A. (2003). Statistical analysis
    of rockfall volume distributions. J. Geophys. Res. 108(B6), 2286.
    """
    if obs.size is None or obs.size_key is None:
        return None
    logs = np.log(obs.size)
    median = float(np.exp(logs.mean()))
    sigma = float(logs.std())
    if sigma == 0.0:
        return {obs.size_key: median}
    return {obs.size_key: {"lognormal": [median, sigma]}}

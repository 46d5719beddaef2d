"""Observation sets: every kind of observation a calibration fits, on every profile.

The ``calibrate:`` section's ``observed:`` is one file of stops, or a list
of observation sets (:class:`~rockfall_design.project.calibrate.ObservedSpec`),
each of a kind:

- ``stops``: where each block stopped (m), read as
  :mod:`.observations` reads the single file (with sizes, if given);
- ``passing_heights``: the height of the block's centre above the ground
  where it passed a station x (m), vertical (a mark on a tree stem: a
  sphere touches a vertical stem at its centre's height) or normal to the
  slope; a CSV with a column ``height_m``, or inline values;
- ``speeds``: the block's translational speed where it passed the station
  (m/s), e.g. from video; a column ``speed_ms``, or inline values.

Each set lies on the project's own section or on one of its ``profiles:``
(other project files of the same site). A profile runs its own slope,
rocks and engine settings, but with the project's materials by name (its
own where the project has no material of that name), so that one set of
ground values is fitted to every profile (:func:`site_materials`).

Every problem is one line naming the file and line (or the project file's
key) and the column, raised as a :class:`~rockfall_design.errors.ProjectError`
(exit code 2).
"""

from __future__ import annotations

import csv
import difflib
import io
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import ProjectError
from ..project import load_project
from ..project.inputs import read_named_text
from .observations import (
    MIN_OBSERVATIONS,
    Observations,
    read_observations,
    size_distribution,
    size_limits,
)

if TYPE_CHECKING:  # pragma: no cover
    from ..project import Project
    from ..project.calibrate import ObservedSpec

__all__ = ["COLUMNS", "ObservationSet", "Site", "passage_limit", "parse_passages",
           "profile_sizes", "read_site", "site_materials"]

#: The CSV column of each kind of passage observation, and its unit.
COLUMNS: dict[str, tuple[str, str]] = {"passing_heights": ("height_m", "m"),
                                       "speeds": ("speed_ms", "m/s")}
#: Standard gravity (m/s2), for the free-fall bound of a passage observation.
G = 9.81


@dataclass(frozen=True)
class ObservationSet:
    """One set of observations of one kind, on one profile.

    Attributes
    ----------
    kind : str
        ``stops``, ``passing_heights`` or ``speeds``.
    values : ndarray
        Stop stations (m), passing heights (m) or speeds (m/s).
    source : str
        The file (or ``FILE: calibrate.observed[i]`` for inline values).
    profile : str
        The profile's name; "" for the project's own section.
    station : float or None
        The station x (m) of a passage observation.
    weight : float
        The weight of its term in the objective.
    measured : str
        Passing heights: ``vertical`` or ``normal`` (to the slope).
    levels : dict
        Stops: name -> (from, to) (m), compared as shares.
    stops : Observations or None
        Stops: the full record (sizes, the file read).
    """

    kind: str
    values: np.ndarray
    source: str
    profile: str = ""
    station: float | None = None
    weight: float = 1.0
    measured: str = "vertical"
    levels: dict[str, tuple[float, float]] = field(default_factory=dict)
    stops: Observations | None = None

    @property
    def n(self) -> int:
        """Number of observations."""
        return int(self.values.size)

    @property
    def label(self) -> str:
        """What the set is, in a few words (``passing heights at x = 25 m, P2``)."""
        what = {"stops": "stops", "passing_heights": f"passing heights ({self.measured})",
                "speeds": "speeds"}[self.kind]
        if self.station is not None:
            what += f" at x = {self.station:g} m"
        return what + (f", profile {self.profile}" if self.profile else "")

    def as_dict(self) -> dict[str, Any]:
        """The set as ``--json`` shows it (without the values)."""
        return {"kind": self.kind, "profile": self.profile or None, "x": self.station,
                "source": self.source, "count": self.n, "weight": self.weight,
                "measured": self.measured if self.kind == "passing_heights" else None}


@dataclass
class Site:
    """The observation sets of a calibration and the profiles they lie on.

    Attributes
    ----------
    sets : list of ObservationSet
        In the order of ``calibrate.observed``.
    profiles : dict
        Name -> the profile's project, as loaded (its materials not yet the
        site's, :func:`site_materials`).
    """

    sets: list[ObservationSet]
    profiles: dict[str, Project] = field(default_factory=dict)

    @property
    def main_stops(self) -> ObservationSet:
        """The first set of stops on the project's own section (the spec requires one)."""
        return next(s for s in self.sets if s.kind == "stops" and not s.profile)

    @property
    def main_observations(self) -> Observations:
        """The stops of :attr:`main_stops` (with their sizes and file)."""
        stops = self.main_stops.stops
        assert stops is not None  # a set of stops always has them
        return stops

    @property
    def single(self) -> bool:
        """Whether this is the single-file form: one set of stops, one section, weight 1."""
        return len(self.sets) == 1 and not self.profiles and self.sets[0].weight == 1.0


def passage_limit(project: Project, station: float, kind: str) -> float:
    """The largest height (m) or speed (m/s) a rock can have at ``station``.

    The energy head of a free fall from the highest point of the section,
    plus the largest release clearance and the head of the release speed
    (with the share a rolling spin adds, 2/5 of it for a sphere), less the
    ground's height at the station: ``H``. A centre's height above the
    ground there is at most ``H``, a speed at most ``sqrt(2 g H)``. A value
    beyond it is a mistake of units (a speed in km/h, heights in cm), not a
    rock. A numeric release spin's energy is left out (small for the spins
    given in practice).
    """
    pts = np.asarray(project.slope.points, dtype=float)
    head = 0.0
    for zone in project.rocks.release:
        v2 = zone.velocity[0] ** 2 + zone.velocity[1] ** 2
        head = max(head, zone.height + 1.4 * v2 / (2 * G))
    H = float(pts[:, 1].max() - np.interp(station, pts[:, 0], pts[:, 1])) + head
    return H if kind == "passing_heights" else math.sqrt(2 * G * max(H, 0.0))


def _check_value(value: float, kind: str, limit: float, fail: Any) -> None:
    """The one-line error (``fail(message)``) for a value < 0 or above ``limit``."""
    unit = COLUMNS[kind][1]
    if value < 0:
        raise fail(f"expected a value >= 0, got {value:g}")
    if value > limit:
        what = "height above the ground" if kind == "passing_heights" else "speed"
        raise fail(f"{value:g} {unit} is more than any rock can have there (a {what} of "
                   f"at most {limit:.3g} {unit}, from a free fall from the top of the "
                   "section): is the column in other units?")


def parse_passages(text: str, source: str, kind: str, limit: float) -> np.ndarray:
    """Passing heights (m) or speeds (m/s) from the CSV ``text`` of the file ``source``.

    A header row, then one row per observation with the column of
    :data:`COLUMNS` (``height_m`` or ``speed_ms``); other columns ignored.

    Raises
    ------
    ProjectError
        An empty file, no such column, a cell that is not a finite number, a
        value < 0 or above ``limit`` (:func:`passage_limit`), fewer than
        :data:`~.observations.MIN_OBSERVATIONS` values: ``file:line: column: message``.
    """
    column, _ = COLUMNS[kind]
    rows = list(csv.reader(io.StringIO(text.removeprefix("\ufeff"))))
    numbered = [(i + 1, r) for i, r in enumerate(rows) if any(c.strip() for c in r)]
    if not numbered:
        raise ProjectError(source, 1, "", f"the file of {kind.replace('_', ' ')} is empty: "
                           f"expected a header row with {column}, then one row per block")
    (_, header), body = numbered[0], numbered[1:]
    names = [h.strip() for h in header]
    if column not in names:
        close = difflib.get_close_matches(column, names, n=1, cutoff=0.5)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        raise ProjectError(source, 1, column, f"no column {column!r} in the header row "
                           f"({', '.join(names)}){hint}")
    at = names.index(column)
    values: list[float] = []
    for line, row in body:
        if len(row) != len(header):
            raise ProjectError(source, line, "", f"expected {len(header)} cells as in the "
                               f"header row, got {len(row)}")
        cell = row[at].strip()
        try:
            value = float(cell)
        except ValueError:
            raise ProjectError(source, line, column, "expected a number, got "
                               f"{repr(cell) if cell else 'an empty cell'}") from None
        if not math.isfinite(value):
            raise ProjectError(source, line, column, f"expected a finite number, got {cell}")
        _check_value(value, kind, limit,
                     lambda m, line=line: ProjectError(source, line, column, m))
        values.append(value)
    if len(values) < MIN_OBSERVATIONS:
        raise ProjectError(source, body[-1][0] if body else 1, column,
                           f"only {len(values)} observation(s): a calibration needs at "
                           f"least {MIN_OBSERVATIONS} per set")
    return np.asarray(values, dtype=float)


def _relative(project: Project, name: str) -> Path:
    """A file named in the project file, relative to it."""
    path = Path(name)
    if not path.is_absolute() and project.source != "<string>":
        path = Path(project.source).parent / path
    return path


def _inline(project: Project, i: int, entry: ObservedSpec, on: Project) -> np.ndarray:
    """The inline values of entry ``i``, each checked (located at its item)."""
    values = np.asarray(entry.values, dtype=float)
    at = ("calibrate", "observed", i, "values")
    if entry.kind == "stops":
        first, last = on.slope.x_range
        for j, x in enumerate(values):
            if not first <= x <= last:
                raise project.error_at((*at, j), f"stop x {x:g} is outside the slope "
                                       f"section [{first:g}, {last:g}] m")
    else:
        limit = passage_limit(on, float(entry.x), entry.kind)
        for j, v in enumerate(values):
            _check_value(float(v), entry.kind, limit,
                         lambda m, j=j: project.error_at((*at, j), m))
    if values.size < MIN_OBSERVATIONS:
        raise project.error_at(at, f"only {values.size} value(s): a calibration needs at "
                               f"least {MIN_OBSERVATIONS} per set")
    return values


def _read_set(project: Project, i: int, entry: ObservedSpec, on: Project,
              override: str | os.PathLike[str] | None) -> ObservationSet:
    """Entry ``i`` of ``calibrate.observed`` read and checked on the project ``on``."""
    common = {"kind": entry.kind, "profile": entry.profile or "", "station": entry.x,
              "weight": float(entry.weight), "measured": entry.measured}
    spec = project.calibrate
    assert spec is not None
    if entry.kind == "stops":
        own = entry.profile is None
        levels = dict(entry.levels if entry.levels is not None
                      else (spec.levels if own else {}))
        common["levels"] = {str(k): (float(a), float(b)) for k, (a, b) in levels.items()}
    if entry.file is None:
        values = _inline(project, i, entry, on)
        source = f"{project.source}: calibrate.observed[{i}]"
        stops = Observations(x=values, source=source) if entry.kind == "stops" else None
        return ObservationSet(values=values, source=source, stops=stops, **common)
    path = Path(override) if override is not None else _relative(project, entry.file)
    shown = os.fspath(path)
    if entry.kind == "stops":
        obs = read_observations(path, on.slope.x_range, size_limits(on.rocks.density))
        return ObservationSet(values=obs.x, source=obs.source, stops=obs, **common)
    try:
        text = read_named_text(path, f"file of {entry.kind.replace('_', ' ')}")
    except ValueError as exc:
        raise ProjectError(shown, None, "", str(exc)) from None
    values = parse_passages(text, shown, entry.kind,
                            passage_limit(on, float(entry.x), entry.kind))
    return ObservationSet(values=values, source=shown, **common)


def _load_profile(project: Project, name: str, file: str) -> Project:
    """The profile ``name``'s project, its file relative to ``project``'s."""
    path = _relative(project, file)
    if not path.is_file():
        raise project.error_at(("calibrate", "profiles", name),
                               f"no profile file {os.fspath(path)}")
    return load_project(path)


def read_site(project: Project, override: str | os.PathLike[str] | None = None) -> Site:
    """Read and check every observation set of ``project``'s ``calibrate:`` section.

    Parameters
    ----------
    project
        A validated project with a ``calibrate:`` section.
    override
        Another file for the first set of stops on the project's own section
        (``--observed``).

    Raises
    ------
    ProjectError
        A profile file that is missing or not a valid project, a station
        outside its profile's section, a bad observation file or value.
    """
    spec = project.calibrate
    assert spec is not None
    profiles = {name: _load_profile(project, name, file) for name, file in spec.profiles.items()}
    sets = []
    replaced = False
    for i, entry in enumerate(spec.entries):
        on = project if entry.profile is None else profiles[entry.profile]
        if entry.x is not None and entry.profile is not None:
            first, last = on.slope.x_range
            if not first <= entry.x <= last:
                raise project.error_at(("calibrate", "observed", i, "x"),
                                       f"station x {entry.x:g} is outside profile "
                                       f"{entry.profile}'s section [{first:g}, {last:g}] m")
        mine = (override is not None and not replaced and entry.kind == "stops"
                and entry.profile is None)
        replaced = replaced or mine
        read = _read_set(project, i, entry, on, override if mine else None)
        sets.append(read)
    return Site(sets=sets, profiles=profiles)


def profile_sizes(sets: list[ObservationSet] | Any, profile: str) -> dict[str, Any] | None:
    """The rock size fitted to the observed blocks of ``profile``'s sets of stops, or None.

    The sizes of every set of stops on the profile that gives them, together
    (:func:`~.observations.size_distribution`).

    Raises
    ------
    ProjectError
        Two sets that give sizes in different columns (volume and mass).
    """
    withsize = [s.stops for s in sets if s.kind == "stops" and s.profile == profile
                and s.stops is not None and s.stops.size is not None]
    if not withsize:
        return None
    key = withsize[0].size_key
    for other in withsize[1:]:
        if other.size_key != key:
            raise ProjectError(other.source, 1, "", f"the sizes are given as {other.size_key} "
                               f"here and as {key} in {withsize[0].source}: give one kind "
                               "for every set of stops of a profile")
    joined = Observations(x=np.concatenate([o.x for o in withsize]), size_key=key,
                          size=np.concatenate([o.size for o in withsize]))
    return size_distribution(joined)


def site_materials(project: Project, profiles: dict[str, Project]) -> dict[str, Any]:
    """The site's materials: the project's, and each profile's of another name.

    A material named in several is the project's (the first profile's among
    profiles): ground classes are shared by name, so one value of a fitted
    parameter holds on every profile.
    """
    out = dict(project.resolved_dict()["materials"])
    for other in profiles.values():
        for name, entry in other.resolved_dict()["materials"].items():
            out.setdefault(name, entry)
    return out

"""Corridors: a project file that lists several sections along a road or railway.

A file with a top-level ``sections:`` list is a corridor. Each section is a
slope of its own (``slope:``, its release zones under ``rocks.release``, its
protected zone ``protect:`` and protected length ``design.site.length_m``,
its ``measures:`` and design ``candidates``); the keys at the top level
(``materials``, ``rocks``, ``analysis``, ``safety``, ``engine``, ``design``)
are shared by every section::

    name: Valley road, km 12 to 13
    materials: {...}
    rocks: {count: 2000, seed: 7, volume: 0.5}
    safety: {concept: spang}
    design: {products: catalogue_products.yaml, costs: {...}, residual: {fraction: 0.01}}
    sections:
      - name: km 12.1
        slope: {points: [...], materials: [...]}
        rocks: {release: {x: [0, 5]}}
        protect: {x: 80}
        design: {site: {length_m: 120}, candidates: [{type: fence, x: [30, 70]}]}

A section's ``rocks``, ``analysis`` and ``design`` are merged key by key into
the shared ones (the section's value of a key wins; a section that gives one
of ``radius``, ``volume``, ``mass`` replaces the shared size), its
``materials`` by name. Loading a corridor gives one ordinary, complete
:class:`~.model.Project` per section, validated as a project file is, so the
engine, the judge and the optimiser see nothing new; an error in a section
names the line in the file and the key as written there
(``corridor.yaml:31: sections[1].protect.x: ...``).

Seeds: a section's rocks do not share the corridor's seed, which would give
every section the same random numbers. Section ``i`` runs with
:func:`section_seed` ``(seed, i)``, derived from the run seed (``rocks.seed``,
or ``--seed``) and its index; the section's project holds it as its
``rocks.seed``, so ``design.yaml`` and ``summary.json`` of a section record
it, and a section may not set ``rocks.seed`` itself.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from ..errors import ProjectError
from .messages import Lines, did_you_mean, key_text, line_of

__all__ = ["Corridor", "CorridorSection", "MAX_SECTIONS", "section_seed", "split_sections"]

#: At most this many sections in one corridor file (each is a full run).
MAX_SECTIONS = 1000

#: The keys a section may give.
SECTION_KEYS = ("name", "description", "slope", "materials", "rocks", "analysis", "protect",
                "measures", "design")
#: Keys that belong to a section only: with ``sections:`` they may not be shared.
SECTION_ONLY = ("slope", "protect", "measures")
#: Mappings a section merges key by key into the shared one.
MERGED = ("materials", "rocks", "analysis", "design")
#: A section giving one of these replaces the shared size (exactly one may be set).
SIZE_KEYS = ("radius", "volume", "mass")


def section_seed(seed: int, index: int) -> int:
    """The seed of section ``index`` of a corridor run with ``seed``.

    Parameters
    ----------
    seed
        The run seed (``rocks.seed`` of the corridor, or ``--seed``), >= 0.
    index
        The section's index in ``sections:`` (0-based).

    Returns
    -------
    int
        A seed in [0, 2**32), a hash of both (numpy's ``SeedSequence``, so
        it is the same on every machine): distinct sections get independent
        random streams, and the same corridor seed gives the same section
        seeds.
    """
    import numpy as np  # here: loading a project file does not need numpy

    state = np.random.SeedSequence([int(seed), int(index)]).generate_state(1, np.uint32)
    return int(state[0])


@dataclass(frozen=True)
class CorridorSection:
    """One section of a corridor: its name, index and ordinary project.

    Attributes
    ----------
    name
        As written under ``sections[i].name``.
    index
        0-based position in ``sections:``.
    project
        The complete project of the section (shared keys merged in); its
        ``rocks.seed`` is :func:`section_seed` of the corridor seed and the index.
    """

    name: str
    index: int
    project: Any  # Project (not imported here: model imports this package's modules)

    @property
    def seed(self) -> int:
        """The section's seed (``rocks.seed`` of its project)."""
        return int(self.project.rocks.seed)

    @property
    def slug(self) -> str:
        """The section's name as a file name (its directory under ``--out``)."""
        return slug(self.name)


@dataclass(frozen=True)
class Corridor:
    """A project file with several sections (see the module's text).

    Attributes
    ----------
    name, description
        The corridor's, from the top level.
    source
        The file it was loaded from.
    seed
        The run seed (``rocks.seed`` at the top level) the sections' seeds derive from.
    sections
        One :class:`CorridorSection` per item of ``sections:``, in order.
    map
        For a corridor along a road on a DEM (``corridor:``), where its
        sections lie on the map (:class:`rockfall_design.terrain.road.CorridorMap`);
        None for one of listed sections.
    """

    name: str
    description: str
    source: str
    seed: int
    sections: tuple[CorridorSection, ...]
    map: Any = None

    def section_seeds(self, seed: int | None = None) -> list[int]:
        """Each section's seed for a run with ``seed`` (default: :attr:`seed`)."""
        run = self.seed if seed is None else int(seed)
        return [section_seed(run, s.index) for s in self.sections]


#: The files a corridor writes beside its sections' directories (``--out``):
#: no section's directory may take one of their names.
_TOP_FILES = frozenset({"summary.json"})


def slug(name: str) -> str:
    """A section name as a file name: runs of other characters than letters, digits,
    ``.``, ``-`` and ``_`` become ``_`` (leading dots too)."""
    text = re.sub(r"[^A-Za-z0-9._-]+", "_", name).lstrip(".")
    return text or "_"


class _SectionLines(dict):
    """The line map of one section's project: project key path -> (line, kind).

    Its keys are the paths of the section's merged project (``("slope",
    "points", 3)``); :func:`~.messages.key_text` asks :meth:`shown` for
    the path as written in the file (``("sections", 1, "slope", "points",
    3)``), so messages name the key where the user wrote it. Plain data
    (no closures), so a section's project can be pickled to a worker.
    """

    def __init__(self, file_lines: Lines, index: int, given: dict[str, frozenset | None],
                 shared: dict[str, frozenset | None]) -> None:
        super().__init__()
        self.file_lines = file_lines
        self.index = index
        #: top-level key -> None (given whole) or the subkeys the section gives
        self.given = given
        #: the same for the shared top-level keys
        self.shared = shared

    def shown(self, path: tuple) -> tuple:
        """The key path in the file of the project path ``path``."""
        here = ("sections", self.index)
        if not path:
            return here
        key = path[0]
        if key in self.given:
            sub = self.given[key]
            if sub is not None and len(path) > 1 and path[1] not in sub and key in self.shared:
                shared = self.shared[key]
                if shared is None or path[1] in shared:
                    return path
            return here + path
        if key in self.shared:
            return path
        return here + path


def _keys(value: Any, merged: bool) -> frozenset | None:
    """The subkeys of a mapping that merges key by key, None for a value given whole."""
    if merged and isinstance(value, dict):
        return frozenset(value)
    return None


def _merge(shared: dict, section: dict) -> dict:
    """The project data of one section: the shared keys with the section's merged in."""
    data = {k: v for k, v in shared.items() if k != "sections"}
    for key, value in section.items():
        base = data.get(key)
        if key in MERGED and isinstance(base, dict) and isinstance(value, dict):
            merged = dict(base)
            if key == "rocks" and any(k in value for k in SIZE_KEYS):
                for k in SIZE_KEYS:
                    merged.pop(k, None)
            merged.update(value)
            data[key] = merged
        else:
            data[key] = value
    return data


def split_sections(data: dict, lines: Lines, source: str) -> list[tuple[str, dict, Lines]]:
    """Check the corridor's structure; (name, project data, line map) per section.

    Raises
    ------
    ProjectError
        The structure is wrong: ``sections`` not a non-empty list of
        mappings, a section without a unique ``name``, an unknown key in a
        section, a section-only key (``slope``, ``protect``, ``measures``)
        at the top level, or ``rocks.seed`` in a section.
    """

    def error(path: tuple, message: str) -> ProjectError:
        return ProjectError(source, line_of(path, lines), key_text(path, lines), message)

    items = data["sections"]
    if not isinstance(items, list) or not items:
        raise error(("sections",), "expected a non-empty list of sections (mappings with a "
                    "name and a slope)")
    if len(items) > MAX_SECTIONS:
        raise error(("sections",), f"expected at most {MAX_SECTIONS:,} sections, "
                    f"got {len(items):,}")
    for key in SECTION_ONLY:
        if key in data:
            raise error((key,), f"with sections:, each section has its own {key}; move it "
                        "into the sections")
    shared_keys = {k: _keys(v, k in MERGED) for k, v in data.items() if k != "sections"}
    out = []
    names: dict[str, int] = {}
    slugs: dict[str, str] = {}
    for i, item in enumerate(items):
        at = ("sections", i)
        if not isinstance(item, dict):
            raise error(at, "expected a mapping (a section with name, slope, ...)")
        for key in item:
            if key not in SECTION_KEYS:
                hint = did_you_mean(str(key), SECTION_KEYS) or (
                    f"; a section takes {', '.join(SECTION_KEYS)}")
                raise error(at + (key,), f"unknown key{hint}")
        name = item.get("name")
        if not isinstance(name, str) or not name.strip():
            raise error(at + ("name",), "every section needs a name (a non-empty string)")
        if name in names:
            raise error(at + ("name",), f"section name {name!r} is given twice (first in "
                        f"sections[{names[name]}])")
        names[name] = i
        if slug(name) in slugs:
            raise error(at + ("name",), f"section names {slugs[slug(name)]!r} and {name!r} "
                        f"give the same directory name {slug(name)!r}")
        if slug(name).lower() in _TOP_FILES:
            raise error(at + ("name",), f"section {name!r}: its directory name "
                        f"{slug(name)!r} is a file the corridor writes beside the sections' "
                        "directories; rename the section")
        slugs[slug(name)] = name
        rocks = item.get("rocks")
        if isinstance(rocks, dict) and "seed" in rocks:
            raise error(at + ("rocks", "seed"), "a section's seed derives from the corridor's "
                        "rocks.seed and the section's index; set rocks.seed at the top level")
        for key in MERGED:
            if key in item and key in data and isinstance(data[key], dict) and not isinstance(
                    item[key], dict):
                raise error(at + (key,), f"expected a mapping, merged key by key into the "
                            f"shared {key}")
        given = {k: _keys(v, k in MERGED and isinstance(data.get(k), dict))
                 for k, v in item.items()}
        section_lines = _SectionLines(lines, i, given, shared_keys)
        project_data = _merge(data, item)
        if "name" in project_data and isinstance(data.get("name"), str):
            project_data["name"] = f"{data['name']} / {name}"
        _fill(section_lines, project_data)
        out.append((name, project_data, section_lines))
    return out


def _fill(section_lines: _SectionLines, data: Any) -> None:
    """Copy into ``section_lines`` the line of every project path of ``data`` (and the root)."""
    file_lines = section_lines.file_lines

    def visit(value: Any, path: tuple) -> None:
        where = section_lines.shown(path)
        if where in file_lines:
            section_lines[path] = file_lines[where]
        if isinstance(value, dict):
            for key, item in value.items():
                visit(item, path + (key,))
        elif isinstance(value, list):
            for i, item in enumerate(value):
                visit(item, path + (i,))

    visit(data, ())

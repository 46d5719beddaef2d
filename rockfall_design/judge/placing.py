"""Placing measures on the section.

The plugins' measures and safety concept built from the project
(:func:`build_measures`, :func:`build_concept`), their footprints placed on
the bare section and checked for fit and overlap (:func:`place_measures`),
and the section with the profile edits applied (:func:`edited_section`).
The plan (:mod:`rockfall_design.judge.plan`) does this once per command.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from ..engine import Section, barrier_table, columns
from ..plugins import blocked_provider, guard
from ..plugins.concept import SafetyConcept
from ..plugins.measure import Barrier, BarrierBehaviour, ProfileEdit, Stand
from .design_block import design_block_of

if TYPE_CHECKING:  # pragma: no cover
    from ..plugins import Registry
    from ..plugins.measure import ProtectiveMeasure
    from ..project import Project


#: Two barriers closer than this (m) stand in each other's place.
MIN_BARRIER_SPACING_M = 1.0


#: A barrier this close (m) to the edge of a profile edit stands on that edge.
_EDGE_TOLERANCE_M = 1e-6


_BEHAVIOUR_CODE = {
    BarrierBehaviour.NET: columns.B_NET,
    BarrierBehaviour.RIGID: columns.B_RIGID,
    BarrierBehaviour.BLOCKS: columns.B_BLOCKS,
}


#: What each registry section's names are, in messages.
_WHAT = {"measure": "measure type", "safety": "safety concept", "cost": "cost model"}


@dataclass(frozen=True)
class PlacedMeasure:
    """A measure with its footprint on the section and its place in the project.

    ``label`` is the measure's ``label()``, obtained once when it was placed.
    """

    index: int
    measure: ProtectiveMeasure
    footprint: Barrier | ProfileEdit
    label: str


def build_measures(project: Project, registry: Registry) -> list[ProtectiveMeasure]:
    """Instantiate the project's ``measures:`` through their plugins.

    Each entry's parameters are validated by the plugin's own model; errors
    name the file, line and key path.
    """
    out = []
    for i, raw in enumerate(project.measures):
        kind = raw["type"]
        cls = registry.measures.get(kind)
        if cls is None:
            raise unknown_measure_type(project, registry, ("measures", i, "type"), kind)
        params = project.validate_params(("measures", i), cls.Params, raw, drop=("type",))
        out.append(guard(registry).instantiate(cls, params))
    return out


def build_concept(project: Project, registry: Registry) -> SafetyConcept:
    """Instantiate the project's safety concept (``safety.concept``, default spang)."""
    raw = dict(project.safety)
    name = raw.get("concept", "spang")
    cls = registry.safety_concepts.get(name)
    if cls is None:
        raise unknown_plugin_name(project, registry, "safety", ("safety", "concept"), name)
    params = project.validate_params(("safety",), cls.Params, raw, drop=("concept",))
    concept = guard(registry).instantiate(cls, params)
    if project.rocks.design_block is not None:
        if not cls.uses_design_block:
            # A design input the concept would silently ignore.
            raise project.error_at(("rocks", "design_block"), (
                f"the safety concept {name!r} designs on the simulated rocks, not on one "
                "design block: choose a concept that uses it (uni11211, onr24810) or remove "
                "rocks.design_block"))
        # Bounded at the concept's confidence; a look of the optimiser at another
        # confidence keeps these bounds (judge.looks.look_concept).
        concept.design_block = design_block_of(project, params.confidence)
    return concept


def required_figures_problem(concept: SafetyConcept, measure_cls: Any,
                             values: dict[str, Any]) -> str | None:
    """What a measure (or catalogue product) lacks that the concept requires, or None.

    ``concept.required_measure_params`` names parameters the concept needs
    wherever a measure's parameter model has them; ``values`` are the
    parameters given (a measure's, or a catalogue product's entry).
    """
    fields = getattr(getattr(measure_cls, "Params", None), "model_fields", {})
    missing = [k for k in concept.required_measure_params
               if k in fields and values.get(k) is None]
    if not missing:
        return None
    return (f"the safety concept {concept.name!r} needs {', '.join(missing)} (the product's "
            "EAD 340059 test figures: take them from its European Technical Assessment)")


def place_measures(
    project: Project,
    registry: Registry,
    measures: Sequence[ProtectiveMeasure],
    section: Section,
) -> list[PlacedMeasure]:
    """Footprints of the measures on the bare section, checked for fit and overlap.

    Every measure's footprint, design properties and label are asked for
    here, through the guarded proxy :func:`~rockfall_design.plugins.guard`,
    before any safety concept or report uses the measure: one that misbehaves is
    named as itself, not as the safety concept that reads
    ``result.measure.design_properties()``.

    Raises
    ------
    ProjectError
        A measure does not fit on the section (its footprint raised
        ValueError), two profile edits overlap, two barriers stand in one
        place, or a measure lies outside the section.
    PluginError
        A measure misbehaved.
    """
    placed = []
    for i, m in enumerate(measures):
        try:
            fp = guard(registry).measure(m).footprint(section)
        except ValueError as exc:
            # A measure that does not fit the section is the user's to fix.
            raise project.error_at(("measures", i), str(exc)) from None
        guarded = guard(registry).measure(m)
        guarded.design_properties()
        placed.append(PlacedMeasure(i, m, fp, guarded.label()))
    edits = sorted(
        (p for p in placed if isinstance(p.footprint, ProfileEdit)),
        key=lambda p: p.footprint.x_start,
    )
    for a, b in zip(edits, edits[1:], strict=False):
        if b.footprint.x_start < a.footprint.x_end:
            raise project.error_at(
                ("measures", b.index),
                f"{b.label} overlaps {a.label} (measures[{a.index}]): "
                f"the ground from x = {b.footprint.x_start:g} m to "
                f"{a.footprint.x_end:g} m would be edited twice",
            )
    bars = sorted((p for p in placed if isinstance(p.footprint, Barrier)),
                  key=lambda p: p.footprint.x)
    for a, b in zip(bars, bars[1:], strict=False):
        if b.footprint.x - a.footprint.x < MIN_BARRIER_SPACING_M:
            raise project.error_at(
                ("measures", b.index, "x"),
                f"{b.label} stands where {a.label} (measures[{a.index}]) "
                f"stands; barriers must be at least {MIN_BARRIER_SPACING_M:g} m apart",
            )
    for b in bars:
        for e in edits:
            lo, hi = e.footprint.x_start, e.footprint.x_end
            # A barrier stands on the ground as the section gives it; inside a
            # stretch that another measure digs out or fills, that ground is
            # gone. At the stretch's edges the ground is unchanged, so a fence
            # on the outer edge of a ditch or berm is fine.
            # A forest keeps the ground: a fence may stand in it.
            if (e.footprint.forest is None
                    and lo + _EDGE_TOLERANCE_M < b.footprint.x < hi - _EDGE_TOLERANCE_M):
                raise project.error_at(
                    ("measures", b.index, "x"),
                    f"{b.label} stands inside {e.label} (measures[{e.index}]), which "
                    f"reshapes the ground from x = {lo:g} m to {hi:g} m; place it at an edge "
                    "of that stretch or outside it",
                )
    x0, x1 = section.x[0], section.x[-1]
    for p in placed:
        fp = p.footprint
        lo, hi = (fp.x, fp.x) if isinstance(fp, Barrier) else (fp.x_start, fp.x_end)
        if lo < x0 or hi > x1:
            raise project.error_at(
                ("measures", p.index, "x"),
                f"{p.label} lies outside the section ({x0:g} to {x1:g} m)",
            )
    return placed


def edited_section(project: Project, section: Section, placed: Sequence[PlacedMeasure]) -> Section:
    """The section with every profile edit spliced into the ground.

    New segments take the edit's material, or else the material of the
    original ground at their midpoint; under an edit with a ``forest`` (a
    protection forest), a copy of that material carrying the stand.
    """
    edits = sorted(
        (p for p in placed if isinstance(p.footprint, ProfileEdit)),
        key=lambda p: p.footprint.x_start,
    )
    if not edits:
        return section
    names = list(project.materials)
    xs, ys, mats = [section.x[0]], [section.y[0]], []

    def original_material(xm: float) -> int:
        k = int(np.clip(np.searchsorted(section.x, xm, side="right") - 1, 0, section.x.size - 2))
        return int(section.segment_material[k])

    def extend(px: np.ndarray, py: np.ndarray, mat: int | None) -> None:
        for x, y in zip(px, py, strict=True):
            if x <= xs[-1]:
                continue
            mats.append(original_material(0.5 * (xs[-1] + x)) if mat is None else mat)
            xs.append(float(x))
            ys.append(float(y))

    materials = list(section.materials)
    copies: dict[tuple[int, Stand], int] = {}

    def forested(mat: int, stand: Stand) -> int:
        # One copy of each material per stand, carrying the stand's trees.
        if (mat, stand) not in copies:
            materials.append(replace(section.materials[mat], **asdict(stand)))
            copies[(mat, stand)] = len(materials) - 1
        return copies[(mat, stand)]

    cursor = section.x[0]
    for p in edits:
        e = p.footprint
        keep = (section.x > cursor) & (section.x < e.x_start)
        extend(section.x[keep], section.y[keep], None)
        pts = np.asarray(e.points, dtype=float)
        if e.material is not None and e.material not in names:
            raise project.unknown_name(
                ("measures", p.index, "material"), e.material, names, "material"
            )
        mat = None if e.material is None else names.index(e.material)
        extend(pts[:1, 0], pts[:1, 1], None)
        first = len(mats)
        extend(pts[1:, 0], pts[1:, 1], mat)
        if e.forest is not None:
            mats[first:] = [forested(m, e.forest) for m in mats[first:]]
        cursor = e.x_end
    keep = section.x > cursor
    extend(section.x[keep], section.y[keep], None)
    return Section(
        np.asarray(xs), np.asarray(ys), np.asarray(mats, dtype=np.int64), tuple(materials)
    )


def _mel_columns(fp: Barrier) -> dict[str, float]:
    """A net's SEL (J) and its SEL and MEL elongations (m) for the engine, 0 where not given.

    The SEL defaults to a third of the MEL, as EAD 340059 defines it, where
    the kit gives an SEL elongation but no SEL energy.
    """
    def given(v: float) -> float:
        return 0.0 if math.isnan(v) else float(v)

    if fp.behaviour != BarrierBehaviour.NET:
        return {}
    sel_kj = fp.capacity_kj / 3.0 if math.isnan(fp.sel_kj) else fp.sel_kj
    return {"sel_j": sel_kj * 1e3, "elongation_sel_m": given(fp.elongation_sel_m),
            "elongation_mel_m": given(fp.elongation_mel_m)}


def barrier_rows(placed: Sequence[PlacedMeasure]) -> tuple[np.ndarray, list[int]]:
    """The engine's barrier table of the placed barriers, and the index of each row's measure."""
    rows, owners = [], []
    for p in placed:
        fp = p.footprint
        if isinstance(fp, Barrier):
            rows.append(
                barrier_table(
                    fp.x,
                    fp.vertical_height_m,
                    fp.capacity_kj * 1e3,
                    _BEHAVIOUR_CODE[fp.behaviour],
                    restitution=fp.restitution,
                    gap_m=fp.gap_m,
                    spacing_m=fp.spacing_m,
                    **_mel_columns(fp),
                )
            )
            owners.append(p.index)
    if not rows:
        return np.zeros((0, columns.N_BARRIER_COLS)), owners
    return np.vstack(rows), owners


def unknown_measure_type(
    project: Project, registry: Registry, at: Sequence[str | int], kind: str
) -> Exception:
    """The error for an unknown measure type at key path ``at``.

    When plugins are blocked (``--block``) and one of them provides ``kind``,
    the message names it ("measure type 'catch_net' is provided by
    rockfall-catchnet, which is blocked (--block)"); otherwise it is an
    unknown name with "did you mean".
    """
    return unknown_plugin_name(project, registry, "measure", at, kind)


def unknown_plugin_name(project: Project, registry: Registry, section: str,
                        at: Sequence[str | int], name: Any) -> Exception:
    """The error for a name no loaded plugin provides, at key path ``at``.

    ``section`` is ``"measure"``, ``"safety"`` or ``"cost"``. When a blocked
    plugin (``--block``) provides the name, the message says so ("safety
    concept 'spang' is provided by rockfall-design, which is blocked
    (--block)"); otherwise it is an unknown name with "did you mean".
    """
    what = _WHAT[section]
    provider = (blocked_provider(registry, section, name)
                if registry.blocked and isinstance(name, str) else None)
    if provider is not None:
        return project.error_at(
            tuple(at), f"{what} {name!r} is provided by {provider}, which is blocked (--block)")
    names = {"measure": registry.measures, "safety": registry.safety_concepts,
             "cost": registry.cost_models}[section]
    return project.unknown_name(at, name, names, what)

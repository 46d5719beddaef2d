"""The design space: families of candidates, catalogue choices, stations on a grid.

A family is a multiset of candidates (each type alone, pairs, the same type
twice, up to ``design.max_measures``). A barrier candidate's designs are its
catalogue choices (product and height, options, continuous parameters on a
lattice of :data:`BARRIER_RANGE_STEPS` steps) at every station of a grid of
:data:`STATION_STEP_M`; a ground edit's are searched on a lattice
(:func:`variables_of`, :func:`decode`).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..plugins.measure import Barrier

if TYPE_CHECKING:  # pragma: no cover
    from ..judge.candidates import CandidateSpec
    from ..plugins.measure import ProtectiveMeasure

#: Spacing (m) of the stations where barrier candidates may stand.
STATION_STEP_M = 0.5
#: Continuous design variables take one of RANGE_STEPS + 1 values across their range.
RANGE_STEPS = 100
#: Lattice (m) of the continuous dimensions of ground edits (ditch width, ...).
EDIT_STEP_M = 0.25
#: Continuous parameters of a barrier candidate take BARRIER_RANGE_STEPS + 1 values.
BARRIER_RANGE_STEPS = 10


# ---- the search space of one family -------------------------------------------------


@dataclass(frozen=True)
class Var:
    """One coordinate of the search vector."""

    slot: int  # which measure of the family
    name: str  # the parameter (for a catalogue choice, the field the plugin declares)
    low: float
    high: float
    integer: bool
    options: tuple[Any, ...] = ()
    step: float = 0.0  # lattice of a continuous variable (0: 1/RANGE_STEPS of the range)
    # "x" (the station), "product" / "height" (index of a catalogue product, of
    # its height), "option" (index into options) or "range" (a value): the role,
    # never the parameter's name, says how a coordinate is decoded.
    role: str = "range"

    @property
    def lattice_step(self) -> float:
        """The step between two of its values: 1 for an index, else its lattice's."""
        if self.integer:
            return 1.0
        return self.step or (self.high - self.low) / RANGE_STEPS


def families(candidates: Sequence[CandidateSpec], max_measures: int) -> list[tuple[int, ...]]:
    """Every multiset of candidates with 1..max_measures members, in a stable order."""
    idx = range(len(candidates))
    out: list[tuple[int, ...]] = []
    for k in range(1, max_measures + 1):
        out.extend(itertools.combinations_with_replacement(idx, k))
    return out


def candidate_name(candidates: Sequence[CandidateSpec], i: int) -> str:
    """'fence', or 'fence 25-92 m' where several candidates share a type."""
    c = candidates[i]
    if sum(d.kind == c.kind for d in candidates) == 1:
        return c.kind
    return f"{c.kind} {c.x_range[0]:g}-{c.x_range[1]:g} m"


def family_name(candidates: Sequence[CandidateSpec], fam: tuple[int, ...]) -> str:
    """'fence + ditch', '2 x fence', 'fence 25-92 m + fence 113-280 m'."""
    counts: dict[int, int] = {}
    for i in fam:
        counts[i] = counts.get(i, 0) + 1
    names = [candidate_name(candidates, i) for i in counts]
    return " + ".join(nm if n == 1 else f"{n} x {nm}" for nm, n in zip(names, counts.values(),
                                                                        strict=True))


def variables_of(
    cands: Sequence[CandidateSpec], fam: tuple[int, ...], edits: set[int] | None = None
) -> list[Var]:
    out: list[Var] = []
    for slot, ci in enumerate(fam):
        c = cands[ci]
        out.append(Var(slot, "x", c.x_range[0], c.x_range[1], False, role="x"))
        if c.products:
            out.append(Var(slot, c.product_field or "", 0, len(c.products) - 1, True,
                            role="product"))
            if c.height_field is not None:
                nh = max(len(p.heights) for p in c.products)
                out.append(Var(slot, c.height_field, 0, nh - 1, True, role="height"))
        for name, (lo, hi) in c.ranges.items():
            step = (hi - lo) / RANGE_STEPS
            if edits and ci in edits:
                # Every new ground edit costs a run: a coarser lattice lets the
                # search come back to designs it has already run.
                step = max(step, EDIT_STEP_M if hi - lo > 4 * EDIT_STEP_M else step)
            out.append(Var(slot, name, lo, hi, False, step=step, role="range"))
        for name, opts in c.options.items():
            out.append(Var(slot, name, 0, len(opts) - 1, True, tuple(opts), role="option"))
    return out


def decode(cands, fam, variables, vec) -> list[tuple[int, dict[str, Any]]]:
    """Search vector -> [(candidate index, measure parameters)] ordered by station."""
    # Only what the search picks; build_candidate_measure adds the fixed values
    # and the product's own parameters.
    params: list[dict[str, Any]] = [{} for _ in fam]
    prods: list[Any] = [None] * len(fam)
    heights: list[int] = [0] * len(fam)
    for v, val in zip(variables, vec, strict=True):
        p = params[v.slot]
        if v.role == "x":
            # Stations on the lattice of the candidate's range (the table's stations).
            lo, hi = v.low, v.high
            k = min(round((float(val) - lo) / STATION_STEP_M),
                    math.floor((hi - lo) / STATION_STEP_M + 1e-9))
            p["x"] = float(lo + max(k, 0) * STATION_STEP_M)
        elif v.role == "product":
            prods[v.slot] = cands[fam[v.slot]].products[int(round(val))]
        elif v.role == "height":
            heights[v.slot] = int(round(val))
        elif v.role == "option":
            p[v.name] = v.options[int(round(val))]
        else:
            # A lattice of 1/RANGE_STEPS of the range: designs an engineer can
            # build, and repeated ground edits come from the cache.
            step = v.lattice_step
            if step > 0:
                k = min(round((float(val) - v.low) / step),
                        math.floor((v.high - v.low) / step + 1e-9))
                p[v.name] = float(v.low + k * step)
            else:
                p[v.name] = float(v.low)
    out = []
    for slot, ci in enumerate(fam):
        p = params[slot]
        prod = prods[slot]
        c = cands[ci]
        if prod is not None and c.product_field is not None:
            p[c.product_field] = prod.name
            if c.height_field is not None:
                p[c.height_field] = prod.heights[min(heights[slot], len(prod.heights) - 1)]
        out.append((ci, p))
    return out


# ---- the search space: barrier options, enumerated ----------------------------------


@dataclass
class Option:
    """One barrier of one candidate: its parameters, measure, footprint and cost."""

    ci: int
    params: dict[str, Any]
    measure: ProtectiveMeasure
    footprint: Barrier
    cost: float
    label: str
    j: int  # station of the table


def lattice(lo: float, hi: float, step: float) -> np.ndarray:
    """lo, lo + step, ... up to hi (inclusive within round-off)."""
    if hi <= lo or step <= 0:
        return np.array([float(lo)])
    return lo + step * np.arange(math.floor((hi - lo) / step + 1e-9) + 1)


def discrete_choices(c: CandidateSpec) -> list[dict[str, Any]]:
    """Every catalogue choice of a candidate: product and height, options, range lattice."""
    axes: list[list[dict[str, Any]]] = []
    if c.products and c.product_field is not None:
        pf, hf = c.product_field, c.height_field
        axes.append([{pf: p.name, hf: h} if hf is not None else {pf: p.name}
                     for p in c.products for h in (p.heights if hf is not None else (None,))])
    for name, opts in c.options.items():
        axes.append([{name: o} for o in opts])
    for name, (lo, hi) in c.ranges.items():
        axes.append([{name: float(v)} for v in lattice(lo, hi, (hi - lo) / BARRIER_RANGE_STEPS)])
    out = []
    for combo in itertools.product(*axes):
        d: dict[str, Any] = {}
        for part in combo:
            d.update(part)
        out.append(d)
    return out

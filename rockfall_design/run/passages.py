"""The rocks passing one place of the section: an analysis station or a barrier.

RocFall's data collectors and CRSP's analysis points give, at a place, the
distribution of what a fence there would see. :class:`Passages` holds it,
per rock that passed: passing height (vertical, and normal to the slope),
translational and angular speed, translational, rotational and total
kinetic energy; and the figures of the measure there to draw on them
(:class:`Mark`: a nominal height, a capacity, ...).

The stations' passages come from the run (:func:`station_passages`); a
barrier's from the judge, which knows the rocks that met it
(:meth:`rockfall_design.judge.evaluation.Evaluation.passages`), through
:func:`barrier_values`. Both use the same quantities (:data:`QUANTITIES`),
so the summary, ``barriers.csv`` and the figures say the same of either.

The height normal to the slope is the distance of the rock centre from the
ground line of the segment the place lies on, ``h cos(beta)`` with ``h``
the vertical passing height and ``beta`` that segment's inclination (at a
vertex, the upslope segment's: the one the rocks come over). EAD 340059
measures a fence's nominal height this way, perpendicular to the slope.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .summary import stat_block

if TYPE_CHECKING:  # pragma: no cover
    from ..engine import Section
    from .simulation import SimulationRun

__all__ = ["QUANTITIES", "Mark", "Passages", "slope_deg_at", "barrier_values",
           "station_passages", "property_marks", "passage_block"]

#: The quantities of a passage: key (as in the summary), what it is, unit.
QUANTITIES: tuple[tuple[str, str, str], ...] = (
    ("passing_height_m", "passing height of the centre, vertical", "m"),
    ("passing_height_normal_m", "passing height of the centre, normal to the slope", "m"),
    ("velocity_ms", "translational speed", "m/s"),
    ("angular_speed_rads", "angular speed", "rad/s"),
    ("translational_energy_kj", "translational kinetic energy", "kJ"),
    ("rotational_energy_kj", "rotational kinetic energy", "kJ"),
    ("energy_kj", "total kinetic energy", "kJ"),
)


@dataclass(frozen=True)
class Mark:
    """A figure of a measure drawn on the distribution of one quantity.

    Attributes
    ----------
    label : str
        What it is, e.g. "height (4 m)" or "capacity (1,000 kJ)".
    quantity : str
        The key in :data:`QUANTITIES` it is drawn on.
    value : float
        In the quantity's unit.
    """

    label: str
    quantity: str
    value: float


@dataclass
class Passages:
    """The rocks passing one place, one value per rock and quantity.

    Attributes
    ----------
    place : str
        ``"station"`` or ``"measure"``.
    index : int
        Position of the station in ``analysis.stations`` or of the measure in
        ``measures:`` (from 0).
    label : str
        "station at x = 110 m" or the measure's label.
    x : float
        Station (m).
    slope_deg : float
        Inclination of the ground there (degrees, positive downslope).
    values : dict of str to ndarray
        Per key of :data:`QUANTITIES`, one value per rock that passed (or met
        the measure), in the key's unit.
    marks : tuple of Mark
    """

    place: str
    index: int
    label: str
    x: float
    slope_deg: float
    values: dict[str, np.ndarray]
    marks: tuple[Mark, ...] = ()

    @property
    def rocks(self) -> int:
        """Rocks that passed (or met the measure)."""
        return int(self.values["passing_height_m"].size)

    def block(self) -> dict[str, Any]:
        """JSON-ready: :func:`passage_block` of these values."""
        return passage_block(self.values, self.slope_deg, self.marks)


def passage_block(values: Mapping[str, np.ndarray], slope_deg: float,
                  marks: tuple[Mark, ...] = ()) -> dict[str, Any]:
    """The statistics of a place: ``rocks``, ``slope_deg``, a block per quantity, ``marks``.

    Each quantity's block is :func:`~rockfall_design.run.summary.stat_block`
    (mean, p50, p95, p99, max; None without a rock).
    """
    out: dict[str, Any] = {"rocks": int(np.size(values["passing_height_m"])),
                           "slope_deg": round(float(slope_deg), 6)}
    for key, _, _ in QUANTITIES:
        out[key] = stat_block(values[key])
    out["marks"] = [{"label": m.label, "quantity": m.quantity, "value": m.value}
                    for m in marks]
    return out


def slope_deg_at(section: Section, x: float) -> float:
    """Inclination (degrees, positive where the ground falls downslope) at ``x``.

    The segment that holds ``x``; at a vertex the upslope one, over which
    the rocks arrive.
    """
    i = int(np.clip(np.searchsorted(section.x, x, side="left") - 1, 0, section.x.size - 2))
    dx = section.x[i + 1] - section.x[i]
    dy = section.y[i] - section.y[i + 1]
    return math.degrees(math.atan2(dy, dx))


def barrier_values(height_m: np.ndarray, speed_ms: np.ndarray, energy_kj: np.ndarray,
                   mass_kg: np.ndarray, radius_m: np.ndarray, slope_deg: float
                   ) -> dict[str, np.ndarray]:
    """Every quantity of :data:`QUANTITIES` from what a barrier records of a meeting.

    A meeting gives the vertical passing height (m), the speed (m/s) and the
    total kinetic energy (kJ); with the rock's mass (kg) and radius (m) the
    rest follows for a sphere (moment of inertia 2/5 m r^2): translational
    energy 1/2 m v^2, rotational energy the difference (clipped at 0 against
    rounding), angular speed ``sqrt(2 E_rot / I)`` (its sense is not
    recorded, so it is the magnitude).

    Parameters
    ----------
    height_m, speed_ms, energy_kj, mass_kg, radius_m : ndarray
        One value per rock that met the barrier.
    slope_deg : float
        Inclination of the ground at the barrier (degrees).

    Returns
    -------
    dict of str to ndarray
    """
    h = np.asarray(height_m, dtype=float)
    v = np.asarray(speed_ms, dtype=float)
    m = np.asarray(mass_kg, dtype=float)
    r = np.asarray(radius_m, dtype=float)
    e = np.asarray(energy_kj, dtype=float)
    e_tr = 0.5 * m * v**2 / 1e3
    e_rot = np.maximum(e - e_tr, 0.0)
    inertia = 0.4 * m * r**2
    with np.errstate(invalid="ignore", divide="ignore"):
        w = np.where(inertia > 0, np.sqrt(2e3 * e_rot / np.where(inertia > 0, inertia, 1.0)),
                     0.0)
    return {"passing_height_m": h,
            "passing_height_normal_m": h * math.cos(math.radians(slope_deg)),
            "velocity_ms": v, "angular_speed_rads": w, "translational_energy_kj": e_tr,
            "rotational_energy_kj": e_rot, "energy_kj": e}


def property_marks(properties: Mapping[str, float]) -> tuple[Mark, ...]:
    """The marks of a measure's design properties, read by their names' units.

    A property whose name holds ``height`` and ends in ``_m`` (a nominal or
    residual height) is drawn on both passing heights; one ending in ``_kj``
    (a capacity, an SEL or MEL) on the total energy. Other properties (a
    width, an elongation) are not quantities of a passage. So a product
    that gives more figures shows them with no change here.
    """
    out: list[Mark] = []
    for key, value in properties.items():
        if value is None or not math.isfinite(float(value)):
            continue
        base = key.rsplit("_", 1)[0]
        words = base.replace("_", " ")
        name = words.upper() if len(base) <= 3 else words
        if key.endswith("_m") and "height" in key:
            label = f"{name} ({float(value):.3g} m)"
            out += [Mark(label, "passing_height_m", float(value)),
                    Mark(label, "passing_height_normal_m", float(value))]
        elif key.endswith("_kj"):
            out.append(Mark(f"{name} ({float(value):,.0f} kJ)", "energy_kj", float(value)))
    return tuple(out)


def station_passages(run: SimulationRun) -> list[Passages]:
    """The passages of every analysis station of an in-memory run (first passage downslope)."""
    a = run.crossing_arrays()
    out = []
    for j, xs in enumerate(run.stations):
        passed = np.isfinite(a["passing_height_m"][:, j])
        values = {key: np.asarray(a[key if key in a else _ARRAY[key]][passed, j], dtype=float)
                  / _SCALE.get(key, 1.0) for key, _, _ in QUANTITIES}
        out.append(Passages("station", j, f"station at x = {float(xs):g} m", float(xs),
                            slope_deg_at(run.section, float(xs)), values))
    return out


#: Keys of QUANTITIES whose array in ``SimulationRun.crossing_arrays`` is named otherwise, in J.
_ARRAY = {"translational_energy_kj": "translational_energy_j",
          "rotational_energy_kj": "rotational_energy_j", "energy_kj": "energy_j"}
_SCALE = {"translational_energy_kj": 1e3, "rotational_energy_kj": 1e3, "energy_kj": 1e3}

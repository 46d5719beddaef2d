"""The contract of a protective measure: what a measure plugin fills in.

A measure is a class with a unique ``kind`` (the ``type:`` of the project
file), a strict parameter model, an example, and methods that say

* where it stands and what it does to rocks (:meth:`ProtectiveMeasure.footprint`):
  either a :class:`Barrier` at a station, which does not change the ground
  (fence, wall, boulder row), or a :class:`ProfileEdit`, which replaces the
  ground over a stretch of the section (ditch, berm);
* what its design properties are (:meth:`ProtectiveMeasure.design_properties`),
  which safety concepts check against the rocks' passing heights, energies
  and reach;
* what quantities it takes per running metre of slope, for costing
  (:meth:`ProtectiveMeasure.quantities`).

The engine never calls a measure: the footprints are turned into plain arrays
once, before the rocks run (``evaluate.py``). A barrier acts on a rock with
one of the behaviours of :class:`BarrierBehaviour`, evaluated exactly where
the rock's path crosses the barrier's station, in either direction.
"""

from __future__ import annotations

import enum
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

if TYPE_CHECKING:  # pragma: no cover
    from .engine import Section

__all__ = [
    "BarrierBehaviour",
    "Barrier",
    "ProfileEdit",
    "ProtectiveMeasure",
    "MeasureParams",
    "Outcome",
    "MeasureResult",
]


class MeasureParams(BaseModel):
    """Base of a measure's parameter model: strict, units in names and descriptions.

    Subclasses declare their own fields; every measure has a station ``x`` (m).
    ``type`` is consumed by the loader and never reaches the model.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    x: float = Field(json_schema_extra={"unit": "m"})
    """Station of the measure (m): its x, or the upslope edge of an edited stretch."""


class BarrierBehaviour(enum.IntEnum):
    """What a barrier does to a rock whose centre passes at or below its top.

    A rock whose centre passes above the top (passing height > height) flies
    or rolls on unchanged ("passed over") with every behaviour.
    """

    #: Flexible net: the rock is caught if its total kinetic energy is within
    #: the capacity; otherwise it breaks through and goes on with the surplus
    #: energy (velocity and spin scaled by sqrt((E - capacity) / E)).
    NET = 0
    #: Rigid wall: within capacity the rock rebounds, its horizontal velocity
    #: reversed and scaled by the wall's restitution (vertical velocity and
    #: spin kept); beyond capacity the wall fails and the rock goes on with the
    #: surplus energy.
    RIGID = 1
    #: Row of blocks with gaps: a rock of diameter D passes through a gap with
    #: probability max(0, gap - D) / spacing (drawn from the rock's own random
    #: stream); otherwise it strikes a block and is stopped within capacity,
    #: or displaces it and goes on with the surplus energy.
    BLOCKS = 2


@dataclass(frozen=True)
class Barrier:
    """An obstacle at a station that leaves the ground as it is.

    Attributes
    ----------
    x : float
        Station (m). The rock meets the barrier where its centre crosses x.
    height_m : float
        Height of the barrier's top above the ground at x (m).
    capacity_kj : float
        Energy the barrier can take (kJ); ``inf`` for none given.
    behaviour : BarrierBehaviour
    restitution : float
        RIGID: coefficient of restitution of the rebound (-), 0..1.
    gap_m : float
        BLOCKS: clear width of a gap between blocks (m).
    spacing_m : float
        BLOCKS: centre-to-centre spacing of the blocks (m), > 0.
    """

    x: float
    height_m: float
    capacity_kj: float
    behaviour: BarrierBehaviour
    restitution: float = 0.0
    gap_m: float = 0.0
    spacing_m: float = 1.0


@dataclass(frozen=True)
class ProfileEdit:
    """A stretch of ground replaced by new vertices (an excavation or a fill).

    Attributes
    ----------
    x_start, x_end : float
        The stretch replaced (m), x_start < x_end. The new ground must meet the
        old one at both ends.
    points : ndarray, shape (k, 2)
        New ground vertices (m) from (x_start, y(x_start)) to
        (x_end, y(x_end)), x strictly increasing.
    catch_from, catch_to : float
        Rocks that come to rest with their centre in [catch_from, catch_to]
        (m) are caught by the measure.
    material : str or None
        Material of the new segments; None keeps the material of the
        original ground at each new segment.
    """

    x_start: float
    x_end: float
    points: np.ndarray
    catch_from: float
    catch_to: float
    material: str | None = None


class Outcome(enum.IntEnum):
    """What happened when a rock first met a measure (per rock and measure)."""

    NOT_MET = 0
    CAUGHT = 1
    PASSED_OVER = 2
    BROKEN_THROUGH = 3
    REBOUNDED = 4
    PASSED_THROUGH_GAP = 5


@dataclass
class MeasureResult:
    """What the rocks did at one measure: the input of the safety concepts.

    Arrays are over the rocks that met the measure (first meeting), in rock
    order. For a barrier: its station was crossed; for a profile edit: the
    rock's centre reached ``x_start``.

    Attributes
    ----------
    measure : ProtectiveMeasure
    index : int
        Position of the measure in the project's ``measures:`` list.
    n_rocks : int
        Rocks in the run.
    met, caught, passed_over, broken_through, rebounded, passed_through_gap : int
        Counts (each rock counted once, by its first meeting).
    passing_height_m : ndarray
        Passing height of the rock centre above the ground at the station (m);
        empty for profile edits.
    velocity_ms : ndarray
        Speed there (m/s).
    energy_kj : ndarray
        Total kinetic energy there (kJ).
    mass_kg, radius_m : ndarray
        Of the rocks that met the measure.
    reach_m : ndarray
        Profile edits: how far beyond ``x_start`` each rock that met the
        measure went (its largest x minus x_start, m); a rock that left the
        caught stretch has a reach beyond it. Empty for barriers.
    """

    measure: ProtectiveMeasure
    index: int
    n_rocks: int
    met: int = 0
    caught: int = 0
    passed_over: int = 0
    broken_through: int = 0
    rebounded: int = 0
    passed_through_gap: int = 0
    passing_height_m: np.ndarray = field(default_factory=lambda: np.zeros(0))
    velocity_ms: np.ndarray = field(default_factory=lambda: np.zeros(0))
    energy_kj: np.ndarray = field(default_factory=lambda: np.zeros(0))
    mass_kg: np.ndarray = field(default_factory=lambda: np.zeros(0))
    radius_m: np.ndarray = field(default_factory=lambda: np.zeros(0))
    reach_m: np.ndarray = field(default_factory=lambda: np.zeros(0))


class ProtectiveMeasure(ABC):
    """Base class of every protective measure.

    Subclasses set the class attributes and implement :meth:`footprint`,
    :meth:`design_properties` and :meth:`quantities`. They are registered by
    returning the class from the ``rockfall_design_measures`` hook (see
    ``hookspecs.py``).

    Class attributes
    ----------------
    kind : str
        Unique name, the ``type:`` in the project file (lower case, no spaces).
    summary : str
        One line for ``rockfall-design plugins`` and reports.
    Params : type of MeasureParams
        The strict parameter model (units in field names or descriptions).
    example : dict
        A complete valid parameter set (without ``type``), used in the docs
        and tests.
    design_variables : dict
        Names of the parameters an optimiser may vary, each with its default
        (low, high) bounds; empty if none.
    """

    kind: ClassVar[str]
    summary: ClassVar[str] = ""
    Params: ClassVar[type[MeasureParams]]
    example: ClassVar[dict[str, Any]] = {}
    design_variables: ClassVar[dict[str, tuple[float, float]]] = {}

    def __init__(self, params: MeasureParams) -> None:
        self.params = params

    @property
    def x(self) -> float:
        """Station of the measure (m)."""
        return float(self.params.x)

    def label(self) -> str:
        """A short human-readable name, e.g. 'fence at x = 70 m'."""
        return f"{self.kind} at x = {self.x:g} m"

    @abstractmethod
    def footprint(self, section: Section) -> Barrier | ProfileEdit:
        """Where the measure stands and what it does to rocks.

        Parameters
        ----------
        section : rockfall_design.engine.Section
            The slope section the measure stands on (before any edits of
            other measures), for ground heights and geometry checks.

        Returns
        -------
        Barrier or ProfileEdit

        Raises
        ------
        ValueError
            If the measure does not fit on the section (the message is shown
            to the user with the measure's key path).
        """

    @abstractmethod
    def design_properties(self) -> dict[str, float]:
        """The properties that safety checks compare with the rocks.

        Known keys: ``height_m`` (nominal height of a barrier), ``capacity_kj``
        (energy capacity), ``width_m`` (width of a catch area such as a
        ditch or berm). A safety concept checks what is present.
        """

    def quantities(self, section: Section) -> dict[str, float]:
        """Quantities per running metre of slope, for costing.

        Keys are free (a cost model documents those it prices), e.g.
        ``height_m``, ``capacity_kj``, ``excavation_m3_per_m``,
        ``blocks_per_m``. The default is the design properties.
        """
        return dict(self.design_properties())

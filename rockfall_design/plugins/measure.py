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
* what quantities it takes per running metre of slope, for costing: named
  and priced by name (:meth:`ProtectiveMeasure.bill`, a list of
  :class:`Quantity`), or as the older free dict
  (:meth:`ProtectiveMeasure.quantities`);
* which of its parameters are design variables, in each ``Params`` field's
  metadata (:data:`DESIGN_KEY`, read by :func:`design_role`).

The engine never calls a measure: the footprints are turned into plain arrays
once, before the rocks run (``evaluate.py``). A barrier acts on a rock with
one of the behaviours of :class:`BarrierBehaviour`, evaluated exactly where
the rock's path crosses the barrier's station, in either direction.
"""

from __future__ import annotations

import enum
import math
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

if TYPE_CHECKING:  # pragma: no cover
    from ..engine import Section

__all__ = [
    "BarrierBehaviour",
    "Barrier",
    "ProfileEdit",
    "ProtectiveMeasure",
    "MeasureParams",
    "Outcome",
    "MeasureResult",
    "Quantity",
    "DESIGN_KEY",
    "DESIGN_ROLES",
    "DesignRole",
    "design_role",
]

#: The key of a ``Params`` field's ``json_schema_extra`` that makes it a design variable.
DESIGN_KEY = "design"
#: The string values ``json_schema_extra={"design": ...}`` may take (see :func:`design_role`).
DESIGN_ROLES = ("catalogue", "catalogue_height", "catalogue_capacity", "options")


class MeasureParams(BaseModel):
    """Base of a measure's parameter model: strict, units in names and descriptions.

    Subclasses declare their own fields; every measure has a station ``x`` (m).
    ``type`` is consumed by the loader and never reaches the model.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    x: float = Field(json_schema_extra={"unit": "m"})
    """Station of the measure (m): its x, or the upslope edge of an edited stretch."""


@dataclass(frozen=True)
class DesignRole:
    """What the optimiser may do with one parameter, as its plugin declares it.

    Read from the field's metadata by :func:`design_role`; see the
    ``DESIGN_KEY`` vocabulary there.

    Attributes
    ----------
    role : str
        ``"range"`` (a free continuous variable within ``bounds``),
        ``"options"`` (a free discrete variable, one of ``options``),
        ``"catalogue"`` (the name of a catalogue product),
        ``"catalogue_height"`` (one of the heights the product comes in, m),
        ``"catalogue_capacity"`` (the product's energy class, kJ).
    bounds : (float, float) or None
        For ``"range"``: default (low, high), in the field's unit.
    options : tuple or None
        For ``"options"``: the default options.
    """

    role: str
    bounds: tuple[float, float] | None = None
    options: tuple[Any, ...] | None = None


def _literal_options(annotation: Any) -> tuple[Any, ...] | None:
    """The values of a ``Literal`` or ``Enum`` annotation (``X | None`` too), or None."""
    import typing

    args = [annotation]
    if typing.get_origin(annotation) is not None and typing.get_origin(annotation) is not Literal:
        args = [a for a in typing.get_args(annotation) if a is not type(None)]
    values: list[Any] = []
    for a in args:
        if typing.get_origin(a) is Literal:
            values += list(typing.get_args(a))
        elif isinstance(a, type) and issubclass(a, enum.Enum):
            values += [m.value for m in a]
        else:
            return None
    return tuple(values) or None


def design_role(model: type[BaseModel], name: str) -> DesignRole | None:
    """The design role that field ``name`` of ``model`` declares, or None.

    A field declares it in its metadata, ``Field(..., json_schema_extra=
    {"design": VALUE})``, where VALUE is

    * ``{"bounds": [low, high]}``: a free continuous design variable, searched
      within these bounds unless the project's candidate gives a value, a
      range or options;
    * ``{"options": [a, b, ...]}``: a free discrete design variable;
    * ``"options"``: a free discrete variable over every value of the field's
      ``Literal`` (or ``Enum``) type;
    * ``"catalogue"``: the catalogue product (a ``str`` field): the optimiser
      picks it among ``design.products`` of the measure's type;
    * ``"catalogue_height"``: one of the heights (m) the chosen product comes in;
    * ``"catalogue_capacity"``: the chosen product's energy class (kJ).

    Parameters
    ----------
    model
        A measure's ``Params``.
    name
        A field of it.

    Returns
    -------
    DesignRole or None
        None where the field declares nothing.

    Raises
    ------
    ValueError
        If the declaration is not one of the above (a fault of the plugin).
    """
    info = model.model_fields[name]
    extra = info.json_schema_extra
    if not isinstance(extra, dict) or DESIGN_KEY not in extra:
        return None
    value = extra[DESIGN_KEY]
    where = f"{model.__name__}.{name}: json_schema_extra {DESIGN_KEY!r}"
    if value == "options":
        options = _literal_options(info.annotation)
        if not options:
            raise ValueError(f"{where} is 'options' but the field is not a Literal or an Enum")
        return DesignRole("options", options=options)
    if value in ("catalogue", "catalogue_height", "catalogue_capacity"):
        return DesignRole(str(value))
    if isinstance(value, dict) and set(value) == {"bounds"}:
        bounds = value["bounds"]
        try:
            low, high = (float(b) for b in bounds)
        except (TypeError, ValueError):
            raise ValueError(f"{where}: bounds must be [low, high], got {bounds!r}") from None
        if not low < high:
            raise ValueError(f"{where}: bounds must be [low, high] with low < high, got {bounds!r}")
        return DesignRole("range", bounds=(low, high))
    if isinstance(value, dict) and set(value) == {"options"}:
        options = value["options"]
        if not isinstance(options, list | tuple) or not options:
            raise ValueError(f"{where}: options must be a non-empty list, got {options!r}")
        return DesignRole("options", options=tuple(options))
    raise ValueError(
        f"{where} = {value!r}: expected {{'bounds': [low, high]}}, {{'options': [...]}}, "
        "'options', 'catalogue', 'catalogue_height' or 'catalogue_capacity'"
    )


@dataclass(frozen=True)
class Quantity:
    """A named quantity a measure takes per running metre of slope, for costing.

    Attributes
    ----------
    name : str
        What is priced, e.g. ``"fence"`` (running metres of a fence product),
        ``"excavation_m3"``, ``"fill_m3"``, ``"block_m3"``, or any name a plugin
        invents (``"embankment_fill_m3"``). The cost model prices it by this
        name; a measure may ship default prices for its own names
        (:attr:`ProtectiveMeasure.default_prices`).
    amount : float
        Amount per running metre of slope, in ``unit`` per m (>= 0, finite).
    unit : str
        Unit of the amount before "per running metre": ``"m"``, ``"m3"``, ...
    product : str or None
        Catalogue product, where the price depends on it.
    size : float or None
        Size of the product where the price depends on it (e.g. a fence's
        height, m).
    """

    name: str
    amount: float
    unit: str
    product: str | None = None
    size: float | None = None


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
    slope_cos : float
        Cosine of the inclination of the ground the barrier stands on (-),
        in (0, 1]: a passing height measured vertically times this is the
        passing height perpendicular to the slope. 1 (level ground) unless
        the measure says.
    height_normal : bool
        ``height_m`` is measured perpendicular to the slope (a fence's
        nominal height, as EAD 340059 defines it), not vertically: the rock's
        centre passes over where its vertical passing height exceeds
        ``height_m / slope_cos`` (:attr:`vertical_height_m`).
    sel_kj : float
        NET: service energy level of the kit (kJ), below ``capacity_kj``
        (its MEL); NaN for none given.
    elongation_sel_m, elongation_mel_m : float
        NET: elongation of the kit in its SEL test and maximum elongation in
        its MEL test (m); NaN for none given. A rock the net catches comes
        to rest its braking distance downslope of ``x``, interpolated by its
        energy between the two tests
        (:func:`rockfall_design.engine.barriers.braking_distance`); without
        ``elongation_mel_m`` it stops at ``x``.
    """

    x: float
    height_m: float
    capacity_kj: float
    behaviour: BarrierBehaviour
    restitution: float = 0.0
    gap_m: float = 0.0
    spacing_m: float = 1.0
    slope_cos: float = 1.0
    height_normal: bool = False
    sel_kj: float = math.nan
    elongation_sel_m: float = math.nan
    elongation_mel_m: float = math.nan

    @property
    def vertical_height_m(self) -> float:
        """Height of the top above the ground at ``x``, measured vertically (m).

        For a height measured perpendicular to the slope (``height_normal``),
        ``height_m / slope_cos``: a rock's centre at that vertical height is
        ``height_m`` from a planar slope of that inclination.
        """
        return self.height_m / self.slope_cos if self.height_normal else self.height_m


@dataclass(frozen=True)
class Stand:
    """A stand of trees a measure grows or keeps on its stretch (a protection forest).

    Attributes
    ----------
    stems_per_ha : float
        Stems per hectare of map area, > 0.
    dbh_mean_cm, dbh_sd_cm : float
        Mean (> 0) and standard deviation (>= 0, at most the mean) of the
        stems' diameter at breast height (cm).
    tree_height_m : float
        Height (m) up to which a passing rock's centre meets a stem.

    See Also
    --------
    rockfall_design.engine.forest : what a stem does to a rock.
    """

    stems_per_ha: float
    dbh_mean_cm: float
    dbh_sd_cm: float
    tree_height_m: float


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
    forest : Stand or None
        Trees on the stretch: each new segment's material carries this
        stand (a protection forest; the points then follow the ground
        unchanged, and a barrier may stand inside the stretch).
    """

    x_start: float
    x_end: float
    points: np.ndarray
    catch_from: float
    catch_to: float
    material: str | None = None
    forest: Stand | None = None


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
        Passing height of the rock centre above the ground at the station,
        measured vertically (m); empty for profile edits.
    passing_height_normal_m : ndarray
        The same, measured perpendicular to the slope the barrier stands on
        (m, ``passing_height_m`` times the barrier's ``slope_cos``).
    height_normal : bool
        The measure's height is rated perpendicular to the slope (a fence's
        nominal height): its height checks use ``passing_height_normal_m``
        (see :attr:`rated_passing_height_m`).
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
    clearance_m : float or None
        Barriers: how far downslope of the station the protected zone starts
        (``protect.x`` - x, m; negative if the station is inside it), for the
        braking-distance check of a fence; None for profile edits and
        without a protected zone.
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
    passing_height_normal_m: np.ndarray = field(default_factory=lambda: np.zeros(0))
    height_normal: bool = False
    velocity_ms: np.ndarray = field(default_factory=lambda: np.zeros(0))
    energy_kj: np.ndarray = field(default_factory=lambda: np.zeros(0))
    mass_kg: np.ndarray = field(default_factory=lambda: np.zeros(0))
    radius_m: np.ndarray = field(default_factory=lambda: np.zeros(0))
    reach_m: np.ndarray = field(default_factory=lambda: np.zeros(0))
    clearance_m: float | None = None

    @property
    def rated_passing_height_m(self) -> np.ndarray:
        """The passing heights to compare with the measure's own height (m).

        Perpendicular to the slope for a measure whose height is rated so (a
        fence's nominal height, EAD 340059), else vertical.
        """
        return self.passing_height_normal_m if self.height_normal else self.passing_height_m


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
        (low, high) bounds; empty if none. A field's own declaration in its
        metadata (``json_schema_extra={"design": ...}``, see
        :func:`design_role`) takes precedence.
    default_prices : dict
        Prices of the measure's own quantities (:meth:`bill`) by name, in the
        cost catalogue's currency per unit of the quantity: a number, or a
        table product -> size -> price. The project's cost catalogue
        overrides them. Empty by default.
    """

    kind: ClassVar[str]
    summary: ClassVar[str] = ""
    Params: ClassVar[type[MeasureParams]]
    example: ClassVar[dict[str, Any]] = {}
    design_variables: ClassVar[dict[str, tuple[float, float]]] = {}
    default_prices: ClassVar[dict[str, Any]] = {}

    def __init__(self, params: MeasureParams) -> None:
        self.params = params

    @property
    def x(self) -> float:
        """Station of the measure (m)."""
        return float(self.params.x)

    def label(self) -> str:
        """A short human-readable name, e.g. 'fence at x = 70 m'."""
        return f"{self.kind} at x = {self.x:g} m"

    def without_station(self) -> tuple[str, str]:
        """What the measure is wherever it stands: its kind and its parameters but ``x``.

        Two designs whose measures agree in this differ only in where they
        stand: the optimiser budgets their decisions together.
        """
        return self.kind, repr(sorted(self.params.model_dump(exclude={"x"}).items()))

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

    def bill(self, section: Section) -> list[Quantity]:
        """Named quantities per running metre of slope, for a cost model to price.

        The default asks :meth:`bill_from` to name the :meth:`quantities`;
        override either.

        Parameters
        ----------
        section : rockfall_design.engine.Section
            The slope section, as for :meth:`footprint`.

        Returns
        -------
        list of Quantity
            Each with a name, an amount per running metre (finite, >= 0) and
            its unit; a product and size where the price depends on them.
        """
        return self.bill_from(self.quantities(section))

    def bill_from(self, quantities: dict[str, float]) -> list[Quantity]:
        """The bill, from this measure's own :meth:`quantities` dict.

        The default, for measures written before bills existed: one running
        metre of the measure, named after its ``kind`` (a cost catalogue
        prices it per running metre, e.g. ``other_per_m`` of ``unit_prices``).
        """
        return [Quantity(name=self.kind, amount=1.0, unit="m")]

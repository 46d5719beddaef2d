"""The contract of a safety concept: turning what the rocks did into checks.

A safety concept receives, for each measure, a
:class:`~rockfall_design.measures.MeasureResult` (the passing heights,
energies, masses and reaches of the rocks that met it, and the measure's
design properties) and returns a list of :class:`Check`: a named factor or
design value, its target, and whether it holds.

Concepts are registered by returning the class from the
``rockfall_design_safety_concepts`` hook (see ``hookspecs.py``); the project
chooses one with ``safety: {concept: NAME, ...parameters}``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, ClassVar

from pydantic import BaseModel, ConfigDict

from .measures import MeasureResult

__all__ = ["Check", "SafetyConcept", "SafetyParams"]


class SafetyParams(BaseModel):
    """Base of a safety concept's parameter model (strict)."""

    model_config = ConfigDict(extra="forbid", frozen=True)


@dataclass(frozen=True)
class Check:
    """One safety check of one measure.

    Attributes
    ----------
    name : str
        Short identifier, e.g. ``height_factor``, ``energy_factor``,
        ``reach_factor``, ``design_energy``.
    value : float or None
        The computed value (None if it cannot be computed, e.g. no rock met
        the measure; then ``ok`` says whether that is acceptable).
    target : float
        What it is compared with.
    ok : bool
        Whether the check holds.
    unit : str
        Unit of value and target ("-" for a factor).
    detail : str
        One line explaining how value and target were obtained.
    """

    name: str
    value: float | None
    target: float
    ok: bool
    unit: str = "-"
    detail: str = ""

    def as_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "value": self.value,
            "target": self.target,
            "ok": self.ok,
            "unit": self.unit,
            "detail": self.detail,
        }


class SafetyConcept(ABC):
    """Base class of every safety concept.

    Class attributes
    ----------------
    name : str
        Unique name, the ``safety.concept`` of the project file.
    summary : str
        One line for ``rockfall-design plugins`` and reports.
    Params : type of SafetyParams
        Targets and partial factors, with documented defaults.
    example : dict
        A complete valid parameter set (without ``concept``).
    """

    name: ClassVar[str]
    summary: ClassVar[str] = ""
    Params: ClassVar[type[SafetyParams]]
    example: ClassVar[dict[str, Any]] = {}

    def __init__(self, params: SafetyParams) -> None:
        self.params = params

    @abstractmethod
    def checks(self, result: MeasureResult) -> list[Check]:
        """The checks of one measure.

        Parameters
        ----------
        result : MeasureResult
            What the rocks did at the measure; ``result.measure.design_properties()``
            gives the measure's ``height_m``, ``capacity_kj`` and/or ``width_m``.

        Returns
        -------
        list of Check
            Empty if the concept has nothing to check for this kind of measure.
        """

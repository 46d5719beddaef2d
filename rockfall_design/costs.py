"""The contract of a cost model: pricing a measure from its quantities.

A cost model turns the quantities of a measure (``measure.quantities()``,
per running metre of slope) into a cost for the length of slope to protect.
Cost models are plugins like measures (hook ``rockfall_design_cost_models``);
the least-cost optimiser (``optimise``) minimises the sum over the measures
of a design.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any, ClassVar

from pydantic import BaseModel, ConfigDict

from .measures import ProtectiveMeasure

__all__ = ["CostModel", "CostParams"]


class CostParams(BaseModel):
    """Base of a cost model's parameter model (strict)."""

    model_config = ConfigDict(extra="forbid", frozen=True)


class CostModel(ABC):
    """Base class of every cost model.

    Class attributes
    ----------------
    name : str
        Unique name, chosen in the project's ``design.costs``.
    summary : str
        One line for ``rockfall-design plugins``.
    Params : type of CostParams
        The catalogue (unit prices), with units in the field names.
    example : dict
        A complete valid parameter set.
    """

    name: ClassVar[str]
    summary: ClassVar[str] = ""
    Params: ClassVar[type[CostParams]]
    example: ClassVar[dict[str, Any]] = {}

    def __init__(self, params: CostParams) -> None:
        self.params = params

    @abstractmethod
    def cost(self, measure: ProtectiveMeasure, quantities: dict[str, float],
             length_m: float) -> float:
        """Cost of ``measure`` over ``length_m`` metres of slope (currency units).

        Raises
        ------
        KeyError or ValueError
            If the catalogue has no price for this measure (the optimiser then
            skips the design and reports why).
        """

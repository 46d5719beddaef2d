"""The contract of a cost model: pricing a measure from its quantities.

A cost model turns the quantities of a measure, per running metre of slope,
into a cost for the length of slope to protect: the named quantities of its
bill (``measure.bill()``, a list of :class:`~rockfall_design.Quantity`) in
:meth:`CostModel.price`, or the older free dict (``measure.quantities()``) in
:meth:`CostModel.cost`. Cost models are plugins like measures (hook
``rockfall_design_cost_models``); the least-cost optimiser (``optimise``)
minimises the sum over the measures of a design.

The program calls :meth:`CostModel.price`; its default calls
:meth:`CostModel.cost`, so a cost model written before bills existed works as
it did. Before any search, :meth:`CostModel.missing_price` is asked whether
each candidate's quantities have a price at all.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any, ClassVar

from pydantic import BaseModel, ConfigDict

from .measure import ProtectiveMeasure, Quantity

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

    def price(
        self,
        measure: ProtectiveMeasure,
        bill: list[Quantity],
        quantities: dict[str, float],
        length_m: float,
    ) -> float:
        """Cost of ``measure`` over ``length_m`` metres of slope, from its bill.

        Parameters
        ----------
        measure
            The measure.
        bill
            Its named quantities per running metre (``measure.bill(section)``).
        quantities
            Its free quantities dict (``measure.quantities(section)``).
        length_m
            Length of slope to protect (m).

        Returns
        -------
        float
            Cost (currency units), finite and >= 0.

        Raises
        ------
        KeyError or ValueError
            If the catalogue has no price for the measure (the design is
            skipped and the reason reported).

        Notes
        -----
        The default calls :meth:`cost` with ``quantities``: override this to
        price by the named quantities.
        """
        return self.cost(measure, quantities, length_m)

    def missing_price(self, measure: ProtectiveMeasure, bill: list[Quantity]) -> str | None:
        """Why this catalogue cannot price a bill of these quantities at all, or None.

        Asked once per candidate before any search, with a sample design of
        it, so that a quantity without a price is reported at once (naming
        the candidate, the quantity and the catalogue file) instead of
        skipping every design. A price missing only for some products or
        sizes is not for here: :meth:`price` raises ``KeyError`` for those.

        Returns
        -------
        str or None
            One line naming the quantity (e.g. ``"no price for quantity
            'embankment_fill_m3' (m3)"``), or None. The default is None
            (the model does not say in advance).
        """
        return None

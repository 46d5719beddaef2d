"""The contract of a safety concept: turning what the rocks did into checks.

A safety concept receives, for each measure, a
:class:`~rockfall_design.plugins.measure.MeasureResult` (the passing heights,
energies, masses and reaches of the rocks that met it, and the measure's
design properties) and returns a list of :class:`Check`: a named factor or
design value, its target, and whether it holds.

Concepts are registered by returning the class from the
``rockfall_design_safety_concepts`` hook (see ``hookspecs.py``); the project
chooses one with ``safety: {concept: NAME, ...parameters}``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

from pydantic import BaseModel, ConfigDict, Field

from .measure import MeasureResult

__all__ = ["Check", "DesignBlock", "DesignValue", "SafetyConcept", "SafetyParams",
           "DEFAULT_CONFIDENCE"]

#: One-sided confidence of the bounds on design values (``safety.confidence``).
DEFAULT_CONFIDENCE = 0.95


class SafetyParams(BaseModel):
    """Base of a safety concept's parameter model (strict).

    Every concept inherits ``confidence``: the one-sided confidence of the
    upper bounds its design values are reported with (and with which the
    optimiser admits a design).
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    confidence: float = Field(
        DEFAULT_CONFIDENCE,
        ge=0.5,
        le=0.9999,
        description="One-sided confidence of the upper bounds of the design values and of "
        "the residual (-), e.g. 0.95.", json_schema_extra={"unit": "-"},
    )


@dataclass(frozen=True)
class DesignValue:
    """One design value or product figure behind a check, in the concept's symbols.

    The report's table of design values shows these as they are, so that a
    concept says what it computed (``v_d``, ``m_d``, ``E_d``, the product's
    ``MEL``) without the report knowing the concept.

    Attributes
    ----------
    symbol : str
        The concept's symbol, e.g. ``v_d``, ``E_d``, ``h_N`` (plain text;
        ``_`` starts a subscript).
    meaning : str
        What it is, in a few words, e.g. "design speed: p95 speed x gamma_F".
    value : float or None
        Its value in ``unit``; None when no rock gives it.
    unit : str
        ``m``, ``m/s``, ``kg``, ``kJ``, ``-`` ...
    bound : float or None
        Its one-sided confidence bound on the unsafe side (``safety.confidence``),
        where the value is a statistic of the rocks; None for a product's figure.
    source : str
        ``"rocks"`` (a statistic of the rocks, with the concept's factors) or
        ``"product"`` (a figure of the measure or its product).
    """

    symbol: str
    meaning: str
    value: float | None
    unit: str = "-"
    bound: float | None = None
    source: str = "rocks"

    def as_dict(self) -> dict[str, Any]:
        return {"symbol": self.symbol, "meaning": self.meaning, "value": self.value,
                "unit": self.unit, "bound": self.bound, "source": self.source}


@dataclass(frozen=True)
class DesignBlock:
    """The project's design block (``rocks.design_block``), for the concepts that use one.

    Attributes
    ----------
    mass_kg : float
        Its mass (kg): the survey's percentile, or the return period's volume,
        times ``rocks.density``.
    lower_kg, upper_kg : float
        The one-sided confidence bounds of a survey's percentile at the
        project's confidence (order statistics); a return period's block,
        which has none, is its own bounds.
    source : str
        One line saying where it comes from, for the report, e.g. "p98 of the
        240 block volumes of survey blocks.csv = 2.10 m3 ...".
    """

    mass_kg: float
    lower_kg: float
    upper_kg: float
    source: str


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
    bound : float or None
        The value computed with the one-sided upper confidence bounds of the
        design values (``safety.confidence``) in place of their point
        estimates; None when there is nothing to bound (no rock met the
        measure) or the sample is too small to bound it (``detail`` says how
        many rocks it needs).
    ok_with_confidence : bool or None
        Whether the check holds with the bound in place of the value. None
        means the concept does not report bounds: the optimiser then admits
        on ``ok`` and the report says so.
    rocks_needed : int or None
        When the sample is too small to bound the value: how many rocks must
        meet the measure for it to be bounded (the optimiser runs more rocks
        before it decides).
    optimistic : float or None
        The value computed with the one-sided *lower* confidence bounds of
        the design values (the most favourable value the measure may have at
        ``safety.confidence``); None when there is nothing to bound or the
        sample is too small.
    fails_with_confidence : bool or None
        Whether the check fails even with ``optimistic`` in place of the
        value: the sample shows with confidence that it does not hold, and
        more rocks would not change that (the optimiser rejects such a
        design). None means the concept does not report it: the optimiser
        then treats a failed point value as failing with confidence only
        where the concept reports no bounds at all (``ok_with_confidence``
        None), and as undecided otherwise.
    symbol : str
        The check's value in the concept's symbols, e.g. ``E_d`` or ``F_h``
        (empty: the report shows ``name``).
    relation : str
        ``"<="`` or ``">="``: how the value must stand to the target (empty:
        not said).
    target_symbol : str
        The target in the concept's symbols, e.g. ``MEL / gamma_E``.
    design_values : tuple of DesignValue
        The design values and product figures the check was computed from, in
        the order a reader follows them (the report's table of design values).
    limits : tuple of float, or None
        ``optimistic`` and ``bound`` as the rocks grow without end: the part of
        the bounds that more rocks do not narrow (an uncertainty beside the
        rocks', such as a design block's survey), as (lower, upper), estimated
        at ``value``. None: both bounds close on ``value``. The report reckons
        the rocks that would decide a marginal design from them.

    See Also
    --------
    rockfall_design.judge.bounds : the order-statistic and Clopper-Pearson bounds.
    """

    name: str
    value: float | None
    target: float
    ok: bool
    unit: str = "-"
    detail: str = ""
    bound: float | None = None
    ok_with_confidence: bool | None = None
    rocks_needed: int | None = None
    optimistic: float | None = None
    fails_with_confidence: bool | None = None
    symbol: str = ""
    relation: str = ""
    target_symbol: str = ""
    design_values: tuple[DesignValue, ...] = ()
    limits: tuple[float, float] | None = None

    @property
    def holds_with_confidence(self) -> bool:
        """``ok_with_confidence``, or ``ok`` for a concept that reports no bounds."""
        return self.ok if self.ok_with_confidence is None else self.ok_with_confidence

    @property
    def rejects(self) -> bool:
        """Does this check fail with confidence (see ``fails_with_confidence``)?

        A concept that reports no bounds at all is judged on its point value,
        as before bounds existed; one that reports upper bounds but not
        ``fails_with_confidence`` never rejects (its failures stay undecided
        until ``design.max_rocks``, where they are marginal).
        """
        if self.fails_with_confidence is not None:
            return self.fails_with_confidence
        return not self.ok if self.ok_with_confidence is None else False

    def as_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "value": self.value,
            "target": self.target,
            "ok": self.ok,
            "unit": self.unit,
            "detail": self.detail,
            "bound": self.bound,
            "ok_with_confidence": self.ok_with_confidence,
            "rocks_needed": self.rocks_needed,
            "optimistic": self.optimistic,
            "fails_with_confidence": self.fails_with_confidence,
            "symbol": self.symbol,
            "relation": self.relation,
            "target_symbol": self.target_symbol,
            "design_values": [d.as_dict() for d in self.design_values],
        } | ({} if self.limits is None else {"limits": list(self.limits)})


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
    #: Measure parameters the concept needs wherever a measure has them: a
    #: measure (or catalogue product) whose parameter model has one of these
    #: fields must give it (not None), else the project is an error at its
    #: line. E.g. ``("max_elongation_m", "residual_height_fraction")``: the
    #: EAD 340059 test figures of a fence, which the EAD concepts check.
    required_measure_params: ClassVar[tuple[str, ...]] = ()
    #: Whether the concept designs on one block and takes its mass from the
    #: project's design block (``rocks.design_block``) where one is given.
    uses_design_block: ClassVar[bool] = False
    #: The project's design block (set by the program after the concept is
    #: built, bounded at the concept's confidence); None: the project gives none.
    design_block: DesignBlock | None = None

    def __init__(self, params: SafetyParams) -> None:
        self.params = params

    def allowed_residual_fraction(self) -> float | None:
        """The largest fraction of rocks that may reach the protected zone, or None.

        A concept that sets the residual target itself (a target reliability
        over the working life, say) returns it (-); the judge and the
        optimiser then hold the residual to the stricter of it and the
        project's own (``protect.allowed_fraction``, ``design.residual``).
        None (the default): the project's target alone.
        """
        return None

    def statements(self, reaching: int | None, rocks: int,
                   results: Sequence[MeasureResult], labels: Sequence[str]) -> list[str]:
        """Sentences the report adds under "How sure", in the concept's own terms.

        Parameters
        ----------
        reaching : int or None
            Rocks that reached the protected zone (None: the project has none).
        rocks : int
            Rocks run.
        results : sequence of MeasureResult
            What the rocks did at each measure.
        labels : sequence of str
            Each measure's label, as the report names it.

        Returns
        -------
        list of str
            Plain sentences (none by default). A concept that judges the
            design as a whole, a probability over the working life say,
            states it here with its bound and its assumptions.
        """
        return []

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

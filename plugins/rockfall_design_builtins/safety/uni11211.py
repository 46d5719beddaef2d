"""The built-in safety concept ``uni11211``: the limit states of UNI 11211-4 for net fences.

An ordinary plugin with an entry point of its own (``uni11211``); it uses
only the public ``rockfall_design`` API and the shared helpers of this
package (:mod:`.shared`, :mod:`.checks`, its limit states in
:mod:`.limit_states`). Units: m, m/s, kg, kJ.
"""

from __future__ import annotations

from typing import Any, ClassVar

from pydantic import Field

from rockfall_design import Check, MeasureResult, SafetyConcept, hookimpl

from .checks import braking_check, gamma_d_field, reach_check, reach_factor_field
from .limit_states import design_energy_check, design_height_check
from .shared import (
    MAX_FREEBOARD_M,
    MAX_PARTIAL,
    StrictParams,
    finite_property,
    percentile_label,
)

__all__ = ["Uni11211Concept", "rockfall_design_safety_concepts"]


class Uni11211Concept(SafetyConcept):
    """Limit-state design of net fences after UNI 11211-4, with partial factors.

    The design values are percentiles of the rocks that met the measure,
    multiplied by partial factors:

    ``design_energy`` (``capacity_kj`` present)
        Design energy :math:`E_d` of the design block at the design speed;
        holds if :math:`E_d \\le E_{cap} / \\gamma_E`. Value :math:`E_d`,
        target :math:`E_{cap} / \\gamma_E` (kJ).
    ``design_height`` (``height_m`` present)
        Design passing height plus freeboard, :math:`h_d + f`; holds if the
        nominal height :math:`h_{nom} \\ge h_d + f`. Value :math:`h_d + f`,
        target :math:`h_{nom}` (m). Where the product gives its residual
        height after the MEL test (``residual_height_m``), the target is
        that residual height instead, and the detail says so.
    ``reach_factor`` (``width_m`` present)
        Width over the ``percentile`` of the reach, as in ``spang``.
    ``braking_distance`` (``max_elongation_m`` present and a protected zone)
        The fence's maximum elongation (m) must not reach the protected
        zone: holds if it is <= ``protect.x`` - x (the distance :math:`d_A`
        of Peila & Ronco (2009) against the elongation; no partial factor
        on the elongation is applied).

    Parameters
    ----------
    params : Uni11211Concept.Params

    Notes
    -----
    With :math:`P` the chosen percentile (default the 95th) over the rocks
    that met the measure, of their speeds :math:`v_i` (m/s), passing heights
    of the centre :math:`h_i` (m), masses :math:`m_i` (kg) and radii
    :math:`r_i` (m):

    .. math::

        \\gamma_F &= \\gamma_{Tr} \\, \\gamma_{Dp} \\\\
        v_d &= P(v_i) \\, \\gamma_F, \\qquad h_d = P(h_i) \\, \\gamma_F \\\\
        m_d &= P(m_i) \\, \\gamma_{VolF} \\, \\gamma_\\gamma \\\\
        E_d &= \\tfrac{1}{2} m_d v_d^2 / 1000 \\quad \\text{(kJ)} \\\\
        d_d &= 2 \\, P(r_i), \\qquad f = \\max(f_{min}, d_d / 2)

    The percentiles of speed, height and mass are taken separately (the
    design block need not be one of the rocks), as the standard does. Where
    the project gives a design block (``rocks.design_block``: a block
    survey's percentile with its order-statistic bounds, or a return
    period's block), :math:`m_d` is that block's mass times
    :math:`\\gamma_{VolF} \\gamma_\\gamma` in place of :math:`P(m_i)`, and
    the check's detail says so.

    The freeboard :math:`f` is at least ``f_min_m`` (0.5 m) and at least
    half the design block, so that the centre of the design block passes at
    least half a block below the top of the fence and the block does not
    graze over it. The requirement as first written says "at most half
    the block size"; we read the standard as requiring the centre to pass
    at least half a block below the top and use the maximum. **This reading
    is flagged for review.**

    The residual height in place of the nominal height is the height a net
    keeps after an impact at its MEL: a block of the design height must
    still be intercepted by a net that has already been loaded. The
    references at hand state the height check on the nominal height; this
    use of the residual height, where the catalogue gives it, is the
    conservative reading and **is flagged for review** against the text of
    UNI 11211-4:2018. Without a residual height the check is the nominal
    one, as before.

    References
    ----------
    .. [1] UNI 11211-4:2018. Opere di difesa dalla caduta massi -- Parte 4:
       Progetto definitivo ed esecutivo. Ente Italiano di Normazione, Milan.
    .. [2] Peila, D. and Ronco, C. (2009). Technical note: Design of rockfall
       net fences and the new ETAG 027 European guideline. Natural Hazards
       and Earth System Sciences 9, 1291-1298.
    """

    name: ClassVar[str] = "uni11211"
    #: m_d from the project's design block where it gives one.
    uses_design_block: ClassVar[bool] = True
    #: An EAD concept: a fence's test figures are required (at their catalogue line).
    required_measure_params: ClassVar[tuple[str, ...]] = (
        "max_elongation_m", "residual_height_fraction")
    summary: ClassVar[str] = (
        "UNI 11211-4 limit states: design energy and design height (with freeboard) "
        "from percentiles times partial factors"
    )

    class Params(StrictParams):
        """Partial factors, freeboard and percentile of the design values."""

        gamma_tr: float = Field(
            1.02,
            ge=1.0,
            le=MAX_PARTIAL,
            description="Partial factor on the trajectory simulation (-): 1.02 for "
            "simulations calibrated by back-analysis, 1.10 otherwise.",
            json_schema_extra={"unit": "-"},
        )
        gamma_dp: float = Field(
            1.02,
            ge=1.0,
            le=MAX_PARTIAL,
            description="Partial factor on the quality of the slope survey (-): 1.02 for a "
            "high-quality survey, 1.10 for a low-quality one.", json_schema_extra={"unit": "-"},
        )
        gamma_volf: float = Field(
            1.02,
            ge=1.0,
            le=MAX_PARTIAL,
            description="Partial factor on the precision of the block-volume survey (-): "
            "1.02 for a precise survey, 1.10 otherwise.", json_schema_extra={"unit": "-"},
        )
        gamma_gamma: float = Field(
            1.0, ge=1.0, le=MAX_PARTIAL,
            description="Partial factor on the unit weight of the rock (-).",
            json_schema_extra={"unit": "-"},
        )
        gamma_e: float = Field(
            1.2,
            ge=1.0,
            le=MAX_PARTIAL,
            description="Partial factor on the energy capacity of the product (-), applied "
            "to the capacity (MEL-based).", json_schema_extra={"unit": "-"},
        )
        f_min_m: float = Field(
            0.5,
            ge=0.0,
            le=MAX_FREEBOARD_M,
            description="Minimum freeboard between the design passing height and the top "
            "(m); the freeboard is also at least half the design block.",
            json_schema_extra={"unit": "m"},
        )
        percentile: float = Field(
            95.0,
            gt=0.0,
            le=100.0,
            description="Percentile (%) of speeds, passing heights, masses and radii of the "
            "rocks that met the measure taken as design values.", json_schema_extra={"unit": "%"},
        )
        reach_factor: float = reach_factor_field()
        gamma_d: float = gamma_d_field()

    example: ClassVar[dict[str, Any]] = {
        "gamma_tr": 1.02,
        "gamma_dp": 1.02,
        "gamma_volf": 1.02,
        "gamma_gamma": 1.0,
        "gamma_e": 1.2,
        "f_min_m": 0.5,
        "percentile": 95.0,
        "reach_factor": 1.0,
        "gamma_d": 1.3,
        "confidence": 0.95,
    }

    params: Params

    def checks(self, result: MeasureResult) -> list[Check]:
        """The design-energy, design-height and reach checks the measure calls for.

        Parameters
        ----------
        result : MeasureResult
            What the rocks did at the measure.

        Returns
        -------
        list of Check
            ``design_energy`` (kJ), ``design_height`` (m), ``reach_factor``
            (-), in that order, for those of ``capacity_kj``, ``height_m``,
            ``width_m`` the measure declares; then ``braking_distance`` (m)
            for a ``max_elongation_m`` with a protected zone.
        """
        params = self.params
        properties = result.measure.design_properties()
        checks = []
        capacity_kj = finite_property(properties, "capacity_kj")
        if capacity_kj is not None:
            checks.append(design_energy_check(result, capacity_kj, params, self.design_block))
        height_m = finite_property(properties, "height_m")
        if height_m is not None:
            checks.append(design_height_check(
                result, height_m, finite_property(properties, "residual_height_m"), params))
        width_m = finite_property(properties, "width_m")
        if width_m is not None:
            checks.append(reach_check(result, width_m, params.reach_factor,
                                       percentile_label(params.percentile), params.confidence))
        checks += braking_check(result, finite_property(properties, "max_elongation_m"),
                                self.params.gamma_d)
        return checks

    @property
    def gamma_f(self) -> float:
        """Partial factor on speeds and heights, :math:`\\gamma_{Tr} \\gamma_{Dp}` (-)."""
        return self.params.gamma_tr * self.params.gamma_dp


@hookimpl
def rockfall_design_safety_concepts() -> list[type[SafetyConcept]]:
    """The built-in ``uni11211`` concept, registered by its own entry point."""
    return [Uni11211Concept]

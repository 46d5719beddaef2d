"""The built-in safety concept ``onr24810``: the Austrian rule for rockfall fences.

An ordinary plugin with an entry point of its own (``onr24810``): the public
``rockfall_design`` API and the shared helpers of this package only.

ONR 24810 (Austrian Standards) designs a net fence on the 99 % fractile of
the simulated kinetic energies and passing heights at the fence, raised by
partial factors that grow with the consequence class, and compares the
design energy with the kit's tested energy: its service energy level (SEL)
for frequent events, which the fence must take without repair, and its
maximum energy level (MEL) for rare events (Volkwein et al. 2011, sect. 6;
Mölk & Stelzer 2013). The kit's figures are those of its European Technical
Assessment (EAD 340059): the concept requires a fence's maximum elongation
and residual height.

Checks, per measure (units m, kJ):

``design_energy`` (``capacity_kj``)
    :math:`E_d = \\gamma_F \\, E_{99}` against :math:`E_{SEL}` (``event:
    frequent``) or :math:`E_{MEL} / \\gamma_R` (``event: rare``).
    With a design block (``rocks.design_block``) of mass :math:`m_d`:
    :math:`E_d = \\gamma_F \\, P_{99}(\\tfrac12 m_d v_i^2)` over the rocks'
    speeds :math:`v_i` (flagged for review).
``design_height`` (``height_m``)
    :math:`h_d + f = \\gamma_F \\, h_{99} + \\max(f_{min}, r_{99})`, the
    passing height perpendicular to the slope for a fence, against its
    nominal height for rare events and its residual height for frequent
    ones (a fence hit by frequent blocks stands at its residual height until
    it is repaired).
``braking_distance`` (a fence's ``max_elongation_m``)
    :math:`\\gamma_d \\, d_{MEL}` within the clearance to the protected zone
    (Peila & Ronco 2009), as in the other concepts.

Each design value carries its order-statistic bounds at the project's
confidence (the 99 % fractile needs at least 299 rocks at the measure to be
bounded at 95 %).

The partial factors' defaults are ILLUSTRATIVE and **flagged for review**:
the text of ONR 24810 was not reached when this was written. The factor on
the actions follows the consequence class as EN 1990 (Annex B) scales
actions by class (:math:`K_{FI}` = 0.9, 1.0, 1.1 for CC1 to CC3) applied
to a base factor of 1.1; set ``gamma_f`` to the value of the edition in
force.

References
----------
.. [1] ONR 24810:2021. Technischer Steinschlagschutz -- Begriffe,
   Einwirkungen, Bemessung und konstruktive Durchbildung, Überwachung und
   Instandhaltung. Austrian Standards International, Vienna.
.. [2] Volkwein, A., Schellenberg, K., Labiouse, V., Agliardi, F., Berger,
   F., Bourrier, F., Dorren, L. K. A., Gerber, W. and Jaboyedoff, M. (2011).
   Rockfall characterisation and structural protection -- a review. Natural
   Hazards and Earth System Sciences 11, 2617-2651.
.. [3] Mölk, M. and Stelzer, G. (2013). Die neue ONR 24810: Stand der
   Technik im Steinschlagschutz. Journal für Wildbach-, Lawinen-, Erosions-
   und Steinschlagschutz 171.
.. [4] EN 1990:2002, Basis of structural design, Annex B (consequence
   classes and :math:`K_{FI}`).
"""

from __future__ import annotations

from typing import Any, ClassVar, Literal

import numpy as np
from pydantic import Field

from rockfall_design import (
    Check,
    DesignValue,
    MeasureResult,
    SafetyConcept,
    hookimpl,
)

from .checks import braking_check, gamma_d_field
from .limit_states import fractile_check
from .shared import StrictParams, finite_property

__all__ = ["Onr24810Concept", "rockfall_design_safety_concepts"]

#: The EN 1990 K_FI of each consequence class times a base factor of 1.1 on
#: the actions: ILLUSTRATIVE, flagged for review against ONR 24810 (see the module).
_GAMMA_F = {"CC1": 0.9 * 1.1, "CC2": 1.0 * 1.1, "CC3": 1.1 * 1.1}


class Onr24810Concept(SafetyConcept):
    """ONR 24810: 99 % fractiles, consequence-class factors, SEL or MEL by event frequency.

    See the module docstring for the checks, their formulas and what is
    flagged for review.
    """

    name: ClassVar[str] = "onr24810"
    summary: ClassVar[str] = (
        "ONR 24810: 99 % fractile energy and passing height with consequence-class factors, "
        "against the SEL (frequent events) or the MEL (rare events)"
    )
    required_measure_params: ClassVar[tuple[str, ...]] = (
        "max_elongation_m", "residual_height_fraction")
    #: E_d from the project's design block where it gives one.
    uses_design_block: ClassVar[bool] = True

    class Params(StrictParams):
        """Consequence class, event frequency and partial factors."""

        consequence_class: Literal["CC1", "CC2", "CC3"] = Field(
            "CC2", description="Consequence class of a failure (EN 1990): CC1 low, CC2 "
            "medium, CC3 high.", json_schema_extra={"unit": None})
        event: Literal["frequent", "rare"] = Field(
            "rare", description="How often the design block comes: 'frequent' designs on the "
            "kit's SEL and residual height, 'rare' on its MEL and nominal height.",
            json_schema_extra={"unit": None})
        gamma_f: float | None = Field(
            None, ge=0.5, le=10.0,
            description="Partial factor on the design energy and passing height (-); default "
            "by consequence class 0.99 / 1.1 / 1.21 (ILLUSTRATIVE, see the docs).",
            json_schema_extra={"unit": "-"})
        gamma_r: float = Field(
            1.0, ge=1.0, le=10.0,
            description="Partial factor on the MEL for rare events (-); ILLUSTRATIVE 1.0.",
            json_schema_extra={"unit": "-"})
        f_min_m: float = Field(
            0.5, ge=0.0, le=100.0,
            description="Least freeboard above the design passing height (m); at least the "
            "99 % fractile radius.", json_schema_extra={"unit": "m"})
        gamma_d: float = gamma_d_field()

    example: ClassVar[dict[str, Any]] = {
        "consequence_class": "CC2", "event": "rare", "gamma_r": 1.0, "f_min_m": 0.5,
        "gamma_d": 1.3, "confidence": 0.95,
    }
    params: Params

    @property
    def factor(self) -> float:
        """:math:`\\gamma_F` (-): ``gamma_f`` or the consequence class's default."""
        p = self.params
        return _GAMMA_F[p.consequence_class] if p.gamma_f is None else p.gamma_f

    def checks(self, result: MeasureResult) -> list[Check]:
        """``design_energy``, ``design_height``, ``braking_distance``, as the measure has them."""
        props = result.measure.design_properties()
        checks = []
        capacity = finite_property(props, "capacity_kj")
        if capacity is not None:
            if self.params.event == "frequent":
                sel = finite_property(props, "sel_kj")
                limit, what = (capacity / 3.0 if sel is None else sel), "SEL"
                symbol = "E_SEL"
            else:
                limit = capacity / self.params.gamma_r
                what = f"MEL / gamma_R {self.params.gamma_r:g}"
                symbol = "E_MEL / gamma_R"
            figure = DesignValue(symbol, f"the kit's {what} (EAD 340059)", limit, "kJ",
                                 source="product")
            checks.append(self._energy_check(result, limit, f"{what} {limit:.1f} kJ", figure))
        height = finite_property(props, "height_m")
        if height is not None:
            residual = finite_property(props, "residual_height_m")
            if self.params.event == "frequent" and residual is not None:
                target, what, symbol = residual, f"residual height {residual:.2f} m", "h_R"
            else:
                target, what, symbol = height, f"nominal height {height:.2f} m", "h_N"
            radius = np.asarray(result.radius_m, dtype=float)
            r99 = float(np.percentile(radius, 99.0)) if radius.size else 0.0
            named = {"symbol": "h_d + f", "relation": "<=", "target_symbol": symbol,
                     "design_values": (DesignValue(symbol, what.split(" ", 2)[0] + " height",
                                                   target, "m", source="product"),)}
            checks.append(self._fractile_check("design_height", result.rated_passing_height_m,
                                             max(self.params.f_min_m, r99), target, what, "m",
                                             named=named))
        checks += braking_check(result, finite_property(props, "max_elongation_m"),
                                self.params.gamma_d)
        return checks

    def _energy_check(self, result: MeasureResult, limit: float, against: str,
                      figure: DesignValue) -> Check:
        """``design_energy``: of the simulated rocks, or of the design block at their speeds.

        With a design block (``rocks.design_block``) of mass :math:`m_d`, the
        energy is that block's at the 99 % fractile speed,
        :math:`E_d = \\gamma_F \\, \\tfrac12 m_d v_{99}^2` (the rocks' speeds
        hardly depend on their size on a slope, the block's mass does not
        come from them); its bounds are the speed's and the block's together.
        **Flagged for review** against the text of ONR 24810.
        """
        block = self.design_block
        named: dict[str, Any] = {"symbol": "E_d", "relation": "<=",
                                 "target_symbol": figure.symbol, "design_values": (figure,)}
        if block is None:
            return self._fractile_check("design_energy", result.energy_kj, 0.0, limit, against,
                                      "kJ", named=named)
        named["design_values"] = (
            DesignValue("m_d", "design mass: the design block (rocks.design_block)",
                        block.mass_kg, "kg", block.upper_kg), figure)
        speeds = np.asarray(result.velocity_ms, dtype=float)
        energy = 0.5 * block.mass_kg * speeds**2 / 1000.0
        return self._fractile_check(
            "design_energy", energy, 0.0, limit, against, "kJ",
            (block.lower_kg / block.mass_kg, block.upper_kg / block.mass_kg),
            f"the design block's energy at the rocks' speeds, 1/2 m v^2 with m = "
            f"{block.mass_kg:.1f} kg (rocks.design_block: {block.source})", named)


    def _fractile_check(self, name: str, values: Any, add: float, target: float, against: str,
                        unit: str, scale: tuple[float, float] = (1.0, 1.0), what: str = "",
                        named: dict[str, Any] | None = None) -> Check:
        """:func:`.limit_states.fractile_check` at this concept's factor and event."""
        p = self.params
        return fractile_check(name, values, add, target, f"{against} ({p.event} events)", unit,
                              self.factor, f"gamma_F {self.factor:.3g} ({p.consequence_class})",
                              p.confidence, scale, what, named)


@hookimpl
def rockfall_design_safety_concepts() -> list[type[SafetyConcept]]:
    """The built-in ``onr24810`` concept, registered by its own entry point."""
    return [Onr24810Concept]

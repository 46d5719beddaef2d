"""The built-in safety concept ``spang``: the safety factors of Spang & Rautenstrauch (1988).

An ordinary plugin with an entry point of its own (``spang``); it uses only
the public ``rockfall_design`` API and the shared helpers of this package
(:mod:`.shared`, :mod:`.checks`). Units: m, kJ.
"""

from __future__ import annotations

from typing import Any, ClassVar, Literal

from pydantic import Field

from rockfall_design import Check, MeasureResult, SafetyConcept, hookimpl

from .checks import braking_check, factor_check, gamma_d_field, reach_check, reach_factor_field
from .shared import MAX_FACTOR, StrictParams, finite_property

__all__ = ["SpangConcept", "rockfall_design_safety_concepts"]


class SpangConcept(SafetyConcept):
    """Safety factors of Spang & Rautenstrauch (1988).

    For each design property the measure declares:

    ``height_factor`` (``height_m`` present)
        Chosen height over the critical height, the ``statistic`` of the
        passing heights of the rock centres over the rocks that met the
        measure; holds if >= ``height_factor`` (the paper: 2 to 3 in
        normal cases).
    ``energy_factor`` (``capacity_kj`` present)
        Energy capacity over the design kinetic energy, the ``statistic``
        of the rocks' total kinetic energies there; holds if >=
        ``energy_factor``.
    ``reach_factor`` (``width_m`` present, berms and ditches)
        Width over the ``statistic`` of the reach of the rocks beyond the
        upslope edge (the paper's maximum grows with the number of rocks);
        holds if >= ``reach_factor`` (values above 1 are normally
        uneconomic).
    ``braking_distance`` (``max_elongation_m`` present and a protected zone)
        The fence's maximum elongation (m) must not reach the protected
        zone: holds if it is <= ``protect.x`` - x.

    The height factor stays on the nominal height even where the product
    gives a residual height (``residual_height_m``): the paper predates the
    fence classes of ETAG 027 and its factor of 2 to 3 on the nominal height
    is its margin for what the net loses in height; taking the residual
    height as well would count that margin twice.

    Parameters
    ----------
    params : SpangConcept.Params

    Notes
    -----
    With :math:`h_i`, :math:`E_i` and :math:`r_i` the passing height (m),
    kinetic energy (kJ) and reach (m) of the rocks that met the measure, and
    :math:`S` the chosen statistic (maximum, 95th or 99th percentile):

    .. math::

        F_h = \\frac{h_{nom}}{S(h_i)}, \\qquad
        F_E = \\frac{E_{cap}}{S(E_i)}, \\qquad
        F_b = \\frac{b}{S(r_i)}

    References
    ----------
    .. [1] Spang, R. M. and Rautenstrauch, R. W. (1988). Empirical and
       mathematical approaches to rockfall protection and their practical
       applications. Proc. 5th International Symposium on Landslides,
       Lausanne, vol. 2, pp. 1237-1243.
    """

    name: ClassVar[str] = "spang"
    summary: ClassVar[str] = (
        "Spang & Rautenstrauch (1988) safety factors: height, energy and berm width "
        "over the rocks' critical height, design energy and reach"
    )

    class Params(StrictParams):
        """Targets of the safety factors and the statistic of the design values."""

        height_factor: float = Field(
            2.0,
            gt=0.0,
            le=MAX_FACTOR,
            description="Target of chosen height / critical height (-); the paper: 2 to 3 "
            "in normal cases.", json_schema_extra={"unit": "-"},
        )
        energy_factor: float = Field(
            1.0, gt=0.0, le=MAX_FACTOR,
            description="Target of energy capacity / design energy (-).",
            json_schema_extra={"unit": "-"},
        )
        reach_factor: float = reach_factor_field()
        # p95 by default, as the README advises: the sample maximum grows with the
        # number of rocks and has no confidence bound.
        statistic: Literal["max", "p95", "p99"] = Field(
            "p95",
            description="Statistic of the passing heights and energies of the rocks that "
            "met the measure giving the critical height and the design energy: the "
            "95th/99th percentile (default p95) or the maximum.",
            json_schema_extra={"unit": None},
        )
        gamma_d: float = gamma_d_field()

    example: ClassVar[dict[str, Any]] = {
        "height_factor": 2.0,
        "energy_factor": 1.0,
        "reach_factor": 1.0,
        "statistic": "p95",
        "gamma_d": 1.3,
        "confidence": 0.95,
    }

    params: Params

    def checks(self, result: MeasureResult) -> list[Check]:
        """The height, energy and reach factors the measure's properties call for.

        Parameters
        ----------
        result : MeasureResult
            What the rocks did at the measure.

        Returns
        -------
        list of Check
            ``height_factor``, ``energy_factor``, ``reach_factor`` (unit "-"),
            in that order, for those of ``height_m``, ``capacity_kj``,
            ``width_m`` the measure declares; then ``braking_distance`` (m)
            for a ``max_elongation_m`` with a protected zone.
        """
        params = self.params
        properties = result.measure.design_properties()
        checks = []
        height_m = finite_property(properties, "height_m")
        if height_m is not None:
            checks.append(
                factor_check(
                    "height_factor",
                    height_m,
                    "m",
                    result.rated_passing_height_m,
                    params.statistic,
                    "passing height",
                    params.height_factor,
                    params.confidence,
                    ("F_h", "h", "h_N", "nominal height"),
                )
            )
        capacity_kj = finite_property(properties, "capacity_kj")
        if capacity_kj is not None:
            checks.append(
                factor_check(
                    "energy_factor",
                    capacity_kj,
                    "kJ",
                    result.energy_kj,
                    params.statistic,
                    "energy",
                    params.energy_factor,
                    params.confidence,
                    ("F_E", "E", "E_cap", "energy capacity (capacity_kj)"),
                )
            )
        width_m = finite_property(properties, "width_m")
        if width_m is not None:
            checks.append(reach_check(result, width_m, params.reach_factor, params.statistic,
                                       params.confidence))
        checks += braking_check(result, finite_property(properties, "max_elongation_m"),
                                self.params.gamma_d)
        return checks


@hookimpl
def rockfall_design_safety_concepts() -> list[type[SafetyConcept]]:
    """The built-in ``spang`` concept, registered by its own entry point."""
    return [SpangConcept]

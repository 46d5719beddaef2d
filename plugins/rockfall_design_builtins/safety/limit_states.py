"""The limit states of the partial-factor concepts for net fences.

Public helpers of the built-in ``uni11211`` and ``onr24810`` concepts that
a third party's partial-factor concept may use too (docs/plugins.md): the
design energy of the design block at the design speed against the
product's capacity, and the design passing height with its freeboard
against the fence's height, each with its order-statistic bounds at the
concept's confidence. The formulas are those of
:class:`~rockfall_design_builtins.safety.uni11211.Uni11211Concept`;
:func:`fractile_check` is the factored 99 % fractile of ``onr24810``.

Units: m, m/s, kg, kJ.

References
----------
.. [1] UNI 11211-4:2018. Opere di difesa dalla caduta massi -- Parte 4:
   Progetto definitivo ed esecutivo. Ente Italiano di Normazione, Milan.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

from rockfall_design import (
    Check,
    DesignBlock,
    DesignValue,
    MeasureResult,
    quantile_with_bounds,
    rocks_to_bound_quantile,
)

from .checks import limit_check, product_name
from .shared import (
    NO_ROCK,
    design_mass,
    number_text,
    percentile_label,
    rocks_text,
    statistic_with_bounds,
)

__all__ = [
    "PartialFactors",
    "design_energy",
    "design_energy_check",
    "design_height_check",
    "fractile_check",
    "gamma_f",
    "required_height",
]


class PartialFactors(Protocol):
    """The parameters the limit states read (as ``Uni11211Concept.Params`` has them)."""

    gamma_tr: float  #: on the trajectory simulation (-)
    gamma_dp: float  #: on the quality of the slope survey (-)
    gamma_volf: float  #: on the block-volume survey (-)
    gamma_gamma: float  #: on the unit weight of the rock (-)
    gamma_e: float  #: on the product's energy capacity (-)
    f_min_m: float  #: least freeboard (m)
    percentile: float  #: percentile of the design values (%)
    confidence: float  #: of the order-statistic bounds (-)


def gamma_f(params: PartialFactors) -> float:
    """Partial factor on speeds and heights, :math:`\\gamma_{Tr} \\gamma_{Dp}` (-)."""
    return params.gamma_tr * params.gamma_dp


def design_energy_check(result: MeasureResult, capacity_kj: float, params: PartialFactors,
                        design_block: DesignBlock | None) -> Check:
    """``design_energy``: :math:`E_d \\le E_{cap} / \\gamma_E` (kJ), with its bounds.

    :math:`E_d = \\tfrac12 m_d v_d^2` with the ``percentile`` speed times
    :math:`\\gamma_F` and the design block's mass (or the rocks'
    ``percentile`` mass) times :math:`\\gamma_{VolF} \\gamma_\\gamma`.
    """
    g_f = gamma_f(params)
    target = capacity_kj / params.gamma_e
    speeds = np.asarray(result.velocity_ms, dtype=float)
    masses = np.asarray(result.mass_kg, dtype=float)
    figures = (DesignValue("E_cap", "energy capacity (capacity_kj, the MEL)", capacity_kj,
                           "kJ", source="product"),
               DesignValue("E_cap / gamma_E", "the limit of the design energy", target, "kJ",
                           source="product"))
    named: dict[str, Any] = {"symbol": "E_d", "relation": "<=",
                             "target_symbol": "E_cap / gamma_E", "design_values": figures}
    if speeds.size == 0 or masses.size == 0:
        return Check("design_energy", None, target, True, "kJ", NO_ROCK, None, True,
                     **named)
    p = percentile_label(params.percentile)
    # One partial sort for each array's percentile and its two bounds.
    speed, speed_l, speed_b = statistic_with_bounds(speeds, p, params.confidence,
                                                    params.percentile)
    mass, mass_l, mass_b, mass_text = design_mass(design_block, masses, p,
                                                  params.confidence)
    e_d = design_energy(params, mass, speed)
    detail = (
        f"E_d = 1/2 m_d v_d^2 = {number_text(e_d, 'kJ')} with m_d = {mass_text} "
        f"x {params.gamma_volf:g} x {params.gamma_gamma:g}, v_d = {p} speed "
        f"{number_text(speed, 'm/s')} x gamma_F {g_f:.4g}, over {rocks_text(speeds.size)}; "
        f"limit {number_text(capacity_kj, 'kJ')} / gamma_E {params.gamma_e:g} = "
        f"{number_text(target, 'kJ')}"
    )
    e_b = (None if speed_b is None or mass_b is None
           else design_energy(params, mass_b, speed_b))
    m_f = params.gamma_volf * params.gamma_gamma
    named["design_values"] = (
        DesignValue("v_d", f"design speed: {p} speed x gamma_F", speed * g_f,
                    "m/s", None if speed_b is None else speed_b * g_f),
        DesignValue("m_d", "design mass: " + ("the design block (rocks.design_block)"
                    if design_block else f"{p} mass") + " x gamma_VolF gamma_gamma",
                    mass * m_f,
                    "kg", None if mass_b is None else mass_b * m_f),
        DesignValue("E_d", "design energy 1/2 m_d v_d^2", e_d, "kJ", e_b), *figures)
    e_l = None if speed_l is None or mass_l is None else design_energy(params, mass_l,
                                                                              speed_l)
    return limit_check("design_energy", e_d, target, "kJ", detail, e_b, e_l, p, speeds.size,
                       params.confidence, **named)

def design_energy(params: PartialFactors, mass_kg: float, speed_ms: float) -> float:
    """E_d (kJ) from a characteristic mass (kg) and speed (m/s)."""
    m_d = mass_kg * params.gamma_volf * params.gamma_gamma
    v_d = speed_ms * gamma_f(params)
    return 0.5 * m_d * v_d**2 / 1000.0

def required_height(params: PartialFactors, height_m: float, radius_m: float) -> float:
    """h_d + f (m) from a characteristic passing height and radius (m)."""
    return height_m * gamma_f(params) + max(params.f_min_m, radius_m)

def design_height_check(result: MeasureResult, nominal_m: float, residual_m: float | None,
                        params: PartialFactors) -> Check:
    """``design_height``: h_d + f against the residual height where given, else the nominal (m).

    :math:`h_d` is the ``percentile`` passing height times :math:`\\gamma_F`,
    :math:`f = \\max(f_{min}, d_d / 2)` with :math:`d_d` twice the
    ``percentile`` radius.
    """
    g_f = gamma_f(params)
    heights = np.asarray(result.rated_passing_height_m, dtype=float)
    radii = np.asarray(result.radius_m, dtype=float)
    if residual_m is None:
        height_m = nominal_m
        against = f"nominal height {number_text(nominal_m, 'm')}"
    else:
        height_m = residual_m
        against = (f"residual height after the MEL test {number_text(residual_m, 'm')} of "
                   f"{product_name(result)} (catalogue; nominal height "
                   f"{number_text(nominal_m, 'm')}), used in place of the nominal height")
    figure = (DesignValue("h_N", "nominal height", nominal_m, "m", source="product"),)
    if residual_m is not None:
        figure += (DesignValue("h_R", "residual height after the MEL test", residual_m, "m",
                               source="product"),)
    named: dict[str, Any] = {"symbol": "h_d + f", "relation": "<=",
                             "target_symbol": "h_N" if residual_m is None else "h_R",
                             "design_values": figure}
    if heights.size == 0:
        return Check("design_height", None, height_m, True, "m", NO_ROCK, None, True,
                     **named)
    p = percentile_label(params.percentile)
    # One partial sort for each array's percentile and its two bounds.
    height, height_l, height_b = statistic_with_bounds(heights, p, params.confidence,
                                                       params.percentile)
    radius, radius_l, radius_b = (statistic_with_bounds(radii, p, params.confidence,
                                                        params.percentile)
                                  if radii.size else (0.0, 0.0, 0.0))
    h_d = height * g_f
    d_d = 2.0 * radius
    freeboard = max(params.f_min_m, d_d / 2.0)
    required = h_d + freeboard
    detail = (
        f"h_d + f = {number_text(required, 'm')} with h_d = {p} passing height "
        f"{number_text(height, 'm')} x gamma_F {g_f:.4g}, f = max({params.f_min_m:g} m, "
        f"d_d/2 = {number_text(d_d / 2.0, 'm')}), over {rocks_text(heights.size)}; "
        f"{against}"
    )
    required_b = (None if height_b is None or radius_b is None
                  else required_height(params, height_b, radius_b))
    named["design_values"] = (
        DesignValue("h_d", f"design height: {p} passing height x gamma_F", h_d, "m",
                    None if height_b is None else height_b * g_f),
        DesignValue("f", "freeboard: max(f_min, d_d / 2)", freeboard, "m"),
        DesignValue("h_d + f", "required height", required, "m", required_b), *figure)
    required_l = (None if height_l is None or radius_l is None
                  else required_height(params, height_l, radius_l))
    return limit_check("design_height", required, height_m, "m", detail, required_b,
                       required_l, p, heights.size, params.confidence, **named)


def fractile_check(name: str, values: Any, add: float, target: float, against: str, unit: str,
                   factor: float, factor_text: str, confidence: float,
                   scale: tuple[float, float] = (1.0, 1.0), what: str = "",
                   named: dict[str, Any] | None = None) -> Check:
    """``factor x P99(values) + add`` against ``target`` (holds if <=), with its bounds.

    ``factor_text`` names the factor in the detail (e.g. ``"gamma_F 1.1
    (CC2)"``), ``against`` what the value is compared with; ``scale``:
    factors on the lower and upper bound of the fractile for an uncertainty
    beside the rocks' (a design block's mass bounds); ``what`` names the
    values in the detail; ``named``: the check's symbols and the figures it
    is compared with (its own design value is added here). Bounds are
    order-statistic bounds of the 99 % fractile at ``confidence``.
    """
    named = dict(named or {})
    figures = named.pop("design_values", ())
    v = np.asarray(values, dtype=float)
    c = confidence
    if v.size == 0:
        return Check(name, None, target, True, unit, NO_ROCK, None, True, **named,
                     design_values=figures)
    point, lower, upper = quantile_with_bounds(v, 0.99, c)
    lower = None if lower is None else lower * scale[0]
    upper = None if upper is None else upper * scale[1]
    g = factor
    value = g * point + add
    detail = (f"{factor_text} x 99 % fractile "
              f"{point:.2f} {unit}" + (f" of {what}" if what else "")
              + (f" + freeboard {add:.2f} m" if add else "")
              + f" = {value:.2f} {unit} over {v.size} rocks, against {against}")
    optimistic = None if lower is None else g * lower + add
    fails = optimistic is not None and optimistic > target
    if scale != (1.0, 1.0):  # what the rocks cannot narrow: the other uncertainty's bounds
        named["limits"] = (g * point * scale[0] + add, g * point * scale[1] + add)
    symbol = named.get("symbol") or "value"
    meaning = f"design value: gamma_F {g:.3g} x 99 % fractile"
    if upper is None:
        need = rocks_to_bound_quantile(0.99, c)
        detail = f"{detail}; {v.size} rocks cannot bound the 99 % fractile: it needs {need}"
        return Check(name, value, target, bool(value <= target), unit, detail, None, False,
                     need, optimistic, fails, **named,
                     design_values=(*figures, DesignValue(symbol, meaning, value, unit, None)))
    bound = g * upper + add
    detail = f"{detail}; with the {100 * c:g} % bound {bound:.2f} {unit}"
    return Check(name, value, target, bool(value <= target), unit, detail, bound,
                 bool(bound <= target), None, optimistic, fails, **named,
                 design_values=(*figures, DesignValue(symbol, meaning, value, unit, bound)))

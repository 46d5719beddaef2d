"""The built-in managed protection forest, ``type: protection_forest``.

An ordinary plugin with an entry point of its own (``protection_forest``).
Lengths in m, stem diameters in cm, costs per hectare and year.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from pydantic import Field, model_validator

from rockfall_design import (
    MeasureParams,
    ProfileEdit,
    ProtectiveMeasure,
    Quantity,
    Stand,
    hookimpl,
)

from .shared import STATION_RANGE, SectionLike, StrictParams, check_stretch

__all__ = ["ProtectionForest", "ProtectionForestParams", "present_worth_factor",
           "rockfall_design_measures"]

#: Price of managing a hectare of protection forest for a year (currency/ha/yr).
#: ILLUSTRATIVE: of the order of the yearly share of the thinning and
#: regeneration interventions a managed Alpine protection forest needs
#: (NaiS, Frehner et al. 2005, sets their targets, not their prices); take
#: the forest service's own figure for the stand.
COST_PER_HA_YEAR = 300.0
#: Working life over which the yearly cost is counted (years). ILLUSTRATIVE:
#: the 50 years often taken for a rockfall fence's service life.
WORKING_LIFE_YEARS = 50.0
#: Real discount rate of the yearly costs (-). ILLUSTRATIVE: 2 %, of the
#: order used in Swiss cost-benefit practice for protective measures.
DISCOUNT_RATE = 0.02


def present_worth_factor(years: float, rate: float) -> float:
    """Present value of 1 a year for ``years`` years at the discount ``rate`` (years).

    The uniform-series present-worth factor (1 - (1 + i)^-n) / i, n years at
    rate i; n itself at i = 0.

    References
    ----------
    .. [1] Newnan, D.G., Eschenbach, T.G. and Lavelle, J.P. (2004).
       Engineering Economic Analysis, 9th ed., ch. 4 (uniform series).
    """
    if rate <= 0.0:
        return float(years)
    return float((1.0 - (1.0 + rate) ** -years) / rate)


class ProtectionForestParams(StrictParams):
    """Parameters of a managed protection forest over a stretch of slope."""

    x: float = Field(
        description="Station of the forest's upslope edge, x_from (m).",
        json_schema_extra={"unit": "m"},
    )
    length: float = Field(
        gt=0, description="Horizontal length of the forested stretch (m): x_to = x + length.",
        json_schema_extra={"unit": "m", "design": {"bounds": [20.0, 150.0]}},
    )
    stems_per_ha: float = Field(
        gt=0, le=20_000, description="Stem density the management keeps (stems per hectare).",
        json_schema_extra={"unit": "1/ha", "design": {"bounds": [200.0, 1200.0]}},
    )
    dbh_mean_cm: float = Field(
        gt=0, le=300, description="Mean stem diameter at breast height the stand has (cm).",
        json_schema_extra={"unit": "cm", "design": {"bounds": [15.0, 45.0]}},
    )
    dbh_sd_cm: float | None = Field(
        default=None, ge=0,
        description="Standard deviation of the DBH (cm), at most the mean; default a "
        "third of the mean (ILLUSTRATIVE).", json_schema_extra={"unit": "cm"},
    )
    tree_height_m: float = Field(
        default=5.0, gt=0, le=100,
        description="Height (m) up to which a passing rock's centre meets a stem "
        "(default 5, ILLUSTRATIVE, as a material's forest:).", json_schema_extra={"unit": "m"},
    )
    working_life_years: float = Field(
        default=WORKING_LIFE_YEARS, gt=0, le=200,
        description="Years of management counted in the cost (default 50, ILLUSTRATIVE).",
        json_schema_extra={"unit": "yr"},
    )
    discount_rate: float = Field(
        default=DISCOUNT_RATE, ge=0, le=0.2,
        description="Real discount rate of the yearly cost (default 0.02, ILLUSTRATIVE).",
        json_schema_extra={"unit": None},
    )

    @model_validator(mode="after")
    def _check_spread(self) -> ProtectionForestParams:
        if self.dbh_sd_cm is not None and self.dbh_sd_cm > self.dbh_mean_cm:
            raise ValueError(f"dbh_sd_cm must be at most dbh_mean_cm ({self.dbh_mean_cm:g})")
        return self


class ProtectionForest(ProtectiveMeasure):
    """A managed protection forest: a stand of trees kept on a stretch of slope.

    Parameters (``Params``)
    -----------------------
    x, length : float
        The stretch [x, x + length] (m) the stand covers.
    stems_per_ha, dbh_mean_cm, dbh_sd_cm, tree_height_m : float
        The stand (``rockfall_design.engine.forest``): a rock meets stems as
        a Poisson stand of that density and loses the energy each takes
        (Dorren & Berger 2006).
    working_life_years, discount_rate : float
        The yearly cost counted over the working life, discounted to today.

    Notes
    -----
    Footprint: a :class:`ProfileEdit` that keeps the ground (its points are
    the section's own) and gives each segment of the stretch a copy of its
    material carrying the stand; rocks that come to rest with their centre
    in the stretch are caught by it (among them those a stem stopped).

    Cost: the stand's area per running metre of slope, length / 10,000 ha,
    times the present worth of a year's management over the working life,
    billed as ``forest_ha_year`` (ha-years of management, discounted) at
    :data:`COST_PER_HA_YEAR` unless the cost model prices it. The model is
    of a stand that already has the density and diameter asked for: it does
    not price, nor wait for, growing one.
    """

    kind: ClassVar[str] = "protection_forest"
    summary: ClassVar[str] = "managed protection forest: a stand of trees kept on a stretch"
    Params: ClassVar[type[MeasureParams]] = ProtectionForestParams
    example: ClassVar[dict[str, Any]] = {
        "x": 60.0,
        "length": 80.0,
        "stems_per_ha": 600.0,
        "dbh_mean_cm": 30.0,
    }
    design_variables: ClassVar[dict[str, tuple[float, float]]] = {
        "x": STATION_RANGE,
        "length": (20.0, 150.0),
        "stems_per_ha": (200.0, 1200.0),
        "dbh_mean_cm": (15.0, 45.0),
    }
    default_prices: ClassVar[dict[str, Any]] = {"forest_ha_year": COST_PER_HA_YEAR}

    params: ProtectionForestParams

    def stand(self) -> Stand:
        """The stand the forest keeps (the DBH spread a third of the mean if not given)."""
        p = self.params
        sd = p.dbh_mean_cm / 3.0 if p.dbh_sd_cm is None else p.dbh_sd_cm
        return Stand(p.stems_per_ha, p.dbh_mean_cm, sd, p.tree_height_m)

    def footprint(self, section: SectionLike) -> ProfileEdit:
        """The stretch [x, x + length] with the stand on it; ValueError if it does not fit."""
        p = self.params
        x_a, x_b = p.x, p.x + p.length
        check_stretch(section, x_a, x_b, "the protection forest")
        xs, ys = np.asarray(section.x, float), np.asarray(section.y, float)
        inner = (xs > x_a) & (xs < x_b)
        px = np.concatenate([[x_a], xs[inner], [x_b]])
        points = np.column_stack([px, np.interp(px, xs, ys)])
        return ProfileEdit(x_start=x_a, x_end=x_b, points=points, catch_from=x_a,
                           catch_to=x_b, forest=self.stand())

    def design_properties(self) -> dict[str, float]:
        """``width_m`` (m): the forest's length along x, its catch area as a ditch's width."""
        return {"width_m": self.params.length}

    def quantities(self, section: SectionLike) -> dict[str, float]:
        """``area_ha_per_m`` (ha/m), ``forest_ha_year_per_m`` (discounted ha-years/m), the stand."""
        p = self.params
        area = p.length / 1e4
        return {"area_ha_per_m": area,
                "forest_ha_year_per_m": area * present_worth_factor(p.working_life_years,
                                                                    p.discount_rate),
                "width_m": p.length, "stems_per_ha": p.stems_per_ha,
                "dbh_mean_cm": p.dbh_mean_cm}

    def bill_from(self, quantities: dict[str, float]) -> list[Quantity]:
        """``forest_ha_year``: discounted ha-years of management per running metre."""
        return [Quantity("forest_ha_year", quantities["forest_ha_year_per_m"], "ha yr")]

    def label(self) -> str:
        p = self.params
        return (f"protection forest ({p.stems_per_ha:g} stems/ha, DBH {p.dbh_mean_cm:g} cm, "
                f"{p.length:g} m long) at x = {p.x:g} m")


@hookimpl
def rockfall_design_measures() -> list[type[ProtectiveMeasure]]:
    """The built-in protection forest, registered by its own entry point."""
    return [ProtectionForest]

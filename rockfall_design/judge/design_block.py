"""The project's design block as the concepts see it: its mass with its bounds.

``rocks.design_block`` (:mod:`rockfall_design.project.design_block`) gives
either a block survey and a percentile or a return period and a
magnitude-frequency relation. This module turns it into a
:class:`~rockfall_design.plugins.concept.DesignBlock`: the mass (kg), the
one-sided order-statistic bounds of a survey's percentile at the concept's
confidence, and one line saying where it comes from, which the concepts
repeat in their checks.

See Also
--------
rockfall_design.judge.bounds.quantile_with_bounds : the distribution-free bounds.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..plugins.concept import DesignBlock
from .bounds import quantile_with_bounds, rocks_to_bound_quantile

if TYPE_CHECKING:  # pragma: no cover
    from ..project import Project

__all__ = ["design_block_of"]

_UNIT = {"volume": "m3", "mass": "kg"}


def design_block_of(project: Project, confidence: float) -> DesignBlock | None:
    """The project's design block at ``confidence``, or None where it gives none.

    Parameters
    ----------
    project : Project
    confidence : float
        One-sided confidence of the bounds of a survey's percentile (-).

    Returns
    -------
    DesignBlock or None
        Mass (kg) and its bounds; a volume is turned into a mass with
        ``rocks.density`` (kg/m3).

    Raises
    ------
    ProjectError
        A survey too small to bound its percentile at ``confidence``, at
        ``rocks.design_block.percentile``: a design block must say how sure
        it is (the error says how many blocks would do).
    """
    spec = project.rocks.design_block
    if spec is None:
        return None
    density = float(project.rocks.density)
    if spec.blocks is None:
        volume = spec.return_period_volume_m3
        assert spec.frequency is not None
        source = (f"return period {spec.return_period_years:g} years of N(>V) = "
                  f"{spec.frequency.a:g} V^-{spec.frequency.b:g} per year: V_T = "
                  f"{volume:.3g} m3 at {density:g} kg/m3 (no confidence bound: the "
                  "relation's parameters are taken as given)")
        mass = volume * density
        return DesignBlock(mass, mass, mass, source)
    values = np.asarray(spec.blocks, dtype=float)
    assert spec.percentile is not None
    q = float(spec.percentile) / 100.0
    point, lower, upper = quantile_with_bounds(values, q, confidence)
    per_kg = density if spec.quantity == "volume" else 1.0
    unit = _UNIT[spec.quantity]
    survey = f"survey {spec.survey}" if spec.survey else "the surveyed blocks"
    source = (f"p{spec.percentile:g} of the {values.size} block {spec.quantity}s of {survey} "
              f"= {point:.3g} {unit}")
    if spec.quantity == "volume":
        source = f"{source} at {density:g} kg/m3"
    if upper is None or lower is None:
        needed = rocks_to_bound_quantile(q, confidence)
        raise project.error_at(
            ("rocks", "design_block", "percentile"),
            f"{values.size} surveyed blocks cannot bound their {spec.percentile:g}th percentile "
            f"at {100 * confidence:g} % confidence: survey at least {needed} blocks, or take "
            "a lower percentile")
    source = (f"{source}, {100 * confidence:g} % bounds {lower:.3g} to {upper:.3g} {unit}")
    return DesignBlock(point * per_kg, lower * per_kg, upper * per_kg, source)

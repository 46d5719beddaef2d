"""Calibrate: the ``calibrate:`` section, a back-analysis of observed stop positions.

.. code-block:: yaml

    calibrate:
      observed: stops.csv            # one row per observed block: x (m); optional
                                     # volume_m3 or mass_kg
      fit:                           # paths as in study.vary, each with its range
        materials.soil.restitution: [0.05, 0.7]
        materials.soil.rolling_resistance: [0.05, 1.2]
      levels: {bench: [33, 41], floor: [41, 110]}   # optional stretches of x (m)
      rocks: 1000                    # simulated rocks per evaluation
      bootstrap: 50                  # replicates for the intervals
      confidence: 0.95
      distance: energy               # or wasserstein

This module checks the section's shape; whether each path names an input
of the project and each end of its range is valid there is checked against
the project itself by :mod:`rockfall_design.calibration`, as the study's
paths are (:func:`rockfall_design.studies.paths.with_values`).
"""

from typing import Annotated, Any, Literal

from pydantic import BeforeValidator, Field, model_validator

from .fields import Integer, Label, String, _as_number, _choice, _Model
from .messages import _fail, describe, fmt

#: Most inputs fitted at once: every one costs evaluations, and a few dozen
#: observed stops cannot pin down more than a handful (the bootstrap says which
#: are not identified). 12 lets ``fit: auto`` run on a section of six spang
#: or rn_rt materials (two calibrated parameters each).
MAX_FITTED = 12
#: Most simulated rocks per evaluation (each replicate makes ~100 evaluations).
MAX_CALIBRATION_ROCKS = 200_000
#: Most bootstrap replicates.
MAX_BOOTSTRAP = 2_000


def _interval(value: Any) -> tuple[float, float]:
    """``[lo, hi]`` with lo < hi, both finite numbers."""
    if not isinstance(value, list | tuple) or len(value) != 2:
        raise _fail(f"expected [lo, hi], got {describe(value)}")
    lo = _as_number(value[0], (0,))
    hi = _as_number(value[1], (1,))
    if not lo < hi:
        raise _fail(f"expected [lo, hi] with lo < hi, got [{fmt(lo)}, {fmt(hi)}]")
    return (lo, hi)


Interval = Annotated[tuple[float, float], BeforeValidator(_interval)]


#: ``fit: auto`` until the project expands it (rockfall_design.project.model):
#: a key no input path can be, so that ``fit`` keeps one type and its errors
#: their plain locations.
AUTO_FIT = "*auto*"


def _auto_fit_marker(value: Any) -> Any:
    """``fit: auto`` as the one-entry mapping the project expands."""
    return {AUTO_FIT: (0.0, 1.0)} if value == "auto" else value


class CalibrateSpec(_Model):
    """The ``calibrate:`` section: observed stops, the inputs fitted and their ranges."""

    observed: Annotated[String, Field(min_length=1)] = Field(
        description="CSV file of the observed blocks (relative to the project file): a "
        "header row, then one row per block with x (its stop station, m) and optionally "
        "volume_m3 or mass_kg."
    )
    fit: Annotated[dict[String, Interval], Field(min_length=1, max_length=MAX_FITTED),
                   BeforeValidator(_auto_fit_marker)] = Field(
        description="Input path (as in study.vary) -> [lo, hi], the range searched; or "
        "auto: for every material on the section the parameters its law calibrates "
        "(CALIBRATED), each over the material's ranges: (docs/calibration.md)."
    )
    levels: dict[Label, Interval] = Field(
        default_factory=dict,
        description="Named stretches of x [from, to) (m) whose shares of the stops are "
        "compared (and fitted) besides the stop positions.",
    )
    rocks: Annotated[Integer, Field(ge=20, le=MAX_CALIBRATION_ROCKS)] = Field(
        1000, description="Simulated rocks per evaluation of the distance (--rocks)."
    )
    bootstrap: Annotated[Integer, Field(ge=0, le=MAX_BOOTSTRAP)] = Field(
        50,
        description="Bootstrap replicates (each a refit on resampled observations with its "
        "own simulation seed) giving the intervals; 0: the best fit only.",
    )
    confidence: Annotated[float, Field(gt=0.5, lt=1.0)] = Field(
        0.95, description="Confidence of the parameters' intervals and the levels' shares."
    )
    distance: Annotated[
        Literal["energy", "wasserstein"], BeforeValidator(_choice("energy", "wasserstein"))
    ] = Field(
        "energy",
        description="Distance between the observed and simulated stop positions: energy "
        "(Szekely & Rizzo) or wasserstein (Wasserstein-1).",
    )

    @model_validator(mode="after")
    def _check_levels(self) -> "CalibrateSpec":
        spans = sorted((lo, hi, name) for name, (lo, hi) in self.levels.items())
        for (_, hi, first), (lo, _, second) in zip(spans, spans[1:], strict=False):
            if lo < hi:
                raise _fail(
                    f"level {second!r} overlaps level {first!r}: each stop belongs to one "
                    "level at most",
                    ("levels", second),
                )
        return self


#: The parameters ``fit: auto`` calibrates, by impact law: the loss in contact
#: that a stop position depends on (rolling resistance, or R_t for the
#: lumped-mass law), and for spang and rn_rt the normal loss (restitution).
#: For rough_soft only the soil's rolling resistance mu_s: on Authume P1 the
#: restitution moves no level's share by more than 0.02 over its class's
#: range, and the obstacle height acts on a stop only through
#: mu_0 = mu_s + h_o / (h_o + r) with mu_s, so stops cannot tell the two apart
#: (fitted together, neither was identified in 10 of 10 refits); both stay at
#: their class's value, the obstacle height keeping the size effect
#: (docs/calibration.md, "Why P2 was not predicted"). Friction is left out:
#: stops hardly constrain it once rolling resistance is fitted.
CALIBRATED: dict[str, tuple[str, ...]] = {
    "spang": ("restitution", "rolling_resistance"),
    "rn_rt": ("restitution", "tangential_restitution"),
    "rough_soft": ("rolling_resistance",),
}

#: The choices of ``distance``, for the command line.
DISTANCES: tuple[str, ...] = ("energy", "wasserstein")

Distance = Literal["energy", "wasserstein"]

__all__ = ["AUTO_FIT", "CALIBRATED", "CalibrateSpec", "DISTANCES", "MAX_FITTED", "Distance"]


"""The design block of a project: ``rocks.design_block``, from a survey or a return period.

The concepts that design on one block (``uni11211``, ``onr24810``) take its
mass, :math:`m_d`, from the design block where the project gives one, in
place of a percentile of the simulated rocks' masses:

``{survey: blocks.csv, percentile: 98}``
    A block survey: a CSV file (relative to the project file) with a header
    row naming a column ``volume_m3`` or ``mass_kg`` (one of them; other
    columns such as an id or a note are ignored), one block a row. The
    design block is the ``percentile`` of the surveyed sizes, with its
    distribution-free confidence bounds (order statistics, at
    ``safety.confidence``). The loader reads the file into ``blocks`` (the
    sizes) and ``quantity`` (``volume`` or ``mass``), so that the run record
    and ``design.yaml`` hold the values; ``blocks`` may also be given inline.
``{return_period_years: 100, frequency: {a: 5.0, b: 0.7}}``
    A magnitude-frequency relation: the power law :math:`N(>V) = a V^{-b}`
    of the yearly number of falls of a volume larger than :math:`V` (m3),
    the form fitted to rockfall inventories by Hungr et al. (1999) and
    Dussauge et al. (2003). The design block is the volume exceeded once in
    the return period :math:`T`: :math:`a V_T^{-b} = 1/T`, so
    :math:`V_T = (a T)^{1/b}`. Its parameters are the user's; no confidence
    bound is attached to it.

A volume becomes a mass with ``rocks.density``.

References
----------
.. [1] Hungr, O., Evans, S. G. and Hazzard, J. (1999). Magnitude and frequency
   of rock falls and rock slides along the main transportation corridors of
   southwestern British Columbia. Canadian Geotechnical Journal 36, 224-238.
.. [2] Dussauge, C., Grasso, J.-R. and Helmstetter, A. (2003). Statistical
   analysis of rockfall volume distributions: implications for rockfall
   dynamics. Journal of Geophysical Research 108(B6), 2286.
.. [3] David, H. A. and Nagaraja, H. N. (2003). Order Statistics, 3rd ed.,
   Wiley, sect. 7.1 (distribution-free confidence intervals for quantiles).
"""

from __future__ import annotations

import csv
import io
import math
from typing import Annotated, Any, Literal

from pydantic import Field, model_validator

from ..errors import ProjectError
from .fields import Number, Positive, SectionModel, String
from .messages import fail

__all__ = ["BlockFrequency", "DesignBlockSpec", "MAX_SURVEY_BLOCKS", "SURVEY_COLUMNS",
           "inline_survey", "parse_block_survey"]

#: The size columns a block survey may have, and the ``quantity`` each gives.
SURVEY_COLUMNS = {"volume_m3": "volume", "mass_kg": "mass"}
#: Most blocks a survey may list: a survey counts blocks by hand or from a
#: point cloud, thousands at most; more is a mistake (a wrong file).
MAX_SURVEY_BLOCKS = 1_000_000


class BlockFrequency(SectionModel):
    """The power law :math:`N(>V) = a V^{-b}`: falls per year larger than ``V`` (m3)."""

    a: Positive = Field(description="Falls per year of a volume of more than 1 m3 (1/year).")
    b: Annotated[Number, Field(gt=0.0, le=10.0)] = Field(
        description="Exponent of the power law (-); inventories give 0.4 to 1 (Dussauge "
        "et al. 2003).")


class DesignBlockSpec(SectionModel):
    """``rocks.design_block``: a survey's percentile, or a return period's block."""

    survey: String | None = Field(
        None, description="Block survey: a CSV file (relative to the project file) with a "
        "column volume_m3 or mass_kg, one block a row.")
    percentile: Annotated[Number, Field(gt=0.0, lt=100.0)] | None = Field(
        None, description="Percentile (%) of the surveyed sizes taken as the design block, "
        "e.g. 98; above 0, below 100.")
    blocks: Annotated[list[Positive], Field(min_length=1, max_length=MAX_SURVEY_BLOCKS)] | None \
        = Field(None, description="The surveyed sizes (m3 or kg, by quantity): read from "
                "the survey file by the loader, or given here inline.")
    quantity: Literal["volume", "mass"] = Field(
        "volume", description="What blocks holds: volume (m3) or mass (kg).")
    return_period_years: Positive | None = Field(
        None, description="Return period (years) of the design block, with frequency.")
    frequency: BlockFrequency | None = Field(
        None, description="Magnitude-frequency relation N(>V) = a V^-b per year, V in m3.")

    @model_validator(mode="after")
    def _one_source(self) -> DesignBlockSpec:
        from_survey = self.survey is not None or self.blocks is not None
        from_period = self.return_period_years is not None or self.frequency is not None
        if from_survey and from_period:
            raise fail("give either a survey (survey, percentile) or a return period "
                        "(return_period_years, frequency), not both", ("return_period_years",))
        if from_survey:
            if self.blocks is None:
                raise fail("the survey file was not read (give survey: a CSV file name)",
                            ("survey",))
            if self.percentile is None:
                raise fail("give the percentile (%) of the surveyed blocks taken as the "
                            "design block, e.g. percentile: 98", ("percentile",))
            return self
        if self.return_period_years is None or self.frequency is None:
            missing = "frequency" if self.return_period_years is not None else \
                "return_period_years"
            raise fail("give the design block as survey: blocks.csv with percentile: 98, "
                        "or as return_period_years with frequency: {a, b}", (missing,))
        if self.percentile is not None:
            raise fail("percentile goes with a survey, not with a return period",
                        ("percentile",))
        return self

    @property
    def return_period_volume_m3(self) -> float:
        """:math:`V_T = (a T)^{1/b}` (m3): the volume exceeded once in the return period."""
        assert self.frequency is not None and self.return_period_years is not None
        return float((self.frequency.a * self.return_period_years) ** (1.0 / self.frequency.b))


def parse_block_survey(text: str, source: str) -> tuple[str, list[float]]:
    """The quantity (``volume`` or ``mass``) and sizes of a block survey's CSV ``text``.

    Parameters
    ----------
    text
        The file's content.
    source
        The file's name as shown in messages.

    Raises
    ------
    ProjectError
        Empty file, no (or two) size columns, a row of another width, a cell
        that is not a finite number > 0: ``file:line: column: message``.
    """
    rows = list(csv.reader(io.StringIO(text.removeprefix("\ufeff"))))
    numbered = [(i + 1, r) for i, r in enumerate(rows) if any(c.strip() for c in r)]
    if not numbered:
        raise ProjectError(source, 1, "", "the block survey is empty: expected a header row "
                           "with volume_m3 or mass_kg, then one row per block")
    (_, header), body = numbered[0], numbered[1:]
    names = [h.strip() for h in header]
    given = [c for c in SURVEY_COLUMNS if c in names]
    if len(given) != 1:
        what = (f"give only one of {' and '.join(given)}" if given else
                f"no column volume_m3 (m3) or mass_kg (kg) in the header row "
                f"({', '.join(names)})")
        raise ProjectError(source, 1, given[1] if len(given) > 1 else "", what)
    column = given[0]
    at = names.index(column)
    if len(body) > MAX_SURVEY_BLOCKS:
        raise ProjectError(source, body[MAX_SURVEY_BLOCKS][0], "",
                           f"more than {MAX_SURVEY_BLOCKS:,} blocks")
    values = []
    for line, row in body:
        if len(row) != len(header):
            raise ProjectError(source, line, "", f"expected {len(header)} cells as in the "
                               f"header row, got {len(row)}")
        values.append(_size(row[at], source, line, column))
    if not values:
        raise ProjectError(source, numbered[0][0], column, "no block below the header row")
    return SURVEY_COLUMNS[column], values


def _size(text: str, source: str, line: int, column: str) -> float:
    """A finite size > 0 from a CSV cell, or the one-line error at its place."""
    cell = text.strip()
    try:
        value = float(cell)
    except ValueError:
        shown = repr(cell) if cell else "an empty cell"
        raise ProjectError(source, line, column, f"expected a number, got {shown}") from None
    if not (math.isfinite(value) and value > 0.0):
        raise ProjectError(source, line, column, f"expected a size > 0, got {cell}")
    return value


def inline_survey(block: Any, read: Any) -> Any:
    """``rocks.design_block`` with its survey file read into ``blocks`` and ``quantity``.

    ``read(name)`` returns ``(text, shown name)`` of the file named in the
    project (its errors are the project's, at the ``survey`` key). A block
    that names no survey, or already holds its ``blocks`` (a run record read
    back), is returned as it is.
    """
    if not isinstance(block, dict) or "survey" not in block or "blocks" in block:
        return block
    text, shown = read(block["survey"])
    quantity, values = parse_block_survey(text, shown)
    return {**block, "blocks": values, "quantity": quantity}

"""The report's context: everything report.html and report.md show, as typed parts.

:func:`.documents.report_context` (simulate, check, optimise, check
--scenarios) and :func:`rockfall_design.calibration.document.report_context`
(calibrate, compare) build a :class:`ReportContext`; the Jinja2 templates
read its fields by name (:meth:`ReportContext.template_values`), so that a
template and the code that fills it agree on one list of names.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

from .sections import Table

__all__ = ["LimitsPart", "ReportContext", "ReportFigure"]


@dataclass
class ReportFigure:
    """A figure of the report.

    Attributes
    ----------
    name : str
        Its name: the file NAME.svg beside report.md, the anchor in report.html.
    caption : str
        What it shows, under it.
    fig : matplotlib.figure.Figure
        The figure itself.
    svg : str or None
        Its inline SVG, set for report.html only.
    file : str or None
        Its file name, set for report.md only.
    """

    name: str
    caption: str
    fig: Any
    svg: Any = None
    file: str | None = None


@dataclass(frozen=True)
class LimitsPart:
    """A part of the section "Model and limits": a heading and its bullets."""

    heading: str
    items: list[str]


@dataclass
class ReportContext:
    """Everything the report templates show, as plain data (text, tables, figures).

    Attributes
    ----------
    title, project, description, command, version, generated : str
        The head of the report: its title, the project's name and description,
        the command, the program's version and when it was written (UTC).
    run : Table or None
        The run: program, project file and hash, rocks, seeds, engine, plugins.
    inputs : list of Table
        Every input of the run, so that the report alone rebuilds the project.
    results : list of Table
        The run's results (ends, stations, checks, passages; a calibration's fit).
    protect : str
        The protected zone and the rocks reaching it, a sentence ("" without one).
    verdict, verdict_state : str
        The verdict's headline and its state's words ("" without a verdict).
    failures : list of str
        What fails (or a calibration's warnings), a line each.
    bill : Table or None
        The chosen design's bill (optimise).
    limits : list of LimitsPart
        The section "Model and limits".
    chosen : str
        The sentence naming the chosen design (optimise; "" otherwise).
    chosen_measures : list of str
        Its measures, a line each.
    design_values : list of Table
        The design values at each measure (check, optimise).
    how_sure : list of str
        How sure the verdict is, a line each ("- " starts a bullet).
    figures : list of ReportFigure
    verdict_ok : bool or None
        Whether the verdict holds with confidence; None: not said (the templates
        then colour the verdict by ``failures``).
    results_note : str or None
        A note above the results; None: none.
    scenarios_note : str or None
        check --scenarios: the verdict over the scenarios in words.
    """

    title: str
    project: str
    description: str
    command: str
    version: str
    generated: str
    run: Table | None
    inputs: list[Table]
    results: list[Table] = field(default_factory=list)
    protect: str = ""
    verdict: str = ""
    verdict_state: str = ""
    failures: list[str] = field(default_factory=list)
    bill: Table | None = None
    limits: list[LimitsPart] = field(default_factory=list)
    chosen: str = ""
    chosen_measures: list[str] = field(default_factory=list)
    design_values: list[Table] = field(default_factory=list)
    how_sure: list[str] = field(default_factory=list)
    figures: list[ReportFigure] = field(default_factory=list)
    verdict_ok: bool | None = None
    results_note: str | None = None
    scenarios_note: str | None = None

    def template_values(self, **overrides: Any) -> dict[str, Any]:
        """The templates' variables: every field, those that are None left out.

        The templates ask ``is defined`` of the optional parts (``verdict_ok``,
        ``results_note``), so a part not given must be absent, not None.
        ``overrides`` replace fields (the figures with their SVG) or add
        variables (``for_print``).
        """
        values = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        values.update(overrides)
        return {k: v for k, v in values.items() if v is not None or k in ("run", "bill")}

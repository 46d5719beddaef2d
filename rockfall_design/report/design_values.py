"""The engineer's words: the design values at each measure, and how sure they are.

A report opens with the verdict, then, per measure, the design values in the
safety concept's own symbols (``h_d``, ``v_d``, ``m_d``, ``E_d``, a braking
distance, a factor) against the product's figures (nominal height, capacity,
residual height, elongation): what the concept's checks report as
:class:`~rockfall_design.plugins.concept.DesignValue` and their ``symbol``,
``relation`` and ``target_symbol``, shown as they are, so that a concept or
a product figure the report has never heard of appears with no change here.
The statistics behind them ("how sure") follow in plain sentences.

Everything is read from a check summary (``check --json``, or the chosen
design's for ``optimise``) and returned as rows of text, which the terminal
(rich) and the documents (Jinja2) lay out each in their own way.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from .rounding import round_value

__all__ = ["DesignTable", "design_tables", "design_columns", "fresh_statements", "how_sure",
           "state_of"]


@dataclass
class DesignTable:
    """The design values of one measure.

    Attributes
    ----------
    title : str
        The measure and what the rocks did there.
    rows : list of list of str
        :func:`design_columns` cells.
    states : list of str
        Per row, the check's state ("" for a design value's row).
    state : str
        The measure's state (the verdict's words), "" if it has none.
    """

    title: str
    rows: list[list[str]]
    states: list[str]
    state: str


def design_columns(confidence: float) -> list[str]:
    """The columns of a design-values table."""
    return ["check", "symbol", "design value or figure", "value",
            f"{100 * confidence:g} % bound", "unit", "state"]


def _fmt(v: Any, unit: str) -> str:
    """A value rounded for its unit (see :func:`~.rounding.round_value`), '-' without one."""
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    r = round_value(v, unit)
    if isinstance(r, int):
        return f"{r:,}"
    return f"{r:,.2f}" if unit in ("-", "m") else f"{r:,g}"


def state_of(check: Mapping[str, Any]) -> str:
    """A check's state, or ``ok``/``FAILS`` for a summary from before states."""
    return str(check.get("state") or ("ok" if check.get("ok") else "FAILS"))


def _requirement(c: Mapping[str, Any]) -> str:
    """'requirement: E_d <= E_cap / gamma_E = 1,667 kJ' (or the check's name and target)."""
    unit = str(c.get("unit", "-"))
    target = _fmt(c.get("target"), unit) + ("" if unit == "-" else f" {unit}")
    symbol, rel = c.get("symbol") or c.get("name"), c.get("relation") or "vs"
    what = c.get("target_symbol") or "target"
    return f"requirement: {symbol} {rel} {what} = {target}"


def _measure_title(m: Mapping[str, Any]) -> str:
    through = int(m.get("broken_through") or 0) + int(m.get("passed_through_gap") or 0)
    met = int(m.get("met") or 0)
    if met == 0:
        return f"{m.get('label') or m.get('type')}: no rock met it (untested)"
    return (f"{m.get('label') or m.get('type')}: {met:,} rocks met it, "
            f"{int(m.get('caught') or 0):,} held, {int(m.get('passed_over') or 0):,} over, "
            f"{through:,} through")


def design_tables(summary: Mapping[str, Any]) -> list[DesignTable]:
    """One table per measure of a check summary: design values, figures, requirements.

    Rows, in the order a reader follows a check: each of its design values
    (from the rocks, with their bounds) and the product's figures it uses,
    then the check itself (its requirement, value, bound and state).
    """
    out = []
    for m in summary.get("measures") or []:
        rows: list[list[str]] = []
        states: list[str] = []
        for c in m.get("checks") or []:
            for d in c.get("design_values") or []:
                unit = str(d.get("unit", "-"))
                what = str(d.get("meaning", ""))
                if d.get("source") == "product":
                    what = f"{what} (product)"
                rows.append(["", str(d.get("symbol", "")), what, _fmt(d.get("value"), unit),
                             _fmt(d.get("bound"), unit), unit, ""])
                states.append("")
            unit = str(c.get("unit", "-"))
            rows.append([str(c.get("name")), str(c.get("symbol") or ""), _requirement(c),
                         _fmt(c.get("value"), unit), _fmt(c.get("bound"), unit), unit,
                         state_of(c)])
            states.append(state_of(c))
        if not rows:
            rows.append(["(none)", "", "the safety concept checks nothing of this measure",
                         "", "", "", ""])
            states.append("")
        out.append(DesignTable(_measure_title(m), rows, states, str(m.get("state") or "")))
    return out


def _pct(f: float) -> str:
    return f"{100 * f:.3g} %"


def how_sure(summary: Mapping[str, Any]) -> list[str]:
    """The statistical proof of a check summary, as plain sentences (one per item).

    What the values are statistics of and with which confidence; what the
    verdict rests on (each open item, each failure); the rocks reaching the
    protected zone with their Clopper-Pearson bound.
    """
    n = int(summary.get("rocks") or 0)
    conf = float(summary.get("confidence") or 0.95)
    at = f"{100 * conf:g} %"
    verdict = summary.get("verdict") or {}
    state = verdict.get("state")
    lines = [f"Every design value above is a statistic of the {n:,} rocks of this run "
             f"(seed {summary.get('seed')}) that met the measure, computed with the safety "
             f"concept's partial factors. Beside each is its one-sided {at} confidence bound "
             "on the unsafe side: a percentile's from the order statistics of the sample "
             "(distribution-free), a maximum's the maximum itself. A requirement holds with "
             "confidence when it still holds with every bound in place of its value."]
    if state == "holds with confidence":
        lines.append(f"Every requirement holds with its bounds in place: the design holds "
                     f"with {at} confidence on these rocks.")
    elif state == "holds on point values only":
        lines.append("Every requirement holds on its value, but not every one with its bound "
                     "in place; so the design holds on point values only. What is open:")
    elif state == "fails":
        lines.append("A requirement is missed on its value itself; no number of rocks turns "
                     "that into a pass. What fails:")
    elif state == "untested":
        lines.append("Nothing was tested: no rock met a measure and there is no protected "
                     "zone to count rocks in.")
    lines += [f"- {d}" for d in verdict.get("details") or []]
    p = summary.get("protect")
    if p:
        upper = p.get("upper_fraction")
        lines.append(
            f"{int(p['reaching']):,} of {n:,} rocks ({_pct(float(p['fraction']))}) reached the "
            f"protected zone at x >= {float(p['x']):g} m"
            + ("" if upper is None else
               f"; with {at} confidence the share of all rocks that would reach it is at most "
               f"{_pct(float(upper))} (Clopper-Pearson upper bound)")
            + (f"; allowed {_pct(float(p['allowed_fraction']))}."
               if p.get("allowed_fraction") is not None else "."))
    lines += [str(s) for s in summary.get("concept_statements") or []]
    return lines


def fresh_statements(best: Mapping[str, Any]) -> list[str]:
    """The safety concept's sentences on the fresh rocks that verified the chosen design."""
    said = list(best.get("fresh_statements") or [])
    if not said:
        return []
    return [f"On the {int(best.get('fresh_rocks') or 0):,} fresh rocks (seed "
            f"{best.get('fresh_seed')}) that verified the chosen design:", *said]

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
from typing import TYPE_CHECKING, Any

from ..judge.records import CheckSummary, MeasureRecord, State, check_of
from ..plugins.concept import Check
from .rounding import round_value

if TYPE_CHECKING:  # pragma: no cover
    from ..optimiser.alternatives import Alternative

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


def state_of(check: Check | Mapping[str, Any], state: str | None = None) -> str:
    """A check's state (``state``, or a dict's own), or ``ok``/``FAILS`` without one.

    A summary judged before the verdict's states existed has none: its
    checks say what the point values say.
    """
    if isinstance(check, Mapping):
        state = state or check.get("state")
        ok = bool(check.get("ok"))
    else:
        ok = check.ok
    return str(state or ("ok" if ok else "FAILS"))


def _requirement(c: Check) -> str:
    """'requirement: E_d <= E_cap / gamma_E = 1,667 kJ' (or the check's name and target)."""
    target = _fmt(c.target, c.unit) + ("" if c.unit == "-" else f" {c.unit}")
    symbol, rel = c.symbol or c.name, c.relation or "vs"
    what = c.target_symbol or "target"
    return f"requirement: {symbol} {rel} {what} = {target}"


def _measure_title(m: MeasureRecord) -> str:
    if m.met == 0:
        return f"{m.label}: no rock met it (untested)"
    return (f"{m.label}: {m.met:,} rocks met it, {m.caught:,} held, {m.passed_over:,} over, "
            f"{m.through:,} through")


def _value_rows(c: Check) -> list[list[str]]:
    """The design values and product figures behind a check, a row each."""
    rows = []
    for d in c.design_values:
        what = f"{d.meaning} (product)" if d.source == "product" else d.meaning
        rows.append(["", d.symbol, what, _fmt(d.value, d.unit), _fmt(d.bound, d.unit),
                     d.unit, ""])
    return rows


def design_tables(summary: CheckSummary | Mapping[str, Any]) -> list[DesignTable]:
    """One table per measure of a check summary: design values, figures, requirements.

    Rows, in the order a reader follows a check: each of its design values
    (from the rocks, with their bounds) and the product's figures it uses,
    then the check itself (its requirement, value, bound and state).
    """
    summary = check_of(summary)
    judged = summary.verdict is not None
    out = []
    for m in summary.measures:
        rows: list[list[str]] = []
        states: list[str] = []
        check_states = m.check_states() if judged else [None] * len(m.checks)
        for c, st in zip(m.checks, check_states, strict=True):
            values = _value_rows(c)
            rows += values
            states += [""] * len(values)
            word = state_of(c, st)
            rows.append([c.name, c.symbol, _requirement(c), _fmt(c.value, c.unit),
                         _fmt(c.bound, c.unit), c.unit, word])
            states.append(word)
        if not rows:
            rows.append(["(none)", "", "the safety concept checks nothing of this measure",
                         "", "", "", ""])
            states.append("")
        state = m.state if judged else None
        out.append(DesignTable(_measure_title(m), rows, states, "" if state is None else state))
    return out


def _pct(f: float) -> str:
    return f"{100 * f:.3g} %"


#: What "How sure" says of each state of the verdict.
_STATE_SENTENCES = {
    State.HOLDS_ON_POINT_VALUES: "Every requirement holds on its value, but not every one "
    "with its bound in place; so the design holds on point values only. What is open:",
    State.FAILS: "A requirement is missed on its value itself; no number of rocks turns "
    "that into a pass. What fails:",
    State.UNTESTED: "Nothing was tested: no rock met a measure and there is no protected "
    "zone to count rocks in.",
}


def how_sure(summary: CheckSummary | Mapping[str, Any]) -> list[str]:
    """The statistical proof of a check summary, as plain sentences (one per item).

    What the values are statistics of and with which confidence; what the
    verdict rests on (each open item, each failure); the rocks reaching the
    protected zone with their Clopper-Pearson bound.
    """
    summary = check_of(summary)
    n = summary.rocks
    at = f"{100 * summary.confidence:g} %"
    verdict = summary.verdict
    lines = [f"Every design value above is a statistic of the {n:,} rocks of this run "
             f"(seed {summary.run.seed}) that met the measure, computed with the safety "
             f"concept's partial factors. Beside each is its one-sided {at} confidence bound "
             "on the unsafe side: a percentile's from the order statistics of the sample "
             "(distribution-free), a maximum's the maximum itself. A requirement holds with "
             "confidence when it still holds with every bound in place of its value."]
    if verdict is not None:
        lines.append(f"Every requirement holds with its bounds in place: the design holds "
                     f"with {at} confidence on these rocks."
                     if verdict.state == State.HOLDS_WITH_CONFIDENCE
                     else _STATE_SENTENCES[verdict.state])
        lines += [f"- {d}" for d in verdict.details]
    p = summary.protect
    if p is not None:
        lines.append(
            f"{p.reaching:,} of {n:,} rocks ({_pct(p.fraction)}) reached the protected zone at "
            f"x >= {p.x:g} m; with {at} confidence the share of all rocks that would reach it "
            f"is at most {_pct(p.upper_fraction)} (Clopper-Pearson upper bound); allowed "
            f"{_pct(p.allowed_fraction)}.")
    lines += list(summary.concept_statements)
    return lines


def fresh_statements(best: Alternative) -> list[str]:
    """The safety concept's sentences on the fresh rocks that verified the chosen design."""
    said = list(best.fresh_statements or [])
    if not said:
        return []
    return [f"On the {int(best.fresh_rocks or 0):,} fresh rocks (seed "
            f"{best.fresh_seed}) that verified the chosen design:", *said]

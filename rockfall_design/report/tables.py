"""Tables of results as pandas DataFrames, rounded to what is meaningful.

Built from the JSON-ready summaries (the dicts that ``--json`` prints), not
from the optimiser's or the engine's objects, so that they keep working
while those change and tolerate keys they do not know.

Rounding (:func:`round_value`): costs to whole currency units, factors to
0.01, lengths and heights to 0.01 m, energies to 1 kJ.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

from ..judge.records import CheckSummary, check_of, run_of
from ..run.passages import QUANTITIES
from ..run.summary import RunSummary
from .rounding import round_value

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

__all__ = [
    "chosen_name",
    "round_value",
    "check_columns",
    "measure_text",
    "alternatives_frame",
    "measures_frame",
    "checks_frame",
    "passages_frame",
]

def chosen_name(summary: Mapping[str, Any]) -> str | None:
    """Family name of an optimise summary's chosen design (None without one).

    ``best`` is the chosen design's object (with its ``name``); a summary
    written before it was has the name itself there, which is read too.
    """
    best = summary.get("best")
    if best is None or isinstance(best, str):
        return best
    return best.get("name")


def check_columns(checks: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """One column per check: ``name`` -> rounded value (``name_2`` for a second one).

    A design of two measures has, say, two ``height_factor`` checks: the
    second is ``height_factor_2``. A check with a ``bound`` (a confidence
    bound of its value) gets a ``name_bound`` column too.
    """
    out: dict[str, Any] = {}
    seen: dict[str, int] = {}
    for c in checks:
        name = str(c.get("name", "check"))
        seen[name] = seen.get(name, 0) + 1
        key = name if seen[name] == 1 else f"{name}_{seen[name]}"
        unit = str(c.get("unit", "-"))
        out[key] = round_value(c.get("value"), unit)
        if c.get("bound") is not None:
            out[f"{key}_bound"] = round_value(c.get("bound"), unit)
    return out


def measure_text(m: Mapping[str, Any]) -> str:
    """A measure of a design, from its ``{type, ...params}`` dict: 'fence RX-100 3 m @ 110.5'.

    Uses the measure's ``label`` when the dict carries one.
    """
    if m.get("label"):
        return str(m["label"])
    bits = [str(m.get("type", "?"))]
    if m.get("product"):
        bits.append(str(m["product"]))
    if m.get("width") is not None and m.get("depth") is not None:
        bits.append(f"{m['width']:.3g} x {m['depth']:.3g} m")
    else:
        for name in ("height", "width", "block_size"):
            if isinstance(m.get(name), int | float):
                bits.append(f"{m[name]:.3g} m")
                break
    if m.get("capacity_kj") is not None:
        bits.append(f"{m['capacity_kj']:,.0f} kJ")
    if isinstance(m.get("x"), int | float):
        bits.append(f"@ {m['x']:g} m")
    return " ".join(bits)


_ALT_FIRST = ("family", "chosen", "feasible", "holds_on_fresh_rocks", "cost", "residual",
              "fresh_residual", "measures")
_ALT_LAST = ("reason", "designs_screened", "checks")


def alternatives_frame(summary: Mapping[str, Any]) -> pd.DataFrame:
    """One row per family of the optimiser's summary; one column per check.

    Parameters
    ----------
    summary : dict
        What ``optimise --json`` prints: its ``alternatives`` (each
        ``Alternative.as_dict()``) and ``best``.

    Returns
    -------
    DataFrame
        ``family``, ``chosen``, ``feasible``, ``holds_on_fresh_rocks``,
        ``cost`` (whole currency units), ``residual``, ``fresh_residual``,
        ``measures`` (one text), one column per check (factors to 0.01,
        heights to 0.01 m, energies to 1 kJ; ``name_2`` for a second
        measure's check of the same name), any further scalar keys of the
        alternatives, then ``reason``, ``designs_screened`` and ``checks``
        (every check as ``name=value/target:ok``, for readers of earlier
        files).
    """
    import pandas as pd  # heavy (a fifth of a second): only where a table is built

    best = chosen_name(summary)
    rows: list[dict[str, Any]] = []
    for a in summary.get("alternatives", []):
        row: dict[str, Any] = {
            "family": a.get("name"),
            "chosen": best is not None and a.get("name") == best,
            "feasible": a.get("feasible"),
            "holds_on_fresh_rocks": a.get("holds_on_fresh_rocks"),
            "cost": round_value(a.get("cost"), "cost"),
            "residual": a.get("residual"),
            "fresh_residual": a.get("fresh_residual"),
            "measures": "; ".join(measure_text(m) for m in a.get("measures") or []),
        }
        checks = a.get("checks") or []
        row.update(check_columns(checks))
        # Keys the optimiser may add later: kept when they are plain values.
        for k, v in a.items():
            if k in ("name", "measures", "checks", "evaluations") or k in row:
                continue
            if v is None or isinstance(v, str | int | float | bool):
                # A number of unknown meaning keeps 4 significant digits: a
                # small fraction must not round to 0.
                row[k] = float(f"{v:.4g}") if isinstance(v, float) and math.isfinite(v) else v
        row["reason"] = a.get("reason", "")
        row["designs_screened"] = a.get("evaluations")
        row["checks"] = "; ".join(
            f"{c.get('name')}={round_value(c.get('value'), str(c.get('unit', '-')))}/"
            f"{round_value(c.get('target'), str(c.get('unit', '-')))}:"
            f"{'ok' if c.get('ok') else 'fails'}" for c in checks)
        rows.append(row)
    frame = pd.DataFrame(rows)
    if frame.empty:
        return pd.DataFrame(columns=list(_ALT_FIRST + _ALT_LAST))
    middle = [c for c in frame.columns if c not in _ALT_FIRST and c not in _ALT_LAST]
    frame = frame[list(_ALT_FIRST) + middle + list(_ALT_LAST)]
    # Integers stay integers where a family has no value (pandas would make floats).
    for col in ("cost", "residual", "fresh_residual", "designs_screened"):
        frame[col] = frame[col].astype("Int64")
    for col in middle:
        values = [v for v in frame[col] if v is not None and not pd.isna(v)]
        if values and all(isinstance(v, int) and not isinstance(v, bool) for v in values):
            frame[col] = frame[col].astype("Int64")  # energies rounded to 1 kJ
    return frame


def measures_frame(summary: Mapping[str, Any]) -> pd.DataFrame:
    """One row per measure of a ``check`` summary: what the rocks did there and whether it holds."""
    import pandas as pd  # heavy (a fifth of a second): only where a table is built

    rows = []
    for i, m in enumerate(summary.get("measures", [])):
        rows.append({
            "measure": i,
            "type": m.get("type"),
            "label": m.get("label"),
            "x_m": m.get("x"),
            "met": m.get("met"),
            "caught": m.get("caught"),
            "passed_over": m.get("passed_over"),
            "broken_through": m.get("broken_through"),
            "rebounded": m.get("rebounded"),
            "passed_through_gap": m.get("passed_through_gap"),
            **check_columns(m.get("checks") or []),
            "ok": m.get("ok"),
        })
    frame = pd.DataFrame(rows)
    if "ok" in frame:  # the verdict last, after the check columns of every measure
        frame = frame[[c for c in frame.columns if c != "ok"] + ["ok"]]
    return frame


def checks_frame(summary: Mapping[str, Any]) -> pd.DataFrame:
    """One row per safety check of a ``check`` summary, with its target and verdict."""
    import pandas as pd  # heavy (a fifth of a second): only where a table is built

    rows = []
    for i, m in enumerate(summary.get("measures", [])):
        for c in m.get("checks") or []:
            unit = str(c.get("unit", "-"))
            rows.append({
                "measure": i,
                "label": m.get("label"),
                "check": c.get("name"),
                "value": round_value(c.get("value"), unit),
                "bound": round_value(c.get("bound"), unit),
                "target": round_value(c.get("target"), unit),
                "unit": unit,
                "ok": c.get("ok"),
                "detail": c.get("detail", ""),
            })
    cols = ["measure", "label", "check", "value", "bound", "target", "unit", "ok", "detail"]
    return pd.DataFrame(rows, columns=cols)


#: The columns of barriers.csv (:func:`passages_frame`).
PASSAGE_COLUMNS = ["place", "number", "label", "x_m", "quantity", "unit", "rocks", "mean",
                   "p50", "p95", "p99", "max", "figures"]


def _passage_rows(place: str, number: int, label: str, x: float,
                  block: Mapping[str, Any]) -> list[dict[str, Any]]:
    """The rows of one place: one per quantity of ``run.passages.QUANTITIES`` it has."""

    marks = block.get("marks") or []
    rows = []
    for key, _what, unit in QUANTITIES:
        stats = block.get(key)
        if not isinstance(stats, Mapping):
            continue
        figures = "; ".join(f"{m['label']}" for m in marks if m.get("quantity") == key)
        rows.append({"place": place, "number": number, "label": label, "x_m": x,
                     "quantity": key, "unit": unit, "rocks": block.get("rocks"),
                     **{k: round_value(stats.get(k), unit) for k in
                        ("mean", "p50", "p95", "p99", "max")},
                     "figures": figures})
    return rows


def passages_frame(summary: RunSummary | CheckSummary | Mapping[str, Any]) -> pd.DataFrame:
    """barriers.csv: one row per place (analysis station or barrier) and quantity.

    Parameters
    ----------
    summary : RunSummary, CheckSummary or dict
        A run's or a check's record, or what ``simulate --json`` or ``check
        --json`` prints (read back as its record): its stations and, for a
        check, each barrier's ``passing`` block.

    Returns
    -------
    DataFrame
        ``place`` (``station`` or ``measure``), ``number`` (from 1, in the
        order of ``analysis.stations`` or ``measures:``), ``label``, ``x_m``,
        ``quantity`` (a key of ``run.passages.QUANTITIES``: passing height
        vertical and normal to the slope, translational and angular speed,
        translational, rotational and total energy), ``unit``, ``rocks``
        (that passed the station or met the barrier), ``mean``, ``p50``,
        ``p95``, ``p99``, ``max`` (rounded for the unit), and ``figures``: the
        measure's figures drawn on that quantity (its heights, its
        capacity), empty where there are none. A ground edit (ditch, berm)
        has no rows: no rock passes it at a station.
    """
    import pandas as pd  # heavy (a fifth of a second): only where a table is built

    if isinstance(summary, Mapping):  # a summary's JSON: its record
        summary = check_of(summary) if "safety_concept" in summary else run_of(summary)
    rows: list[dict[str, Any]] = []
    for j, st in enumerate(run_of(summary).stations):
        block = {**st.to_json(), "rocks": st.crossings}
        rows += _passage_rows("station", j + 1, f"station at x = {st.x:g} m", st.x, block)
    measures = summary.measures if isinstance(summary, CheckSummary) else ()
    for i, m in enumerate(measures):
        if m.passing:
            rows += _passage_rows("measure", i + 1, str(m.label), m.x, m.passing)
    return pd.DataFrame(rows, columns=PASSAGE_COLUMNS)

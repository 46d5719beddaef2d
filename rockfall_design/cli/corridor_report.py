"""What a corridor's commands print and write in total: the corridor's JSON and its tables.

:func:`corridor_summary` adds the sections' JSON objects up (rocks, reaching,
cost, failures, the binding scenario); the ``_print_*`` functions draw the
totals in the terminal.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover
    from ..project import Corridor, CorridorSection


def section_block(section: CorridorSection, summary: dict[str, Any]) -> dict[str, Any]:
    """A section's item of ``sections``: its name and index, then its usual JSON object."""
    return {"name": section.name, "index": section.index, **summary}


def corridor_summary(corridor: Corridor, command: str, seed: int,
                     blocks: Sequence[dict[str, Any]],
                     costs: Sequence[float | None] = (),
                     scenarios: bool = False) -> dict[str, Any]:
    """The corridor's JSON: the run, every section's block, and the totals.

    Parameters
    ----------
    corridor
        The corridor run.
    command
        ``simulate``, ``check``, ``optimise`` or ``study``.
    seed
        The run seed the sections' seeds derive from.
    blocks
        One :func:`section_block` per section, in order.
    costs
        ``optimise``: each section's chosen design's cost (None: no design).
    scenarios
        ``check --scenarios``: each block is the section's ``check
        --scenarios`` JSON; the totals count every scenario's rocks and name
        the binding scenario of the corridor, and the JSON says
        ``"scenarios": true``.
    """
    totals: dict[str, Any] = {
        "sections": len(blocks),
        "rocks": int(sum(int(b.get("rocks", 0)) for b in blocks)),
    }
    if command == "study":
        # a section's "rocks" is per scenario: the rocks run are per scenario times scenarios
        totals["scenarios"] = int(sum(len(b["scenarios"]) for b in blocks))
        totals["rocks"] = int(sum(int(b["rocks"]) * len(b["scenarios"]) for b in blocks))
    failures: list[str] = []
    if scenarios:
        # a section's "rocks" is per scenario, as in a study
        totals["scenarios"] = int(sum(int(b["of"]) for b in blocks))
        totals["rocks"] = int(sum(int(b["rocks"]) * int(b["of"]) for b in blocks))
        totals["ok"] = all(bool(b["ok"]) for b in blocks)
        bind = min(blocks, key=lambda b: (math.inf if b["binding"]["margin"] is None
                                          else b["binding"]["margin"], b["index"]))
        totals["binding"] = {"section": bind["name"], **bind["binding"]}
        totals["failures"] = [f"{b['name']}: {f}" for b in blocks for f in b["failures"]]
        verdict = _corridor_verdict(blocks, command)
        if verdict is not None and verdict["state"] == "untested":
            totals["ok"] = False
        return {**({"verdict": verdict} if verdict else {}), "name": corridor.name,
                "command": command, "scenarios": True,
                "seed": int(seed), "sections": list(blocks), "totals": totals}
    if command in ("simulate", "check"):
        reaching = [b["protect"]["reaching"] for b in blocks if b.get("protect")]
        totals["reaching"] = int(sum(reaching)) if reaching else None
    if command == "check":
        totals["ok"] = all(bool(b.get("ok")) for b in blocks)
        failures = [f"{b['name']}: {f}" for b in blocks for f in b.get("failures", [])]
    if command == "optimise":
        found = [c for c in costs if c is not None]
        totals["ok"] = len(found) == len(blocks)
        totals["cost"] = float(sum(found)) if totals["ok"] else None
        currencies = sorted({str(b.get("currency") or "") for b in blocks} - {""})
        totals["currency"] = currencies[0] if len(currencies) == 1 else ""
        failures = [f"{b['name']}: no admissible design: {b.get('reason', '')}"
                    for b, c in zip(blocks, costs, strict=True) if c is None]
    if command in ("check", "optimise"):
        totals["failures"] = failures
    if command == "optimise":  # the corridor's bill: each section's, and the total
        bills = [(b["name"], b.get("bill")) for b in blocks]
        if all(bill is not None for _, bill in bills):
            totals["bill"] = {
                "sections": [{"section": name, "total": bill["total"], "items": bill["items"]}
                             for name, bill in bills],
                "total": float(sum(bill["total"] for _, bill in bills)),
                "currency": totals["currency"]}
    verdict = _corridor_verdict(blocks, command)
    if command == "check" and verdict is not None and verdict["state"] == "untested":
        totals["ok"] = False
    return {**({"verdict": verdict} if verdict else {}), "name": corridor.name,
            "command": command, "seed": int(seed), "sections": list(blocks), "totals": totals}


def _corridor_verdict(blocks: Sequence[dict[str, Any]], command: str) -> dict[str, Any] | None:
    """The corridor's verdict (its weakest section's), each block given its own verdict."""
    if command not in ("check", "optimise"):
        return None
    from ..judge.verdict import DesignVerdict, verdict_of, verdict_of_sections

    items = []
    for b in blocks:
        if "verdict" not in b and command == "check":
            b["verdict"] = verdict_of(b).as_dict()
        if "verdict" not in b:
            return None
        items.append((str(b["name"]), DesignVerdict.from_dict(b["verdict"])))
    return verdict_of_sections(items).as_dict()


def print_totals(summary: dict[str, Any]) -> None:
    """The corridor's table: one row per section, and the total."""
    from rich.markup import escape
    from rich.table import Table
    from rich.text import Text

    from ..report.tables import chosen_name
    from ..report.terminal import fitted_console

    command, totals = summary["command"], summary["totals"]
    if summary.get("scenarios"):
        _print_scenario_totals(summary)
        return
    cur = escape(totals.get("currency") or "")  # words from files: never markup
    table = Table(show_edge=False)
    columns = ["section", "seed", "rocks"]
    if command == "study":
        columns.append("scenarios")
    if command in ("simulate", "check"):
        columns.append("reaching")
    if command == "check":
        columns.append("holds")
    if command == "optimise":
        columns += ["design", f"cost {cur}".strip()]
    for col in columns:
        table.add_column(col, justify="left" if col in ("section", "design", "holds") else
                         "right")
    for block in summary["sections"]:
        row: list[Any] = [Text(block["name"]), str(block["seed"]), f"{block['rocks']:,}"]
        if command == "study":  # rocks of all its scenarios
            k = len(block["scenarios"])
            row[2] = f"{block['rocks'] * k:,}"
            row.append(f"{k:,}")
        if command in ("simulate", "check"):
            protect = block.get("protect")
            row.append("-" if not protect else f"{protect['reaching']:,}")
        if command == "check":
            row.append("yes" if block["ok"] else "NO")
        if command == "optimise":
            best = chosen_name(block)
            cost = next((a["cost"] for a in block["alternatives"] if a["name"] == best), None)
            row += [Text(best or "none"), "-" if cost is None else f"{cost:,.0f}"]
        table.add_row(*row)
    last = ["total", "", f"{totals['rocks']:,}"]
    if command == "study":
        last.append(f"{totals['scenarios']:,}")
    if command in ("simulate", "check"):
        last.append("-" if totals["reaching"] is None else f"{totals['reaching']:,}")
    if command == "check":
        last.append("yes" if totals["ok"] else "NO")
    if command == "optimise":
        last += ["", "-" if totals["cost"] is None else f"{totals['cost']:,.0f}"]
    table.add_row(*last, style="bold")
    console = fitted_console(table)
    _print_verdict(console, summary)
    console.print(f"{summary['name']}: {totals['sections']} sections, run seed "
                  f"{summary['seed']} (each section's seed derives from it)",
                  style="bold", markup=False, highlight=False)
    console.print(table)
    for line in totals.get("failures", []):
        console.print(line, style="red", markup=False, highlight=False)


def _print_verdict(console: Any, summary: dict[str, Any]) -> None:
    """The corridor's verdict first, in the words of every report."""
    v = summary.get("verdict")
    if v:
        console.print(v["headline"], style="bold green" if v["state"] == "holds with confidence"
                      else "bold red" if v["state"] == "fails" else "bold yellow",
                      markup=False, highlight=False)


def _margin(b: dict[str, Any]) -> str:
    return "-" if b["margin"] is None else f"#{b['index']} {100 * b['margin']:+.1f} %"


def _print_scenario_totals(summary: dict[str, Any]) -> None:
    """The corridor's table of ``check --scenarios``: a row per section, and the total."""
    from rich.table import Table
    from rich.text import Text

    from ..report.terminal import fitted_console

    totals = summary["totals"]
    table = Table(show_edge=False)
    for col in ("section", "seed", "rocks", "scenarios", "holds in", "required", "binding",
                "binds at", "holds"):
        table.add_column(col, justify="right" if col in ("seed", "rocks", "scenarios",
                                                         "holds in", "required") else "left")
    for b in summary["sections"]:
        table.add_row(Text(b["name"]), str(b["seed"]), f"{b['rocks'] * b['of']:,}", f"{b['of']:,}",
                      f"{b['holds_in']:,}", f"{b['required']:,}", _margin(b["binding"]),
                      b["binding"]["binds_at"] or "-", "yes" if b["ok"] else "NO",
                      style="" if b["ok"] else "red")
    bind = totals["binding"]
    table.add_row("total", "", f"{totals['rocks']:,}", f"{totals['scenarios']:,}", "", "",
                  f"{bind['section']} {_margin(bind)}", bind["binds_at"] or "-",
                  "yes" if totals["ok"] else "NO", style="bold")
    console = fitted_console(table)
    _print_verdict(console, summary)
    console.print(f"{summary['name']}: {totals['sections']} sections checked over their "
                  f"scenarios, run seed {summary['seed']} (each section's seed derives from "
                  "it, each scenario's from its section's)", style="bold", markup=False,
                  highlight=False)
    console.print(table)
    verdict = ("The corridor holds: every section holds in its required scenarios."
               if totals["ok"] else "The corridor fails: a section holds in too few "
               "scenarios.")
    console.print(verdict, style="bold green" if totals["ok"] else "bold red", markup=False,
                  highlight=False)
    for line in totals["failures"]:
        console.print(line, style="red", markup=False, highlight=False)


def section_rule(section: CorridorSection, of: int, seed: int) -> None:
    """The heading of a section's report; ``seed`` is the one it ran with (``--seed`` too)."""
    from rich.rule import Rule

    from ..report.terminal import fitted_console

    rule = Rule(f"section {section.index + 1} of {of}: {section.name} (seed {seed})")
    fitted_console(rule).print(rule)

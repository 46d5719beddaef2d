"""What a corridor's commands print in total: the corridor's tables in the terminal.

The corridor's result and its JSON are made in :mod:`rockfall_design.studies.corridor`
(:func:`~rockfall_design.studies.corridor.corridor_summary`); :func:`print_totals`
draws its totals, :func:`print_section_rule` heads each
section's own report.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ..report.tables import chosen_name
from ..report.terminal import fitted_console
from ..results import Binding, CorridorSummary, SectionBlock

if TYPE_CHECKING:  # pragma: no cover
    from ..project import CorridorSection

__all__ = ["print_section_rule", "print_totals"]


def _optimise_cells(block: SectionBlock) -> list[Any]:
    """A section's design and its cost, as the table of ``optimise`` shows them."""
    from rich.text import Text


    best = chosen_name(block.data)
    cost = next((a["cost"] for a in block.data.get("alternatives", ()) if a["name"] == best),
                None)
    return [Text(best or "none"), "-" if cost is None else f"{cost:,.0f}"]


def print_totals(summary: CorridorSummary) -> None:
    """The corridor's table: one row per section, and the total."""
    from rich.markup import escape
    from rich.table import Table
    from rich.text import Text


    command, totals = summary.command, summary.totals
    if summary.across:
        _print_scenario_totals(summary)
        return
    cur = escape(totals.currency)  # words from files: never markup
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
    for block in summary.sections:
        row: list[Any] = [Text(block.name), str(block.seed), f"{block.rocks:,}"]
        if command == "study":  # rocks of all its scenarios
            row[2] = f"{block.rocks * block.scenarios:,}"
            row.append(f"{block.scenarios:,}")
        if command in ("simulate", "check"):
            row.append("-" if block.reaching is None else f"{block.reaching:,}")
        if command == "check":
            row.append("yes" if block.ok else "NO")
        if command == "optimise":
            row += _optimise_cells(block)
        table.add_row(*row)
    last = ["total", "", f"{totals.rocks:,}"]
    if command == "study":
        last.append(f"{totals.scenarios:,}")
    if command in ("simulate", "check"):
        last.append("-" if totals.reaching is None else f"{totals.reaching:,}")
    if command == "check":
        last.append("yes" if totals.ok else "NO")
    if command == "optimise":
        last += ["", "-" if totals.cost is None else f"{totals.cost:,.0f}"]
    table.add_row(*last, style="bold")
    console = fitted_console(table)
    _print_verdict(console, summary)
    console.print(f"{summary.name}: {totals.sections} sections, run seed "
                  f"{summary.seed} (each section's seed derives from it)",
                  style="bold", markup=False, highlight=False)
    console.print(table)
    for line in totals.failures:
        console.print(line, style="red", markup=False, highlight=False)


def _print_verdict(console: Any, summary: CorridorSummary) -> None:
    """The corridor's verdict first, in the words of every report."""
    v = summary.verdict
    if v is not None:
        console.print(v.headline, style="bold green" if v.state == "holds with confidence"
                      else "bold red" if v.state == "fails" else "bold yellow",
                      markup=False, highlight=False)


def _margin(b: Binding | None) -> str:
    return "-" if b is None or b.margin is None else f"#{b.index} {100 * b.margin:+.1f} %"


def _print_scenario_totals(summary: CorridorSummary) -> None:
    """The corridor's table of ``check --scenarios``: a row per section, and the total."""
    from rich.table import Table
    from rich.text import Text


    totals = summary.totals
    table = Table(show_edge=False)
    for col in ("section", "seed", "rocks", "scenarios", "holds in", "required", "binding",
                "binds at", "holds"):
        table.add_column(col, justify="right" if col in ("seed", "rocks", "scenarios",
                                                         "holds in", "required") else "left")
    for b in summary.sections:
        table.add_row(Text(b.name), str(b.seed), f"{b.rocks * b.scenarios:,}",
                      f"{b.scenarios:,}", f"{b.data['holds_in']:,}", f"{b.data['required']:,}",
                      _margin(b.binding), (b.binding and b.binding.binds_at) or "-",
                      "yes" if b.ok else "NO", style="" if b.ok else "red")
    bind = totals.binding
    table.add_row("total", "", f"{totals.rocks:,}", f"{totals.scenarios:,}", "", "",
                  f"{totals.binding_section} {_margin(bind)}",
                  (bind and bind.binds_at) or "-", "yes" if totals.ok else "NO",
                  style="bold")
    console = fitted_console(table)
    _print_verdict(console, summary)
    console.print(f"{summary.name}: {totals.sections} sections checked over their "
                  f"scenarios, run seed {summary.seed} (each section's seed derives from "
                  "it, each scenario's from its section's)", style="bold", markup=False,
                  highlight=False)
    console.print(table)
    verdict = ("The corridor holds: every section holds in its required scenarios."
               if totals.ok else "The corridor fails: a section holds in too few "
               "scenarios.")
    console.print(verdict, style="bold green" if totals.ok else "bold red", markup=False,
                  highlight=False)
    for line in totals.failures:
        console.print(line, style="red", markup=False, highlight=False)


def print_section_rule(section: CorridorSection, of: int, seed: int) -> None:
    """The heading of a section's report; ``seed`` is the one it ran with (``--seed`` too)."""
    from rich.rule import Rule


    rule = Rule(f"section {section.index + 1} of {of}: {section.name} (seed {seed})")
    fitted_console(rule).print(rule)

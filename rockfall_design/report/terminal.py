"""The terminal's reports (rich), and the one call that writes a run's figures.

The terminal side of the report room (:mod:`rockfall_design.report`); it was
the module ``rockfall_design/report.py``, whose names the package still offers.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from rich.console import Console, Group
from rich.markup import escape
from rich.panel import Panel
from rich.table import Table
from rich.text import Text

from ..judge.records import (
    Bill,
    CheckSummary,
    DesignVerdict,
    State,
    check_from_json,
    check_of,
    run_of,
)
from ..plugins.listing import SECTIONS, parameter_list
from ..project import dump_yaml
from ..run.summary import RunSummary
from .design_values import design_columns, design_tables, fresh_statements, how_sure
from .listed import SHOWN, forest_text, listed_lines
from .outputs import OutputSet
from .tables import alternatives_frame

if TYPE_CHECKING:  # pragma: no cover
    from ..plugins import Registry
    from ..run.simulation import SimulationRun
    from ..run.streamed import StreamedRun

__all__ = [
    "print_simulation",
    "print_check",
    "print_optimise",
    "alternatives_table",
    "design_yaml",
    "plot_run",
    "plugins_table",
]


#: The widest a report printed to a pipe or a file is made (characters).
MAX_FILE_WIDTH = 200


#: Marginal or undecided cheaper designs the optimise panel shows (the cheapest).
_MARGINAL_SHOWN = SHOWN

def fitted_console(renderable: Any, file: Any = None) -> Console:
    """A console as wide as the report's output can show it.

    On a terminal, rich measures the terminal and tables shrink or wrap their
    cells to fit it. Printed to a pipe or a file there is no width to fit and
    rich would fall back to 80 columns, wrapping every long line; there the
    console is as wide as the content needs (at least 80 columns, at most
    :data:`MAX_FILE_WIDTH`), unless ``COLUMNS`` says otherwise.
    """
    import os

    from rich.measure import Measurement

    console = Console(file=file)
    if console.is_terminal or os.environ.get("COLUMNS"):
        return console
    wide = Console(file=file, width=MAX_FILE_WIDTH)
    need = Measurement.get(wide, wide.options, renderable).maximum
    return Console(file=file, width=max(80, min(MAX_FILE_WIDTH, need)))


def _fmt(v: float | None, digits: int = 2) -> str:
    return "-" if v is None else f"{v:,.{digits}f}"


#: The end states a run's panel lists: label and field of StopsSummary.
_ENDS = (("stopped on the section", "stopped"), ("left downslope end", "exit_downslope"),
         ("left upslope end", "exit_upslope"), ("unresolved (event limit)", "unresolved"),
         ("caught by a barrier", "caught"))


def _ends_table(run: RunSummary) -> Table:
    """How the paths ended: rocks and share per end state (caught only where any were)."""
    st = run.stops
    ends = Table(title="How the paths ended", show_edge=False, title_justify="left")
    ends.add_column("end")
    ends.add_column("rocks", justify="right")
    ends.add_column("share", justify="right")
    for label, key in _ENDS:
        count = st.count(key)
        if key == "caught" and not count:
            continue
        ends.add_row(label, f"{count:,}", f"{100 * count / max(run.rocks, 1):.1f} %")
    return ends


def _stations_table(run: RunSummary) -> Table:
    """The analysis stations: rocks passing, passing heights, speed and energies."""
    tab = Table(
        title="Analysis stations (first passage downslope)",
        caption="h: passing height of the rock centre above ground (m); "
        "v: speed (m/s); E: total kinetic energy (kJ)",
        title_justify="left",
        caption_justify="left",
        show_edge=False,
    )
    tab.add_column("x (m)", justify="right", no_wrap=True)
    tab.add_column("rocks", justify="right", no_wrap=True)
    for q in ("p95", "p99", "max"):
        tab.add_column(f"h {q}", justify="right", no_wrap=True)
    tab.add_column("v max", justify="right")
    for q in ("p95", "p99", "max"):
        tab.add_column(f"E {q}", justify="right", no_wrap=True)
    for s in run.stations:
        h, e = s.passing_height_m, s.energy_kj
        tab.add_row(f"{s.x:g}", f"{s.crossings:,}", *(_fmt(h.at(q)) for q in ("p95", "p99", "max")),
                    _fmt(s.velocity_ms.max, 1), *(_fmt(e.at(q), 0) for q in ("p95", "p99", "max")))
    return tab


def _run_notes(run: RunSummary) -> list[Any]:
    """The protected zone's count, the forest, a streamed run's accuracy, unresolved paths."""
    parts: list[Any] = []
    p = run.protect
    if p is not None:
        style = "bold red" if p.reaching else "bold green"
        parts += [Text(""), Text.assemble(
            f"Protected zone x >= {p.x:g} m: ",
            (f"{p.reaching:,} rocks reach it ({100 * p.fraction:.2f} %)", style),
            (f", {p.unresolved:,} of them unresolved paths counted as reaching it"
             if p.unresolved else "", style))]
    if run.forest is not None:
        parts += [Text(""), Text(forest_text(run))]
    stats = run.statistics
    if stats.method == "histograms":
        parts += [Text(""), Text(
            f"A large run, streamed in chunks of {stats.chunk_rocks:,} rocks: counts, "
            "means and maxima are exact, percentiles within "
            f"{100 * (stats.relative_error or 0.0):g} % (stop positions within "
            f"{stats.stop_x_error_m:.2g} m).", style="dim")]
    if run.stops.unresolved:
        parts.append(Text(
            f"{run.stops.unresolved} rocks reached the event limit and are reported as "
            "unresolved (counted as reaching the protected zone, on the safe side); "
            "raise engine.max_events.", style="yellow"))
    return parts


def simulation_renderable(summary: RunSummary | CheckSummary | Mapping[str, Any]) -> Group:
    """The rich renderable of a ``simulate`` summary (a record, or its JSON read back)."""
    run = run_of(summary)
    n = run.rocks
    rate = n / run.runtime_s if run.runtime_s > 0 else float("nan")
    head = Text.assemble(
        (run.project, "bold"),
        f"   {n:,} rocks, seed {run.seed}, "
        f"{run.runtime_s:.2f} s ({rate:,.0f} rocks/s, {run.events:,} events)",
    )
    sx = run.stops.x
    stops = Text(
        f"Stop position x (m) of the rocks at rest: mean {_fmt(sx.mean, 1)}, "
        f"p50 {_fmt(sx.p50, 1)}, p95 {_fmt(sx.p95, 1)}, max {_fmt(sx.max, 1)}"
    )
    parts: list[Any] = [head, Text(""), _ends_table(run), Text(""), stops]
    if run.stations:
        parts += [Text(""), _stations_table(run)]
    return Group(*parts, *_run_notes(run))


def print_simulation(summary: RunSummary | Mapping[str, Any],
                     console: Console | None = None) -> None:
    panel = Panel(simulation_renderable(summary), title="rockfall-design simulate")
    (console or fitted_console(panel)).print(panel)


def _value(v: float | None, unit: str) -> str:
    if v is None:
        return "-"
    return f"{v:,.2f}" if unit == "-" else f"{v:,.2f} {unit}"


#: The style of each verdict's headline (rockfall_design.judge.verdict.STATES).
_VERDICT_STYLE = {"holds with confidence": "bold green",
                  "holds on point values only": "bold yellow",
                  "fails": "bold red", "untested": "bold magenta"}


def _bill_table(bill: Bill) -> Table:
    """The bill of the chosen design: a line per quantity and fixed cost, the total."""
    # Words from the catalogue and the plugins are shown as written, never as markup.
    cur = escape(bill.currency or "")
    tab = Table(title=f"Bill ({escape(bill.model)}; site length {bill.length_m:g} m)",
                title_justify="left", show_edge=False, caption="count: over the whole site "
                "length; unit prices as the catalogue gives them", caption_justify="left")
    for col, just in (("measure", "left"), ("quantity", "left"), ("count", "right"),
                      ("unit", "left"), (f"unit price {cur}".strip(), "right"),
                      (f"amount {cur}".strip(), "right")):
        tab.add_column(col, justify=just)
    last = None
    for it in bill.items:
        tab.add_row("" if it.measure == last else Text(it.measure), Text(it.quantity),
                    f"{it.count:,.2f}", Text(it.unit), f"{it.unit_price:,.2f}",
                    f"{it.amount:,.2f}")
        last = it.measure
    tab.add_row("total", "", "", "", "", f"{bill.total:,.2f}", style="bold")
    return tab


def _state_text(state: str) -> Text:
    """A check's or measure's state in its verdict's style ("ok"/"FAILS" from before states)."""
    style = _VERDICT_STYLE.get(state, "bold red" if state == "FAILS" else "green")
    return Text(state, style=style.replace("bold ", "") if state != "fails" else style)


def _design_value_tables(summary: CheckSummary) -> list[Any]:
    """The design values of every measure of a check summary, a rich table each.

    See :func:`rockfall_design.report.design_values.design_tables`: the
    concept's symbols against the product's figures, each check's
    requirement and state.
    """
    conf = summary.confidence
    parts: list[Any] = []
    for t in design_tables(summary):
        tab = Table(title=Text(t.title), title_justify="left", show_edge=False)
        for col in design_columns(conf):
            tab.add_column(col, justify="right" if col in ("value", f"{100 * conf:g} % bound")
                           or col.endswith("bound") else "left")
        for row, state in zip(t.rows, t.states, strict=True):
            # Names from the project and the catalogue are text, never markup.
            cells: list[Any] = [Text(str(c)) for c in row[:-1]]
            cells.append(_state_text(state) if state else "")
            tab.add_row(*cells, style="bold" if state else "")
        parts += [tab, Text("")]
    return parts


def _opening(verdict: DesignVerdict | None) -> list[Any]:
    """The verdict and, when the design fails, what fails: the first lines of a report.

    The verdict's other details (what is open with confidence, how many rocks
    would settle it) are the statistics': they follow under "How sure".
    """
    if verdict is None:
        return []
    parts: list[Any] = [Text(verdict.headline, style=_VERDICT_STYLE.get(verdict.state, "bold"))]
    if verdict.state == State.FAILS:
        parts += [Text(f"  - {line}", style="red") for line in verdict.details]
    return parts


def _how_sure_renderable(summary: CheckSummary, extra: list[str] | None = None) -> Group:
    """The section "How sure": the statistics behind the verdict, in plain sentences."""
    parts: list[Any] = [Text("How sure", style="bold underline")]
    for line in [*how_sure(summary), *(extra or [])]:
        parts.append(Text(line, style="yellow" if line.startswith("- ") else ""))
    return Group(*parts)


def _details(summary: CheckSummary) -> list[Any]:
    """How each check's value was computed, one dim line each."""
    parts: list[Any] = []
    for m in summary.measures:
        for c in m.checks:
            if c.detail:
                parts.append(Text(f"  {m.label}: {c.name}: {c.detail}", style="dim"))
    return [Text("How each value was computed", style="bold"), *parts] if parts else []


def check_renderable(summary: CheckSummary | Mapping[str, Any]) -> Group:
    """The rich renderable of a ``check`` summary (a record, or its JSON read back).

    The verdict first, then the design values at each measure against the
    product's figures, then the run (how the paths ended, the stations, the
    protected zone), then "How sure" and how each value was computed.
    """
    summary = check_of(summary)
    opening = _opening(summary.verdict)
    parts: list[Any] = [*opening, Text("")] if opening else []
    parts += [Text(f"Design values (safety concept: {summary.safety_concept})",
                   style="bold underline"), Text("")]
    parts += _design_value_tables(summary)
    parts += list(simulation_renderable(summary).renderables)
    if summary.verdict is None:  # a summary from before verdicts: the point values' word
        parts += [Text(""), Text("Design holds on the point values." if summary.ok
                                 else "Design fails:", style="bold")]
        for line in summary.failures:
            parts.append(Text(f"  - {line}", style="red"))
    parts += [Text(""), _how_sure_renderable(summary), Text(""), *_details(summary)]
    return Group(*parts)


def print_check(summary: CheckSummary | Mapping[str, Any],
                console: Console | None = None) -> None:
    panel = Panel(check_renderable(summary), title="rockfall-design check")
    (console or fitted_console(panel)).print(panel)


def _measure_short(m: Any) -> str:
    """'fence RX-100 3 m @ 110.5' / 'ditch 5.2 x 1.5 m @ 124'."""
    p = m.params
    bits = [m.kind]
    if getattr(p, "product", None):
        bits.append(str(p.product))
    if getattr(p, "width", None) is not None and getattr(p, "depth", None) is not None:
        bits.append(f"{p.width:.3g} x {p.depth:.3g} m")
    else:
        for name in ("height", "width", "block_size"):
            v = getattr(p, name, None)
            if v is not None:
                bits.append(f"{v:.3g} m")
                break
    bits.append(f"@ {m.x:g}")
    return " ".join(bits)


def _factors(alt: Any) -> str:
    """An alternative's factors in a few characters each: 'h 1.52 e 2.10!' (! misses)."""
    out = []
    for c in map(check_from_json, alt.checks):
        if c.value is None:
            continue
        mark = "" if c.ok else "!"
        out.append(f"{c.name.removesuffix('_factor')[:1]} {c.value:.2f}{mark}")
    return " ".join(out)


def _alternatives_renderable(result: Any) -> tuple[Table, list[Any]]:
    """The optimiser's comparison of the families (the chosen one marked), and its order."""
    cur = escape(result.currency or "")
    tab = Table(show_edge=False, title="Alternatives (cheapest design of each family)",
                title_justify="left", caption="factors: h height, e energy, r reach "
                "(! = misses its target); res.: rocks reaching the protected zone; fresh: "
                "holds on fresh rocks", caption_justify="left")
    for col, just in (("", "left"), ("family", "left"),
                      (f"cost {cur}" if cur else "cost", "right"), ("measures", "left"),
                      ("factors", "left"), ("res.", "right"), ("fresh", "left")):
        tab.add_column(col, justify=just)
    order = sorted(result.alternatives, key=lambda a: (not a.holds, a.cost))
    for a in order:
        star = "*" if result.best is a else ""
        style = "bold green" if result.best is a else ("" if a.holds else "dim")
        fresh = "-" if a.holds_on_fresh_rocks is None else (
            "yes" if a.holds_on_fresh_rocks else "NO")
        cost = "-" if not np.isfinite(a.cost) else f"{a.cost:,.0f}"
        tab.add_row(star, Text(a.name), cost if a.holds else f"({cost})",
                    Text("\n".join(_measure_short(m) for m in a.measures) or "-"),
                    _factors(a) or "-",
                    "-" if a.residual is None else f"{a.residual}", fresh, style=style)
    return tab, order


def _search_sentence(result: Any) -> str:
    """How the design was found and decided, in one sentence."""
    return (f"The optimiser searched with {result.search_rocks or result.rocks:,} rocks (seed "
            f"{result.seed}), screening {result.evaluations:,} designs, "
            f"{result.exact_evaluations} of them evaluated exactly and {result.edit_runs} "
            f"ground edits simulated; the chosen design was decided with {result.rocks:,} "
            f"rocks and checked again on {result.fresh_rocks:,} fresh rocks (seed "
            f"{result.fresh_seed}), every bound at {100 * result.confidence:g} % confidence "
            f"({result.wall_s:.1f} s).")


def _marginal_lines(result: Any) -> list[str]:
    """The cheaper designs that are marginal or not decided, one sentence each."""
    return listed_lines(getattr(result, "marginal", None), escape(result.currency or ""),
                        _MARGINAL_SHOWN)


def _bare_slope_line(result: Any) -> list[Any]:
    bare = getattr(result, "bare_slope", None)
    if not (bare and bare["holds"]):
        return []
    return [Text(
        f"The bare slope already meets the residual target: {bare['reaching']:,} of "
        f"{bare['rocks']:,} search rocks reach x = {bare['x']:g} m, at most "
        f"{100 * bare['upper']:.3f} % with {100 * result.confidence:g} % confidence "
        f"(allowed {100 * bare['allowed']:.3f} %). No measure is needed for the "
        "residual; a family's cheapest design may be one that meets few or no rocks.",
        style="bold yellow")]


def print_optimise(result: Any, project: Any, console: Console | None = None,
                   summary: Mapping[str, Any] | None = None,
                   design: CheckSummary | Mapping[str, Any] | None = None) -> None:
    """The optimiser's report: the engineer's words first, the proof after.

    The verdict; the chosen design, its design values at each measure
    against the product's figures (from ``design``, the chosen design's
    check summary, ``OptimiseResult.design.summary``) and its bill (from
    ``summary``, ``OptimiseResult.summary``); the alternatives; then "How
    sure": how the design was searched and decided, its statistics, the
    optimiser's proof and the cheaper designs left marginal or undecided.
    """
    cur = escape(result.currency or "")
    verdict = (summary or {}).get("verdict")
    opening = _opening(None if not verdict else DesignVerdict.from_json(verdict))
    bill = (summary or {}).get("bill")
    design = None if design is None else check_of(design)
    parts: list[Any] = [*opening, Text("")] if opening else []
    if result.best is not None:
        b = result.best
        parts.append(Text(f"Chosen: {b.name}, {b.cost:,.0f} {cur}: "
                          + "; ".join(m.label() for m in b.measures), style="bold green"))
        if b.holds_on_fresh_rocks is False:
            parts.append(Text("Warning: the chosen design does not hold on the fresh rocks: "
                              + "; ".join(b.fresh_failures), style="bold yellow"))
        parts.append(Text(""))
        if design is not None:
            parts += [Text(f"Design values (safety concept: {design.safety_concept})",
                           style="bold underline"), Text(""), *_design_value_tables(design)]
        if bill:
            parts += [_bill_table(Bill.from_json(bill)), Text("")]
    else:
        parts += [Text(f"No admissible design: {result.reason}", style="bold red"), Text("")]
    parts += _bare_slope_line(result)
    tab, order = _alternatives_renderable(result)
    parts += [Text.assemble((project.name, "bold")), tab, Text("")]
    extra = [_search_sentence(result)]
    if result.best is not None and result.best.proof:
        extra.append(f"The optimiser's record of the decision: {result.best.proof}.")
    if result.best is not None:
        extra += fresh_statements(result.best)
    extra += _marginal_lines(result)
    if design is not None:
        parts.append(_how_sure_renderable(design, extra))
    else:
        parts += [Text("How sure", style="bold underline"),
                  *(Text(line, style="yellow" if line.startswith("- ") else "")
                    for line in extra)]
    for a in order:
        if (not a.holds or a.dominated) and a.reason:
            parts.append(Text(f"  {a.name}: {a.reason}", style="dim"))
    panel = Panel(Group(*parts), title="rockfall-design optimise")
    (console or fitted_console(panel)).print(panel)


def alternatives_table(result: Any) -> Any:
    """alternatives.csv: one row per family, one column per check, rounded numbers.

    See :func:`rockfall_design.report.tables.alternatives_frame`.
    """

    return alternatives_frame(result.summary())


def _margin_line(best: Any, rocks: int, confidence: float) -> str:
    """design.yaml's line on the checker's margin the design was admitted with, if any."""
    power = (getattr(best, "fresh_looks", None) or {}).get("checker_power")
    if power is None:
        return ""
    return (f"# margin: admitted only as a design that a check of {2 * rocks} rocks "
            f"at a seed of your own confirms with {100 * confidence:g} % confidence at "
            f"least {100 * power:g} % of the time\n#   (design.checker_power; "
            "docs/sequential-decisions.md)\n")


def _listed_head(listed: Any) -> str:
    """design.yaml's lines on the cheaper designs not admitted, as comments ("" if none)."""
    lines = listed_lines(listed)
    if not lines:
        return ""
    return ("# cheaper designs not admitted (neither shown to hold nor to fail; the "
            "cheapest first):\n" + "".join(f"#   {line}\n" for line in lines))


def design_yaml(best: Any, project_file: Any, search_rocks: int | None = None,
                looks: Any = None, listed: Any = None) -> str:
    """The project with the chosen measures, as YAML that ``check`` accepts.

    Its head records how the design was decided (the looks of the sequential
    decision, see :mod:`rockfall_design.judge.sequential`), how to repeat
    the verification on fresh rocks, and the cheaper designs left marginal or
    undecided (``listed``: ``SearchOutcome.marginal``; default the
    chosen family's own) with the rocks that would decide each.
    """

    ev = best.evaluation
    data = ev.run.project.resolved_dict()
    data.pop("design", None)
    safety = {"concept": ev.concept.name, **ev.concept.params.model_dump(mode="json")}
    if looks is not None:
        # The project's confidence, not the look's (each look bounds at a higher
        # one, its share of the error): a checker's check of this one design is
        # one look, and the checker's margin the design was admitted with is
        # for a check at the project's confidence.
        safety["confidence"] = float(looks.confidence)
    # The rocks that decided the design (the exact run that admitted it).
    rocks = {**data["rocks"], "count": int(ev.run.result.n), "seed": int(ev.run.seed)}
    data.update(rocks=rocks, safety=safety, measures=[
        {"type": m.kind, **m.params.model_dump(mode="json")} for m in best.measures])
    head = (
        f"# Chosen by rockfall-design optimise from {project_file}: {best.name}, "
        f"cost {best.cost:,.0f}.\n"
        f"# rocks: below are the rocks that decided it (seed {ev.run.seed}, "
        f"{ev.run.result.n} rocks; search: {search_rocks} rocks).\n"
        + (f"# decision: admitted at the look of {ev.run.result.n} rocks of the looks "
           f"{', '.join(str(k) for k in looks.sizes)}, each at "
           f"{100 * looks.look_confidence:.4g} % (together {100 * looks.confidence:g} %)\n"
           if looks is not None else "")
        + f"# verification: seed {best.fresh_seed}, {best.fresh_rocks} rocks: "
        f"{'holds' if best.holds_on_fresh_rocks else 'FAILS'}"
        + (f" (the look of {best.fresh_rocks} fresh rocks of the looks "
           f"{', '.join(str(k) for k in best.fresh_looks['rocks'])}, each at "
           f"{100 * best.fresh_looks['look_confidence']:.4g} %)"
           if getattr(best, "fresh_looks", None) else "")
        + "; reproduce with\n"
        f"#   rockfall-design check design.yaml --seed {best.fresh_seed} "
        f"--rocks {best.fresh_rocks}\n"
        + _margin_line(best, ev.run.result.n, safety["confidence"])
        + _listed_head(getattr(best, "marginal", None) if listed is None else listed)
        + "# The design: section is left out (its catalogue paths are relative to the\n"
        "# original project); check this file with: rockfall-design check design.yaml\n"
    )
    # dump_yaml quotes a name the project loader would read as a number (1e3).
    return head + dump_yaml(data)


# ---- figures -----------------------------------------------------------------


def plot_run(
    run: SimulationRun | StreamedRun,
    directory: str | Path,
    evaluation: Any = None,
    outputs: OutputSet | None = None,
    formats: tuple[str, ...] = ("png",),
) -> list[Path]:
    """Write profile, envelopes and stops figures into ``directory``, in each format.

    With an ``evaluation`` (from ``check``) the measures are drawn too. The
    figures join the output set ``outputs`` of the command they belong to
    and land when it commits; without one they land together on return.
    The figures are built by :mod:`rockfall_design.report.figures` (no pyplot, no
    backend switch). Returns the paths written.
    """
    # The drawing module imports matplotlib at its top (a fifth of a second).
    from .figures import run_figures, save_figures

    return save_figures(run_figures(run, evaluation), directory, formats, outputs)


# ---- the plugins command ------------------------------------------------------


def plugins_table(registry: Registry) -> Group:
    """The registry as rich tables (``rockfall-design plugins``)."""

    titles = {"measures": "Measures", "safety_concepts": "Safety concepts",
              "cost_models": "Cost models"}
    parts: list[Any] = []
    for section, _what, _hook, _base, name_attr, key in SECTIONS:
        table = Table(title=titles[section], title_justify="left", expand=False)
        table.add_column(name_attr, style="bold")
        table.add_column("summary")
        table.add_column("parameters (unit)")
        table.add_column("provider", style="dim")
        # The entry point: the name that --block takes for this one.
        table.add_column("plugin", style="dim")
        entries = getattr(registry, section)
        for name, cls in entries.items():
            shown = ", ".join(
                p["name"] + (f" ({p['unit']})" if p["unit"] not in (None, "") else "")
                for p in parameter_list(cls))
            origin = registry.origins.get((key, name))
            table.add_row(name, str(getattr(cls, "summary", "") or ""), shown,
                          registry.provider.get((key, name), ""),
                          origin.plugin if origin else "")
        if not entries:
            table.add_row(Text("(none)", style="dim"), "", "", "", "")
        parts.append(table)
    if not any(getattr(registry, section[0]) for section in SECTIONS):
        parts.append(Text(
            "No plugin provides anything. The built-in plugins are found through the "
            "entry points of the installed distribution: is rockfall-design installed "
            "(pip install -e .)?", style="yellow"))
    if registry.blocked:
        table = Table(title="Blocked", title_justify="left")
        table.add_column("name")
        for name in registry.blocked:
            table.add_row(name)
        parts.append(table)
    if registry.failures:
        table = Table(title="Failures", title_justify="left")
        table.add_column("plugin", style="bold")
        table.add_column("distribution")
        table.add_column("reason", style="red")
        for f in registry.failures:
            table.add_row(f.plugin, f.distribution or "-", f.reason)
        parts.append(table)
    return Group(*parts)

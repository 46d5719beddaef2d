"""The report's sections: tables and texts built from a result's summary.

Each function reads what a command prints with ``--json`` (and the project
and plugins it ran with) and returns a :class:`Table` or a text for the
templates of :mod:`.documents`; numbers are formatted here, once.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

from ..judge.records import (
    Bill,
    CheckSummary,
    MeasureRecord,
    ProtectRecord,
    check_from_json,
    check_of,
    run_of,
)
from ..plugins.concept import Check
from ..run.passages import QUANTITIES
from ..run.summary import RunStatistics, RunSummary
from ..version import __version__
from .design_values import state_of
from .listed import forest_text
from .tables import measure_text, passages_frame, round_value

if TYPE_CHECKING:  # pragma: no cover
    from ..optimiser.alternatives import Alternative, SearchOutcome
    from ..studies.scenario_checks import ScenariosCheck


@dataclass
class Table:
    """A table of the report: a title, column headers, rows of text, an optional note."""

    title: str
    columns: list[str]
    rows: list[list[str]]
    note: str = ""
    highlight: list[bool] = field(default_factory=list)  # rows to emphasise (chosen design)


def _num(v: Any, unit: str = "-", none: str = "-") -> str:
    """A number as text, rounded for its unit (see :func:`.tables.round_value`)."""
    if v is None:
        return none
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float) and not math.isfinite(v):
        return str(v)
    r = round_value(v, unit)
    if isinstance(r, int):
        return f"{r:,}"
    if isinstance(r, float):
        return f"{r:,.2f}" if unit in ("-", "m") else f"{r:,g}"
    return str(r)


def _fixed(v: Any, digits: int) -> str:
    return "-" if v is None else f"{float(v):,.{digits}f}"


def _text(v: Any) -> str:
    """A value of the project as compact text: lists joined, mappings as key value pairs."""
    if isinstance(v, dict):
        return "; ".join(f"{k} {_text(x)}" for k, x in v.items()) or "-"
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_text(x) for x in v) + "]"
    if isinstance(v, float):
        return format(v, ".10g")  # every digit a survey or a catalogue may give
    return "-" if v is None else str(v)


def _flat(d: Mapping[str, Any], prefix: str = "") -> list[list[str]]:
    """Rows ``[key.path, value]`` of every leaf of a nested mapping (lists kept whole)."""
    rows: list[list[str]] = []
    for k, v in d.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict) and v:
            rows += _flat(v, key + ".")
        else:
            rows.append([key, _text(v)])
    return rows


def _block_text(block: Mapping[str, Any]) -> str:
    """``rocks.design_block`` in a line: a survey's values are in their own table."""
    if not block.get("blocks"):
        return _text(dict(block))
    unit = "m3" if block.get("quantity", "volume") == "volume" else "kg"
    head = {k: v for k, v in block.items() if k not in ("blocks", "quantity")}
    return (f"{_text(head)}; {len(block['blocks'])} block {block.get('quantity', 'volume')}s "
            f"({unit}) in the table 'Block survey'")


def _survey_table(block: Mapping[str, Any], per_row: int = 10) -> Table:
    """The surveyed block sizes of ``rocks.design_block``, ``per_row`` a row, in file order."""
    values = list(block["blocks"])
    unit = "m3" if block.get("quantity", "volume") == "volume" else "kg"
    rows = [[f"{i + 1}-{min(i + per_row, len(values))}",
             ", ".join(_text(float(v)) for v in values[i:i + per_row])]
            for i in range(0, len(values), per_row)]
    return Table("Block survey", ["blocks", f"{block.get('quantity', 'volume')} ({unit})"],
                 rows, note=f"{len(values)} blocks of rocks.design_block, as read from "
                 f"{block.get('survey') or 'the project'}; the design block is their "
                 f"{_text(block.get('percentile'))}th percentile.")


@dataclass(frozen=True)
class ProjectInputs:
    """The project as run, section by section, in the project file's own syntax.

    A :meth:`Project.resolved_dict <rockfall_design.project.Project.resolved_dict>`
    (every default filled in) read once, with what the run resolved in place of
    what the file wrote (:func:`resolved_inputs`): the report lists every input
    from it, so that the report alone rebuilds the project.

    Attributes
    ----------
    slope : mapping
        ``points`` ([x, y] in m) and ``materials`` (one per segment).
    materials : mapping
        Each ground material's parameters and ``scatter``, by name.
    rocks, analysis, engine : mapping
        The sections of those names.
    protect : mapping or None
        The protected zone; None without one.
    measures : list of mapping
        ``{type, **params}`` each (every parameter resolved where a check ran).
    safety : mapping or None
        The safety concept's ``concept`` and parameters.
    design : mapping or None
        The design section (candidates, settings, catalogues inline).
    """

    slope: Mapping[str, Any]
    materials: Mapping[str, Mapping[str, Any]]
    rocks: Mapping[str, Any]
    analysis: Mapping[str, Any]
    engine: Mapping[str, Any]
    protect: Mapping[str, Any] | None = None
    measures: list[Mapping[str, Any]] = field(default_factory=list)
    safety: Mapping[str, Any] | None = None
    design: Mapping[str, Any] | None = None

    @classmethod
    def of(cls, resolved: Mapping[str, Any]) -> ProjectInputs:
        """From a project's resolved dict (its sections beyond these are not inputs of a run
        the report lists: ``study`` and ``calibrate`` have their own tables)."""
        return cls(slope=resolved["slope"], materials=resolved["materials"],
                   rocks=resolved["rocks"], analysis=resolved["analysis"],
                   engine=resolved.get("engine") or {}, protect=resolved.get("protect"),
                   measures=list(resolved.get("measures") or []),
                   safety=resolved.get("safety"), design=resolved.get("design"))


def _ground_inputs(d: ProjectInputs) -> list[Table]:
    """The slope section's points and the ground materials, as resolved."""
    out = []
    pts = d.slope["points"]
    per_segment = d.slope["materials"]
    rows = [[_text(float(p[0])), _text(float(p[1])),
             per_segment[i] if i < len(pts) - 1 else ""] for i, p in enumerate(pts)]
    out.append(Table("Slope section", ["x (m)", "elevation (m)", "material of the next segment"],
                     rows, note=f"{len(pts)} points, as resolved from the project's slope "
                     "(a survey file's points included)."))
    mats = d.materials
    keys = list(dict.fromkeys(k for m in mats.values() for k in m if k != "scatter"))
    sc_keys = list(dict.fromkeys(k for m in mats.values() for k in (m.get("scatter") or {})))
    out.append(Table(
        "Ground materials", ["material", *keys, *(f"scatter of {k}" for k in sc_keys)],
        [[name, *(_text(m.get(k)) for k in keys),
          *(_text((m.get("scatter") or {}).get(k, 0.0)) for k in sc_keys)]
         for name, m in mats.items()],
        note="Restitution, friction and rolling resistance are dimensionless; roughness_deg "
        "in degrees, roughness_height_m and velocity_scaling_k as named. Scatter: the "
        "standard deviation of each parameter, drawn per impact (truncated normal)."))
    return out


def inputs_table(project: Any, command: str,
                 resolved: ProjectInputs | Mapping[str, Any] | None = None,
                 concepts: Mapping[str, str] | None = None) -> list[Table]:
    """Every input of the run, so that the report alone rebuilds the project.

    ``resolved`` is the project as run (measures and safety concept with
    every parameter resolved, defaults included; a resolved dict is read as
    :class:`ProjectInputs`), default the project's resolved dict;
    ``concepts`` the summary line of each safety concept (what it follows).
    """
    if not isinstance(resolved, ProjectInputs):
        resolved = ProjectInputs.of(resolved if resolved is not None
                                    else project.resolved_dict())
    d = resolved
    out = _ground_inputs(d)
    r = d.rocks
    block = r.get("design_block") or {}
    rows = [[k, _text(v)] for k, v in r.items() if k not in ("release", "design_block")]
    for i, z in enumerate(r["release"]):
        rows.append([f"release zone {i + 1}", _text(z)])
    if block:
        rows.append(["design_block", _block_text(block)])
    out.append(Table("Rocks", ["quantity", "value"], rows,
                     note="density kg/m3; radius m, volume m3 or mass kg (a number or a "
                     "distribution with its parameters); release: x (m, a range is sampled "
                     "uniformly), height above the ground (m), velocity [vx, vy] (m/s), spin "
                     "(rad/s), weight (share of the rocks). count and seed as written; the run "
                     "table gives the rocks and seeds used."))
    if block.get("blocks"):
        out.append(_survey_table(block))
    rows = [[k, _text(v)] for k, v in d.analysis.items()]
    if d.protect:
        rows += [[f"protect.{k}", _text(v)] for k, v in d.protect.items()]
    out.append(Table("Analysis", ["setting", "value"], rows))
    out.append(Table("Engine", ["setting", "value"], _flat(d.engine)))
    if d.measures:
        out.append(Table("Measures checked" if command == "check" else "Measures of the project",
                         ["measure", "parameters"], _measure_rows(d.measures)))
    if command in ("check", "optimise"):
        sft = d.safety or {}
        name = str(sft.get("concept", "spang"))
        rows = [[k, _text(v)] for k, v in sft.items()]
        if concepts and concepts.get(name):
            rows.append(["follows", concepts[name]])
        out.append(Table("Safety concept", ["parameter", "value"], rows,
                         note="Its standard or paper, and how its factors map to it: the "
                         "section 'Model and limits' below."))
    if command == "optimise" and d.design:
        out += _design_inputs(dict(d.design))
    return out


def _measure_rows(measures: list[Mapping[str, Any]]) -> list[list[str]]:
    """A row per measure: its type, then its parameters as ``name value``."""
    return [[m["type"], ", ".join(f"{k} {_text(v)}" for k, v in m.items() if k != "type")]
            for m in measures]


def _design_inputs(des: dict[str, Any]) -> list[Table]:
    """The design section: candidates, settings, product and cost catalogues."""
    rows = [[c.get("type", "?"), ", ".join(f"{k} {_text(v)}" for k, v in c.items()
                                           if k != "type")]
            for c in des.pop("candidates", [])]
    out = [Table("Candidate measures of the design", ["type", "range"], rows)]
    products = des.pop("products", None) or {}
    costs = des.pop("costs", None) or {}
    out.append(Table("Design settings", ["setting", "value"], _flat(des)))
    if products:
        out.append(Table("Product catalogue", ["measure type", "product", "properties"],
                         [[kind, name, _text(p)] for kind, table in products.items()
                          for name, p in table.items()],
                         note="capacity_kj: energy class (kJ); heights: nominal heights "
                         "(m) on offer."))
    if costs:
        out.append(Table("Cost catalogue", ["price", "value"], _flat(costs),
                         note="Prices in the catalogue's currency, per the unit each key "
                         "names; a barrier's by product and height (m), per running metre."))
    return out


def _plugin_rows(registry: Any, used: list[tuple[str, str]]) -> list[list[str]]:
    """One row per plugin the run used: its kind and name, distribution and version."""
    rows = []
    for key, name in dict.fromkeys(used):
        origin = registry.origins.get((key, name)) if registry is not None else None
        dist = "-" if origin is None else (
            f"{origin.distribution or origin.plugin} {origin.version or ''}".strip())
        rows.append([f"plugin: {key} {name}", dist])
    return rows


def _used_plugins(d: ProjectInputs, command: str) -> list[tuple[str, str]]:
    """The plugins a run of ``command`` used, as (kind, name): its measures, candidates,
    cost model and safety concept."""
    used = [("measure", str(m["type"])) for m in d.measures]
    if command == "optimise" and d.design:
        used += [("measure", str(c["type"])) for c in d.design.get("candidates", [])]
        used.append(("cost", str((d.design.get("costs") or {}).get("model", "unit_prices"))))
    if command in ("check", "optimise"):
        used.append(("safety", str((d.safety or {}).get("concept", "spang"))))
    return used


def _optimise_rows(result: Any) -> list[list[str]]:
    """The rocks and seeds of an optimisation: search, decision, verification; its looks."""
    opt = result.result
    design = getattr(result, "design", None)
    rows = [["search rocks and seed", f"{int(opt.search_rocks or 0):,} rocks, seed {opt.seed}"],
            ["decision rocks and seed", f"{int(opt.rocks):,} rocks, seed {opt.seed}"
             + (" (the chosen design's statistics below)" if design is not None else "")],
            ["verification (fresh rocks) and seed",
             f"{int(opt.fresh_rocks):,} rocks, seed {opt.fresh_seed}"],
            ["designs screened", f"{int(opt.evaluations or 0):,}; "
             f"{int(opt.exact_evaluations or 0):,} evaluated exactly"]]
    looks = opt.looks
    if looks is not None:
        rows.append(["sequential looks (rocks)", ", ".join(f"{n:,}" for n in looks.sizes)
                     + f"; each at {100 * float(looks.look_confidence):.4g} %"])
    return rows


def _statistics_row(stats: RunStatistics) -> list[list[str]]:
    """How the statistics were taken: exact, or streamed with their accuracy."""
    if stats.method == "histograms":
        return [["statistics", "streamed in chunks: counts, means and maxima exact, "
                 f"percentiles within {100 * (stats.relative_error or 0.0):g} %"]]
    return [["statistics", "exact, over every rock"]] if stats.method else []


def run_table(result: Any, summary: RunSummary | CheckSummary | Mapping[str, Any] | None,
              ) -> Table:
    """The report's table of the run: program, project and its hash, rocks, seeds, engine.

    ``summary`` is the run's or the check's (None for ``optimise``, whose
    run is the optimiser's result).
    """
    import platform

    project = result.project
    if isinstance(summary, Mapping) and result.command != "optimise":
        summary = check_of(summary) if "safety_concept" in summary else run_of(summary)
    run = None if result.command == "optimise" else run_of(summary)
    if run is None:
        conf: float | None = float(result.result.confidence)
        runtime = round(float(result.result.wall_s), 3)
    else:
        conf = summary.confidence if isinstance(summary, CheckSummary) else None
        runtime = run.runtime_s
    rows = [["program", f"rockfall-design {__version__}, command {result.command}; Python "
             f"{platform.python_version()}"],
            ["project file", str(project.source)],
            ["project hash (sha256 of the resolved project)",
             str((run.project_hash if run is not None else "") or project.resolved_hash())]]
    rows += _optimise_rows(result) if run is None else [["rocks", f"{run.rocks:,}"],
                                                        ["seed", str(run.seed)]]
    if conf is not None:
        rows.append(["confidence (one-sided, of every bound)", f"{100 * float(conf):g} %"])
    rows.append(["run time", f"{runtime:,.1f} s"])
    if run is not None:
        rows += _statistics_row(run.statistics)
    if isinstance(summary, CheckSummary) and summary.safety_concept:
        rows.append(["safety concept", summary.safety_concept])
    e = project.engine
    rows.append(["engine", f"exact events (flight parabolas, impacts, rolling and sliding in "
                 f"closed form); contact when a rebound's hop is below max(roughness "
                 f"height, {e.contact_hop_ratio:g} r); v_contact {e.v_contact:g} m/s, "
                 f"v_stop {e.v_stop:g} m/s, max_events {e.max_events:,}"])
    registry = getattr(result, "registry", None) or getattr(result, "_registry", None)
    rows += _plugin_rows(registry, _used_plugins(ProjectInputs.of(project.resolved_dict()),
                                                 result.command))
    return Table("", ["item", "value"], rows)


def stations_table(summary: RunSummary | CheckSummary) -> Table | None:
    """The passages at each station (height, velocity, energy); None without stations."""
    stations = run_of(summary).stations
    if not stations:
        return None
    cols = ["x (m)", "rocks passing", "h p50 (m)", "h p95 (m)", "h p99 (m)", "h max (m)",
            "v p95 (m/s)", "v max (m/s)", "E p50 (kJ)", "E p95 (kJ)", "E p99 (kJ)",
            "E max (kJ)"]
    rows = []
    for s in stations:
        h, v, e = s.passing_height_m, s.velocity_ms, s.energy_kj
        rows.append([f"{s.x:g}", f"{s.crossings:,}",
                     *(_fixed(h.at(q), 2) for q in ("p50", "p95", "p99", "max")),
                     _fixed(v.p95, 1), _fixed(v.max, 1),
                     *(_fixed(e.at(q), 0) for q in ("p50", "p95", "p99", "max"))])
    return Table("Analysis stations (first passage downslope)", cols, rows,
                 note="h: passing height of the rock centre above the ground; v: speed; "
                 "E: total kinetic energy. Percentiles over the rocks passing the station.")


def ends_table(summary: RunSummary | CheckSummary) -> Table:
    """How the rocks' paths ended: stopped on the section, left at either end, ..."""
    run = run_of(summary)
    st = run.stops
    n = max(run.rocks, 1)
    rows = []
    for label, key in (("stopped on the section", "stopped"),
                       ("left downslope end", "exit_downslope"),
                       ("left upslope end", "exit_upslope"),
                       ("caught by a barrier", "caught"),
                       ("unresolved (event limit)", "unresolved")):
        count = st.count(key)
        rows.append([label, f"{count:,}", f"{100 * count / n:.1f} %"])
    sx = st.x
    note = ("Stop position x of the rocks at rest (m): "
            f"mean {_fixed(sx.mean, 1)}, p50 {_fixed(sx.p50, 1)}, "
            f"p95 {_fixed(sx.p95, 1)}, max {_fixed(sx.max, 1)}.")
    forest = forest_text(run)
    if forest:
        note += " " + forest
    return Table("How the paths ended", ["end", "rocks", "share"], rows, note=note)


def protect_text(summary: RunSummary | CheckSummary) -> str:
    """The protected zone and the rocks that reach it (with its bound), as a sentence."""
    p = summary.protect
    if p is None:
        return ""
    text = (f"Protected zone x >= {p.x:g} m: {p.reaching:,} of {run_of(summary).rocks:,} rocks "
            f"reach it ({100 * p.fraction:.2f} %)")
    if isinstance(p, ProtectRecord):
        text += (f", upper confidence bound {100 * p.upper_fraction:.2f} %"
                 f"; allowed {100 * p.allowed_fraction:.2f} %")
    if p.unresolved:
        text += f"; {p.unresolved:,} unresolved paths counted as reaching it"
    return text + "."


def _check_rows(m: MeasureRecord, states: list[str], bounds: bool, width: int) -> list[list[str]]:
    """A measure's rows of the checks table: its counts, then a row per check."""
    head = [m.label, f"{m.met:,}", f"{m.caught:,}", f"{m.passed_over:,}", f"{m.through:,}"]
    if not m.checks:
        return [head + ["(none)"] + [""] * (width - 6)]
    rows = []
    for k, (c, state) in enumerate(zip(m.checks, states, strict=True)):
        row = (head if k == 0 else [""] * 5) + [c.name, _num(c.value, c.unit)]
        if bounds:
            row.append(_num(c.bound, c.unit))
        rows.append(row + [_num(c.target, c.unit), c.unit, state, c.detail])
    return rows


def checks_table(summary: RunSummary | CheckSummary) -> Table | None:
    """Each measure's checks (demand, capacity, factor); None without measures."""
    if not isinstance(summary, CheckSummary):
        return None
    bounds = any(c.bound is not None for m in summary.measures for c in m.checks)
    cols = ["measure", "met", "caught", "over", "through", "check", "value"]
    cols += ["bound"] if bounds else []
    cols += ["target", "unit", "verdict", "how"]
    judged = summary.verdict is not None
    rows = []
    for m in summary.measures:
        states = [state_of(c, st.value if judged else None)
                  for c, st in zip(m.checks, m.check_states(), strict=True)]
        rows += _check_rows(m, states, bounds, len(cols))
    return Table("Measures and their checks", cols, rows,
                 note="met: rocks that reached the measure; over: passed over it; through: "
                 "broke through or passed a gap. Value against target as the safety concept "
                 "defines it; verdict in the verdict's words (untested: no rock met the "
                 "measure, so its checks say nothing).")


def passages_table(summary: RunSummary | CheckSummary | Mapping[str, Any]) -> Table | None:
    """Results at every station and barrier: a row per place and quantity (barriers.csv).

    The rows of barriers.csv (:func:`.tables.passages_frame`).
    """
    frame = passages_frame(summary)
    if frame.empty:
        return None
    cols = ["place", "quantity", "unit", "rocks", "mean", "p50", "p95", "p99", "max",
            "measure's figures"]
    what = {key: text for key, text, _ in QUANTITIES}
    rows = []
    last = None
    for r in frame.itertuples(index=False):
        where = f"{r.label}" if r.label != last else ""
        last = r.label
        rows.append([where, what.get(str(r.quantity), str(r.quantity)), str(r.unit),
                     _num(r.rocks, "count"),
                     *(_num(getattr(r, k), str(r.unit)) for k in
                       ("mean", "p50", "p95", "p99", "max")), str(r.figures or "")])
    return Table("Results at every station and barrier", cols, rows,
                 note="Per analysis station the rocks passing it downslope for the first time, "
                 "per barrier the rocks that met it: passing height of the centre vertical and "
                 "normal to the slope, translational and angular speed, translational, "
                 "rotational and total kinetic energy; the barrier's figures (its heights and "
                 "capacities) beside the quantity they bound. As barriers.csv of --out; the "
                 "figures passing_station_N and passing_measure_N show the distributions.")


def _alternative_cost(a: Alternative) -> float | None:
    """An alternative's cost as ``--json`` gives it: to the cent, None where not priced."""
    return None if not math.isfinite(a.cost) else round(a.cost, 2)


def _alternative_measures(a: Alternative) -> str:
    """An alternative's measures, a text each, as the project file would write them."""
    return "; ".join(measure_text({"type": m.kind, **m.params.model_dump(mode="json")})
                     for m in a.measures) or "-"


def _keyed_checks(checks: list[Check]) -> list[tuple[str, Check]]:
    """Each check with its column key: ``name``, ``name_2`` for a second of that name."""
    seen: dict[str, int] = {}
    out = []
    for c in checks:
        seen[c.name] = seen.get(c.name, 0) + 1
        out.append((c.name if seen[c.name] == 1 else f"{c.name}_{seen[c.name]}", c))
    return out


def alternatives_table(opt: SearchOutcome) -> Table:
    """The optimiser's alternatives with their costs and outcomes."""
    cur = opt.currency or ""
    best = None if opt.best is None else opt.best.name
    alts = sorted(opt.alternatives, key=lambda a: (
        not a.feasible, _alternative_cost(a) is None, _alternative_cost(a) or 0))
    keyed = [_keyed_checks([check_from_json(c) for c in a.checks]) for a in alts]
    names: list[tuple[str, str]] = []
    for checks in keyed:
        for key, c in checks:
            if key not in [n for n, _ in names]:
                names.append((key, c.unit))
    cols = ["", "family", f"cost ({cur})" if cur else "cost", "measures", "residual",
            "fresh rocks", *(n.removesuffix("_factor") + ("" if u == "-" else f" ({u})")
                             for n, u in names), "reason"]
    rows, marks = [], []
    for a, checks in zip(alts, keyed, strict=True):
        values = {key: _num(c.value, c.unit) + ("" if c.ok else " !") for key, c in checks}
        fresh = a.holds_on_fresh_rocks
        chosen = best is not None and a.name == best
        cost = _num(_alternative_cost(a), "cost")
        rows.append(["*" if chosen else "", str(a.name), cost if a.feasible else f"({cost})",
                     _alternative_measures(a), _num(a.residual, "count"),
                     "-" if fresh is None else ("holds" if fresh else "FAILS"),
                     *(values.get(n, "") for n, _ in names), str(a.reason or "")])
        marks.append(chosen)
    return Table("Alternatives: the cheapest design of each family", cols, rows,
                 note="* the chosen design; a cost in brackets: not admissible; ! a check "
                 "that misses its target; residual: rocks reaching the protected zone; fresh "
                 "rocks: whether the design holds on rocks not used in the search.",
                 highlight=marks)


def chosen_text(opt: SearchOutcome) -> tuple[str, list[str]]:
    """The sentence naming the chosen design, and the reasons listed under it."""
    best = opt.best
    if best is None:
        return f"No admissible design: {opt.reason}", []
    cur = opt.currency or ""
    head = (f"Chosen design: {best.name}, cost {_num(_alternative_cost(best), 'cost')} "
            f"{cur}").rstrip() + "."
    if opt.reason:
        head += f" Note: {opt.reason}."
    return head, [measure_text({"type": m.kind, **m.params.model_dump(mode="json")})
                  for m in best.measures]


def resolved_inputs(result: Any) -> tuple[ProjectInputs, dict[str, str]]:
    """The project as run (every parameter resolved) and each safety concept's summary."""
    d = ProjectInputs.of(result.project.resolved_dict())
    evaluation = getattr(result, "evaluation", None)
    if result.command == "optimise" and getattr(result, "best", None) is not None:
        evaluation = result.design.evaluation
    if evaluation is not None:
        run = ProjectInputs.of(evaluation.resolved_project().resolved_dict())
        d = replace(d, measures=run.measures if result.command == "check" else d.measures,
                    safety=run.safety or d.safety)
    if result.command == "optimise" and d.protect and result.project.design:
        # optimise judges the residual against design.residual, not the file's
        # protect.allowed_fraction: the table says what the checks used.
        design = result.project.design
        allowed = design.residual_fraction
        if allowed is None:
            allowed = (design.residual_count or 0) / max(int(result.n_rocks), 1)
        d = replace(d, protect={**d.protect, "allowed_fraction": (
            f"{allowed:.6g} ({100 * allowed:.2f} %): design.residual, which every check of "
            "optimise uses (the file's protect.allowed_fraction does not apply)")})
    registry = getattr(result, "registry", None) or getattr(result, "_registry", None)
    concepts = {} if registry is None else {
        name: str(getattr(cls, "summary", "") or "")
        for name, cls in registry.safety_concepts.items()}
    return d, concepts


def _money(v: float) -> str:
    return f"{v:,.2f}"


def bill_table(bill: Bill) -> Table:
    """The chosen design's bill: a line per quantity and fixed cost, and the total."""
    cur = bill.currency or ""
    unit = f" ({cur})" if cur else ""
    rows = [[it.measure, it.quantity, _money(it.count), it.unit, _money(it.unit_price),
             _money(it.amount), it.source] for it in bill.items]
    rows.append(["total", "", "", "", "", _money(bill.total), ""])
    return Table(f"Bill of the chosen design (site length {bill.length_m:g} m)",
                 ["measure", "quantity", "count", "unit", f"unit price{unit}",
                  f"amount{unit}", "price from"], rows,
                 note="count: the quantity over the whole site length (running metres, m3, "
                 "or each); amount = count x unit price; the total is the design's cost as the "
                 f"optimiser compared it, priced by the cost model {bill.model}.",
                 highlight=[False] * len(bill.items) + [True])


def margin_text(margin: Any, binds_at: Any) -> str:
    """The design's margin and the check that binds, as words."""
    return "no check to bind" if margin is None else (
        f"margin {100 * float(margin):+.1f} % at {binds_at}")


def scenarios_table(found: ScenariosCheck, paths: list[str]) -> Table:
    """Every scenario of ``check --scenarios``: values, seed, verdicts, margin, what binds."""
    b = found.binding.index
    cols = ["", "#", *paths, "seed", "reaching", "holds", "with confidence", "margin",
            "binds at"]
    rows, marks = [], []
    for p in found.scenarios:
        s = p.binding
        reach = p.reaching
        rows.append(["*" if s.index == b else "", str(s.index),
                     *(str(s.values.get(k, "-")) for k in paths), str(s.seed),
                     "-" if reach is None else f"{reach:,}",
                     "yes" if p.ok else "FAILS",
                     "yes" if p.holds_with_confidence else "no",
                     "-" if s.margin is None else f"{100 * s.margin:+.1f} %",
                     str(s.binds_at or "-")])
        marks.append(s.index == b)
    return Table(f"Scenarios: {found.of}, each with its own rocks "
                 f"({int(found.rocks):,} rocks, its own seed)", cols, rows,
                 note="* the binding scenario (the one that decides the count required; with every "
                 "scenario required, the least margin). holds: every check and the "
                 "residual on the point values, as check judges them; with confidence: with "
                 "the confidence bounds in place. margin: the smallest relative slack of a "
                 "check or of the residual with the confidence bounds in place, negative "
                 "where it fails. reaching: rocks reaching the protected zone.",
                 highlight=marks)

"""The report an engineer hands in: report.html (self-contained) and report.md.

Both are rendered from one context (plain data: headings, tables of text,
figures) by the Jinja2 templates shipped in ``rockfall_design/report/templates``.
The HTML file embeds every figure as inline SVG and references no other
file or URL, so it can be mailed or archived alone; the Markdown twin
references its figures as SVG files written beside it.

Everything comes from the result's JSON summary and project, never from
engine columns, so the report says what ``--json`` says.
"""

from __future__ import annotations

import datetime as _dt
import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..version import __version__
from .tables import chosen_name, measure_text, round_value

if TYPE_CHECKING:  # pragma: no cover
    from .outputs import OutputSet

__all__ = ["Table", "MODEL_LIMITS", "report_context", "render_html", "render_markdown",
           "write_report"]


@dataclass
class Table:
    """A table of the report: a title, column headers, rows of text, an optional note."""

    title: str
    columns: list[str]
    rows: list[list[str]]
    note: str = ""
    highlight: list[bool] = field(default_factory=list)  # rows to emphasise (chosen design)


def _num(v: Any, unit: str = "-", none: str = "-") -> str:
    """A number as text, rounded for its unit (see :func:`tables.round_value`)."""
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


#: The report's section "Model and limits": (heading, bullets). docs/model-and-limits.md
#: carries every bullet word for word (tests/report/test_model_limits.py).
MODEL_LIMITS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("What is modelled", (
        "A 2-D slope section: every rock moves in the vertical plane of the section, over "
        "straight ground segments with their own material.",
        "The rock is a rigid sphere (mass 4/3 pi r^3 rho, moment of inertia 2/5 m r^2): free "
        "fall, bouncing, rolling and sliding and every transition between them, after Spang "
        "& Rautenstrauch (1988), each phase solved in closed form from one event to the next "
        "(no time step).",
        "Impacts by Newton restitution and Coulomb friction with the spin that friction "
        "gives the rock (impact_model spang), or by normal and tangential restitution "
        "(rn_rt), optionally scaled with the impact speed (Pfeiffer & Bowen 1989).",
        "Scatter: restitution, friction and rolling resistance are drawn per impact from "
        "truncated normals with the standard deviations of scatter:, and the impact normal "
        "is tilted by the roughness; every draw comes from a seeded stream per rock.",
        "Fences and walls are barriers at a station with a nominal height and an energy "
        "capacity; ditches and berms reshape the ground; boulder rows are blocks with gaps.",
        "Design values are statistics of the rocks that met a measure, stated with one-sided "
        "order-statistic confidence bounds; the fraction of rocks reaching the protected "
        "zone with a Clopper-Pearson bound.",
    )),
    ("What is not modelled", (
        "Nothing across the section: no lateral spreading, no convergence of paths in "
        "gullies, no path that leaves the plane; the site length only multiplies the "
        "quantities and the cost.",
        "No shape but the sphere (slabs, discs and columns only through the scatter of the "
        "ground parameters), no fragmentation of a rock on impact, no rock hitting another.",
        "No trees or forest, no air drag, no ground that deforms or is cratered beyond what "
        "restitution and friction represent.",
        "A fence is a line at its station: in the simulation a rock is stopped where its "
        "centre crosses the station, with no braking distance (maximum elongation) and no "
        "loss of height (residual height) after an impact, no difference between hitting a "
        "post, a cable or the middle of the net, no load on posts, anchors or foundations. "
        "Where the product gives its maximum elongation and residual height, the checks use "
        "them (below). The catalogue's capacity_kj is one number; SEL and MEL are not told "
        "apart.",
        "A wall is rigid: no structural check of the wall, the embankment or its foundation; "
        "a ditch or berm holds a rock that comes to rest in it, with no check of its slopes.",
    )),
    ("Safety concepts and the standards they follow", (
        "spang follows Spang & Rautenstrauch (1988): height factor = nominal height / "
        "critical height (the statistic of the passing heights of the rock centres), "
        "target height_factor (the paper: 2 to 3 in normal cases); energy factor = "
        "capacity_kj / design energy (the statistic of the kinetic energies), target "
        "energy_factor; reach factor = width of a ditch or berm / the statistic of the "
        "reach, target reach_factor. The paper took the maximum over a few hundred paths; "
        "here statistic chooses the maximum or the 95th or 99th percentile. The height "
        "factor stays on the nominal height, as in the paper, also where the product gives "
        "a residual height.",
        "uni11211 follows UNI 11211-4 (2018), with Peila & Ronco (2009): design speed and "
        "passing height are the percentile times gamma_F = gamma_tr gamma_dp, the design "
        "mass the percentile times gamma_volf gamma_gamma; the design energy E_d = 1/2 m_d "
        "v_d^2 must not exceed capacity_kj / gamma_e, with capacity_kj the product's MEL; the "
        "nominal height must be at least h_d + f, f = max(f_min_m, half the design block); "
        "where the product gives its residual height, the residual height must be at least "
        "h_d + f instead (the conservative reading, flagged for review against the text of "
        "the standard).",
        "Fence classes follow ETAG 027, now EAD 340059: a kit is tested at its service "
        "energy level SEL and its maximum energy level MEL (SEL = MEL / 3); the MEL test "
        "gives the maximum elongation (braking distance) and the residual height (category "
        "A at least 50 % of the nominal height, B 30 to 50 %, C at most 30 %). The energy "
        "is checked against capacity_kj. Where the catalogue gives a fence product's "
        "max_elongation_m and residual_height_fraction (or a checked fence has them), both "
        "concepts check that the protected zone (protect.x) does not start within the "
        "maximum elongation downslope of the fence (braking_distance, naming the product), "
        "and uni11211 checks the design height against the residual height; without them "
        "the braking distance is not checked and the height is checked against the nominal "
        "height.",
    )),
)


# ---- the parts of the context -------------------------------------------------


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


def _inputs(project: Any, command: str, resolved: Mapping[str, Any] | None = None,
            concepts: Mapping[str, str] | None = None) -> list[Table]:
    """Every input of the run, so that the report alone rebuilds the project.

    ``resolved`` is the project as run (measures and safety concept with
    every parameter resolved, defaults included); ``concepts`` the summary
    line of each safety concept (what it follows).
    """
    d = dict(resolved) if resolved is not None else project.resolved_dict()
    out = []
    slope = d["slope"]
    pts = slope["points"]
    rows = [[_text(float(p[0])), _text(float(p[1])),
             slope["materials"][i] if i < len(pts) - 1 else ""] for i, p in enumerate(pts)]
    out.append(Table("Slope section", ["x (m)", "elevation (m)", "material of the next segment"],
                     rows, note=f"{len(pts)} points, as resolved from the project's slope "
                     "(a survey file's points included)."))
    mats = d["materials"]
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
    r = d["rocks"]
    rows = [[k, _text(r[k])] for k in r if k != "release"]
    for i, z in enumerate(r["release"]):
        rows.append([f"release zone {i + 1}", _text(z)])
    out.append(Table("Rocks", ["quantity", "value"], rows,
                     note="density kg/m3; radius m, volume m3 or mass kg (a number or a "
                     "distribution with its parameters); release: x (m, a range is sampled "
                     "uniformly), height above the ground (m), velocity [vx, vy] (m/s), spin "
                     "(rad/s), weight (share of the rocks). count and seed as written; the run "
                     "table gives the rocks and seeds used."))
    a = d["analysis"]
    rows = [[k, _text(v)] for k, v in a.items()]
    if d.get("protect"):
        rows += [[f"protect.{k}", _text(v)] for k, v in d["protect"].items()]
    out.append(Table("Analysis", ["setting", "value"], rows))
    out.append(Table("Engine", ["setting", "value"], _flat(d.get("engine") or {})))
    if d.get("measures"):
        out.append(Table("Measures checked" if command == "check" else "Measures of the project",
                         ["measure", "parameters"],
                         [[m["type"], ", ".join(f"{k} {_text(v)}" for k, v in m.items()
                                                if k != "type")]
                          for m in d["measures"]]))
    if command in ("check", "optimise"):
        sft = d.get("safety") or {}
        name = str(sft.get("concept", "spang"))
        rows = [[k, _text(v)] for k, v in sft.items()]
        if concepts and concepts.get(name):
            rows.append(["follows", concepts[name]])
        out.append(Table("Safety concept", ["parameter", "value"], rows,
                         note="Its standard or paper, and how its factors map to it: the "
                         "section 'Model and limits' below."))
    if command == "optimise" and d.get("design"):
        des = dict(d["design"])
        rows = [[c.get("type", "?"), ", ".join(f"{k} {_text(v)}" for k, v in c.items()
                                               if k != "type")]
                for c in des.pop("candidates", [])]
        out.append(Table("Candidate measures of the design", ["type", "range"], rows))
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


def _used_plugins(d: Mapping[str, Any], command: str) -> list[tuple[str, str]]:
    used = [("measure", str(m["type"])) for m in d.get("measures") or []]
    if command == "optimise" and d.get("design"):
        used += [("measure", str(c["type"])) for c in d["design"].get("candidates", [])]
        used.append(("cost", str((d["design"].get("costs") or {}).get("model", "unit_prices"))))
    if command in ("check", "optimise"):
        used.append(("safety", str((d.get("safety") or {}).get("concept", "spang"))))
    return used


def _run_table(result: Any, summary: Mapping[str, Any]) -> Table:
    import platform

    project = result.project
    rows = [["program", f"rockfall-design {__version__}, command {result.command}; Python "
             f"{platform.python_version()}"],
            ["project file", str(project.source)],
            ["project hash (sha256 of the resolved project)",
             str(summary.get("project_hash") or project.resolved_hash())]]
    conf = summary.get("confidence")
    if result.command == "optimise":
        design = getattr(result, "design", None)
        rows += [["search rocks and seed", f"{int(summary.get('search_rocks') or 0):,} rocks, "
                  f"seed {summary['seed']}"],
                 ["decision rocks and seed", f"{int(summary['rocks']):,} rocks, seed "
                  f"{summary['seed']}" + (" (the chosen design's statistics below)"
                                          if design is not None else "")],
                 ["verification (fresh rocks) and seed",
                  f"{int(summary['fresh_rocks']):,} rocks, seed {summary['fresh_seed']}"],
                 ["designs screened", f"{int(summary.get('designs_evaluated', 0)):,}; "
                  f"{int(summary.get('exact_evaluations') or 0):,} evaluated exactly"]]
        looks = summary.get("looks")
        if looks:
            rows.append(["sequential looks (rocks)", ", ".join(f"{n:,}" for n in looks["rocks"])
                         + f"; each at {100 * float(looks['look_confidence']):.4g} %"])
    else:
        rows += [["rocks", f"{int(summary['rocks']):,}"],
                 ["seed", str(summary["seed"])]]
    if conf is not None:
        rows.append(["confidence (one-sided, of every bound)", f"{100 * float(conf):g} %"])
    if summary.get("runtime_s") is not None:
        rows.append(["run time", f"{float(summary['runtime_s']):,.1f} s"])
    stats = summary.get("statistics") or {}
    if stats.get("method") == "histograms":
        rows.append(["statistics", "streamed in chunks: counts, means and maxima exact, "
                     f"percentiles within {100 * stats['relative_error']:g} %"])
    elif stats:
        rows.append(["statistics", "exact, over every rock"])
    if summary.get("safety_concept"):
        rows.append(["safety concept", str(summary["safety_concept"])])
    e = project.engine
    rows.append(["engine", f"exact events (flight parabolas, impacts, rolling and sliding in "
                 f"closed form); v_contact {e.v_contact:g} m/s, v_stop {e.v_stop:g} m/s, "
                 f"max_events {e.max_events:,}"])
    registry = getattr(result, "registry", None) or getattr(result, "_registry", None)
    rows += _plugin_rows(registry, _used_plugins(project.resolved_dict(), result.command))
    return Table("", ["item", "value"], rows)


def _stations_table(summary: Mapping[str, Any]) -> Table | None:
    stations = summary.get("stations") or []
    if not stations:
        return None
    cols = ["x (m)", "rocks passing", "h p50 (m)", "h p95 (m)", "h p99 (m)", "h max (m)",
            "v p95 (m/s)", "v max (m/s)", "E p50 (kJ)", "E p95 (kJ)", "E p99 (kJ)",
            "E max (kJ)"]
    rows = []
    for s in stations:
        h, v, e = s["passing_height_m"], s["velocity_ms"], s["energy_kj"]
        rows.append([f"{s['x']:g}", f"{s['crossings']:,}",
                     *(_fixed(h[q], 2) for q in ("p50", "p95", "p99", "max")),
                     _fixed(v["p95"], 1), _fixed(v["max"], 1),
                     *(_fixed(e[q], 0) for q in ("p50", "p95", "p99", "max"))])
    return Table("Analysis stations (first passage downslope)", cols, rows,
                 note="h: passing height of the rock centre above the ground; v: speed; "
                 "E: total kinetic energy. Percentiles over the rocks passing the station.")


def _ends_table(summary: Mapping[str, Any]) -> Table:
    st = summary["stops"]
    n = max(int(summary["rocks"]), 1)
    rows = []
    for label, key in (("stopped on the section", "stopped"),
                       ("left downslope end", "exit_downslope"),
                       ("left upslope end", "exit_upslope"),
                       ("caught by a barrier", "caught"),
                       ("unresolved (event limit)", "unresolved")):
        rows.append([label, f"{st[key]:,}", f"{100 * st[key] / n:.1f} %"])
    sx = st["x"]
    note = ("Stop position x of the rocks at rest (m): "
            f"mean {_fixed(sx['mean'], 1)}, p50 {_fixed(sx['p50'], 1)}, "
            f"p95 {_fixed(sx['p95'], 1)}, max {_fixed(sx['max'], 1)}.")
    return Table("How the paths ended", ["end", "rocks", "share"], rows, note=note)


def _protect_text(summary: Mapping[str, Any]) -> str:
    p = summary.get("protect")
    if not p:
        return ""
    text = (f"Protected zone x >= {p['x']:g} m: {p['reaching']:,} of {summary['rocks']:,} rocks "
            f"reach it ({100 * p['fraction']:.2f} %)")
    if p.get("upper_fraction") is not None:
        text += f", upper confidence bound {100 * p['upper_fraction']:.2f} %"
    if p.get("allowed_fraction") is not None:
        text += f"; allowed {100 * p['allowed_fraction']:.2f} %"
    if p.get("unresolved"):
        text += f"; {p['unresolved']:,} unresolved paths counted as reaching it"
    return text + "."


def _checks_table(summary: Mapping[str, Any]) -> Table | None:
    measures = summary.get("measures")
    if measures is None:
        return None
    bounds = any(c.get("bound") is not None for m in measures for c in m.get("checks", []))
    cols = ["measure", "met", "caught", "over", "through", "check", "value"]
    cols += ["bound"] if bounds else []
    cols += ["target", "unit", "verdict", "how"]
    rows = []
    for m in measures:
        through = m.get("broken_through", 0) + m.get("passed_through_gap", 0)
        head = [m.get("label", m.get("type", "?")), f"{m['met']:,}", f"{m['caught']:,}",
                f"{m['passed_over']:,}", f"{through:,}"]
        for k, c in enumerate(m.get("checks") or [None]):
            first = head if k == 0 else [""] * 5
            if c is None:
                rows.append(first + ["(none)"] + [""] * (len(cols) - 6))
                continue
            unit = str(c.get("unit", "-"))
            row = first + [str(c["name"]), _num(c.get("value"), unit)]
            if bounds:
                row.append(_num(c.get("bound"), unit))
            row += [_num(c.get("target"), unit), unit, "ok" if c.get("ok") else "FAILS",
                    str(c.get("detail", ""))]
            rows.append(row)
    return Table("Measures and their checks", cols, rows,
                 note="met: rocks that reached the measure; over: passed over it; through: "
                 "broke through or passed a gap. Value against target as the safety concept "
                 "defines it.")


def _alternatives_table(summary: Mapping[str, Any]) -> Table:
    cur = summary.get("currency") or ""
    best = chosen_name(summary)
    alts = sorted(summary.get("alternatives", []),
                  key=lambda a: (not a.get("feasible"), a.get("cost") is None,
                                 a.get("cost") or 0))
    names: list[tuple[str, str]] = []
    for a in alts:
        seen: dict[str, int] = {}
        for c in a.get("checks") or []:
            seen[c["name"]] = seen.get(c["name"], 0) + 1
            key = c["name"] if seen[c["name"]] == 1 else f"{c['name']}_{seen[c['name']]}"
            if key not in [n for n, _ in names]:
                names.append((key, str(c.get("unit", "-"))))
    cols = ["", "family", f"cost ({cur})" if cur else "cost", "measures", "residual",
            "fresh rocks", *(n.removesuffix("_factor") + ("" if u == "-" else f" ({u})")
                             for n, u in names), "reason"]
    rows, marks = [], []
    for a in alts:
        values: dict[str, Any] = {}
        seen = {}
        for c in a.get("checks") or []:
            seen[c["name"]] = seen.get(c["name"], 0) + 1
            key = c["name"] if seen[c["name"]] == 1 else f"{c['name']}_{seen[c['name']]}"
            values[key] = _num(c.get("value"), str(c.get("unit", "-"))) + (
                "" if c.get("ok") else " !")
        fresh = a.get("holds_on_fresh_rocks")
        chosen = best is not None and a.get("name") == best
        rows.append(["*" if chosen else "", str(a.get("name")),
                     _num(a.get("cost"), "cost") if a.get("feasible")
                     else f"({_num(a.get('cost'), 'cost')})",
                     "; ".join(measure_text(m) for m in a.get("measures") or []) or "-",
                     _num(a.get("residual"), "count"),
                     "-" if fresh is None else ("holds" if fresh else "FAILS"),
                     *(values.get(n, "") for n, _ in names),
                     str(a.get("reason") or "")])
        marks.append(chosen)
    return Table("Alternatives: the cheapest design of each family", cols, rows,
                 note="* the chosen design; a cost in brackets: not admissible; ! a check "
                 "that misses its target; residual: rocks reaching the protected zone; fresh "
                 "rocks: whether the design holds on rocks not used in the search.",
                 highlight=marks)


def _chosen_text(summary: Mapping[str, Any]) -> tuple[str, list[str]]:
    best = chosen_name(summary)
    if best is None:
        return f"No admissible design: {summary.get('reason', '')}", []
    alt = next(a for a in summary["alternatives"] if a.get("name") == best)
    cur = summary.get("currency") or ""
    head = f"Chosen design: {best}, cost {_num(alt.get('cost'), 'cost')} {cur}".rstrip() + "."
    if summary.get("reason"):
        head += f" Note: {summary['reason']}."
    return head, [measure_text(m) for m in alt.get("measures") or []]


def _resolved_inputs(result: Any) -> tuple[dict[str, Any], dict[str, str]]:
    """The project as run (every parameter resolved) and each safety concept's summary."""
    d = result.project.resolved_dict()
    evaluation = getattr(result, "evaluation", None)
    if result.command == "optimise" and getattr(result, "best", None) is not None:
        evaluation = result.design.evaluation
    if evaluation is not None:
        run = evaluation.resolved_project().resolved_dict()
        if result.command == "check":
            d["measures"] = run.get("measures") or []
        d["safety"] = run.get("safety") or d.get("safety")
    registry = getattr(result, "registry", None) or getattr(result, "_registry", None)
    concepts = {} if registry is None else {
        name: str(getattr(cls, "summary", "") or "")
        for name, cls in registry.safety_concepts.items()}
    return d, concepts


def report_context(result: Any, figures: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Everything the report templates show, as plain data.

    Parameters
    ----------
    result : SimulationResult, CheckResult or OptimiseResult
    figures : mapping of str to Figure, optional
        Default: ``result.figures()``.
    """
    from .figures import CAPTIONS

    if getattr(result, "across", False):  # check --scenarios
        return _scenarios_context(result, figures)
    summary = result.summary
    project = result.project
    command = result.command
    ctx: dict[str, Any] = {
        "title": f"{project.name}: rockfall {'design' if command == 'optimise' else command}",
        "project": project.name,
        "description": project.description,
        "command": command,
        "version": __version__,
        "generated": _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "run": _run_table(result, summary),
        "inputs": _inputs(project, command, *_resolved_inputs(result)),
        "results": [],
        "protect": "",
        "verdict": "",
        "verdict_state": "",
        "failures": [],
        "bill": None,
        "limits": [],
        "chosen": "",
        "chosen_measures": [],
    }
    design = result.design if command == "optimise" else None
    stats_summary = design.summary if design is not None else (
        summary if command != "optimise" else None)
    if command == "optimise":
        ctx["chosen"], ctx["chosen_measures"] = _chosen_text(summary)
        ctx["results"].append(_alternatives_table(summary))
    if stats_summary is not None:
        ctx["results"].append(_ends_table(stats_summary))
        st = _stations_table(stats_summary)
        if st is not None:
            ctx["results"].append(st)
        ct = _checks_table(stats_summary)
        if ct is not None:
            ctx["results"].append(ct)
        ctx["protect"] = _protect_text(stats_summary)
    _set_verdict(ctx, summary.get("verdict"))
    if command == "check" and not summary.get("verdict"):  # a summary from before verdicts
        ctx["verdict"] = ("Design holds on the point values." if summary["ok"]
                          else "Design fails.")
        ctx["failures"] = list(summary.get("failures", []))
    if summary.get("bill"):
        ctx["bill"] = _bill_table(summary["bill"])
    if design is not None:
        ctx["results_note"] = (
            "Statistics, checks and figures of the chosen design on the "
            f"{int(design.summary['rocks']):,} rocks that decided it (seed "
            f"{design.summary['seed']}); the search used {int(summary.get('search_rocks') or 0):,} "
            f"rocks and the verification {int(summary.get('fresh_rocks') or 0):,} fresh rocks "
            f"(seed {summary.get('fresh_seed')}); confidence "
            f"{100 * float(summary.get('confidence') or 0.95):g} %.")
    if command in ("check", "optimise"):
        ctx["limits"] = [{"heading": h, "items": list(items)} for h, items in MODEL_LIMITS]
    figs = figures if figures is not None else result.figures()
    ctx["figures"] = [{"name": name, "caption": CAPTIONS.get(name, ""), "fig": fig}
                      for name, fig in figs.items()]
    return ctx


def _set_verdict(ctx: dict[str, Any], verdict: Mapping[str, Any] | None) -> None:
    """The verdict (``summary["verdict"]``) as the report's first lines."""
    if not verdict:
        return
    ctx["verdict"] = verdict["headline"]
    ctx["verdict_state"] = verdict["state"]
    ctx["verdict_ok"] = verdict["state"] == "holds with confidence"
    ctx["failures"] = list(verdict.get("details") or [])


def _money(v: float) -> str:
    return f"{v:,.2f}"


def _bill_table(bill: Mapping[str, Any]) -> Table:
    """The chosen design's bill: a line per quantity and fixed cost, and the total."""
    cur = bill.get("currency") or ""
    unit = f" ({cur})" if cur else ""
    rows = [[str(it["measure"]), str(it["quantity"]), _money(it["count"]), str(it["unit"]),
             _money(it["unit_price"]), _money(it["amount"]), str(it.get("source") or "")]
            for it in bill["items"]]
    rows.append(["total", "", "", "", "", _money(bill["total"]), ""])
    return Table(f"Bill of the chosen design (site length {bill['length_m']:g} m)",
                 ["measure", "quantity", "count", "unit", f"unit price{unit}",
                  f"amount{unit}", "price from"], rows,
                 note="count: the quantity over the whole site length (running metres, m3, "
                 "or each); amount = count x unit price; the total is the design's cost as the "
                 f"optimiser compared it, priced by the cost model {bill.get('model', '')}.",
                 highlight=[False] * len(bill["items"]) + [True])


def _values_text(values: Mapping[str, Any]) -> str:
    return ", ".join(f"{k} = {v}" for k, v in values.items()) or "as written"


def _margin_text(margin: Any, binds_at: Any) -> str:
    return "no check to bind" if margin is None else (
        f"margin {100 * float(margin):+.1f} % at {binds_at}")


def _scenarios_table(summary: Mapping[str, Any], paths: list[str]) -> Table:
    """Every scenario of ``check --scenarios``: values, seed, verdicts, margin, what binds."""
    b = summary["binding"]["index"]
    cols = ["", "#", *paths, "seed", "reaching", "holds", "with confidence", "margin",
            "binds at"]
    rows, marks = [], []
    for p in summary["scenarios"]:
        prot = p.get("protect")
        rows.append(["*" if p["index"] == b else "", str(p["index"]),
                     *(str(p["values"].get(k, "-")) for k in paths), str(p["seed"]),
                     "-" if not prot else f"{prot['reaching']:,}",
                     "yes" if p["ok"] else "FAILS",
                     "yes" if p["holds_with_confidence"] else "no",
                     "-" if p["margin"] is None else f"{100 * p['margin']:+.1f} %",
                     str(p["binds_at"] or "-")])
        marks.append(p["index"] == b)
    return Table(f"Scenarios: {summary['of']}, each with its own rocks "
                 f"({int(summary['rocks']):,} rocks, its own seed)", cols, rows,
                 note="* the binding scenario (the one that decides the count required; with every "
                 "scenario required, the least margin). holds: every check and the "
                 "residual on the point values, as check judges them; with confidence: with "
                 "the confidence bounds in place. margin: the smallest relative slack of a "
                 "check or of the residual with the confidence bounds in place, negative "
                 "where it fails. reaching: rocks reaching the protected zone.",
                 highlight=marks)


def _scenarios_context(result: Any, figures: Mapping[str, Any] | None) -> dict[str, Any]:
    """The report of ``check --scenarios``: every scenario, the binding one in full.

    The binding scenario's part is the report of ``check`` in that scenario
    (:func:`report_context` of its :class:`~rockfall_design.results.CheckResult`),
    its tables and figures titled with the scenario.
    """
    from types import SimpleNamespace

    from .figures import CAPTIONS

    summary = result.summary
    project = result.project
    binding = result.binding_check
    b = summary["binding"]
    figs = dict(figures) if figures is not None else result.figures()
    ctx = report_context(binding, {k: v for k, v in figs.items() if k != "margins"})
    name = f"binding scenario {b['index']} ({_values_text(b['values'])})"
    # The run: the project as written, the run seed the scenarios' seeds derive from.
    head = SimpleNamespace(project=project, command="check")
    run = _run_table(head, {**binding.summary, "seed": summary["seed"],
                            "project_hash": project.resolved_hash()})
    for row in run.rows:
        if row[0] == "seed":
            row[0] = "run seed (each scenario's seed derives from it)"
        if row[0] == "rocks":
            row[0] = "rocks per scenario"
        if row[0] == "program":
            row[1] = f"rockfall-design {__version__}, command check --scenarios"
    at = next(i for i, row in enumerate(run.rows) if row[0].startswith("run seed")) + 1
    run.rows[at:at] = [
        ["scenarios", f"{summary['of']}; the design must hold in {summary['required']} "
         f"(design.scenarios share {summary['share']:g})"],
        ["binding scenario", f"{b['index']} ({_values_text(b['values'])}), seed {b['seed']}: "
         + _margin_text(b["margin"], b["binds_at"])],
    ]
    ctx["run"] = run
    study = project.resolved_dict().get("study") or {}
    vary = study.get("vary") or {}
    ctx["inputs"] = _inputs(project, "check") + [Table(
        "Study: the varied inputs", ["input (path in the project)", "values"],
        [[k, ", ".join(map(str, v)) if isinstance(v, list) else str(v)]
         for k, v in vary.items()],
        note=f"Scenarios: {study.get('scenarios')}; seeds: {study.get('seeds')}. The other "
        "inputs are as written above.")]
    paths = list(dict.fromkeys(k for p in summary["scenarios"] for k in p["values"]))
    ctx["results"] = [_scenarios_table(summary, paths)] + [
        Table(f"{name[0].upper()}{name[1:]}: {t.title}", t.columns, t.rows, t.note, t.highlight)
        for t in ctx["results"]]
    if ctx["protect"]:
        ctx["protect"] = f"{name[0].upper()}{name[1:]}: {ctx['protect']}"
    ctx["results_note"] = (
        "Every scenario of the study first; then the binding scenario (the one that decides "
        "the count required), "
        f"in full as check shows one scenario: scenario {b['index']}, seed {b['seed']}, "
        + _margin_text(b["margin"], b["binds_at"]) + ".")
    ok = bool(summary["ok"])
    ctx["title"] = f"{project.name}: rockfall check over {summary['of']} scenarios"
    ctx["command"] = "check --scenarios"
    ctx["verdict"] = (
        f"Design {'holds' if ok else 'fails'}: it holds in {summary['holds_in']} of "
        f"{summary['of']} scenarios (on the point values; "
        f"{summary['holds_with_confidence_in']} with the confidence bounds); required: "
        f"{summary['required']}. Binding: scenario {b['index']}, "
        + _margin_text(b["margin"], b["binds_at"]) + ".")
    ctx["verdict_ok"] = ok
    ctx["failures"] = list(summary.get("failures", []))
    if summary.get("verdict"):
        ctx["scenarios_note"] = ctx["verdict"]
        _set_verdict(ctx, summary["verdict"])
        ctx["failures"] = [ctx["scenarios_note"], *ctx["failures"]]
    for f in ctx["figures"]:
        f["caption"] = f"{name[0].upper()}{name[1:]}: {f['caption']}"
    if "margins" in figs:  # first: the report begins with every scenario
        ctx["figures"].insert(0, {"name": "margins", "caption": CAPTIONS["margins"],
                                  "fig": figs["margins"]})
    return ctx


# ---- rendering ------------------------------------------------------------------


def _environment(markdown: bool) -> Any:
    try:
        import jinja2
    except ImportError:  # pragma: no cover - a core dependency
        from ..errors import InputError

        raise InputError("--report needs Jinja2: python -m pip install jinja2") from None
    env = jinja2.Environment(
        loader=jinja2.PackageLoader("rockfall_design.report", "templates"),
        autoescape=not markdown,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
        undefined=jinja2.StrictUndefined,
        # report.md escapes what it shows as report.html does: a project's
        # name or description with <script> or <iframe> stays text.
        finalize=_md_text if markdown else None,
    )
    env.filters["md"] = _md_cell
    env.filters["rendered"] = _Rendered
    return env


#: What could start HTML in Markdown: a tag, a closing tag, a comment or
#: declaration (``<x``, ``</``, ``<!``, ``<?``) and an entity (``&name;``, ``&#``).
_HTML_START = re.compile(r"<(?=[A-Za-z/!?])|&(?=#|[A-Za-z][A-Za-z0-9]*;)")


class _Rendered(str):
    """Markdown the template has escaped already (a macro's output, ``|rendered``)."""


def _md_text(value: Any) -> Any:
    """A value shown in report.md, with whatever could start HTML as an entity.

    ``<script>`` becomes ``&lt;script>``, as report.html escapes it; a
    comparison (``e < 1``) or an ampersand between words stays as written.
    A macro's output (a table) was escaped cell by cell and is left as it
    is: escaped again, ``&lt;`` would show as itself.
    """
    if not isinstance(value, str) or isinstance(value, _Rendered):
        return value
    return _HTML_START.sub(lambda m: "&lt;" if m.group() == "<" else "&amp;", value)


def _md_cell(text: Any) -> str:
    """Text safe inside a Markdown table cell (pipes escaped, one line)."""
    return " ".join(str(text).split()).replace("|", "\\|")


def render_html(context: Mapping[str, Any]) -> str:
    """report.html: self-contained, every figure inline as SVG."""
    from markupsafe import Markup

    from .figures import figure_svg

    figs = [{**f, "svg": Markup(figure_svg(f["fig"]))} for f in context["figures"]]
    return _environment(False).get_template("report.html.j2").render(**{**context,
                                                                        "figures": figs})


def render_markdown(context: Mapping[str, Any]) -> str:
    """report.md: figures referenced as NAME.svg beside it."""
    figs = [{**f, "file": f"{f['name']}.svg"} for f in context["figures"]]
    return _environment(True).get_template("report.md.j2").render(**{**context,
                                                                     "figures": figs})


def write_report(result: Any, directory: str | os.PathLike[str],
                 outputs: OutputSet | None = None,
                 figures: Mapping[str, Any] | None = None) -> list[Path]:
    """Write DIR/report.html, DIR/report.md and the Markdown's figures DIR/NAME.svg.

    Parameters
    ----------
    result : SimulationResult, CheckResult, OptimiseResult, or a result with a
        ``report_context(figures)`` method (CalibrationResult, ComparisonResult)
    directory : path
    outputs : OutputSet, optional
        The command's output set: the files land when it commits (all or
        none). Without one they land together on return.
    figures : mapping of str to Figure, optional
        Default: ``result.figures()``.

    Returns
    -------
    list of Path
    """
    from .figures import save_figures
    from .outputs import OutputSet

    if outputs is None:
        with OutputSet() as own:
            return write_report(result, directory, own, figures)
    out = Path(directory)
    # A result that builds its own context (calibrate, compare) is rendered by
    # the same templates; the others' context is built here.
    own = getattr(result, "report_context", None)
    ctx = own(figures) if callable(own) else report_context(result, figures)
    figs = {f["name"]: f["fig"] for f in ctx["figures"]}
    written = save_figures(figs, out, ("svg",), outputs)
    outputs.write_text(out / "report.html", render_html(ctx))
    outputs.write_text(out / "report.md", render_markdown(ctx))
    return [*written, out / "report.html", out / "report.md"]

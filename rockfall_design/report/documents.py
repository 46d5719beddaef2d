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
import os
import re
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..version import __version__
from .sections import (
    Table,
    _alternatives_table,
    _bill_table,
    _checks_table,
    _chosen_text,
    _ends_table,
    _margin_text,
    _protect_text,
    _resolved_inputs,
    _run_table,
    _scenarios_table,
    _stations_table,
    inputs_table,
    values_text,
)

if TYPE_CHECKING:  # pragma: no cover
    from .outputs import OutputSet

__all__ = ["Table", "MODEL_LIMITS", "report_context", "render_html", "render_markdown",
           "write_report"]


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
        "(rn_rt), optionally scaled with the impact speed (Pfeiffer & Bowen 1989), or by "
        "spang's law with a resistance from the block's radius against the ground's "
        "obstacles and from its softness, growing with the speed (rough_soft). The rolling "
        "resistance acts in impacts as in contact, so the spang and rough_soft results do "
        "not depend on engine.v_contact; rn_rt's do.",
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
        "inputs": inputs_table(project, command, *_resolved_inputs(result)),
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
    name = f"binding scenario {b['index']} ({values_text(b['values'])})"
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
        ["binding scenario", f"{b['index']} ({values_text(b['values'])}), seed {b['seed']}: "
         + _margin_text(b["margin"], b["binds_at"])],
    ]
    ctx["run"] = run
    study = project.resolved_dict().get("study") or {}
    vary = study.get("vary") or {}
    ctx["inputs"] = inputs_table(project, "check") + [Table(
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

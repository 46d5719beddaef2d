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
import warnings
from collections.abc import Callable, Mapping
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any

from ..errors import InputError
from ..judge.records import CheckSummary, DesignVerdict, State
from ..project.study import values_text
from ..run.summary import RunSummary
from ..version import __version__
from .context import LimitsPart, ReportContext, ReportFigure
from .design_values import design_columns, design_tables, fresh_statements, how_sure
from .formats import CAPTIONS, figure_svg, inline_svg, svg_document
from .listed import listed_lines
from .outputs import OutputSet
from .pdf import html_to_pdf, pdf_turned_off, pdf_unavailable
from .sections import (
    Table,
    alternatives_table,
    bill_table,
    checks_table,
    chosen_text,
    ends_table,
    inputs_table,
    margin_text,
    passages_table,
    protect_text,
    resolved_inputs,
    run_table,
    scenarios_table,
    stations_table,
)

if TYPE_CHECKING:  # pragma: no cover
    from ..optimiser.alternatives import SearchOutcome
    from ..studies.scenario_checks import ScenariosCheck

__all__ = ["Table", "MODEL_LIMITS", "ReportContext", "model_limits", "report_context",
           "report_figures", "render_html", "render_markdown", "write_report"]


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
        "obstacles and from its softness, growing with the speed, that acts in impacts as "
        "in contact (rough_soft).",
        "A rebound whose hop (the height its centre would rise above the ground) is below "
        "the contact height max(roughness_height_m, engine.contact_hop_ratio x radius) "
        "continues on the ground, rolling or sliding: the bounce-to-contact transition is a "
        "property of the rock and the ground, and engine.v_contact is only a numerical floor "
        "below which the answer no longer moves (tests/engine/test_engine_transition.py). "
        "The ratio (0.1 by default) is ILLUSTRATIVE, not a published value.",
        "Scatter: restitution, friction and rolling resistance are drawn per impact from "
        "truncated normals with the standard deviations of scatter:, and the impact normal "
        "is tilted by the roughness; every draw comes from a seeded stream per rock.",
        "Fences and walls are barriers at a station with a nominal height and an energy "
        "capacity; ditches and berms reshape the ground; boulder rows are blocks with gaps; "
        "a protection forest is a stand of stems on a stretch.",
        "A forest on the ground (a material's forest:): stems met with the probability the "
        "rock's path and the stand give, each taking the energy of Dorren & Berger's (2006) "
        "law; the run counts the rocks that met stems and those the forest stopped, with "
        "Clopper-Pearson bounds.",
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
        "Of trees, only a stand of stems on a material (forest:) or the protection_forest "
        "measure: a rock meets stems as a Poisson stand gives them, below the stem height, "
        "and each takes Dorren & Berger's (2006) E_max = 38.7 DBH^2.31 J. Every impact is "
        "taken as central (the most a stem can take; an eccentric one takes less and turns "
        "the rock aside, which a section cannot show), without a species factor; no "
        "deadwood, no crowns, no stand that grows, thins or has gaps; stems met only on "
        "downslope travel. Treat the forest's effect as the most a stand of that density "
        "and diameter gives, and check it against the stand on site (scars, stopped blocks).",
        "No air drag, no ground that deforms or is cratered beyond what restitution and "
        "friction represent.",
        "A fence is a line at its station with a braking distance. Its nominal height "
        "is measured perpendicular to the slope, as EAD 340059 defines it: a rock "
        "passes over where its centre is more than the nominal height from the ground "
        "segment under the station (h_vertical x cos(slope) > h_nominal, so the "
        "vertical top is h_nominal / cos(slope)); reports give the passing height both "
        "ways, vertical and normal to the slope. A rock caught below it comes to rest "
        "its braking distance downslope of the station, taken horizontally (on the safe "
        "side: the elongation is measured along the slope): the SEL test's elongation "
        "up to the SEL (MEL / 3 unless the product gives sel_kj), the MEL test's "
        "maximum elongation from the MEL on, linear in the rock's energy in between; "
        "with only the MEL elongation, that for every caught rock; without an MEL "
        "elongation the rock stops at the station as before. So stop positions, the "
        "protected zone and a barrier below see the deflection (a net carried into a "
        "barrier below is not modelled: the braking check keeps the zone clear of it). "
        "Above the MEL the rock breaks through with the surplus energy. No difference "
        "between hitting a post, a cable or the middle of the net, no loss of height "
        "after earlier impacts in the run, no load on posts, anchors or foundations.",
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
        "energy level SEL and its maximum energy level MEL (SEL = MEL / 3); the tests "
        "give the elongation (braking distance) and the residual height (category A at "
        "least 50 % of the nominal height, B 30 to 50 %, C at most 30 %). Where a fence "
        "has max_elongation_m and a protected zone is given, every concept checks "
        "braking_distance: gamma_d x the maximum elongation must not exceed the "
        "distance from the fence to protect.x, gamma_d = 1.3 for an elongation from the "
        "MEL test after Peila & Ronco (2009) (a concept parameter). uni11211 checks the "
        "design height against the residual height; onr24810 against the nominal height "
        "for rare events and the residual height for frequent ones. The EAD concepts "
        "(uni11211, onr24810) require every catalogue fence to give max_elongation_m "
        "and residual_height_fraction: a product without them is an error at its line "
        "in the catalogue.",
        "onr24810 follows ONR 24810 as Volkwein et al. (2011) and Mölk & Stelzer (2013) "
        "describe it: the 99 % fractiles of the energies and of the passing heights "
        "(normal to the slope) at the fence, times gamma_F by consequence class, "
        "against the SEL (event: frequent) or MEL / gamma_R (event: rare), the height "
        "with a freeboard max(f_min_m, the 99 % fractile radius). The defaults of "
        "gamma_F (0.99 / 1.1 / 1.21 for CC1 / CC2 / CC3, EN 1990's K_FI on a base "
        "factor of 1.1) and gamma_R (1.0) are ILLUSTRATIVE and flagged for review: the "
        "text of the standard was not at hand; set them from the edition in force.",
        "reliability follows Marchelli, De Biagi & Peila (2020): falls arrive as a "
        "Poisson process of annual_falls per year, so the probability that at least one "
        "block fails within working_life_years is 1 - exp(-lambda T p), p the simulated "
        "per-block probability. Each measure's p (rocks passing over, breaking through "
        "or slipping through a gap, of all rocks) and the protected zone's (the "
        "residual) must keep that probability within target_failure_probability, judged "
        "with their Clopper-Pearson bounds; the probability that at least one of these "
        "happens to a block is at most their sum. A target of 1e-4 over 2.5 falls a "
        "year for 50 years allows p = 8.0e-7 per block, which zero failures show only "
        "with 3.7 million rocks at 95 %: the check says so (rocks_needed) and such a "
        "design stays undecided (marginal) within design.max_rocks. The rocks must be a "
        "fair sample of the falls that annual_falls counts (same release zones and "
        "block sizes). Each block meets the measures intact: the damage a fence takes from "
        "earlier blocks within its working life is not modelled (it is taken to be "
        "repaired after each event), which is optimistic for a fence hit often.",
        "The design block (rocks.design_block) of uni11211 and onr24810 is the block's mass "
        "only; its speed and passing height are the simulated rocks' percentiles, as the "
        "codes combine them. A design block far larger than the simulated rocks is given "
        "their speeds, which is right only as far as size does not change the paths; where "
        "it does (the roughness and the rolling against the radius), simulate rocks of about "
        "the design block's size. onr24810's use of it (E_d = gamma_F x the 99 % fractile "
        "of 1/2 m_d v^2) is flagged for review against the standard's text.",
    )),
)


# ---- the parts of the context -------------------------------------------------


def _opening_context(result: Any) -> ReportContext:
    """The head of the context: titles, the run's table, the inputs, empty result parts."""
    project, command = result.project, result.command
    run = run_table(result, None if command == "optimise" else result.record)
    return ReportContext(
        title=f"{project.name}: rockfall {'design' if command == 'optimise' else command}",
        project=project.name, description=project.description, command=command,
        version=__version__, generated=_dt.datetime.now(_dt.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        run=run, inputs=inputs_table(project, command, *resolved_inputs(result)))


def _statistics_context(ctx: ReportContext, stats: RunSummary | CheckSummary) -> None:
    """The run's tables (ends, stations, checks, passages), the protected zone, how sure."""
    ctx.results.append(ends_table(stats))
    for table in (stations_table(stats), checks_table(stats), passages_table(stats)):
        if table is not None:
            ctx.results.append(table)
    ctx.protect = protect_text(stats)
    if isinstance(stats, CheckSummary):
        ctx.design_values = _design_value_tables(stats)
        ctx.how_sure = how_sure(stats)


def model_limits(command: str) -> list[LimitsPart]:
    """The section "Model and limits": the concepts' part where a command judged."""
    return [LimitsPart(h, list(items)) for h, items in MODEL_LIMITS
            if command in ("check", "optimise") or not h.startswith("Safety")]


def report_figures(figures: Mapping[str, Any]) -> list[ReportFigure]:
    """The report's figures in their order, each with its caption."""
    return [ReportFigure(name, CAPTIONS.get(name, ""), fig) for name, fig in figures.items()]


def report_context(result: Any, figures: Mapping[str, Any] | None = None) -> ReportContext:
    """Everything the report templates show, as plain data.

    Parameters
    ----------
    result : SimulationResult, CheckResult or OptimiseResult
        Read through its records (``record``, ``design.record``,
        ``bill_record``); an optimisation's own figures through its summary.
    figures : mapping of str to Figure, optional
        Default: ``result.figures()``.
    """
    if getattr(result, "across", False):  # check --scenarios
        return _scenarios_context(result, figures)
    command = result.command
    ctx = _opening_context(result)
    design = result.design if command == "optimise" else None
    stats = design.record if design is not None else (
        result.record if command != "optimise" else None)
    if command == "optimise":
        ctx.chosen, ctx.chosen_measures = chosen_text(result.result)
        ctx.results.append(alternatives_table(result.result))
    if stats is not None:
        _statistics_context(ctx, stats)
    if command == "optimise":
        ctx.how_sure += optimiser_sentences(result.result)
        _set_verdict(ctx, result.verdict)
        if result.bill_record is not None:
            ctx.bill = bill_table(result.bill_record)
    elif isinstance(stats, CheckSummary):
        _set_verdict(ctx, stats.verdict)
    if design is not None:
        ctx.results_note = _decided_note(result, design.record)
    # Every report says what the model is and is not; the concepts' part where one judged.
    ctx.limits = model_limits(command)
    ctx.figures = report_figures(figures if figures is not None else result.figures())
    return ctx


def _decided_note(result: Any, design: CheckSummary) -> str:
    """Which rocks the chosen design's statistics are of, and the search's and verification's."""
    opt = result.result
    return ("Statistics, checks and figures of the chosen design on the "
            f"{design.rocks:,} rocks that decided it (seed {design.run.seed}); the search "
            f"used {int(opt.search_rocks or 0):,} rocks and the verification "
            f"{int(opt.fresh_rocks or 0):,} fresh rocks (seed {opt.fresh_seed}); confidence "
            f"{100 * float(opt.confidence):g} %.")


def _design_value_tables(summary: CheckSummary) -> list[Table]:
    """The design values at each measure, a table each (:mod:`.design_values`)."""
    cols = design_columns(summary.confidence)
    return [Table(t.title, cols, t.rows, highlight=[bool(x) for x in t.states])
            for t in design_tables(summary)]


def optimiser_sentences(opt: SearchOutcome) -> list[str]:
    """How ``optimise`` searched and decided, and its record of the decision, as sentences."""
    out = [f"The optimiser searched with {int(opt.search_rocks or 0):,} rocks "
           f"(seed {opt.seed}), screening {int(opt.evaluations or 0):,} designs, "
           f"{int(opt.exact_evaluations or 0):,} of them evaluated exactly; the "
           f"chosen design was decided with {int(opt.rocks or 0):,} rocks and "
           f"checked again on {int(opt.fresh_rocks or 0):,} fresh rocks (seed "
           f"{opt.fresh_seed}), every bound at {100 * float(opt.confidence or 0.95):g} % "
           "confidence."]
    best = opt.best
    if best is not None and best.proof:
        out.append(f"The optimiser's record of the decision: {best.proof}.")
    if best is not None:
        out += fresh_statements(best)
    # The cheaper designs it could not decide, each with the rocks that would.
    return out + listed_lines(opt.marginal, str(opt.currency or ""))


def _set_verdict(ctx: ReportContext, verdict: DesignVerdict | None) -> None:
    """The verdict as the report's first lines.

    What fails is said at once; what is open with confidence belongs to the
    statistics and is said under "How sure" (its ``details`` are there).
    """
    if verdict is None:
        return
    ctx.verdict = verdict.headline
    ctx.verdict_state = verdict.state.value
    ctx.verdict_ok = verdict.with_confidence
    ctx.failures = list(verdict.details) if verdict.state == State.FAILS else []


def _scenarios_context(result: Any, figures: Mapping[str, Any] | None) -> ReportContext:
    """The report of ``check --scenarios``: every scenario, the binding one in full.

    The binding scenario's part is the report of ``check`` in that scenario
    (:func:`report_context` of its :class:`~rockfall_design.results.CheckResult`),
    its tables and figures titled with the scenario. ``result.check`` is the
    :class:`~rockfall_design.studies.scenario_checks.ScenariosCheck` it reads.
    """
    found: ScenariosCheck = result.check
    project = result.project
    b = found.binding
    figs = dict(figures) if figures is not None else result.figures()
    margins = figs.pop("margins", None)
    ctx = report_context(result.binding_check, figs)
    name = f"Binding scenario {b.index} ({values_text(b.values)})"
    ctx.run = _scenarios_run_table(result, found)
    study = project.resolved_dict().get("study") or {}
    vary = study.get("vary") or {}
    ctx.inputs = inputs_table(project, "check") + [Table(
        "Study: the varied inputs", ["input (path in the project)", "values"],
        [[k, ", ".join(map(str, v)) if isinstance(v, list) else str(v)]
         for k, v in vary.items()],
        note=f"Scenarios: {study.get('scenarios')}; seeds: {study.get('seeds')}. The other "
        "inputs are as written above.")]
    paths = list(dict.fromkeys(k for p in found.scenarios for k in p.binding.values))
    ctx.results = [scenarios_table(found, paths)] + [
        Table(f"{name}: {t.title}", t.columns, t.rows, t.note, t.highlight)
        for t in ctx.results]
    if ctx.protect:
        ctx.protect = f"{name}: {ctx.protect}"
    ctx.results_note = (
        "Every scenario of the study first; then the binding scenario (the one that decides "
        "the count required), "
        f"in full as check shows one scenario: scenario {b.index}, seed {b.seed}, "
        + margin_text(b.margin, b.binds_at) + ".")
    ctx.title = f"{project.name}: rockfall check over {found.of} scenarios"
    ctx.command = "check --scenarios"
    _scenarios_verdict(ctx, found)
    for f in ctx.figures:
        f.caption = f"{name}: {f.caption}"
    if margins is not None:  # first: the report begins with every scenario
        ctx.figures[:0] = report_figures({"margins": margins})
    return ctx


def _scenarios_run_table(result: Any, found: ScenariosCheck) -> Table:
    """The run of ``check --scenarios``: the project as written, the run seed the
    scenarios' seeds derive from, the scenarios and the binding one."""
    project, b = result.project, found.binding
    record = result.binding_check.record
    head = SimpleNamespace(project=project, command="check")
    run = run_table(head, replace(record, run=replace(
        record.run, seed=found.seed, project_hash=project.resolved_hash())))
    for row in run.rows:
        if row[0] == "seed":
            row[0] = "run seed (each scenario's seed derives from it)"
        if row[0] == "rocks":
            row[0] = "rocks per scenario"
        if row[0] == "program":
            row[1] = f"rockfall-design {__version__}, command check --scenarios"
    at = next(i for i, row in enumerate(run.rows) if row[0].startswith("run seed")) + 1
    run.rows[at:at] = [
        ["scenarios", f"{found.of}; the design must hold in {found.required} "
         f"(design.scenarios share {found.share:g})"],
        ["binding scenario", f"{b.index} ({values_text(b.values)}), seed {b.seed}: "
         + margin_text(b.margin, b.binds_at)],
    ]
    return run


def _scenarios_verdict(ctx: ReportContext, found: ScenariosCheck) -> None:
    """The verdict over the scenarios, then the verdict's own words and what is open."""
    b = found.binding
    ctx.verdict = (
        f"Design {'holds' if found.ok else 'fails'}: it holds in {found.holds_in} of "
        f"{found.of} scenarios (on the point values; "
        f"{found.holds_with_confidence_in} with the confidence bounds); required: "
        f"{found.required}. Binding: scenario {b.index}, "
        + margin_text(b.margin, b.binds_at) + ".")
    ctx.verdict_ok = bool(found.ok)
    ctx.scenarios_note = ctx.verdict
    _set_verdict(ctx, found.verdict)  # its failures: the verdict's details where it fails
    if found.verdict.state != State.FAILS:  # what is open: under "How sure"
        ctx.how_sure = [*ctx.how_sure, "Over the scenarios:",
                        *(f"- {d}" for d in found.verdict.details)]
    ctx.failures = [ctx.scenarios_note, *ctx.failures]


# ---- rendering ------------------------------------------------------------------


def _environment(markdown: bool) -> Any:
    try:
        import jinja2
    except ImportError:  # pragma: no cover - a core dependency

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
    env.filters["wbr"] = _wbr
    return env


def _wbr(text: Any) -> Any:
    """A column header, escaped, that may break after each underscore (``<wbr>``).

    A printed table of many columns (the ground materials) then wraps
    ``rolling_resistance`` at its underscore rather than in the middle of a
    word, or not at all and past the page's edge.
    """
    from markupsafe import Markup, escape

    return Markup(str(escape(str(text))).replace("_", "_<wbr>"))


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


def render_html(context: ReportContext, for_print: bool = False,
                svgs: Mapping[str, str] | None = None) -> str:
    """report.html: self-contained, every figure inline as SVG.

    ``for_print``: the page report.pdf is printed from, whose column headers
    may break after an underscore (``<wbr>``), so that a table of many
    columns fits the page; report.html keeps its headers as plain text.
    ``svgs``: each figure's SVG by name, if drawn already (for both pages).
    """
    from markupsafe import Markup


    figs = [replace(f, svg=Markup(svgs[f.name] if svgs and f.name in svgs
                                  else figure_svg(f.fig))) for f in context.figures]
    return _environment(False).get_template("report.html.j2").render(
        **context.template_values(figures=figs, for_print=for_print))


def render_markdown(context: ReportContext) -> str:
    """report.md: figures referenced as NAME.svg beside it."""
    figs = [replace(f, file=f"{f.name}.svg") for f in context.figures]
    return _environment(True).get_template("report.md.j2").render(
        **context.template_values(figures=figs))


def write_report(result: Any, directory: str | os.PathLike[str],
                 outputs: OutputSet | None = None,
                 figures: Mapping[str, Any] | None = None,
                 pdf: bool = True, note: Callable[[str], None] | None = None) -> list[Path]:
    """Write DIR/report.html, DIR/report.md, the Markdown's figures DIR/NAME.svg and
    DIR/report.pdf.

    report.pdf is report.html printed by Chromium (:mod:`.pdf`: A4, the
    project and date on every page, page numbers, vector figures). Where it
    cannot be made (no ``pdf`` extra, no Chromium) the rest is written and
    ``note`` is called with one line that says how to get it (default: a
    :class:`UserWarning`); a report.pdf of an earlier run is removed then, so
    that it does not sit beside a newer report.

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
    pdf : bool
        Write report.pdf too (default).
    note : callable, optional
        Called with the one line that says why report.pdf was not written.

    Returns
    -------
    list of Path
    """

    if outputs is None:
        with OutputSet() as own:
            return write_report(result, directory, own, figures, pdf, note)
    out = Path(directory)
    # A result that builds its own context (calibrate, compare) is rendered by
    # the same templates; the others' context is built here.
    own = getattr(result, "report_context", None)
    ctx = own(figures) if callable(own) else report_context(result, figures)
    figs = {f.name: f.fig for f in ctx.figures}
    # Each figure drawn once: its SVG file and the pages' inline copy are the same text.
    documents = {name: svg_document(fig) for name, fig in figs.items()}
    written = []
    for name, document in documents.items():
        outputs.write_text(out / f"{name}.svg", document)
        written.append(out / f"{name}.svg")
    svgs = {name: inline_svg(document) for name, document in documents.items()}
    page = render_html(ctx, svgs=svgs)
    outputs.write_text(out / "report.html", page)
    outputs.write_text(out / "report.md", render_markdown(ctx))
    written += [out / "report.html", out / "report.md"]
    if pdf and pdf_turned_off():
        outputs.remove(out / "report.pdf")  # never an older PDF beside a newer report
    elif pdf and _write_pdf(render_html(ctx, for_print=True, svgs=svgs), ctx,
                            out / "report.pdf", outputs, note):
        written.append(out / "report.pdf")
    return written


def _write_pdf(page: str, ctx: ReportContext, path: Path, outputs: OutputSet,
               note: Callable[[str], None] | None) -> bool:
    """report.pdf from report.html into the output set; False (and the note) where it
    cannot be made, a stale report.pdf removed."""
    why = pdf_unavailable()
    if why is None:
        try:
            data = html_to_pdf(page, str(ctx.project or ctx.title), str(ctx.generated))
        except RuntimeError as exc:
            why = str(exc)
        else:
            outputs.write_with(path, lambda fh: fh.write(data))
            return True
    outputs.remove(path)
    if note is None:
        warnings.warn(why, UserWarning, stacklevel=3)
    else:
        note(why)
    return False

"""The calibration's and the comparison's report: report.html and report.md.

:func:`report_context` builds, from a :class:`~.calibration_result.CalibrationResult`
or a :class:`~.calibration_result.ComparisonResult`, the same plain context the other
commands' reports are rendered from (:mod:`rockfall_design.report.documents`,
whose templates and escaping it shares): the observed set, the fitted
inputs with their intervals and a flag for those the observations do not
pin down, their correlation, the fit statistics, the level shares, the
figures, and what is needed to repeat the run.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import math
import platform
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..report.context import LimitsPart, ReportContext, ReportFigure
from ..report.documents import model_limits
from ..report.sections import Table, inputs_table
from ..version import __version__
from .charts import CAPTIONS
from .distances import FitStatistics, LevelShare, verdict
from .terms import SetStatistics
from .uncertainty import INTERVAL, rounded

__all__ = ["CALIBRATION_LIMITS", "report_context"]

#: Stop positions per row of the table of observed blocks.
_PER_ROW = 10

#: The report's section "What the calibration says and does not": heading, bullets.
CALIBRATION_LIMITS: tuple[str, tuple[str, ...]] = (
    "What the calibration says and does not", (
        "A fitted value is conditional on every input held fixed: with another value of an "
        "input that was not fitted, the fitted ones change. What a fit gives is a set of "
        "values that reproduces the observed stops on this section, not the ground's true "
        "coefficients.",
        "The intervals come from a bootstrap of the observed blocks (each replicate refitted "
        "to a resample with its own simulation seed): they hold the luck of which blocks were "
        "observed and which rocks were simulated, not the error of the model itself (a sphere "
        "on a 2-D section).",
        "An input whose refitted values spread over its range is flagged as not pinned down "
        "(identified: no): the observations cannot tell its values apart, and its best value "
        "must not be used as if it were known. Fit fewer inputs, or add another kind of "
        "observation.",
        "After a fit the Kolmogorov-Smirnov p-value is optimistic (the inputs were chosen to "
        "match these very stops); the fair test is compare on observations the fit did not "
        "see (a second profile or held-out blocks).",
        "The fit runs on the bare slope (the project's measures are left out: the "
        "observations are of the site as it was). A simulated rock that leaves the section "
        "at its lower end counts as stopped at its end.",
        "calibrated.yaml (--out) keeps each material's own per-impact scatter (the ground's "
        "variability) and records the bootstrap spread of a fitted value (what the "
        "observations leave unknown) as comments that no run draws from; a study over the "
        "interval's ends carries that uncertainty into a design (--widen-scatter adds it to "
        "the scatter instead).",
        "With fit: auto the fit is regularised by the classes' values and ranges (a prior): "
        "an input held near its class's value by the prior, not by the observations, is "
        "flagged, and an input that moves the criterion by less than its sampling noise is "
        "left out and keeps its class's value (docs/calibration.md, The method).",
    ))


def _g(v: Any, digits: int = 3) -> str:
    """A number with ``digits`` significant digits, or '-'."""
    if v is None:
        return "-"
    v = float(v)
    return f"{v:.{digits}g}" if math.isfinite(v) else str(v)


def _sha256(path: str) -> str:
    """The file's sha256, or why it could not be read (the report is still written)."""
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError as exc:
        return f"not readable when the report was written ({exc.strerror or exc})"


def _observed_tables(result: Any) -> list[Table]:
    """The observed blocks: file, count, sizes, and every stop position in file order."""
    obs = result.observations
    rows = [["file", obs.source], ["sha256 of the file", _sha256(obs.source)],
            ["observed blocks", f"{obs.n:,}"]]
    if obs.size is not None:
        unit = "m3" if obs.size_key == "volume" else "kg"
        rows.append([f"{obs.size_key} of the blocks ({unit})",
                     f"{_g(obs.size.min())} to {_g(obs.size.max())}, median "
                     f"{_g(float(np.median(obs.size)))}"])
        rows.append(["simulated rock size (fitted to the observed)",
                     ", ".join(f"{k} {v}" for k, v in (result.sizes or {}).items())])
    tables = [Table("Observed blocks", ["item", "value"], rows,
                    note="The simulated rocks take the observed blocks' sizes (a lognormal "
                    "fitted to them) where the file gives them; otherwise the project's.")]
    cols = ["blocks", "stop position x (m)"]
    out = []
    for i in range(0, obs.n, _PER_ROW):
        part = obs.x[i:i + _PER_ROW]
        row = [f"{i + 1}-{i + len(part)}", ", ".join(f"{x:g}" for x in part)]
        if obs.size is not None:
            row.append(", ".join(f"{s:g}" for s in obs.size[i:i + _PER_ROW]))
        out.append(row)
    if obs.size is not None:
        cols.append(f"{obs.size_key} ({'m3' if obs.size_key == 'volume' else 'kg'})")
    tables.append(Table("Observed stop positions (file order)", cols, out,
                        note="As read from the file, so that the report alone repeats the "
                        "run."))
    return tables


def _settings_table(result: Any) -> Table:
    """The calibrate: section as run: fitted inputs and ranges, levels, method."""
    p = result.problem
    rows = [[f"fit: {path}", f"{lo:g} .. {hi:g}"] for path, lo, hi in zip(p.paths, p.low,
                                                                         p.high, strict=True)]
    rows += [[f"level: {name}", f"{lo:g} .. {hi:g} m"] for name, (lo, hi) in p.levels.items()]
    rows += [["distance", str(p.kind)],
             ["simulated rocks per evaluation", f"{int(p.rocks):,}"],
             ["bootstrap replicates", f"{result.bootstrap_replicates:,}"],
             ["confidence of the intervals", f"{100 * float(result.confidence):g} %"],
             ["interval", INTERVAL]]
    if result.rough:
        rows.append(["intervals flagged", str(result.rough)])
    return Table("Calibration settings", ["setting", "value"], rows,
                 note="Ranges searched (the fitted inputs' values in the tables above are "
                 "where the search started); levels: stretches [from, to) of x whose shares "
                 "of the stops are compared and fitted.")


def _parameters_table(result: Any) -> Table:
    conf = f"{100 * result.confidence:g} %"
    if result.rough:
        conf = f"ROUGH, not {conf}"
    rows = []
    for p in result.parameters:
        ident = {True: "yes", False: "NO: not pinned down", None: "-"}[p.identified]
        if p.held_by_prior:
            ident = f"NO: held by the prior ({100 * (p.prior_share or 0.0):.0f} % of its sd)"
        share = "-" if p.width_share is None else f"{100 * p.width_share:.0f} %"
        r = rounded(p)  # to the interval's precision
        rows.append([p.path, _g(r.value, 12), _g(r.low, 12), _g(r.high, 12),
                     f"{p.range[0]:g} .. {p.range[1]:g}", share, _g(p.sd, 2), ident,
                     p.at_bound or "-"])
    return Table("Fitted inputs", ["input", "best value", f"low ({conf})", f"high ({conf})",
                                   "range searched", "interval / range", "sd of refits",
                                   "identified", "at bound"], rows,
                 note="best value: the fit to the observed stops, to the precision of its "
                 "interval (two digits of its half-width); low, high: the bootstrap "
                 "interval; interval / range: how much of the searched range the interval "
                 "fills; identified NO: the refits spread over the range (their standard "
                 "deviation above half that of values spread evenly over it), so the "
                 "observations do not pin the input down; held by the prior: a regularised "
                 "fit kept it near its class's value, the observations narrowing its prior "
                 "sd by less than a factor 1/sqrt(2); at bound: the best value lies at "
                 "that end of the range (widen it if the physics allows).")


def _correlation_table(result: Any) -> Table | None:
    if result.correlation is None:
        return None
    paths = result.problem.paths
    rows = [[f"{i + 1} {path}", *(f"{v:+.2f}" for v in result.correlation[i])]
            for i, path in enumerate(paths)]
    return Table("Correlation of the fitted inputs (bootstrap refits)",
                 ["input", *(str(j + 1) for j in range(len(paths)))], rows,
                 note="Near +1 or -1: the observations fix a combination of the two inputs "
                 "rather than each (e.g. a bouncier ground with more rolling resistance stops "
                 "the blocks at the same places).")


def _fit_table(fit: FitStatistics, after_fit: bool) -> Table:
    rows = [[label, f"{int(d.count):,}", *(f"{float(v):.1f}" for v in d.row)]
            for label, d in (("observed", fit.observed), ("simulated", fit.simulated))]
    note = (f"{fit.distance_kind} distance {float(fit.distance):.2f} m; two-sample "
            f"Kolmogorov-Smirnov D = {float(fit.ks_statistic):.3f}, p = "
            f"{float(fit.ks_pvalue):.3g}")
    if fit.beyond_section is not None:
        note += (f"; {100 * float(fit.beyond_section):.1f} % of the simulated rocks left "
                 "the section at its lower end (counted at its end)")
    note += (". After a fit the p-value is optimistic (the inputs were chosen to match these "
             "stops)." if after_fit else ". The project was not fitted to these "
             "observations: the p-value is a fair test of the prediction.")
    return Table("Fit statistics: observed and simulated stop positions (m)",
                 ["", "count", "mean", "p5", "p25", "p50", "p75", "p95"], rows, note=note)


def _levels_table(levels: Sequence[LevelShare], confidence: float) -> Table | None:
    if not levels:
        return None
    rows = [[s.name, f"{s.x[0]:g} .. {s.x[1]:g}", f"{s.observed_count:,}",
             f"{s.observed_share:.2f}", f"{s.low:.2f} .. {s.high:.2f}",
             f"{s.simulated_share:.2f}", "yes" if s.consistent else "NO: outside"]
            for s in levels]
    return Table("Levels: share of the stops", ["level", "x (m)", "observed blocks",
                                                "observed share",
                                                f"Wilson interval ({100 * confidence:g} %)",
                                                "simulated share", "consistent"], rows,
                 note="The observed share with its Wilson score interval (Wilson 1927); "
                 "consistent: the simulated share lies in it.")


def _sets_table(sets: Sequence[SetStatistics], after_fit: bool) -> Table | None:
    """Each observation set (kind, profile, station): observed and simulated, the test."""
    if not sets:
        return None
    rows = []
    for s in sets:
        f = s.fit
        unit = "m/s" if s.kind == "speeds" else "m"
        if f is None:
            stats = ["-", "no simulated rock passed", "-", "-"]
        else:
            stats = [f"{float(f.observed.p50_m):.2f} {unit}",
                     f"{float(f.simulated.p50_m):.2f} {unit}",
                     f"{float(f.distance):.2f} {unit}", f"{float(f.ks_pvalue):.3g}"]
        passed = s.passed_share
        rows.append([s.label, str(s.source), f"{float(s.weight):g}",
                     f"{int(s.count):,}", *stats,
                     "-" if passed is None else f"{100 * float(passed):.0f} %",
                     "yes" if s.consistent else "NO"])
    return Table("Observation sets", ["set", "source", "weight", "observed", "observed median",
                                      "simulated median", "distance", "KS p",
                                      "simulated rocks passing", "consistent"], rows,
                 note="Each set of observations (stops, passing heights, speeds; on each "
                 "profile) against the simulation" + (" at the best fit" if after_fit else "")
                 + ": heights and speeds over the simulated rocks that passed the station; "
                 "consistent: the two-sample Kolmogorov-Smirnov test at 5 % passes and the "
                 "set's levels' shares lie in their Wilson intervals."
                 + (" After a fit the p-values are optimistic." if after_fit else ""))


def _run_table(result: Any, command: str) -> Table:
    project = result.project
    obs = result.observations
    rows = [["program", f"rockfall-design {__version__}, command {command}; Python "
             f"{platform.python_version()}"],
            ["project file", str(project.source)],
            ["project hash (sha256 of the resolved project)", project.resolved_hash()],
            ["observations", f"{obs.source} ({obs.n:,} blocks)"],
            ["seed", str(result.seed)]]
    if command == "calibrate":
        rocks, boot = int(result.problem.rocks), int(result.bootstrap_replicates)
        rows += [["rocks per evaluation", f"{rocks:,}"],
                 ["bootstrap replicates", f"{boot:,}; replicate b has its own "
                  "seed, derived from the seed above"],
                 ["evaluations of the distance", f"{int(result.evaluations):,}"],
                 ["run time", f"{float(getattr(result, 'runtime_s', 0.0)):,.1f} s"]]
        repeat = (f"rockfall-design calibrate {project.source} --observed {obs.source} "
                  f"--seed {result.seed} --rocks {rocks} --bootstrap {boot}")
    else:
        rocks = int(result.rocks)
        rows.append(["simulated rocks", f"{rocks:,}"])
        repeat = (f"rockfall-design compare {project.source} --observed {obs.source} "
                  f"--seed {result.seed} --rocks {rocks}")
    e = project.engine
    rows += [["engine", f"exact events; contact hop ratio {e.contact_hop_ratio:g}; v_contact "
              f"{e.v_contact:g} m/s, v_stop {e.v_stop:g} m/s, max_events {e.max_events:,}"],
             ["to repeat", repeat + " (the same numbers wherever the replicates run)"]]
    return Table("", ["item", "value"], rows)


def _verdict(result: Any, command: str, warnings: Sequence[str]) -> tuple[str, str]:
    """The headline and its state (the report.html template colours it: ok or warn)."""
    n = result.observations.n
    if command == "calibrate":
        params = result.parameters
        loose = [p.path for p in params if p.identified is False]
        head = (f"Calibrated {len(params)} input{'s' if len(params) != 1 else ''} on {n:,} "
                "observed blocks")
        if loose:
            head += f": {len(loose)} not pinned down by the observations ({', '.join(loose)})"
        elif all(p.identified for p in params):
            head += ": every input pinned down by the observations"
        else:
            head += " (no bootstrap: no intervals)"
        return head + ".", ("fit with warnings" if warnings else "fit without warnings")
    fit = result.fit
    consistent, line = verdict(fit, result.levels)
    head = (f"Prediction of {n:,} observed blocks: {fit.distance_kind} distance "
            f"{float(fit.distance):.2f} m, KS D = {float(fit.ks_statistic):.2f}: "
            f"{line}.")
    return head, ("fit with warnings" if not consistent or warnings else "fit without warnings")


def report_context(result: Any,
                   figures: Mapping[str, Any] | None = None) -> ReportContext:
    """Everything the report templates show for ``calibrate`` or ``compare``, as plain data.

    Parameters
    ----------
    result : CalibrationResult or ComparisonResult
    figures : mapping of str to Figure, optional
        Default: ``result.figures()``.

    Returns
    -------
    ReportContext
        The context of :func:`rockfall_design.report.documents.render_html`
        and :func:`~rockfall_design.report.documents.render_markdown`.

    See Also
    --------
    rockfall_design.report.documents.report_context : the other commands' context.
    """
    # A calibration has fitted inputs; a comparison (compare) has none. Told
    # apart by that rather than by class, so that this module need not import
    # the results that import it.
    calibrated = hasattr(result, "parameters")
    command = "calibrate" if calibrated else "compare"
    project = result.project
    warnings = list(result.warnings)
    verdict, state = _verdict(result, command, warnings)
    # What was simulated: the project as fitted (observed sizes set, measures left out).
    resolved = result.problem.base if calibrated else None
    inputs = inputs_table(project, command, resolved)
    inputs += _observed_tables(result)
    results: list[Table] = []
    if calibrated:
        inputs.append(_settings_table(result))
        results.append(_parameters_table(result))
        corr = _correlation_table(result)
        if corr is not None:
            results.append(corr)
    results.append(_fit_table(result.fit, calibrated))
    confidence = result.confidence if calibrated else 0.95
    more = (_levels_table(result.levels, confidence),
            _sets_table(getattr(result, "sets", []), calibrated))
    results += [table for table in more if table is not None]
    figs = figures if figures is not None else result.figures()
    limits = [LimitsPart(CALIBRATION_LIMITS[0], list(CALIBRATION_LIMITS[1])),
              *model_limits(command)]
    if calibrated:
        note = ("The fitted inputs first, then the statistics of the stops simulated at the "
                "best fit against the observed ones.")
    else:
        note = ("The project as it is (nothing fitted) against observations: how well a "
                "calibration predicts blocks it did not see.")
    return ReportContext(
        title=f"{project.name}: rockfall {'calibration' if calibrated else 'comparison'}",
        project=project.name, description=project.description, command=command,
        version=__version__, generated=_dt.datetime.now(_dt.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        run=_run_table(result, command), inputs=inputs, results=results, results_note=note,
        verdict=verdict, verdict_state=state, failures=warnings, limits=limits,
        figures=[ReportFigure(name, CAPTIONS.get(name, ""), fig) for name, fig in figs.items()])

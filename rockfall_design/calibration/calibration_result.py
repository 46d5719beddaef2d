"""Results of a calibration and of a comparison: JSON, tables, calibrated project, figures.

:class:`CalibrationResult` holds the fitted parameters with their
intervals and flags, the correlation between them, the fit statistics and
level shares at the best fit, and every bootstrap replicate; it writes the
calibrated project (:meth:`CalibrationResult.calibrated_data`).
:class:`ComparisonResult` holds the same statistics for a project that was
not fitted to the observations (``compare``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..project import Project, dump_yaml
from ..report.documents import write_report
from ..report.terminal import fitted_console
from ..studies.paths import set_input, with_values
from .charts import cloud_figure, stops_figure
from .distances import FitStatistics, LevelShare, verdict
from .document import report_context
from .fit import FitProblem
from .observations import Observations, observed_file
from .prior import PRIOR_SIGMAS
from .screen import Screened
from .terms import SetStatistics
from .uncertainty import INTERVAL, FittedParameter, Replicate, intervals_flag, rounded

if TYPE_CHECKING:  # pragma: no cover
    import os
    from collections.abc import Mapping
    from pathlib import Path

    import pandas as pd
    from matplotlib.figure import Figure
    from rich.console import Console

    from ..report.context import ReportContext

__all__ = ["CalibrationResult", "ComparisonResult", "FIGURES", "SCATTER_KEYS"]

#: The figures of ``calibrate --plot`` by file stem (``compare`` draws the first).
FIGURES = ("calibration_stops", "calibration_cloud")
#: Material parameters that have a per-impact scatter in the project file.
SCATTER_KEYS = ("restitution", "friction", "rolling_resistance")


def _material_key(path: str) -> tuple[str, str] | None:
    """(material, parameter) of a path ``materials.NAME.PARAM`` with a scatter, else None."""
    parts = path.split(".")
    if len(parts) == 3 and parts[0] == "materials" and parts[2] in SCATTER_KEYS:
        return parts[1], parts[2]
    return None


def _warnings(parameters: list[FittedParameter], fit: FitStatistics,
              levels: list[LevelShare], rough: str | None = None) -> list[str]:
    """What a reader of the calibration must not miss, one sentence each."""
    out = [rough] if rough else []
    for p in parameters:
        if p.held_by_prior:
            out.append(f"{p.path}: held near its class's value by the prior, not pinned down "
                       f"by the observations (its posterior sd is {100 * (p.prior_share or 0):.0f}"
                       " % of the prior's): its value is the literature's, not the site's")
        elif p.identified is False:
            out.append(f"{p.path}: not identified by the observations (its refits spread "
                       f"over its range, the interval {100 * (p.width_share or 0.0):.0f} % of "
                       "it): do not use its value as if it were known")
        if p.at_bound:
            out.append(f"{p.path}: the best value lies at the {p.at_bound} end of its "
                       "range: widen the range if the physics allows")
    if (fit.beyond_section or 0.0) > 0.05:
        out.append(f"{100 * (fit.beyond_section or 0.0):.0f} % of the simulated rocks leave "
                   "the section at its lower end, where no block was observed")
    for share in levels:
        if not share.consistent:
            out.append(f"level {share.name}: the simulated share {share.simulated_share:.2f} is "
                       f"outside the observed share's interval [{share.low:.2f}, "
                       f"{share.high:.2f}]")
    return out


@dataclass
class ComparisonResult:
    """How a project predicts observed stops, with nothing fitted (``compare``)."""

    project: Project
    observations: Observations
    fit: FitStatistics
    levels: list[LevelShare]
    simulated: np.ndarray
    seed: int
    rocks: int
    sizes: dict[str, Any] | None = None
    #: Each observation set's statistics (:func:`~.terms.set_statistics`), when
    #: the project's observation sets were compared (compare without --observed).
    sets: list[SetStatistics] = field(default_factory=list)

    @property
    def summary(self) -> dict[str, Any]:
        """``compare --json``: ``fit``, ``levels``, ``observations``, ``seed``, ``rocks``.

        With observation sets, also ``sets`` (each set's statistics and verdict).
        """
        out = {
            "project": self.project.name,
            "observations": {"file": self.observations.source, "count": self.observations.n,
                             "sizes": self.sizes},
            "fit": self.fit.to_json(),
            "levels": [s.as_dict() for s in self.levels],
            "seed": self.seed,
            "rocks": self.rocks,
            "verdict": self.verdict_line,
            "consistent": self.consistent,
            "warnings": self.warnings,
        }
        if self.sets:
            out["sets"] = [s.to_json() for s in self.sets]
        return out

    @property
    def warnings(self) -> list[str]:
        """What a reader of the comparison must not miss, one sentence each."""
        return _warnings([], self.fit, self.levels) + _set_warnings(self.sets)

    @property
    def consistent(self) -> bool:
        """Whether the prediction is consistent with every observation compared."""
        if self.sets:
            return all(s.consistent for s in self.sets)
        return verdict(self.fit, self.levels)[0]

    @property
    def verdict_line(self) -> str:
        """Whether the prediction is consistent with the observations, naming the test."""
        if not self.sets:
            return verdict(self.fit, self.levels)[1]
        bad = [s.label for s in self.sets if not s.consistent]
        if not bad:
            return (f"consistent with every one of the {len(self.sets)} observation sets "
                    "(two-sample Kolmogorov-Smirnov tests at 5 % and the levels' shares, "
                    "each set on its own)")
        return (f"NOT consistent with the observations: {len(bad)} of {len(self.sets)} "
                f"sets fail their test ({'; '.join(bad)})")

    def figures(self) -> dict[str, Figure]:
        """The stop positions' figure (:data:`FIGURES` [0])."""
        levels = {s.name: s.x for s in self.levels}
        return {FIGURES[0]: stops_figure(self.observations.x, self.simulated, levels,
                                         f"{self.project.name}: {self.observations.source}")}

    def report_context(self, figures: Mapping[str, Figure] | None = None) -> ReportContext:
        """The report's context (:func:`~.document.report_context`)."""
        return report_context(self, figures)

    def save_report(self, directory: str | os.PathLike[str]) -> list[Path]:
        """Write ``report.html`` (self-contained) and ``report.md`` (with SVG figures)."""
        return write_report(self, directory)

    def print(self, console: Console | None = None) -> None:
        """The fit statistics and the levels as rich tables."""
        from rich.markup import escape

        console = _print_fit(self.project.name, self.fit, self.levels, console,
                   f"{self.observations.n} observed blocks, {self.rocks:,} simulated rocks, "
                   f"seed {self.seed}")
        _print_sets(self.sets, console)
        colour = "green" if self.consistent else "red"
        console.print(f"[{colour}]verdict:[/{colour}] {escape(self.verdict_line)}")
        for w in self.warnings:
            console.print(f"[yellow]warning:[/yellow] {escape(w)}")


@dataclass
class CalibrationResult:
    """A calibration: fitted parameters with intervals, fit statistics, replicates.

    Attributes
    ----------
    parameters : list of FittedParameter
        Per fitted input (:func:`~.uncertainty.summarise`).
    correlation : ndarray or None
        The parameters' correlation over the bootstrap replicates.
    fit : FitStatistics
        :func:`~.distances.fit_statistics` at the best fit.
    levels : list of LevelShare
    replicates : list of Replicate
        Replicate 0 (the fit) and the bootstrap replicates.
    simulated : ndarray
        The simulated stops at the best fit (m).
    """

    project: Project
    problem: FitProblem
    observations: Observations
    parameters: list[FittedParameter]
    correlation: np.ndarray | None
    replicates: list[Replicate]
    fit: FitStatistics
    levels: list[LevelShare]
    simulated: np.ndarray
    seed: int
    confidence: float
    sizes: dict[str, Any] | None = None
    runtime_s: float = 0.0
    #: Each observation set's statistics at the best fit (:func:`~.terms.set_statistics`);
    #: empty for the single-file form.
    sets: list[SetStatistics] = field(default_factory=list)
    #: The screen of a ``fit: auto`` (:func:`~.screen.screen`): every input
    #: measured, those left out with ``kept`` False; empty without a screen.
    screened: list[Screened] = field(default_factory=list)
    _figures: dict[str, Any] = field(default_factory=dict, repr=False)

    @property
    def values(self) -> dict[str, float]:
        """Path -> best value."""
        return {p.path: p.value for p in self.parameters}

    @property
    def bootstrap(self) -> np.ndarray:
        """(B, d) refitted values of the bootstrap replicates, in the order of the paths."""
        return np.array([[r.values[p] for p in self.problem.paths]
                         for r in self.replicates[1:]]).reshape(-1, len(self.problem.paths))

    @property
    def bootstrap_replicates(self) -> int:
        """Bootstrap replicates B (replicate 0, the fit, not counted)."""
        return len(self.replicates) - 1

    @property
    def evaluations(self) -> int:
        """Evaluations of the distance over every replicate."""
        return int(sum(r.evaluations for r in self.replicates))

    @property
    def warnings(self) -> list[str]:
        """What a reader of the calibration must not miss, one sentence each."""
        return ([s.line for s in self.screened if not s.kept]
                + _warnings(self.parameters, self.fit, self.levels, self.rough)
                + _set_warnings(self.sets))

    @property
    def summary(self) -> dict[str, Any]:
        """``calibrate --json``."""
        corr = None
        if self.correlation is not None:
            corr = {"paths": list(self.problem.paths),
                    "matrix": [[float(v) for v in row] for row in self.correlation]}
        return {
            "project": self.project.name,
            "parameters": [p.to_json() for p in self.parameters],
            "correlation": corr,
            "fit": self.fit.to_json(),
            "levels": [s.as_dict() for s in self.levels],
            "observations": {"file": self.observations.source, "count": self.observations.n,
                             "sizes": self.sizes},
            "method": {"distance": self.problem.kind, "rocks": self.problem.rocks,
                       "bootstrap": self.bootstrap_replicates, "confidence": self.confidence,
                       "interval": INTERVAL, "rough_intervals": self.rough, "seed": self.seed,
                       "evaluations": self.evaluations, "prior": self.prior_summary,
                       "screen": [x.to_json() for x in self.screened] or None},
            "warnings": self.warnings,
            **({"sets": [s.to_json() for s in self.sets],
                "profiles": {o.name: o.project.source for o in self.problem.others}}
               if self.sets else {}),
        }

    @property
    def prior_summary(self) -> dict[str, Any] | None:
        """``method.prior`` of ``--json``: the prior's modes, its sd and weight; None without.

        ``modes``: path -> the class's value; ``noise``: s_D of the fit itself
        (:func:`~.prior.criterion_noise`); ``penalty``: the prior's term at the
        best fit, s_D * sum z**2 (the criterion alone is ``objective`` of
        ``replicates.csv``).
        """
        if not self.problem.prior:
            return None
        first = self.replicates[0]
        return {"kind": f"two-piece normal, the range at +-{PRIOR_SIGMAS:g} sd of the value",
                "modes": dict(zip(self.problem.paths, self.problem.prior, strict=True)),
                "noise": first.noise, "penalty": first.penalty}

    @property
    def rough(self) -> str | None:
        """Why the intervals are not of the stated confidence (too few replicates), or None."""
        return intervals_flag(self.bootstrap_replicates, self.confidence)

    def parameters_table(self) -> pd.DataFrame:
        """One row per fitted input (``parameters.csv``)."""
        import pandas as pd

        rows = [{k: (v if not isinstance(v, list) else f"{v[0]:g}..{v[1]:g}")
                 for k, v in p.to_json().items()} for p in self.parameters]
        return pd.DataFrame(rows)

    def replicates_table(self) -> pd.DataFrame:
        """One row per replicate (``replicates.csv``): index, seed, objective, values."""
        import pandas as pd

        prior = {} if not self.problem.prior else None
        return pd.DataFrame([{"replicate": r.index, "seed": r.seed,
                              "objective": r.objective, "evaluations": r.evaluations,
                              **(prior if prior is not None else
                                 {"prior_penalty": r.penalty, "prior_noise": r.noise}),
                              **r.values} for r in self.replicates])

    def calibrated_data(self, relative_to: str | None = None, spread: bool = False
                        ) -> dict[str, Any]:
        """The calibrated project as data (``calibrated.yaml``).

        The fitted inputs set to their best values; the rocks' size fitted
        to the observed blocks' (if they had sizes); every material's
        per-impact scatter as the project (or its library class) gives it:
        the ground's variability from one impact to the next (aleatory). The
        uncertainty of a fitted value (the bootstrap's standard deviation,
        epistemic) is not drawn by a run: it is recorded beside the values
        (:meth:`uncertainty_lines`, ``parameters.csv``). ``spread=True``
        widens the scatter of a fitted material parameter by that standard
        deviation (added in quadrature) instead (the former default).
        The ``calibrate:`` section is kept, its ``observed`` the file this
        calibration fitted (``--observed`` if given, else the project's),
        relative to ``relative_to`` (the directory the file is written to),
        so that a rerun fits the same observations and ``compare`` finds its
        levels.

        Notes
        -----
        A per-impact scatter is drawn anew at every impact, whereas the
        uncertainty of a calibrated mean is one unknown value for the whole
        slope. Written into the scatter it is averaged over the impacts of a
        path, and it shifts where the rocks stop wherever a value sits near a
        threshold (Authume P1's slope share 0.06 became 0.30,
        docs/calibration.md), so it is not the default. The rigorous way to
        carry it is a study (``study:`` with the interval's ends in
        ``vary``), with the intervals of ``--json``.
        """
        import copy
        import os


        data = copy.deepcopy(self.problem.base)
        for p in self.parameters:
            # To its interval's precision: the digits beyond are noise.
            set_input(data, p.path, rounded(p).value)
            key = _material_key(p.path)
            if spread and key is not None and p.sd is not None:
                scatter = data["materials"][key[0]].setdefault("scatter", {})
                old = float(scatter.get(key[1]) or 0.0)
                scatter[key[1]] = float(f"{math.hypot(old, p.sd):.2g}")
        spec = self.project.resolved_dict().get("calibrate")
        if spec is not None:
            fitted = self.observations.path or observed_file(self.project)
            path = None if fitted is None else os.fspath(fitted.resolve())
            if relative_to is not None and path is not None:
                path = os.path.relpath(path, relative_to)
            if isinstance(spec["observed"], str):
                data["calibrate"] = {**spec, "observed": path}
            else:
                data["calibrate"] = self._sets_section(spec, path, relative_to)
        return data

    def _sets_section(self, spec: dict[str, Any], fitted: str | None,
                      relative_to: str | None) -> dict[str, Any]:
        """The ``calibrate:`` section of the list form, its files relative to ``relative_to``.

        The first set of stops on the project's own section names the file
        this run fitted (``fitted``); every other file and every profile is
        the one the project names, found from where the calibrated project
        is written; ``fit`` the inputs this run fitted (with ``fit: auto``
        over profiles, theirs too), so that a rerun fits the same.
        """
        import os
        from pathlib import Path

        home = Path(self.project.source).parent if self.project.source != "<string>" \
            else Path.cwd()

        def moved(name: str) -> str:
            path = os.fspath((home / name).resolve())
            return os.path.relpath(path, relative_to) if relative_to is not None else path

        entries, first = [], True
        for entry in spec["observed"]:
            entry = dict(entry)
            if entry.get("file") is not None:
                own = entry["kind"] == "stops" and entry.get("profile") is None
                entry["file"] = fitted if own and first else moved(entry["file"])
                first = first and not own
            entries.append(entry)
        fit = {p: [lo, hi] for p, lo, hi in zip(self.problem.paths, self.problem.low,
                                                  self.problem.high, strict=True)}
        return {**spec, "observed": entries, "fit": fit,
                **({"profiles": {k: moved(v) for k, v in spec["profiles"].items()}}
                   if spec.get("profiles") else {})}

    def calibrated_project(self, spread: bool = False) -> Project:
        """:meth:`calibrated_data` validated as a project."""
        return with_values(self.problem.project, {}, base=self.calibrated_data(spread=spread))

    def materials_library(self, spread: bool = False) -> dict[str, Any]:
        """The calibrated project's materials, as a library file holds them."""
        return self.calibrated_data(spread=spread)["materials"]

    def materials_library_text(self, spread: bool = False, when: str | None = None) -> str:
        """The calibrated materials as a library file, each entry with its law and source.

        Every entry is preceded by the two comment lines the bundled library
        has (``projects/materials.yaml``, docs/materials.md): ``law:`` (its
        impact model) and ``source:``: for an entry with a fitted parameter,
        "calibrated on FILE (N blocks), DATE, seed S" with the fitted
        parameters, their values and intervals; for the others, that they
        are the project's, not fitted.

        Parameters
        ----------
        spread
            As :meth:`calibrated_data`.
        when
            The date written (default: today, UTC, ``YYYY-MM-DD``).
        """
        import datetime as dt


        day = when or dt.datetime.now(dt.UTC).strftime("%Y-%m-%d")
        fitted: dict[str, list[str]] = {}
        for p in self.parameters:
            key = p.path.split(".")
            if len(key) != 3 or key[0] != "materials":
                continue  # not a material's parameter (e.g. the release height)
            _, material, name = key
            r = rounded(p)
            interval = "" if r.low is None else f" [{r.low:g}, {r.high:g}]"
            sd = "" if r.sd is None else f" sd {r.sd:g}"
            flag = " NOT IDENTIFIED" if p.identified is False else ""
            fitted.setdefault(material, []).append(f"{name} {r.value:g}{interval}{sd}{flag}")
        observed = f"{self.observations.source} ({self.observations.n} blocks)"
        if self.sets:  # every set fitted, each with where it was observed
            observed = "; ".join(f"{x.label} from {x.source} ({x.count})" for x in self.sets)
        parts = []
        for name, entry in self.materials_library(spread=spread).items():
            if name in fitted:
                what = self.rough or f"{100 * self.confidence:g} % intervals"
                source = (f"calibrated on {observed}, {day}, seed {self.seed} (rockfall-design "
                          f"calibrate; fitted: {'; '.join(fitted[name])}, {what})")
            else:
                source = f"the project {self.project.source}, not fitted by this calibration"
            law = entry.get("impact_model", "spang")
            parts.append(f"# law: {law}\n# source: {' '.join(source.split())}\n"
                         + dump_yaml({name: entry}))
        return "".join(parts)

    def uncertainty_lines(self, spread: bool = False) -> list[str]:
        """Comment lines (without ``#``) on the fitted values' uncertainty, one per input.

        Each fitted input's best value, its bootstrap standard deviation and
        interval, and whether the written file draws that standard deviation
        (``spread``) or not: the values' uncertainty (epistemic) is recorded,
        not mixed into the per-impact scatter (aleatory), unless asked.
        """
        if not any(p.sd is not None for p in self.parameters):
            return []
        how = ("added in quadrature to the per-impact scatter of a fitted material parameter"
               if spread else "NOT drawn by a run (the scatter is the materials' own)")
        out = [f"uncertainty of the fitted values (bootstrap sd, {how}):"]
        for p in self.parameters:
            r = rounded(p)
            if r.sd is None:
                continue
            flag = ", NOT IDENTIFIED" if p.identified is False else ""
            out.append(f"  {p.path} = {r.value:g}, sd {r.sd:g}, interval [{r.low:g}, "
                       f"{r.high:g}]{flag}")
        return out

    def figures(self) -> dict[str, Figure]:
        """The stops' figure and the bootstrap cloud (:data:`FIGURES`)."""
        levels = {s.name: s.x for s in self.levels}
        return {
            FIGURES[0]: stops_figure(self.observations.x, self.simulated, levels,
                                     f"{self.project.name}: best fit"),
            FIGURES[1]: cloud_figure(self.problem.paths, self.bootstrap, self.parameters),
        }

    def report_context(self, figures: Mapping[str, Figure] | None = None) -> ReportContext:
        """The report's context (:func:`~.document.report_context`)."""
        return report_context(self, figures)

    def save_report(self, directory: str | os.PathLike[str]) -> list[Path]:
        """Write ``report.html`` (self-contained) and ``report.md`` (with SVG figures)."""
        return write_report(self, directory)

    def print(self, console: Console | None = None) -> None:
        """The parameters, the fit and the levels as rich tables."""
        from rich.markup import escape
        from rich.table import Table


        replicates = self.bootstrap_replicates
        kind = ("ROUGH intervals, not " if self.rough else "") + f"{100 * self.confidence:g} %"
        t = Table(title=f"fitted inputs ({kind}, {replicates} bootstrap replicates)")
        for col in ("input", "value", "low", "high", "range", "identified"):
            t.add_column(col, justify="left" if col in ("input", "identified") else "right")
        for p in self.parameters:
            def num(v: Any) -> str:
                return "-" if v is None else f"{v:g}"
            r = rounded(p)
            ident = {True: "yes", False: "[red]NO[/red]", None: "-"}[p.identified]
            if p.held_by_prior:
                ident = "[red]NO[/red] (prior)"
            t.add_row(escape(p.path), num(r.value), num(r.low), num(r.high),
                      f"{p.range[0]:g}..{p.range[1]:g}", ident)
        console = console or fitted_console(t)
        console.print(t)
        prior = self.prior_summary
        if prior is not None:
            console.print(f"regularised by the prior (each input's value in the project, its "
                          f"range as +-{PRIOR_SIGMAS:g} sd), weighed by the criterion's "
                          f"sampling noise s_D = {prior['noise']:.3g}; the prior's term at the "
                          f"best fit {prior['penalty']:.3g}, the criterion "
                          f"{self.replicates[0].objective:.3g} (--no-prior: the criterion "
                          "alone)")
        if self.correlation is not None:
            c = Table(title="correlation of the fitted inputs (bootstrap)")
            c.add_column("")
            for j in range(len(self.problem.paths)):
                c.add_column(str(j + 1), justify="right")
            for i, path in enumerate(self.problem.paths):
                c.add_row(f"{i + 1} {escape(path)}",
                          *(f"{v:+.2f}" for v in self.correlation[i]))
            console.print(c)
        _print_fit(self.project.name, self.fit, self.levels, console,
                   f"{self.observations.n} observed blocks, {self.problem.rocks:,} rocks per "
                   f"evaluation, seed {self.seed}, {self.runtime_s:.1f} s")
        _print_sets(self.sets, console)
        for w in self.warnings:
            console.print(f"[yellow]warning:[/yellow] {escape(w)}")


def _set_warnings(sets: list[SetStatistics]) -> list[str]:
    """Each observation set the simulation does not reproduce, one sentence each."""
    return [f"{s.label}: {s.verdict}" for s in sets if not s.consistent]


def _level_rows(title: str, levels: list[LevelShare], console: Console) -> None:
    """A table of levels: each one's observed share, its interval, the simulated share."""
    from rich.markup import escape
    from rich.table import Table

    lt = Table(title=title)
    for col in ("level", "x (m)", "observed", "interval", "simulated", ""):
        lt.add_column(col, justify="left" if col in ("level", "") else "right")
    for s in levels:
        lt.add_row(escape(s.name), f"{s.x[0]:g}..{s.x[1]:g}",
                   f"{s.observed_share:.2f} ({s.observed_count})",
                   f"{s.low:.2f}..{s.high:.2f}", f"{s.simulated_share:.2f}",
                   "" if s.consistent else "[red]outside[/red]")
    console.print(lt)


def _print_sets(sets: list[SetStatistics], console: Console) -> None:
    """One row per observation set: counts, medians, distance, KS p; a profile's levels."""
    from rich.markup import escape
    from rich.table import Table

    if not sets:
        return
    t = Table(title="observation sets (each kind, each profile)")
    for col in ("set", "source", "weight", "count", "observed p50", "simulated p50",
                "distance", "KS p", "passed", ""):
        t.add_column(col, justify="left" if col in ("set", "source", "") else "right")
    for s in sets:
        f = s.fit
        unit = "m/s" if s.kind == "speeds" else "m"
        row = ["-", "none passed", "-", "-"] if f is None else [
            f"{f.observed.p50_m:.2f} {unit}", f"{f.simulated.p50_m:.2f} {unit}",
            f"{f.distance:.2f} {unit}", f"{f.ks_pvalue:.2g}"]
        passed = s.passed_share
        t.add_row(escape(s.label), escape(str(s.source)), f"{s.weight:g}",
                  f"{s.count:,}", *row, "-" if passed is None else f"{100 * passed:.0f} %",
                  "" if s.consistent else "[red]NOT[/red]")
    console.print(t)
    for s in sets:
        if s.profile and s.levels:  # the project's own levels are printed above
            _level_rows(f"levels of {escape(s.label)}: share of the stops", s.levels, console)


def _print_fit(name: str, fit: FitStatistics, levels: list[LevelShare],
               console: Console | None, head: str) -> Console:
    """The fit statistics and the level shares (shared by calibrate and compare); the console."""
    from rich.markup import escape
    from rich.table import Table


    t = Table(title=f"{escape(name)}: observed and simulated stops ({head})")
    for col in ("", "count", "mean", "p5", "p25", "p50", "p75", "p95"):
        t.add_column(col, justify="left" if not col else "right")
    for label, d in (("observed", fit.observed), ("simulated", fit.simulated)):
        t.add_row(label, f"{d.count:,}", *(f"{v:.1f}" for v in d.row))
    console = console or fitted_console(t)
    console.print(t)
    console.print(f"{fit.distance_kind} distance {fit.distance:.2f} m; Kolmogorov-Smirnov "
                  f"D = {fit.ks_statistic:.3f}, p = {fit.ks_pvalue:.3g}")
    if levels:
        _level_rows("levels: share of the stops", levels, console)
    return console

"""The result objects of the API: a simulation, a check, an optimisation.

Each wraps what a command computed (the run's statistics, the judge's
evaluation, the optimiser's alternatives) and offers it as a notebook or a
script wants it: ``.summary`` (as the command's ``--json``), tables as
pandas DataFrames, figures, the report. :mod:`rockfall_design.api`'s
functions return them.
"""

from __future__ import annotations

import os
from dataclasses import replace
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .judge.costing import design_bill
from .judge.evaluation import evaluate
from .judge.plan import design_of, plan_for
from .judge.records import Bill, CheckSummary, DesignVerdict, State, run_of
from .judge.verdict import judged
from .report.documents import write_report
from .report.formats import save_figures
from .report.tables import alternatives_frame, checks_frame, measures_frame, passages_frame
from .run import simulation
from .run.passages import station_passages
from .run.streamed import StreamedRun
from .run.summary import RunSummary

# The typed results of corridors, scenario checks and terrain sections, for
# the front ends (each documented where it is defined).
from .studies.corridor import CorridorSummary, SectionBlock, SectionOutcome  # noqa: F401
from .studies.scenario_checks import Binding, ScenariosCheck  # noqa: F401
from .terrain.cut import TerrainSection  # noqa: F401
from .terrain.dem import Dem  # noqa: F401

# The drawing modules (report.figures, report.passage_figures,
# report.design_figures) import matplotlib at their top, a fifth of a second,
# as their figures subclass its Figure: the plot methods import them, so that
# a result that is not drawn (simulate --json) never loads matplotlib.

FAILS, HOLDS_ON_POINT_VALUES = State.FAILS, State.HOLDS_ON_POINT_VALUES

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd
    from matplotlib.figure import Figure

    from .judge.evaluation import Evaluation
    from .optimiser.alternatives import SearchOutcome
    from .plugins import Registry
    from .project import Project
    from .run.passages import Passages
    from .run.simulation import SimulationRun
    from .run.streamed import StreamedRun


#: Rock paths kept for the profile figure (the first rocks of the run).
DEFAULT_TRAJECTORIES = 60


def _stations_frame(run: RunSummary) -> pd.DataFrame:
    """One row per analysis station: crossings and the statistics of each quantity."""
    rows = []
    for s in run.stations:
        row: dict[str, Any] = {"x_m": s.x, "crossings": s.crossings}
        for key, block in s.blocks.items():
            base, _, unit = key.rpartition("_")
            for stat, value in block.to_json().items():
                row[f"{base}_{stat}_{unit}"] = value
        rows.append(row)
    import pandas as pd  # on first use: simulate without tables need not load it

    return pd.DataFrame(rows)


class SimulationResult:
    """What ``simulate`` found: summary, tables and figures of a run.

    Attributes
    ----------
    project : Project
    run : SimulationRun or StreamedRun
        The run itself (engine-level; prefer the tables below).
    """

    #: The command whose ``--json`` :attr:`summary` matches.
    command = "simulate"

    def __init__(self, project: Project, run: SimulationRun | StreamedRun,
                 rocks_tables: list[pd.DataFrame] | None = None) -> None:
        self.project = project
        self.run = run
        self._rocks_tables = rocks_tables
        self._evaluation: Evaluation | None = None

    def __repr__(self) -> str:
        return (f"<{type(self).__name__} {self.project.name!r}: {self.run.n:,} rocks, "
                f"seed {self.run.seed}>")

    @property
    def seed(self) -> int:
        """The seed of the run."""
        return int(self.run.seed)

    @property
    def n_rocks(self) -> int:
        """The number of rocks of the run."""
        return int(self.run.n)

    @cached_property
    def record(self) -> RunSummary:
        """The run's summary as an object (:class:`~rockfall_design.run.summary.RunSummary`):
        what the report reads."""
        return self.run.run_summary()

    @cached_property
    def summary(self) -> dict[str, Any]:
        """The JSON-ready summary: the same dict as ``rockfall-design simulate --json``
        (:attr:`record`'s ``to_json()``)."""
        return self.record.to_json()

    @property
    def streamed(self) -> bool:
        """True for a run of more than ``EXACT_ROCKS`` rocks (statistics from histograms)."""

        return isinstance(self.run, StreamedRun)

    @cached_property
    def rocks(self) -> pd.DataFrame:
        """One row per rock: size, release, how and where its path ended (m, kg, s)."""
        if self.streamed:
            if self._rocks_tables is None:
                raise ValueError("the per-rock table of this streamed run was not kept")
            import pandas as pd

            return pd.concat(self._rocks_tables, ignore_index=True)
        return self.run.rocks_table()

    @property
    def crossings(self) -> pd.DataFrame:
        """One row per rock and analysis station (first passage downslope; m, m/s, kJ)."""
        if self.streamed:
            raise ValueError(
                f"a run of more than {self._exact_rocks():,} rocks is streamed and does not keep "
                "its crossings; use fewer rocks, or rockfall-design simulate --out DIR, which "
                "writes crossings.csv as the run goes")
        return self.run.crossings_table()

    @staticmethod
    def _exact_rocks() -> int:

        return simulation.EXACT_ROCKS

    @cached_property
    def stations(self) -> pd.DataFrame:
        """One row per analysis station: rocks passing and the statistics of height (m),
        speed (m/s) and energies (kJ), columns such as ``passing_height_p95_m``."""
        return _stations_frame(run_of(self.record))

    @property
    def envelopes(self) -> pd.DataFrame:
        """Envelopes along x of passing height (m) and energy (kJ), and rocks passing."""
        return self.run.envelopes()

    # ---- figures ---------------------------------------------------------
    def plot_profile(self) -> Figure:
        """The slope section with a sample of paths, stations and measures."""
        from .report.figures import profile_figure

        return profile_figure(self.run, self._evaluation)

    def plot_envelopes(self, min_rocks: int | None = None) -> Figure:
        """Envelopes of height and energy where at least ``min_rocks`` rocks pass.

        ``min_rocks`` defaults to the project's ``analysis.min_rocks_envelope``.
        """
        from .report.figures import envelopes_figure

        return envelopes_figure(self.run, self._evaluation, min_rocks)

    def plot_stops(self) -> Figure:
        """Where the rocks come to rest (says why when none does)."""
        from .report.figures import stops_figure

        return stops_figure(self.run, self._evaluation)

    def passages(self) -> list[Passages]:
        """The rocks passing each analysis station and meeting each barrier.

        Per place every quantity of :data:`rockfall_design.run.passages.QUANTITIES`
        per rock, with the barrier's figures (its heights and capacities) as
        marks. Empty for a streamed run (more than ``EXACT_ROCKS`` rocks),
        which keeps no rock's values; its summary still has each station's
        statistics.
        """

        if self.streamed:
            return []
        out = station_passages(self.run)
        if self._evaluation is not None:
            out += self._evaluation.passages()
        return out

    @property
    def barriers(self) -> pd.DataFrame:
        """barriers.csv: one row per station or barrier and quantity, with its statistics.

        See :func:`rockfall_design.report.tables.passages_frame`.
        """

        return passages_frame(self.summary)

    def plot_passages(self) -> dict[str, Figure]:
        """Histograms and empirical CDFs at every station and barrier, by figure name.

        Names ``passing_station_N`` and ``passing_measure_N`` (from 1); see
        :func:`rockfall_design.report.passage_figures.passage_figure`.
        """
        from .report.passage_figures import passage_figure, passage_name

        return {passage_name(p): passage_figure(p, self.project.name) for p in self.passages()}

    def figures(self) -> dict[str, Figure]:
        """Every figure of the result, by name (the file names of ``--plot``)."""
        return {"profile": self.plot_profile(), "envelopes": self.plot_envelopes(),
                "stops": self.plot_stops(), **self.plot_passages()}

    def plot(self, which: str = "profile") -> Figure:
        """One figure by name: ``profile``, ``envelopes``, ``stops`` or ``passing_...``.

        Returns a :class:`matplotlib.figure.Figure` (shown by a notebook
        when it is a cell's value; ``fig.savefig(path)`` writes it).
        """
        methods = {"profile": self.plot_profile, "envelopes": self.plot_envelopes,
                   "stops": self.plot_stops}
        if which.startswith("passing_"):
            figs = self.plot_passages()
            if which in figs:
                return figs[which]
            raise ValueError(f"unknown figure {which!r}; the places of this run: "
                             f"{', '.join(figs) or 'none'}")
        if which not in methods:
            raise ValueError(f"unknown figure {which!r}; choose one of {', '.join(methods)}")
        return methods[which]()

    def save_figures(self, directory: str | os.PathLike[str],
                     formats: tuple[str, ...] = ("png",)) -> list[Path]:
        """Write every figure into ``directory`` as NAME.FORMAT (png, svg, pdf)."""

        return save_figures(self.figures(), directory, formats)

    def save_report(self, directory: str | os.PathLike[str]) -> list[Path]:
        """Write ``report.html`` (self-contained), ``report.md`` (with SVG figures) and
        ``report.pdf`` (with the pdf extra; else a warning says how to get it)."""

        return write_report(self, directory)


class CheckResult(SimulationResult):
    """What ``check`` found: the run with the measures, and each measure's checks.

    Attributes
    ----------
    evaluation : Evaluation
        The design evaluated on the rocks (engine-level; prefer the tables).
    """

    command = "check"

    def __init__(self, project: Project, evaluation: Evaluation,
                 registry: Registry | None = None) -> None:
        super().__init__(project, evaluation.run)
        self.evaluation = evaluation
        self._evaluation = evaluation
        #: The plugins the check ran with (for the report's provenance); None if not known.
        self.registry = registry

    @cached_property
    def record(self) -> CheckSummary:
        """The check's summary as an object, judged
        (:class:`~rockfall_design.judge.records.CheckSummary`): what the report reads."""
        return judged(self.evaluation.record())

    @cached_property
    def summary(self) -> dict[str, Any]:
        """The JSON-ready summary: the same dict as ``rockfall-design check --json``.

        :attr:`record`'s ``to_json()``. It begins with ``verdict``
        (:func:`rockfall_design.judge.verdict.verdict_of`); a check of
        nothing (``untested``) is not ``ok``.
        """
        return self.record.to_json()

    @property
    def verdict(self) -> DesignVerdict:
        """The verdict (:class:`~rockfall_design.judge.verdict.DesignVerdict`): one of
        "holds with confidence", "holds on point values only", "fails", "untested"."""
        verdict = self.record.verdict
        assert verdict is not None  # judged above
        return verdict

    @property
    def ok(self) -> bool:
        """True when every check holds and the residual is within what is allowed.

        False when nothing was tested (no measure met and no protected zone).
        """
        return self.record.ok

    @property
    def failures(self) -> list[str]:
        """One line per failed check."""
        return list(self.record.failures)

    @cached_property
    def rocks(self) -> pd.DataFrame:
        """One row per rock, with ``caught_by_measure`` (index in ``measures:``, -1 none)."""
        rocks = self.run.rocks_table()
        rocks["caught_by_measure"] = self.evaluation.caught_by_measure()
        return rocks

    @cached_property
    def measures(self) -> pd.DataFrame:
        """One row per measure: rocks met, caught, over, through; a column per check."""

        return measures_frame(self.summary)

    @cached_property
    def checks(self) -> pd.DataFrame:
        """One row per safety check: value, confidence bound (if any), target, verdict."""

        return checks_frame(self.summary)

    @property
    def outcomes(self) -> pd.DataFrame:
        """One row per rock and measure: the outcome of the first meeting and its values."""
        return self.evaluation.outcomes_table()


class OptimiseResult:
    """What ``optimise`` found: the alternatives, the chosen design and its figures.

    Built from the optimiser's result through its summary, ``best`` and
    ``alternatives`` only, so it does not depend on how the search works.

    Attributes
    ----------
    project : Project
    result : SearchOutcome
        The optimiser's own outcome
        (:class:`~rockfall_design.optimiser.alternatives.SearchOutcome`).
    """

    command = "optimise"

    def __init__(self, project: Project, result: SearchOutcome,
                 registry: Registry) -> None:
        self.project = project
        self.result = result
        self._registry = registry

    def __repr__(self) -> str:
        best = self.best
        chosen = "no admissible design" if best is None else f"chosen {best['name']!r}"
        return f"<OptimiseResult {self.project.name!r}: {chosen}>"

    @cached_property
    def summary(self) -> dict[str, Any]:
        """The JSON-ready summary: the same dict as ``rockfall-design optimise --json``.

        It begins with ``verdict`` (the chosen design's, see :attr:`verdict`)
        and has the chosen design's ``bill`` beside ``best`` (None without one).
        """
        summary = self.result.summary()
        out = {"verdict": self.verdict.as_dict(), **summary}
        out["bill"] = self.bill
        return out

    @cached_property
    def verdict(self) -> DesignVerdict:
        """The verdict on the chosen design (:class:`~rockfall_design.judge.verdict.DesignVerdict`).

        The chosen design's check on the rocks that decided it, as ``check``
        gives it; a design that then fails on the fresh rocks holds on point
        values only; without a chosen design, ``fails`` with the reason.
        """
        best = self.result.best
        if best is None:
            reason = self.result.reason or "no family meets the targets"
            return DesignVerdict(FAILS, f"Fails: no admissible design: {reason}",
                                 confidence=float(self.result.confidence))
        design = self.design
        assert design is not None
        verdict = design.verdict
        if best.holds_on_fresh_rocks is False and verdict.holds:
            verdict = replace(
                verdict, state=HOLDS_ON_POINT_VALUES,
                headline="Holds on point values only: admitted on its deciding rocks, but it "
                f"does not hold on {best.fresh_rocks:,} fresh rocks (seed {best.fresh_seed}).",
                details=(*best.fresh_failures, *verdict.details))
        return verdict

    @cached_property
    def bill_record(self) -> Bill | None:
        """The bill of the chosen design as an object (None without one).

        Its lines (``measure``, ``quantity``, ``unit``, ``count``,
        ``unit_price``, ``amount``, ``per_m``, ``source``), ``total`` (the
        chosen design's cost), ``currency``, ``length_m`` (the site length,
        m): see :func:`rockfall_design.judge.costing.design_bill`.
        """
        best = self.result.best
        if best is None:
            return None

        d = self.project.design
        source = (f"catalogue {d.costs.file}" if d.costs.file else "design.costs.params")
        plan = plan_for(self.project, self._registry)
        bill = design_bill(self._registry, design_of(self.project, self._registry),
                           best.measures, plan.bare, source)
        return replace(bill, currency=self.result.currency or "")

    @property
    def bill(self) -> dict[str, Any] | None:
        """:attr:`bill_record` as the ``bill`` of ``optimise --json`` (None without one)."""
        bill = self.bill_record
        return None if bill is None else bill.to_json()

    @property
    def seed(self) -> int:
        return int(self.result.seed)

    @property
    def n_rocks(self) -> int:
        return int(self.result.rocks)

    @property
    def ok(self) -> bool:
        """True when a design meets every target."""
        return self.result.best is not None

    @cached_property
    def best(self) -> dict[str, Any] | None:
        """The chosen design (name, measures, cost, checks, residual, ...), None if none."""
        return None if self.result.best is None else self.result.best.as_dict()

    @cached_property
    def alternatives(self) -> pd.DataFrame:
        """One row per family: cost (currency units), residual, a column per check, reason."""

        return alternatives_frame(self.summary)

    @cached_property
    def design(self) -> CheckResult | None:
        """The chosen design checked again on the search rocks, with paths for the figures.

        None when no design meets the targets. The design's residual target
        is the protected zone's allowance, as in the optimiser.
        """
        best = self.best
        if best is None:
            return None

        project = self.design_project()
        # The same ground as the optimised project's: its section is not built again.
        plan_for(project, self._registry, bare=plan_for(self.project, self._registry).bare)
        ev = evaluate(project, self._registry, rocks=self.n_rocks, seed=self.seed,
                      n_trajectories=DEFAULT_TRAJECTORIES)
        return CheckResult(project, ev, self._registry)

    def design_project(self) -> Project:
        """The project with the chosen measures in ``measures:``, as ``check`` would read it."""
        best = self.best
        if best is None:
            raise ValueError(f"no design to check: {self.summary.get('reason', '')}")
        p = self.project
        d = p.design
        allowed = d.residual_fraction
        if allowed is None:
            allowed = (d.residual_count or 0) / max(self.n_rocks, 1)
        protect = p.protect.model_copy(update={"allowed_fraction": allowed})
        return p.model_copy(update={"measures": [dict(m) for m in best["measures"]],
                                    "protect": protect})

    # ---- figures ---------------------------------------------------------
    def plot_alternatives(self) -> Figure:
        """A bar per family: cost, residual and the check that binds or fails."""
        from .report.design_figures import alternatives_figure

        s = self.summary
        return alternatives_figure(s["alternatives"], s["best_name"], s.get("currency", ""),
                                   self.project.name)

    def figures(self) -> dict[str, Figure]:
        """The alternatives figure, and the chosen design's profile, envelopes and stops."""
        out = {"alternatives": self.plot_alternatives()}
        if self.design is not None:
            out.update(self.design.figures())
        return out

    def plot(self, which: str = "alternatives") -> Figure:
        """One figure by name: ``alternatives``, or the chosen design's ``profile``,
        ``envelopes`` or ``stops``."""
        if which == "alternatives":
            return self.plot_alternatives()
        if self.design is None:
            raise ValueError(f"no design to draw: {self.summary.get('reason', '')}")
        return self.design.plot(which)

    def save_figures(self, directory: str | os.PathLike[str],
                     formats: tuple[str, ...] = ("png",)) -> list[Path]:
        """Write every figure into ``directory`` as NAME.FORMAT (png, svg, pdf)."""

        return save_figures(self.figures(), directory, formats)

    def save_report(self, directory: str | os.PathLike[str]) -> list[Path]:
        """Write ``report.html`` (self-contained), ``report.md`` (with SVG figures) and
        ``report.pdf`` (with the pdf extra; else a warning says how to get it)."""

        return write_report(self, directory)

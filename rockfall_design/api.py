"""The public Python API: load a project, simulate, check, optimise; tables and figures.

>>> import rockfall_design as rd
>>> p = rd.load_project("projects/design_two_zones.yaml")   # doctest: +SKIP
>>> r = rd.optimise(p, rocks=2000, seed=1)                  # doctest: +SKIP
>>> r.best["name"], r.alternatives, r.plot()                # doctest: +SKIP

The functions do what the commands of the same name do, and the CLI is a
layer over them: ``.summary`` of a result is the dict that ``--json``
prints. Tables are pandas DataFrames; figures are
:class:`matplotlib.figure.Figure` objects built without pyplot, so nothing
here chooses or switches matplotlib's backend (a notebook's inline figures
stay as they were).
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .arguments import MAX_BOOTSTRAP, MAX_ROCKS, whole_number
from .errors import InputError

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd
    from matplotlib.figure import Figure

    from .judge.evaluation import Evaluation
    from .optimiser.alternatives import OptimisationResult
    from .plugins import Registry
    from .project import Project
    from .run.simulation import Study
    from .run.streamed import StreamedStudy

__all__ = [
    "load_project",
    "simulate",
    "check",
    "optimise",
    "study",
    "calibrate",
    "compare",
    "SimulationResult",
    "CheckResult",
    "OptimiseResult",
    "DEFAULT_TRAJECTORIES",
]

#: Rock paths kept for the profile figure (the first rocks of the run).
DEFAULT_TRAJECTORIES = 60


_REGISTRIES: dict[tuple[str, ...], Registry] = {}


def default_registry(block: tuple[str, ...] = ()) -> Registry:
    """The installed plugins, loaded once per process (per set of blocked names).

    A plugin that fails to load is named in a :class:`UserWarning`; the
    others are used.
    """
    from .plugins import load_registry

    key = tuple(sorted(block))
    if key not in _REGISTRIES:
        registry = load_registry(blocked=key)
        for f in registry.failures:
            warnings.warn(f"plugin {f.plugin!r} was not loaded: {f.reason}", stacklevel=3)
        _REGISTRIES[key] = registry
    return _REGISTRIES[key]


def load_project(path: str | os.PathLike[str], *, registry: Registry | None = None) -> Project:
    """Read a project file and validate all of it, the plugins' sections included.

    Parameters
    ----------
    path : str or path-like
        The YAML project file.
    registry : Registry, optional
        The plugins to validate ``measures:``, ``safety:`` and ``design:``
        with (default: the installed ones).

    Returns
    -------
    Project
        The validated, normalised project (pydantic model; ``p.rocks.count``,
        ``p.analysis.stations``, ``p.resolved_dict()``, ...).

    Raises
    ------
    ProjectError
        The file is not a valid project: one line ``file:line: key.path: message``.
    """
    from .project import load_project as _load


    project = _load(path)
    validate_project(project, registry or default_registry())
    return project


def _project(project: Any, registry: Registry | None = None) -> Project:
    """A Project from a Project or a path (validated with ``registry``)."""
    if isinstance(project, str | os.PathLike):
        return load_project(project, registry=registry)
    from .project import Corridor

    if isinstance(project, Corridor):
        raise InputError("a corridor runs section by section: pass one section's project "
                         "(corridor.sections[i].project), or use the command line, which "
                         "runs every section")
    return project


def _progress_callback(progress: bool | Callable[..., None], total: int,
                       stages: bool = False) -> tuple[Any, Any]:
    """(context manager or None, callback or None) for ``progress``.

    True shows a rich progress bar on stderr; a callable is called as the
    engine reports (``done`` rocks, or ``stage, done, total`` for the
    optimiser); False shows nothing.
    """
    if callable(progress):
        return None, progress
    if not progress:
        return None, None
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn

    bar = Progress("[progress.description]{task.description}", BarColumn(),
                   MofNCompleteColumn(), TimeElapsedColumn(),
                   console=Console(stderr=True), transient=True)
    if not stages:
        task = bar.add_task("rocks", total=total)
        return bar, (lambda done: bar.update(task, completed=done))
    tasks: dict[str, Any] = {}

    def staged(stage: str, done: int, of: int) -> None:
        if stage not in tasks:
            tasks[stage] = bar.add_task(stage, total=of)
        bar.update(tasks[stage], completed=done, total=of)

    return bar, staged


def _call(progress: bool | Callable[..., None], total: int, fn: Callable[..., Any],
          stages: bool = False, **kw: Any) -> Any:
    bar, callback = _progress_callback(progress, total, stages)
    if callback is not None:
        kw["progress"] = callback
    if bar is None:
        return fn(**kw)
    with bar:
        return fn(**kw)


# ---- results --------------------------------------------------------------------


def _stations_frame(summary: dict[str, Any]) -> pd.DataFrame:
    """One row per analysis station: crossings and the statistics of each quantity."""
    rows = []
    for s in summary.get("stations", []):
        row: dict[str, Any] = {"x_m": s["x"], "crossings": s["crossings"]}
        for key, block in s.items():
            if not isinstance(block, dict):
                continue
            base, _, unit = key.rpartition("_")
            for stat, value in block.items():
                row[f"{base}_{stat}_{unit}"] = value
        rows.append(row)
    import pandas as pd  # on first use: simulate without tables need not load it

    return pd.DataFrame(rows)


class SimulationResult:
    """What ``simulate`` found: summary, tables and figures of a run.

    Attributes
    ----------
    project : Project
    study : Study or StreamedStudy
        The run itself (engine-level; prefer the tables below).
    """

    #: The command whose ``--json`` :attr:`summary` matches.
    command = "simulate"

    def __init__(self, project: Project, study: Study | StreamedStudy,
                 rocks_tables: list[pd.DataFrame] | None = None) -> None:
        self.project = project
        self.study = study
        self._rocks_tables = rocks_tables
        self._evaluation: Evaluation | None = None

    def __repr__(self) -> str:
        return (f"<{type(self).__name__} {self.project.name!r}: {self.study.n:,} rocks, "
                f"seed {self.study.seed}>")

    @property
    def seed(self) -> int:
        """The seed of the run."""
        return int(self.study.seed)

    @property
    def n_rocks(self) -> int:
        """The number of rocks of the run."""
        return int(self.study.n)

    @cached_property
    def summary(self) -> dict[str, Any]:
        """The JSON-ready summary: the same dict as ``rockfall-design simulate --json``."""
        return self.study.summary()

    @property
    def streamed(self) -> bool:
        """True for a run of more than ``EXACT_ROCKS`` rocks (statistics from histograms)."""
        from .run.streamed import StreamedStudy

        return isinstance(self.study, StreamedStudy)

    @cached_property
    def rocks(self) -> pd.DataFrame:
        """One row per rock: size, release, how and where its path ended (m, kg, s)."""
        if self.streamed:
            if self._rocks_tables is None:
                raise ValueError("the per-rock table of this streamed run was not kept")
            import pandas as pd

            return pd.concat(self._rocks_tables, ignore_index=True)
        return self.study.rocks_table()

    @property
    def crossings(self) -> pd.DataFrame:
        """One row per rock and analysis station (first passage downslope; m, m/s, kJ)."""
        if self.streamed:
            raise ValueError(
                f"a run of more than {self._exact_rocks():,} rocks is streamed and does not keep "
                "its crossings; use fewer rocks, or rockfall-design simulate --out DIR, which "
                "writes crossings.csv as the run goes")
        return self.study.crossings_table()

    @staticmethod
    def _exact_rocks() -> int:
        from .run.simulation import EXACT_ROCKS

        return EXACT_ROCKS

    @cached_property
    def stations(self) -> pd.DataFrame:
        """One row per analysis station: rocks passing and the statistics of height (m),
        speed (m/s) and energies (kJ), columns such as ``passing_height_p95_m``."""
        return _stations_frame(self.summary)

    @property
    def envelopes(self) -> pd.DataFrame:
        """Envelopes along x of passing height (m) and energy (kJ), and rocks passing."""
        return self.study.envelopes()

    # ---- figures ---------------------------------------------------------
    def plot_profile(self) -> Figure:
        """The slope section with a sample of paths, stations and measures."""
        from .report.figures import profile_figure

        return profile_figure(self.study, self._evaluation)

    def plot_envelopes(self, min_rocks: int | None = None) -> Figure:
        """Envelopes of height and energy where at least ``min_rocks`` rocks pass.

        ``min_rocks`` defaults to the project's ``analysis.min_rocks_envelope``.
        """
        from .report.figures import envelopes_figure

        return envelopes_figure(self.study, self._evaluation, min_rocks)

    def plot_stops(self) -> Figure:
        """Where the rocks come to rest (says why when none does)."""
        from .report.figures import stops_figure

        return stops_figure(self.study, self._evaluation)

    def figures(self) -> dict[str, Figure]:
        """Every figure of the result, by name (the file names of ``--plot``)."""
        return {"profile": self.plot_profile(), "envelopes": self.plot_envelopes(),
                "stops": self.plot_stops()}

    def plot(self, which: str = "profile") -> Figure:
        """One figure by name: ``profile``, ``envelopes`` or ``stops``.

        Returns a :class:`matplotlib.figure.Figure` (shown by a notebook
        when it is a cell's value; ``fig.savefig(path)`` writes it).
        """
        methods = {"profile": self.plot_profile, "envelopes": self.plot_envelopes,
                   "stops": self.plot_stops}
        if which not in methods:
            raise ValueError(f"unknown figure {which!r}; choose one of {', '.join(methods)}")
        return methods[which]()

    def save_figures(self, directory: str | os.PathLike[str],
                     formats: tuple[str, ...] = ("png",)) -> list[Path]:
        """Write every figure into ``directory`` as NAME.FORMAT (png, svg, pdf)."""
        from .report.figures import save_figures

        return save_figures(self.figures(), directory, formats)

    def save_report(self, directory: str | os.PathLike[str]) -> list[Path]:
        """Write ``report.html`` (self-contained) and ``report.md`` (with SVG figures)."""
        from .report.documents import write_report

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
        super().__init__(project, evaluation.study)
        self.evaluation = evaluation
        self._evaluation = evaluation
        #: The plugins the check ran with (for the report's provenance); None if not known.
        self.registry = registry

    @cached_property
    def summary(self) -> dict[str, Any]:
        """The JSON-ready summary: the same dict as ``rockfall-design check --json``.

        It begins with ``verdict`` (:func:`rockfall_design.judge.verdict.verdict_of`);
        a check of nothing (``untested``) is not ``ok``.
        """
        from .judge.verdict import with_verdict

        return with_verdict(self.evaluation.summary())

    @property
    def verdict(self) -> Any:
        """The verdict (:class:`~rockfall_design.judge.verdict.DesignVerdict`): one of
        "holds with confidence", "holds on point values only", "fails", "untested"."""
        from .judge.verdict import verdict_of

        return verdict_of(self.summary)

    @property
    def ok(self) -> bool:
        """True when every check holds and the residual is within what is allowed.

        False when nothing was tested (no measure met and no protected zone).
        """
        return bool(self.summary["ok"])

    @property
    def failures(self) -> list[str]:
        """One line per failed check."""
        return list(self.summary.get("failures", []))

    @cached_property
    def rocks(self) -> pd.DataFrame:
        """One row per rock, with ``caught_by_measure`` (index in ``measures:``, -1 none)."""
        rocks = self.study.rocks_table()
        rocks["caught_by_measure"] = self.evaluation.caught_by_measure()
        return rocks

    @cached_property
    def measures(self) -> pd.DataFrame:
        """One row per measure: rocks met, caught, over, through; a column per check."""
        from .report.tables import measures_frame

        return measures_frame(self.summary)

    @cached_property
    def checks(self) -> pd.DataFrame:
        """One row per safety check: value, confidence bound (if any), target, verdict."""
        from .report.tables import checks_frame

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
    result : OptimisationResult
        The optimiser's own result object.
    """

    command = "optimise"

    def __init__(self, project: Project, result: OptimisationResult,
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
    def verdict(self) -> Any:
        """The verdict on the chosen design (:class:`~rockfall_design.judge.verdict.DesignVerdict`).

        The chosen design's check on the rocks that decided it, as ``check``
        gives it; a design that then fails on the fresh rocks holds on point
        values only; without a chosen design, ``fails`` with the reason.
        """
        from dataclasses import replace

        from .judge.verdict import FAILS, HOLDS_ON_POINT_VALUES, DesignVerdict, verdict_of

        best = self.result.best
        if best is None:
            reason = self.result.reason or "no family meets the targets"
            return DesignVerdict(FAILS, f"Fails: no admissible design: {reason}",
                                 confidence=float(self.result.confidence))
        design = self.design
        assert design is not None
        verdict = verdict_of(design.summary)
        if best.holds_on_fresh_rocks is False and verdict.holds:
            verdict = replace(
                verdict, state=HOLDS_ON_POINT_VALUES,
                headline="Holds on point values only: admitted on its deciding rocks, but it "
                f"does not hold on {best.fresh_rocks:,} fresh rocks (seed {best.fresh_seed}).",
                details=(*best.fresh_failures, *verdict.details))
        return verdict

    @cached_property
    def bill(self) -> dict[str, Any] | None:
        """The bill of the chosen design (None without one).

        ``items`` (``measure``, ``quantity``, ``unit``, ``count``,
        ``unit_price``, ``amount``, ``per_m``, ``source``), ``total`` (the
        chosen design's cost), ``currency``, ``length_m`` (the site length,
        m): see :func:`rockfall_design.optimiser.design_spec.design_bill`.
        """
        best = self.result.best
        if best is None:
            return None
        from .optimiser.design_spec import design_bill, resolve_design
        from .run.releases import section_from_project

        d = self.project.design
        source = (f"catalogue {d.costs.file}" if d.costs.file else "design.costs.params")
        bill = design_bill(self._registry, resolve_design(self.project, self._registry),
                           best.measures, section_from_project(self.project), source)
        return {**bill, "currency": self.result.currency or ""}

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
        from .report.tables import alternatives_frame

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
        from .judge.evaluation import evaluate

        project = self.design_project()
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
        from .report.figures import alternatives_figure

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
        from .report.figures import save_figures

        return save_figures(self.figures(), directory, formats)

    def save_report(self, directory: str | os.PathLike[str]) -> list[Path]:
        """Write ``report.html`` (self-contained) and ``report.md`` (with SVG figures)."""
        from .report.documents import write_report

        return write_report(self, directory)


# ---- the functions --------------------------------------------------------------


def simulate(
    project: Project | str | os.PathLike[str],
    *,
    rocks: int | None = None,
    seed: int | None = None,
    progress: bool | Callable[[int], None] = False,
    trajectories: int = DEFAULT_TRAJECTORIES,
) -> SimulationResult:
    """Simulate the rocks of a project on the bare slope (``rockfall-design simulate``).

    Parameters
    ----------
    project : Project or path
        From :func:`load_project`, or the path of a project file.
    rocks : int, optional
        Number of rocks (default: ``rocks.count`` of the project).
    seed : int, optional
        Random seed (default: ``rocks.seed`` of the project). The same seed
        and count give the same rocks.
    progress : bool or callable
        True: a progress bar on stderr; a callable is called with the number
        of rocks done.
    trajectories : int
        Paths of the first rocks kept for :meth:`SimulationResult.plot_profile`.

    Returns
    -------
    SimulationResult
        ``.summary`` (as ``--json``), ``.rocks`` (one row per rock),
        ``.stations``, ``.crossings``, ``.envelopes``, ``.plot()``.
    """
    from .run.simulation import EXACT_ROCKS

    _checked(seed=seed, trajectories=trajectories)
    p = _project(project)
    n = _count(p, rocks)
    tables: list[pd.DataFrame] | None = None
    on_chunk = None
    if n > EXACT_ROCKS:
        # A streamed run keeps statistics only; the per-rock rows are small
        # enough to keep for a DataFrame (not the crossings: rows x stations).
        tables = []

        def on_chunk(part: Any) -> None:
            tables.append(part.rocks_table())

    study = run_simulation(p, rocks=n, seed=seed, progress=progress,
                           trajectories=trajectories, on_chunk=on_chunk)
    return SimulationResult(p, study, tables)


def run_simulation(project: Project, *, rocks: int | None, seed: int | None,
                   progress: bool | Callable[[int], None], trajectories: int,
                   on_chunk: Callable[[Study], None] | None = None) -> Study | StreamedStudy:
    """The run behind :func:`simulate` (and the CLI, which streams its tables to files)."""
    from .run.simulation import simulate as _simulate

    n = _count(project, rocks)
    return _call(progress, n, _simulate, project=project, rocks=n, seed=seed,
                 n_trajectories=trajectories, on_chunk=on_chunk)


def _count(project: Project, rocks: int | None) -> int:
    """``rocks``, checked as ``--rocks`` is, or the project's ``rocks.count``."""
    if rocks is None:
        return int(project.rocks.count)
    return whole_number(rocks, "rocks", 1, MAX_ROCKS)


def _checked(*, seed: Any = None, workers: Any = None, bootstrap: Any = None,
             trajectories: Any = None) -> None:
    """Check the numbers a run takes as the command line checks its options.

    Raises
    ------
    ArgumentError
        An :class:`InputError` naming the keyword, in the command line's words.
    """
    if seed is not None:
        whole_number(seed, "seed", 0, what="seed")
    if workers is not None:
        whole_number(workers, "workers", 1, what="number of workers")
    if bootstrap is not None:
        whole_number(bootstrap, "bootstrap", 0, MAX_BOOTSTRAP, "number of replicates")
    if trajectories is not None:
        whole_number(trajectories, "trajectories", 0, what="number")


def check(
    project: Project | str | os.PathLike[str],
    *,
    rocks: int | None = None,
    seed: int | None = None,
    progress: bool | Callable[[int], None] = False,
    trajectories: int = DEFAULT_TRAJECTORIES,
    registry: Registry | None = None,
) -> CheckResult:
    """Check the project's measures against its safety concept (``rockfall-design check``).

    Parameters
    ----------
    project : Project or path
    rocks, seed, progress, trajectories
        As :func:`simulate`.
    registry : Registry, optional
        The plugins (default: the installed ones).

    Returns
    -------
    CheckResult
        ``.ok``, ``.summary`` (as ``--json``), ``.measures`` and ``.checks``
        (DataFrames), ``.rocks`` (with ``caught_by_measure``), ``.crossings``,
        ``.plot()``.
    """
    from .judge.evaluation import evaluate

    _checked(seed=seed, trajectories=trajectories)
    p = _project(project, registry)
    n = _count(p, rocks)
    reg = registry or default_registry()
    ev = _call(progress, n, evaluate, project=p, registry=reg,
               rocks=n, seed=seed, n_trajectories=trajectories)
    return CheckResult(p, ev, reg)


def optimise(
    project: Project | str | os.PathLike[str],
    *,
    rocks: int | None = None,
    seed: int | None = None,
    progress: bool | Callable[[str, int, int], None] = False,
    registry: Registry | None = None,
) -> OptimiseResult:
    """Find the least-cost design of every family (``rockfall-design optimise``).

    Parameters
    ----------
    project : Project or path
        With a ``design:`` section.
    rocks, seed : int, optional
        Search rocks and seed (default: the project's).
    progress : bool or callable
        True: progress bars on stderr; a callable is called as
        ``progress(stage, done, total)``.
    registry : Registry, optional
        The plugins (default: the installed ones).

    Returns
    -------
    OptimiseResult
        ``.best`` (dict, None without an admissible design),
        ``.alternatives`` (DataFrame), ``.summary`` (as ``--json``),
        ``.design`` (the chosen design as a :class:`CheckResult`),
        ``.plot()`` (the alternatives compared).

    Raises
    ------
    ProjectError
        The project has no ``design:`` section.
    """
    from .optimiser.section import optimise as _optimise

    _checked(seed=seed)
    p = _project(project, registry)
    if p.design is not None and p.design.scenarios is not None:
        # design.scenarios: the cheapest design that holds across the study's scenarios
        from .optimiser.across import optimise_across as _optimise  # type: ignore[assignment]
    if p.design is None:
        raise p.error_at((), "the project has no design: section to optimise "
                             "(see the README, 'Designing protection')")
    reg = registry or default_registry()
    n = _count(p, rocks)
    if "max_rocks" in p.design.model_fields_set and p.design.max_rocks < n:
        # The last look of a decision with fewer rocks than the search: no look at all.
        raise p.error_at(("design", "max_rocks"), f"expected at least the {n:,} rocks of the "
                         f"search, got {p.design.max_rocks:,}: a decision looks at more rocks "
                         "than the search, never fewer")
    result = _call(progress, n, _optimise, stages=True, project=p, registry=reg, rocks=n,
                   seed=seed)
    return OptimiseResult(p, result, reg)


def study(
    project: Project | str | os.PathLike[str],
    *,
    rocks: int | None = None,
    seed: int | None = None,
    workers: int | None = None,
    scheduler: Any = None,
    progress: bool | Callable[[int, int, int], None] = False,
    registry: Registry | None = None,
    pool: str = "threads",
    envelopes: bool = True,
) -> Any:
    """Run the parametric study of a project's ``study:`` section (``rockfall-design study``).

    Every scenario is a full Monte Carlo run of ``simulate`` with the
    scenario's values and its own seed; the scenarios run as independent
    tasks (see :mod:`rockfall_design.studies.executors`), with the same results
    wherever they run.

    Parameters
    ----------
    project : Project or path
        A project with a ``study:`` section, or the path of its file.
    rocks : int, optional
        Rocks per scenario (default: ``rocks.count``).
    seed : int, optional
        The study's seed (default: ``rocks.seed``); scenario ``i`` runs with
        the seed :func:`~rockfall_design.studies.scenario_seed` derives from it.
    workers : int, optional
        Scenarios run at once locally (default: every usable core); 1 runs
        them in this process, one after the other, each on every core.
    scheduler : str or dask.distributed.Client, optional
        Run on a Dask cluster instead (``"tcp://127.0.0.1:8786"``); needs the
        ``study`` extra.
    progress : bool or callable
        True: a progress bar on stderr (scenarios done, rocks per second); a
        callable is called as ``progress(done, total, rocks_done)``.
    registry : Registry, optional
        The plugins (default: the installed ones).
    pool : {"threads", "processes"}
        The local pool of ``workers`` > 1: threads of this process, each
        scenario with one engine thread (the default: nothing to start), or
        a process pool. The results are the same.
    envelopes : bool
        Compute every scenario's envelopes along x, for
        ``.plot_envelopes()`` (default). False skips them, which saves about
        a tenth of each scenario's time; every number of ``.summary`` is the
        same either way.

    Returns
    -------
    StudyResult
        ``.summary`` (as ``--json``), ``.scenarios`` and ``.sensitivity``
        (DataFrames), ``.plot_envelopes()``, ``.plot_tornado()``, ``.print()``.
    """
    from .studies.runner import run_parametric

    _checked(seed=seed, workers=workers)
    registry = registry or default_registry()
    p = _project(project, registry)
    n = _count(p, rocks)
    bar, callback = _study_progress(progress)
    kw = dict(rocks=n, seed=seed, workers=workers, scheduler=scheduler, progress=callback,
              pool=pool, envelopes=envelopes)
    if bar is None:
        return run_parametric(p, registry, **kw)
    with bar:
        return run_parametric(p, registry, **kw)


def calibrate(
    project: Project | str | os.PathLike[str],
    *,
    observed: str | os.PathLike[str] | None = None,
    rocks: int | None = None,
    bootstrap: int | None = None,
    seed: int | None = None,
    workers: int | None = None,
    scheduler: Any = None,
    progress: bool | Callable[[int, int], None] = False,
    registry: Registry | None = None,
    pool: str = "threads",
) -> Any:
    """Back-analyse the inputs of a project's ``calibrate:`` section (``calibrate`` command).

    The fitted inputs are set by their paths (as in ``study.vary``); each
    evaluation runs the engine with the same rocks (common random numbers)
    and measures the distance of their stop positions from the observed
    ones; the intervals come from a bootstrap of the observations, each
    replicate refitted with its own seed (see :mod:`rockfall_design.calibration`).

    Parameters
    ----------
    project : Project or path
        A project with a ``calibrate:`` section, or the path of its file.
    observed : path, optional
        Another file of observed stops than ``calibrate.observed``.
    rocks : int, optional
        Simulated rocks per evaluation (default ``calibrate.rocks``).
    bootstrap : int, optional
        Bootstrap replicates (default ``calibrate.bootstrap``; 0: the fit only).
    seed : int, optional
        The calibration's seed (default ``rocks.seed``).
    workers, scheduler, pool
        Where the replicates run, as for :func:`study`; the numbers are the
        same wherever they run.
    progress : bool or callable
        True: a progress bar on stderr; a callable is called as
        ``progress(done, total)`` with replicates done.
    registry : Registry, optional
        The plugins (default: the installed ones).

    Returns
    -------
    CalibrationResult
        ``.summary`` (as ``--json``), ``.parameters``, ``.values``,
        ``.calibrated_project()``, ``.figures()``, ``.print()``.
    """
    from .calibration.procedure import run_calibration

    _checked(seed=seed, workers=workers, bootstrap=bootstrap)
    if rocks is not None:
        whole_number(rocks, "rocks", 1, MAX_ROCKS)
    p = _project(project, registry or default_registry())
    kw = dict(observed=observed, rocks=rocks, bootstrap=bootstrap, seed=seed, workers=workers,
              scheduler=scheduler, pool=pool)
    bar, callback = _replicate_progress(progress)
    if bar is None:
        return run_calibration(p, on_done=callback, **kw)
    with bar:
        return run_calibration(p, on_done=callback, **kw)


def compare(
    project: Project | str | os.PathLike[str],
    observed: str | os.PathLike[str],
    *,
    rocks: int | None = None,
    seed: int | None = None,
    registry: Registry | None = None,
) -> Any:
    """How well a project predicts observed stops, nothing fitted (``rockfall-design compare``).

    Parameters
    ----------
    project : Project or path
        E.g. the ``calibrated.yaml`` of a calibration on another profile.
    observed : path
        CSV of the observed stops (as ``calibrate.observed``).
    rocks, seed : int, optional
        Simulated rocks and their seed (default ``rocks.count``, ``rocks.seed``).
    registry : Registry, optional
        The plugins (default: the installed ones).

    Returns
    -------
    ComparisonResult
        ``.summary`` (``fit``, ``levels``), ``.figures()``, ``.print()``.
    """
    from .calibration.procedure import run_comparison

    _checked(seed=seed)
    if rocks is not None:
        whole_number(rocks, "rocks", 1, MAX_ROCKS)
    p = _project(project, registry or default_registry())
    kind = p.calibrate.distance if p.calibrate is not None else "energy"
    confidence = p.calibrate.confidence if p.calibrate is not None else 0.95
    return run_comparison(p, observed, rocks=rocks, seed=seed, kind=kind,
                          confidence=confidence)


def _replicate_progress(progress: bool | Callable[[int, int], None]) -> tuple[Any, Any]:
    """(rich progress or None, callback(done, total) or None) of a calibration's replicates."""
    if callable(progress):
        return None, progress
    if not progress:
        return None, None
    bar, update = _progress_callback(True, 0, stages=True)
    return bar, (lambda done, total: update("fits (best + bootstrap)", done, total))


def _study_progress(progress: bool | Callable[[int, int, int], None]) -> tuple[Any, Any]:
    """(rich progress or None, callback(done, total, rocks_done) or None) of a study."""
    if callable(progress):
        return None, progress
    if not progress:
        return None, None
    import time

    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn

    bar = Progress("[progress.description]{task.description}", BarColumn(),
                   MofNCompleteColumn(), "{task.fields[rate]}", TimeElapsedColumn(),
                   console=Console(stderr=True), transient=True)
    task: list[Any] = []
    start = time.perf_counter()

    def callback(done: int, total: int, rocks_done: int) -> None:
        if not task:
            task.append(bar.add_task("scenarios", total=total, rate=""))
        elapsed = time.perf_counter() - start
        rate = f"{rocks_done / elapsed:,.0f} rocks/s" if rocks_done and elapsed > 0 else ""
        bar.update(task[0], completed=done, rate=rate)

    return bar, callback


def validate_project(project: Project, registry: Registry) -> None:
    """Check the sections of a project that its plugins own, whatever the command.

    Loading a project validates the core sections; ``measures:``, ``safety:``
    and ``design:`` belong to plugins and are checked here: every measure's
    parameters and its place on the section (fit, overlaps), the safety
    concept's parameters, and the design's candidates, catalogues and cost
    model. Every command calls it, so a bad project file is reported by
    ``simulate`` too, although ``simulate`` runs the bare slope.

    Raises
    ------
    ProjectError
        Exit code 2, located at the offending key.
    PluginError
        Exit code 3, if a plugin misbehaves.
    """
    from .judge.plan import plan_for
    from .studies.paths import check_study

    plan_for(project, registry)
    if project.design is not None:
        # Imported only here: the optimiser (scipy's optimisers with it) is not
        # loaded for a project without a design section.
        from .optimiser.design_spec import resolve_design

        resolve_design(project, registry)
    if project.study is not None:
        # the study's paths and values, against this project (after the sections above it)
        check_study(project, registry)

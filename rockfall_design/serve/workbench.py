"""What the browser app works on: projects, their runs, and measures placed on the table.

Nothing here knows about HTTP: :mod:`rockfall_design.serve.app` turns a
:class:`ServeError` into a response with its status and one-line message.

A run (:meth:`ProjectEntry.start_run`) is the optimiser's screening run
(:class:`~rockfall_design.optimiser.screening.Screening`) of the project's
rocks on the bare slope, with its table stations every
:data:`TABLE_STEP_M` along the whole section: per rock, its passing height,
energy and speed at its first passage of every station. A fence or wall
placed anywhere is then judged from that table by the screening's own
judgement and the project's safety concept (:meth:`Bench.place`), in
milliseconds, without running a rock again.
"""

from __future__ import annotations

import math
import os
import re
import tempfile
import threading
import time
import uuid
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from ..optimiser.screening import Screening
    from ..plugins import Registry
    from ..project import Project

#: Spacing (m) of the table stations along the whole section. A placed
#: barrier is judged at the table station nearest to it; 1 m keeps a table of
#: 10,000 rocks on a 300 m section near 75 MB.
TABLE_STEP_M = 1.0

#: Spacing (m) of the restart stations, where every rock's full state is kept
#: so that a ditch or berm re-runs only the rocks from the station above it
#: (14 numbers per rock and station: 10,000 rocks on 300 m near 35 MB).
RESTART_STEP_M = 10.0

#: Largest request body (bytes): a project file or a section to import.
MAX_BODY_BYTES = 1_000_000

#: Files that may be imported into a project's directory.
UPLOAD_SUFFIXES = (".csv", ".dxf", ".yaml", ".yml")

#: Most rocks one run of the app may have (the table holds rocks x stations).
MAX_RUN_ROCKS = 50_000

#: Rocks whose paths are drawn on the section (the first rocks of the run).
PATHS_DRAWN = 40

#: Bins of the where-rocks-stop histogram along the section.
STOP_BINS = 120

# A string in a project that names a file: no blanks, and a path separator
# or a file extension the project format reads.
_FILE_LIKE = re.compile(r"^[^\s]*(/|\\|\.(ya?ml|csv|dxf|json|txt))[^\s]*$", re.IGNORECASE)


class ServeError(Exception):
    """A request the app refuses: an HTTP status and one line saying why."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = int(status)
        self.message = message


class Cancelled(Exception):
    """Raised from a run's progress callback when its job was cancelled."""


# ---- paths --------------------------------------------------------------------------


def inside(base: Path, name: str) -> Path:
    """``name`` resolved against ``base``, refused unless it stays inside ``base``.

    Symbolic links are followed before the check, so a link that points out
    of the directory is refused as well.

    Raises
    ------
    ServeError
        403 if the path leaves ``base``; 400 if it is empty or malformed.
    """
    if not isinstance(name, str) or not name.strip() or "\x00" in name:
        raise ServeError(400, "path: expected a file name inside the project's directory")
    root = base.resolve()
    target = (root / name).resolve()
    if not target.is_relative_to(root):
        raise ServeError(403, f"path {name!r} lies outside the project's directory ({root})")
    return target


def referenced_outside(text: str, base: Path, root: Path) -> str | None:
    """The first string of a project's YAML that names a file outside ``root``, or None.

    A project names its survey section, materials library and catalogues as
    paths relative to its own directory ``base``; an edited project must not
    make the app read anything outside the project's directory ``root``.
    The YAML is composed, not constructed, and every node visited once, so
    that aliases cannot multiply the work (the loader's own limits come
    after this check).
    """
    import yaml

    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.YAMLError:
        return None  # the project loader says where and why
    seen: set[int] = set()
    todo = [node] if node is not None else []
    root = root.resolve()
    while todo:
        n = todo.pop()
        if id(n) in seen:
            continue
        seen.add(id(n))
        if isinstance(n, yaml.ScalarNode):
            value = n.value
            if isinstance(value, str) and _FILE_LIKE.match(value):
                target = (base / value).resolve()
                if not target.is_relative_to(root):
                    return value
        elif isinstance(n, yaml.SequenceNode):
            todo.extend(n.value)
        elif isinstance(n, yaml.MappingNode):
            for k, v in n.value:
                todo.extend((k, v))
    return None


# ---- jobs ---------------------------------------------------------------------------


@dataclass
class Job:
    """Work in a background thread: progress, cancel, and its result or error.

    ``kind`` is ``simulate``, ``check``, ``optimise``, ``study`` or
    ``calibrate``; ``stage`` the optimiser's stage (``search``, ``check``);
    ``result`` the JSON-ready answer of a finished check, optimise, study or
    calibration (their ``--json`` summaries), ``tables`` what the page shows
    of a study or calibration (``title``, ``columns``, ``rows``) and
    ``files`` what it offers for download (``design.yaml``, ``report.html``
    as ``--report`` writes it, and the figures as PNG and SVG, drawn on the
    first request).
    """

    kind: str
    total: int
    id: str = field(default_factory=lambda: uuid.uuid4().hex[:12])
    done: int = 0
    stage: str = ""
    state: str = "running"  # running, done, cancelled, failed
    error: str = ""
    result: dict[str, Any] | None = None
    files: dict[str, Any] = field(default_factory=dict)  # text, bytes, or a loader of bytes
    tables: list[dict[str, Any]] = field(default_factory=list)
    started: float = field(default_factory=time.monotonic)
    runtime_s: float = 0.0
    cancel_event: threading.Event = field(default_factory=threading.Event)

    def progress(self, done: int) -> None:
        """Record ``done`` rocks; stop the run if the job was cancelled."""
        self.done = int(done)
        if self.cancel_event.is_set():
            raise Cancelled

    def staged(self, stage: str, done: int, total: int) -> None:
        """The optimiser's progress (``stage``, ``done`` of ``total``); stop if cancelled."""
        self.stage, self.total = stage, int(total)
        self.progress(done)

    def as_dict(self) -> dict[str, Any]:
        return {"id": self.id, "kind": self.kind, "state": self.state, "done": self.done,
                "total": self.total, "stage": self.stage, "error": self.error,
                "runtime_s": round(self.runtime_s or time.monotonic() - self.started, 3),
                "result": self.result, "files": sorted(self.files),
                "tables": self.tables}


# ---- a run's table and what is placed on it -------------------------------------


def _finite_percentiles(a: np.ndarray, qs: Sequence[float]) -> dict[str, list[float | None]]:
    """Per column of ``a`` (rocks x stations): the percentiles and maximum of its finite values."""
    a = np.where(np.isfinite(a), a, np.nan)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # columns no rock passed
        p = np.nanpercentile(a, list(qs), axis=0) if a.shape[0] else np.full((len(qs), 0), np.nan)
        mx = np.nanmax(a, axis=0) if a.shape[0] else np.zeros(0)
    out = {f"p{q:g}": _json_list(p[i]) for i, q in enumerate(qs)}
    out["max"] = _json_list(mx)
    return out


def _p95_bounds(a: np.ndarray, confidence: float) -> list[list[float | None]]:
    """Per column of ``a``: [lower, upper] confidence bound of the 95th percentile of its
    finite values (None where too few rocks passed to bound it)."""
    from ..judge.bounds import quantile_lower_bound, quantile_upper_bound

    out = []
    for j in range(a.shape[1]):
        v = a[:, j]
        v = v[np.isfinite(v)]
        lo = quantile_lower_bound(v, 0.95, confidence) if v.size else None
        hi = quantile_upper_bound(v, 0.95, confidence) if v.size else None
        out.append([_num(lo), _num(hi)])
    return out


def _json_list(v: np.ndarray) -> list[float | None]:
    return [None if not math.isfinite(float(x)) else round(float(x), 4) for x in v]


def _num(v: float | None) -> float | None:
    return None if v is None or not math.isfinite(float(v)) else float(v)


@dataclass
class Bench:
    """One finished run: the screening table and what the page draws from it."""

    screening: Screening
    rocks: int
    seed: int
    runtime_s: float
    envelopes: dict[str, Any]
    stops: dict[str, Any]
    paths: list[list[list[float]]]

    def place(self, entry: ProjectEntry, raws: Sequence[Any]) -> dict[str, Any]:
        """Judge fences and walls at the given stations from the table.

        Parameters
        ----------
        entry
            The project the run belongs to.
        raws
            Measures as the project file writes them (``{"type": "fence",
            "x": 120, "height": 5, "capacity_kj": 2000}``); barriers only.

        Returns
        -------
        dict
            ``measures`` (label, station used, counts, checks with their
            bounds), ``residual`` (rocks reaching the protected zone with
            the Clopper-Pearson bounds and the target), ``admitted`` and
            ``rejected`` as the optimiser's screening decides them, and
            ``elapsed_ms``.

        Raises
        ------
        ServeError
            400 for a measure the plugins reject or one that does not fit.

        Notes
        -----
        A ditch or berm (a measure that reshapes the ground) is judged by
        running again only the rocks that pass the restart station just
        above it, from their saved state, on the edited ground (the
        screening's own way, cached per shape and place): a fraction of a
        second, so the page sends it when the measure is let go, not on
        every move (``reshapes_ground`` in the answer says so).
        """
        from ..errors import ProjectError
        from ..judge.bounds import fraction_lower_bound, fraction_upper_bound
        from ..judge.placing import edited_section, place_measures
        from ..plugins.measure import Barrier, ProfileEdit

        t0 = time.perf_counter()
        sc = self.screening
        measures = [entry.build_measure(raw, i) for i, raw in enumerate(raws)]
        try:
            placed = place_measures(entry.project, entry.registry, measures, sc.section)
        except ProjectError as exc:
            raise ServeError(400, _placed_message(exc.message)) from None
        edits = [p.footprint for p in placed if isinstance(p.footprint, ProfileEdit)]
        table = sc.bare
        if edits:
            try:
                # The screening's table for edited ground (its private helper: the
                # one place that resumes rocks at a restart station).
                table = sc._table_for(edits, edited_section(entry.project, sc.section, placed))
            except ValueError as exc:
                raise ServeError(400, f"{' + '.join(p.label for p in placed)}: {exc}") from None
        cost = math.nan
        if sc.spec.cost_model is not None:
            try:
                cost = sc.cost([p.measure for p in placed])
            except (KeyError, ValueError):
                cost = math.nan  # the cost model has no price for it: shown as unknown
        res = sc.screen_placed(placed, table, cost)
        n = sc.n
        out_measures = []
        for p, r, checks in zip(placed, res.results, res.checks, strict=True):
            fp = p.footprint
            x = float(fp.x) if isinstance(fp, Barrier) else float(fp.x_start)
            out_measures.append({
                "index": p.index, "label": p.label, "type": raws[p.index]["type"],
                "x": x, "x_table": float(sc.grid[sc.station(x)]),
                "reshapes_ground": not isinstance(fp, Barrier),
                "met": int(r.met), "caught": int(r.caught), "passed_over": int(r.passed_over),
                "broken_through": int(r.broken_through), "rebounded": int(r.rebounded),
                "checks": [_check_dict(c) for c in checks],
                "ok": all(c.ok for c in checks),
            })
        reaching = int(res.residual)
        residual = {
            "reaching": reaching, "rocks": n, "fraction": reaching / n if n else 0.0,
            "upper_bound": fraction_upper_bound(reaching, n, sc.confidence),
            "lower_bound": fraction_lower_bound(reaching, n, sc.confidence),
            "allowed_fraction": sc.allowed_fraction, "allowed": sc.allowed_residual,
            "confidence": sc.confidence, "x": sc.protect_x,
            # Without protect: in the project, the foot of the section stands in.
            "protected_zone": entry.project.protect is not None,
        }
        residual["ok"] = reaching <= sc.allowed_residual
        residual["ok_with_confidence"] = residual["upper_bound"] <= sc.allowed_fraction
        return {
            "measures": out_measures, "residual": residual,
            "admitted": bool(res.feasible), "near": bool(res.near),
            "rejected": not res.feasible and not res.near,
            "approximate": bool(res.approximate), "cost": _num(cost),
            "reshapes_ground": bool(edits),
            "rerun_rocks": int(table.rows.size) if table.rows is not None else 0,
            "elapsed_ms": round((time.perf_counter() - t0) * 1e3, 3),
        }


def _placed_message(message: str) -> str:
    """A placement error without the project file's line: the measure is the page's."""
    return re.sub(r"^.*?:\d+: ", "", message)


def _check_dict(c: Any) -> dict[str, Any]:
    d = c.as_dict()
    for k in ("value", "target", "bound", "optimistic"):
        d[k] = _num(d.get(k))
    d["holds_with_confidence"] = bool(c.holds_with_confidence)
    return d


# ---- one project ------------------------------------------------------------------


@dataclass
class ProjectEntry:
    """A project file the app serves, its plugins and its latest run."""

    id: str
    path: Path
    project: Project
    registry: Registry
    bench: Bench | None = None
    job: Job | None = None
    lock: threading.Lock = field(default_factory=threading.Lock)
    #: Changes made in the page and not saved (the project in memory differs from its file).
    edits: list[str] = field(default_factory=list)

    @property
    def directory(self) -> Path:
        """The project's directory: the only place requests may read or write."""
        return self.path.parent.resolve()

    # -- what the page draws ------------------------------------------------------
    def describe(self) -> dict[str, Any]:
        """The section and everything on it, in metres, for the page."""
        from ..run.releases import section_from_project

        p = self.project
        sec = section_from_project(p)
        # Material of every segment of the ground, by its name in the project
        # where the slope names them segment by segment.
        named = list(getattr(p.slope, "materials", None) or [])
        if len(named) != len(sec.x) - 1:
            named = [f"material {int(i) + 1}" for i in sec.segment_material]
        pts = np.column_stack([sec.x, sec.y])
        releases = []
        for r in p.rocks.release:
            d = r.model_dump() if hasattr(r, "model_dump") else dict(r)
            releases.append({k: d.get(k) for k in ("x", "height", "weight")})
        measures = [{k: _plain(v) for k, v in dict(raw).items()} for raw in p.measures]
        # Their labels, as the reports write them (the project validated when loaded).
        from ..judge.placing import build_measures, place_measures

        placed = place_measures(p, self.registry, build_measures(p, self.registry), sec)
        labels = {q.index: q.label for q in placed}
        for i, m in enumerate(measures):
            m["label"] = labels.get(i, m.get("type", ""))
        return {
            "id": self.id, "name": p.name, "description": getattr(p, "description", "") or "",
            "file": self.path.name,
            "ground": pts.round(4).tolist(),
            "materials": [str(m) for m in named],
            "releases": releases,
            "stations": [float(s) for s in p.analysis.stations],
            "protect": None if p.protect is None else {"x": float(p.protect.x)},
            "measures": measures,
            "rocks": int(p.rocks.count), "seed": int(p.rocks.seed),
            "has_design": p.design is not None,
            "has_study": p.study is not None,
            "has_calibrate": p.calibrate is not None,
            "library": self.library_name(),
            "edits": list(self.edits),
            "run": None if self.bench is None else self.run_dict(),
            "job": None if self.job is None else self.job.as_dict(),
        }

    def run_dict(self) -> dict[str, Any]:
        b = self.bench
        assert b is not None
        return {"rocks": b.rocks, "seed": b.seed, "runtime_s": round(b.runtime_s, 3),
                "envelopes": b.envelopes, "stops": b.stops, "paths": b.paths}

    # -- measures from the page ---------------------------------------------------
    def build_measure(self, raw: Any, i: int) -> Any:
        """A measure from ``{"type": ..., parameters}``, validated by its plugin's model."""
        from ..plugins import guard
        from ..project.locator import params_problem

        if not isinstance(raw, dict) or not isinstance(raw.get("type"), str):
            raise ServeError(400, f"measures[{i}]: expected an object with a 'type'")
        kind = raw["type"]
        cls = self.registry.measures.get(kind)
        if cls is None:
            known = ", ".join(sorted(self.registry.measures))
            raise ServeError(400, f"measures[{i}].type: unknown measure {kind!r} "
                             f"(installed: {known})")
        values = {k: v for k, v in raw.items() if k != "type"}
        problem = params_problem(cls.Params, values)
        if problem is not None:
            loc, message = problem
            where = ".".join(str(p) for p in loc)
            raise ServeError(400, f"measures[{i}]{'.' + where if where else ''}: {message}")
        return guard(self.registry).instantiate(cls, cls.Params(**values))

    # -- runs -----------------------------------------------------------------------
    def _rocks_seed(self, rocks: int | None, seed: int | None) -> tuple[int, int]:
        n = int(self.project.rocks.count if rocks is None else rocks)
        s = int(self.project.rocks.seed if seed is None else seed)
        if not 1 <= n <= MAX_RUN_ROCKS:
            raise ServeError(400, f"rocks: expected 1 to {MAX_RUN_ROCKS:,}, got {n:,}")
        if s < 0:
            raise ServeError(400, f"seed: expected a whole number >= 0, got {s}")
        return n, s

    def _start(self, kind: str, total: int, work: Callable[[Job], None]) -> Job:
        """Run ``work(job)`` in a thread; one job at a time per project.

        Raises
        ------
        ServeError
            409 when a job of this project is under way.
        """
        with self.lock:
            if self.job is not None and self.job.state == "running":
                raise ServeError(409, f"a {self.job.kind} of {self.id} is under way "
                                 f"(job {self.job.id})")
            job = Job(kind, total)
            self.job = job
        threading.Thread(target=self._work, args=(job, work), daemon=True,
                         name=f"rockfall-serve-{job.id}").start()
        return job

    @staticmethod
    def _work(job: Job, work: Callable[[Job], None]) -> None:
        try:
            work(job)
        except Cancelled:
            job.state = "cancelled"
        except Exception as exc:  # noqa: BLE001 -- reported to the page, the app stays up
            job.state, job.error = "failed", " ".join(str(exc).split()) or type(exc).__name__
        else:
            job.state = "done"
        job.runtime_s = time.monotonic() - job.started

    def start_run(self, rocks: int | None, seed: int | None) -> Job:
        """Start the screening run of the project (see :func:`build_bench`).

        Raises
        ------
        ServeError
            409 when a job of this project is under way; 400 for a rock
            count or seed out of range.
        """
        n, s = self._rocks_seed(rocks, seed)

        def work(job: Job) -> None:
            self.bench = build_bench(self.project, self.registry, n, s, job.progress)
            job.done = n

        return self._start("simulate", n, work)

    def start_check(self, raws: Sequence[Any] | None, rocks: int | None,
                    seed: int | None) -> Job:
        """Start ``check`` of the project with these measures (None: the project's own).

        Every rock runs against the measures (ditches and berms too); the
        job's result is the summary ``rockfall-design check --json`` prints.

        Raises
        ------
        ServeError
            400 for measures the plugins reject or rocks or seed out of
            range; 409 while a job of this project runs.
        """
        from ..errors import ProjectError
        from ..judge.evaluation import evaluate
        from ..judge.placing import place_measures
        from ..run.releases import section_from_project

        n, s = self._rocks_seed(rocks, seed)
        project = self.project
        if raws is not None:
            measures = [self.build_measure(raw, i) for i, raw in enumerate(raws)]
            try:
                place_measures(project, self.registry, measures, section_from_project(project))
            except ProjectError as exc:
                raise ServeError(400, _placed_message(exc.message)) from None
            project = project.model_copy(update={"measures": [dict(r) for r in raws]})

        def work(job: Job) -> None:
            from ..results import DEFAULT_TRAJECTORIES, CheckResult
            from .reports import lazy_files

            ev = evaluate(project, self.registry, rocks=n, seed=s, progress=job.progress,
                          n_trajectories=DEFAULT_TRAJECTORIES)
            report = CheckResult(project, ev, self.registry)
            job.result = report.summary
            job.files.update(lazy_files(report))
            job.done = n

        return self._start("check", n, work)

    def start_optimise(self, rocks: int | None, seed: int | None) -> Job:
        """Start ``optimise`` of the project: the same search and result as the command.

        The job's result is the summary ``rockfall-design optimise --json``
        prints; with a design, ``design.yaml`` (as ``--out`` writes it) is
        offered for download.

        Raises
        ------
        ServeError
            400 without a ``design:`` section, or with ``design.scenarios``
            (optimise those with the command line); 409 while a job runs.
        """
        from ..optimiser.section import optimise
        from ..report.terminal import design_yaml

        if self.project.design is None:
            raise ServeError(400, f"{self.path.name}: the project has no design: section to "
                             "optimise")
        if self.project.design.scenarios is not None:
            raise ServeError(400, f"{self.path.name}: design.scenarios: a design across "
                             "scenarios is optimised with rockfall-design optimise")
        n, s = self._rocks_seed(rocks, seed)
        project = self.project

        def work(job: Job) -> None:
            from ..results import OptimiseResult
            from .reports import lazy_files

            res = optimise(project, self.registry, rocks=n, seed=s, progress=job.staged)
            job.result = res.summary()
            if res.best is not None:
                job.files["design.yaml"] = design_yaml(res.best, self.path.name,
                                                       res.search_rocks, res.looks)
            # The report checks the chosen design again (for its figures): on request.
            job.files.update(lazy_files(OptimiseResult(project, res, self.registry)))

        return self._start("optimise", n, work)

    def start_study(self, rocks: int | None, seed: int | None) -> Job:
        """Start the project's parametric study, as ``rockfall-design study`` runs it.

        The job counts scenarios; a cancel stops it once the scenarios
        under way finish. Its result is the summary ``study --json`` prints,
        and ``tables`` the scenarios and the sensitivity, for the page.

        Raises
        ------
        ServeError
            400 without a ``study:`` section or with rocks or seed out of
            range; 409 while a job of this project runs.
        """
        from ..studies.runner import run_parametric

        if self.project.study is None:
            raise ServeError(400, f"{self.path.name}: the project has no study: section")
        n, s = self._rocks_seed(rocks, seed)
        project = self.project

        def work(job: Job) -> None:
            def progress(done: int, total: int, rocks_done: int) -> None:
                job.total = int(total)
                job.progress(done)

            res = run_parametric(project, self.registry, rocks=n, seed=s, progress=progress,
                                 envelopes=False)
            job.result = res.summary
            job.tables = study_tables(res)

        job = self._start("study", 0, work)
        job.stage = "scenarios"
        return job

    def start_calibrate(self, rocks: int | None, seed: int | None,
                        bootstrap: int | None) -> Job:
        """Start the calibration of the project's ``calibrate:`` inputs, as the command does.

        The job counts the fit and its bootstrap replicates; a cancel stops
        it once the replicates under way finish. Its result is the summary
        ``calibrate --json`` prints, and ``tables`` the fitted values with
        their intervals and the fit's distance, for the page.

        Raises
        ------
        ServeError
            400 without a ``calibrate:`` section or with rocks, seed or
            bootstrap out of range; 409 while a job runs.
        """
        from ..arguments import MAX_BOOTSTRAP
        from ..calibration.procedure import run_calibration

        spec = self.project.calibrate
        if spec is None:
            raise ServeError(400, f"{self.path.name}: the project has no calibrate: section")
        n, s = self._rocks_seed(int(spec.rocks) if rocks is None else rocks, seed)
        b = int(spec.bootstrap if bootstrap is None else bootstrap)
        if not 0 <= b <= MAX_BOOTSTRAP:
            raise ServeError(400, f"bootstrap: expected 0 to {MAX_BOOTSTRAP:,}, got {b:,}")
        project = self.project

        def work(job: Job) -> None:
            def on_done(done: int, total: int) -> None:
                job.total = int(total)
                job.progress(done)

            res = run_calibration(project, rocks=n, bootstrap=b, seed=s, on_done=on_done)
            job.result = res.summary
            job.tables = calibration_tables(res.summary)

        job = self._start("calibrate", b + 1, work)
        job.stage = "replicates"
        return job

    # -- materials from a library ---------------------------------------------------
    def library_name(self) -> str | None:
        """The materials library the project file names (``materials: {library: FILE}``)."""
        import yaml

        try:
            data = yaml.safe_load(self.path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, yaml.YAMLError):
            return None
        materials = data.get("materials") if isinstance(data, dict) else None
        name = materials.get("library") if isinstance(materials, dict) else None
        return name if isinstance(name, str) else None

    def library(self, name: str | None = None) -> dict[str, Any]:
        """The entries of a materials library in the project's directory, with their law
        and values.

        Parameters
        ----------
        name
            The library file, relative to the project's directory; default
            the one the project file names.

        Returns
        -------
        dict
            ``path`` and ``materials``: per entry its ``name``, ``law`` (the
            impact law, ``impact_model``), ``values`` (every parameter, the
            defaults filled in) and ``source`` (the entry's ``# source:``
            comment line, empty without one).

        Raises
        ------
        ServeError
            404 without a library or file; 403 outside the directory; 400 for
            a file that is not a library (the first bad entry, one line).
        """
        import yaml
        from pydantic import ValidationError

        from ..project.schema import Material

        name = name or self.library_name()
        if name is None:
            raise ServeError(404, f"{self.path.name} names no materials library "
                             "(materials: {library: FILE}); give its path")
        target = inside(self.directory, name)
        if not target.is_file():
            raise ServeError(404, f"no materials library {name!r} in the project's directory")
        if target.stat().st_size > MAX_BODY_BYTES:
            raise ServeError(413, f"{name}: larger than {MAX_BODY_BYTES:,} bytes")
        try:
            text = target.read_text(encoding="utf-8")
            # The composer first: an alias bomb is refused before it expands.
            if referenced_outside(text, target.parent, self.directory) is not None:
                raise ServeError(403, f"{name}: names a file outside the project's directory")
            data = yaml.safe_load(text)
        except UnicodeDecodeError:
            raise ServeError(400, f"{name}: not a UTF-8 text file") from None
        except yaml.YAMLError as exc:
            mark = getattr(exc, "problem_mark", None)
            line = f":{mark.line + 1}" if mark is not None else ""
            raise ServeError(400, f"{name}{line}: not valid YAML") from None
        if not isinstance(data, dict) or not data:
            raise ServeError(400, f"{name}: expected a mapping of material names to materials")
        sources = _library_comments(text)
        out = []
        for key, value in data.items():
            try:
                m = Material.model_validate(value)
            except ValidationError as exc:
                err = exc.errors()[0]
                where = ".".join(str(p) for p in err["loc"])
                raise ServeError(400, f"{name}: {key}{'.' + where if where else ''}: "
                                 f"{err['msg']}") from None
            out.append({"name": str(key), "law": m.impact_model,
                        "values": _plain(m.model_dump(mode="json", exclude_none=True)),
                        "source": sources.get(str(key), "")})
        return {"path": str(target.relative_to(self.directory)), "materials": out}

    def apply_material(self, segment: int, material: str, library: str | None) -> dict[str, Any]:
        """Give a segment of the section a material of the library, in memory.

        The project the app works on changes (its run is dropped: the table
        was of the old ground); its file does not. The answer carries the
        changed project as YAML (every value resolved, the library's
        material inline) for the editor, where Save writes it on request.

        Raises
        ------
        ServeError
            400 for a segment out of range or a material the library lacks;
            409 while a job of this project runs.
        """
        from ..api import validate_project
        from ..errors import RockfallError
        from ..project import dump_yaml

        p = self.project
        n = len(p.slope.materials)
        if isinstance(segment, bool) or not isinstance(segment, int) or not 0 <= segment < n:
            raise ServeError(400, f"segment: expected 0 to {n - 1}, got {segment!r}")
        lib = self.library(library)
        entry = next((m for m in lib["materials"] if m["name"] == material), None)
        if entry is None:
            names = ", ".join(m["name"] for m in lib["materials"])
            raise ServeError(400, f"material: {material!r} is not in {lib['path']} "
                             f"(it has {names})")
        from ..project.schema import Material

        # A material of the project with that name but other values stays the
        # project's under a name of its own: the library's comes in as NAME
        # from LIBRARY.
        new = Material.model_validate(entry["values"])
        name = material
        if name in p.materials and p.materials[name] != new:
            name = f"{material} ({Path(lib['path']).stem})"
        with self.lock:
            if self.job is not None and self.job.state == "running":
                raise ServeError(409, f"a {self.job.kind} of {self.id} is under way "
                                 f"(job {self.job.id})")
            names = list(p.slope.materials)
            names[segment] = name
            slope = p.slope.model_copy(update={"materials": names})
            used = set(names)
            # Materials no segment uses any more drop out, as a file would not keep them.
            materials = {k: v for k, v in {**p.materials, name: new}.items() if k in used}
            project = p.model_copy(update={"slope": slope, "materials": materials})
            try:
                validate_project(project, self.registry)
            except RockfallError as exc:
                raise ServeError(400, " ".join(str(exc).split())) from None
            self.project, self.bench = project, None
            self.edits.append(f"segment {segment + 1}: {p.slope.materials[segment]} -> "
                              f"{name} from {lib['path']}")
        return {**self.describe(), "yaml": dump_yaml(project.resolved_dict())}

    # -- the project file -----------------------------------------------------------
    def save(self, text: str, name: str | None) -> Path:
        """Validate ``text`` as a project and write it to ``name`` in the project's directory.

        Nothing is written unless the text is a valid project that names no
        file outside the directory; the file is replaced in one step.

        Raises
        ------
        ServeError
            403 for a target or a referenced file outside the directory, 400
            for a project that does not validate (its one-line message).
        """
        target = inside(self.directory, self.path.name if name is None else name)
        if not target.parent.is_dir():
            raise ServeError(400, f"path {name!r}: no such directory in the project's directory")
        if target.is_dir():
            raise ServeError(400, f"path {name!r} is a directory")
        project = self.validate(text, target)
        _write_atomically(target, text)
        if target == self.path.resolve():
            self.project, self.bench, self.edits = project, None, []
        return target

    def upload(self, name: str, text: str, replace: bool = False) -> Path:
        """Write an imported file (a CSV or DXF section, a materials library) beside the project.

        Raises
        ------
        ServeError
            403 outside the project's directory; 400 for another kind of
            file or text that is not a string; 409 when the file exists and
            ``replace`` is not set.
        """
        target = inside(self.directory, name)
        if target.suffix.lower() not in UPLOAD_SUFFIXES:
            raise ServeError(400, f"path {name!r}: expected a file ending in "
                             f"{', '.join(UPLOAD_SUFFIXES)}")
        if not isinstance(text, str):
            raise ServeError(400, "text: expected the file's text as a string")
        if not target.parent.is_dir():
            raise ServeError(400, f"path {name!r}: no such directory in the project's directory")
        if target.exists() and not replace:
            raise ServeError(409, f"{name} exists already (send \"replace\": true to replace it)")
        if target.resolve() == self.path.resolve():
            raise ServeError(400, f"{name} is the project file: save it from the editor")
        _write_atomically(target, text)
        return target

    def validate(self, text: str, target: Path | None = None) -> Project:
        """The project in ``text``, validated as if it were the file ``target``.

        Raises
        ------
        ServeError
            403 when it names a file outside the project's directory; 400
            with the command line's one-line message when it is not valid.
        """
        from ..api import validate_project
        from ..errors import RockfallError
        from ..project.loading import load_project_text

        target = target or self.path.resolve()
        if not isinstance(text, str):
            raise ServeError(400, "text: expected the project file as a string")
        hit = referenced_outside(text, target.parent, self.directory)
        if hit is not None:
            raise ServeError(403, f"{target.name}: {hit!r} lies outside the project's "
                             f"directory ({self.directory})")
        try:
            project = load_project_text(text, str(target.name), base_dir=target.parent)
            validate_project(project, self.registry)
        except RockfallError as exc:
            raise ServeError(400, " ".join(str(exc).split())) from None
        return project


def study_tables(res: Any) -> list[dict[str, Any]]:
    """A study's scenarios (the varied values and the statistics at every station,
    without their bounds) and its sensitivity, as tables for the page."""
    sc = res.scenarios
    cols = [c for c in sc.columns if c != "seed" and not str(c).endswith((" upper", " lower"))]
    sens = res.sensitivity
    scols = [c for c in ("parameter", "target", "effect", "unit", "low", "high", "resolved")
             if c in sens.columns]
    return [_table("Scenarios", sc[cols]), _table("Sensitivity", sens[scols])]


def calibration_tables(summary: dict[str, Any]) -> list[dict[str, Any]]:
    """A calibration's fitted values with their bootstrap intervals, and its fit."""
    rows = [[p["path"], p["value"], p["low"], p["high"], p["range"], p["identified"],
             p.get("at_bound") or ""] for p in summary["parameters"]]
    fit = summary["fit"]
    fit_rows = [[k, fit[k]] for k in ("distance_kind", "distance", "ks_statistic", "ks_pvalue")
                if k in fit]
    return [{"title": "Fitted inputs", "rows": _plain(rows),
             "columns": ["input", "value", "low", "high", "range", "identified", "at bound"]},
            {"title": "Fit", "columns": ["item", "value"], "rows": _plain(fit_rows)}]


def _table(title: str, frame: Any) -> dict[str, Any]:
    rows = [[_cell(v) for v in row] for row in frame.itertuples(index=False)]
    return {"title": title, "columns": [str(c) for c in frame.columns], "rows": rows}


def _cell(v: Any) -> Any:
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return _plain(v)


def _library_comments(text: str) -> dict[str, str]:
    """Each library entry's ``# source:`` comment line (the bundled library's convention)."""
    out: dict[str, str] = {}
    source = ""
    for line in text.splitlines():
        m = re.match(r"#\s*source:\s*(.*)$", line)
        if m:
            source = m.group(1).strip()
            continue
        m = re.match(r"([A-Za-z0-9_][^:#\s]*)\s*:", line)
        if m:
            if source:
                out[m.group(1)] = source
            source = ""
    return out


def _write_atomically(target: Path, text: str) -> None:
    """Write ``text`` to ``target`` in one step: a reader sees the old file or the new one."""
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _plain(v: Any) -> Any:
    if isinstance(v, dict):
        return {str(k): _plain(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [_plain(x) for x in v]
    if isinstance(v, float | int | str | bool) or v is None:
        return v
    return str(v)


def default_spec(project: Project, registry: Registry) -> Any:
    """The project's design section, or targets alone for a project without one.

    Without ``design:`` no rock may reach the protected zone (a count of 0)
    and nothing is priced.
    """
    from ..optimiser.design_spec import DesignSpec, resolve_design

    if project.design is not None:
        return resolve_design(project, registry)
    return DesignSpec(max_measures=4, residual_count=0, residual_fraction=None,
                      fresh_rocks=None, fresh_seed=None, length_m=1.0, candidates=(),
                      cost_model=None, products={})


def build_bench(project: Project, registry: Registry, rocks: int, seed: int,
                progress: Callable[[int], None] | None = None) -> Bench:
    """Run the rocks on the bare slope once and keep the screening table.

    Parameters
    ----------
    project, registry
        The project and its plugins.
    rocks, seed
        Rocks of the run and its seed (the same rocks as ``simulate`` and
        the optimiser's screening draw for this seed).
    progress
        Called with the rocks done; an exception it raises stops the run.
    """
    from ..engine import Releases, run_ensemble
    from ..engine.columns import STOPPED
    from ..engine.trajectory import centre_points
    from ..judge.placing import build_concept
    from ..optimiser.screening import Screening
    from ..run.releases import section_from_project

    section = section_from_project(project)
    x0, x1 = float(section.x[0]), float(section.x[-1])
    stations = np.arange(x0, x1 + 1e-9, TABLE_STEP_M)
    judged = project
    if project.protect is None:
        # The screening counts rocks reaching a protected zone; without one,
        # the foot of the section stands in (the page says there is none).
        from ..project.schema import Protect

        judged = project.model_copy(update={"protect": Protect(x=x1)})
    t0 = time.perf_counter()
    sc = Screening(judged, registry, default_spec(project, registry),
                   build_concept(project, registry), rocks=rocks, seed=seed,
                   stations=stations, rock_progress=progress,
                   restart_stations=np.arange(x0, x1 + 1e-9, RESTART_STEP_M))
    runtime = time.perf_counter() - t0
    qs = sorted({50.0, 95.0, *[float(q) for q in project.analysis.percentiles]})
    t = sc.bare
    ground = section.ground_height(sc.grid)
    envelopes = {
        "x": [round(float(v), 4) for v in sc.grid],
        "ground": _json_list(ground),
        "crossings": [int(c) for c in np.isfinite(t.h).sum(axis=0)],
        "height": _finite_percentiles(t.h, qs),
        "energy": _finite_percentiles(t.e_kj, qs),
        "percentiles": [f"p{q:g}" for q in qs],
        # The 95th percentile's distribution-free bounds at the project's
        # confidence (the judge's order statistics), for the hover.
        "confidence": sc.confidence,
        "height_p95_bounds": _p95_bounds(t.h, sc.confidence),
        "energy_p95_bounds": _p95_bounds(t.e_kj, sc.confidence),
    }
    stopped = t.status == STOPPED
    counts, edges = np.histogram(t.x_end[stopped], bins=STOP_BINS, range=(x0, x1))
    reach = 0
    if project.protect is not None:
        from ..run.reach import reaches_protected_zone

        reach = int(reaches_protected_zone(t.max_x, t.status, float(project.protect.x)).sum())
    stops = {"edges": [round(float(e), 4) for e in edges], "counts": counts.tolist(),
             "stopped": int(stopped.sum()), "reaching": reach,
             "p95_x": _num(float(np.percentile(t.x_end[stopped], 95))) if stopped.any() else None}
    # The first rocks' paths, from the same random streams (rock i draws from
    # stream i of the run's key): the rocks of the table, drawn.
    k = min(PATHS_DRAWN, rocks)
    rel = sc.releases
    sub = Releases(radius=rel.radius[:k], density=rel.density, x=rel.x[:k],
                   height=rel.height[:k], vx=rel.vx[:k], vy=rel.vy[:k], spin=rel.spin[:k],
                   spin_rolling=rel.spin_rolling[:k])
    tr = run_ensemble(section, sub, key=sc.key, settings=sc.settings, n_trajectories=k)
    paths = []
    for traj in tr.trajectories:
        px, py = centre_points(traj, 12)
        paths.append(np.column_stack([px, py]).round(3).tolist())
    return Bench(sc, rocks, seed, runtime, envelopes, stops, paths)


def load_entries(paths: Sequence[Path], registry: Registry) -> list[ProjectEntry]:
    """A :class:`ProjectEntry` per project file, with unique ids from the file names.

    Raises
    ------
    ProjectError
        A file is not a valid project (the command line's one-line message).
    """
    from ..api import validate_project
    from ..project import load_project

    out: list[ProjectEntry] = []
    seen: set[str] = set()
    for path in paths:
        project = load_project(path)
        validate_project(project, registry)
        base = re.sub(r"[^A-Za-z0-9_-]+", "-", Path(path).stem) or "project"
        pid, k = base, 2
        while pid in seen:
            pid, k = f"{base}-{k}", k + 1
        seen.add(pid)
        out.append(ProjectEntry(pid, Path(path).resolve(), project, registry))
    return out

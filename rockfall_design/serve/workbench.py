"""What the browser app works on: projects, their runs, and measures placed on the table.

Nothing here knows about HTTP: :mod:`rockfall_design.serve.app` turns a
:class:`ServeError` into a response with its status and one-line message.

A run (:meth:`ProjectEntry.start_run`) is the optimiser's screening run
(:class:`~rockfall_design.optimiser.screening.Screening`) of the project's
rocks on the bare slope, with its table stations every
:data:`~.page_run.TABLE_STEP_M` along the whole section: per rock, its passing height,
energy and speed at its first passage of every station. A fence or wall
placed anywhere is then judged from that table by the screening's own
judgement and the project's safety concept (:meth:`PageRun.place`), in
milliseconds, without running a rock again.
"""

from __future__ import annotations

import re
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..api import calibrate, check, optimise, plan, study, validate_project
from ..errors import ProjectError, RockfallError
from ..limits import MAX_BOOTSTRAP
from ..plugins import guard
from ..project import dump_yaml, load_project
from ..project.loading import load_project_text
from ..project.locator import params_problem
from ..project.schema import Material
from ..report.terminal import design_yaml
from ..results import DEFAULT_TRAJECTORIES
from .guards import (
    MAX_BODY_BYTES,
    UPLOAD_KINDS,
    UPLOAD_SUFFIXES,
    ServeError,
    file_kind,
    hidden_part,
    inside,
    library_comments,
    referenced_outside,
    same_version,
    write_atomically,
)
from .job_tables import calibration_tables, plain_json, study_tables
from .jobs import Cancelled, Job
from .page_run import PageRun, build_page_run, placed_message
from .reports import lazy_files

if TYPE_CHECKING:  # pragma: no cover
    from ..plugins import Registry
    from ..project import Project


#: Most rocks one run of the app may have (the table holds rocks x stations).
MAX_RUN_ROCKS = 50_000


# ---- paths --------------------------------------------------------------------------


# ---- jobs ---------------------------------------------------------------------------


# ---- a run's table and what is placed on it -------------------------------------


# ---- one project ------------------------------------------------------------------


@dataclass
class ProjectEntry:
    """A project file the app serves, its plugins and its latest run."""

    id: str
    path: Path
    project: Project
    registry: Registry
    run: PageRun | None = None
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
        p = self.project
        planned = plan(p, self.registry)  # built when the project was loaded: kept
        sec = planned.bare
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
        measures = [{k: plain_json(v) for k, v in dict(raw).items()} for raw in p.measures]
        # Their labels, as the reports write them (the project validated when loaded).
        labels = {q.index: q.label for q in planned.placed}
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
            "run": None if self.run is None else self.run_dict(),
            "job": None if self.job is None else self.job.as_dict(),
        }

    def run_dict(self) -> dict[str, Any]:
        b = self.run
        assert b is not None
        return {"rocks": b.rocks, "seed": b.seed, "runtime_s": round(b.runtime_s, 3),
                "envelopes": b.envelopes, "stops": b.stops, "paths": b.paths}

    # -- measures from the page ---------------------------------------------------
    def build_measure(self, raw: Any, i: int) -> Any:
        """A measure from ``{"type": ..., parameters}``, validated by its plugin's model."""
        if not isinstance(raw, dict) or not isinstance(raw.get("type"), str):
            raise ServeError(400, f"measures[{i}]: expected an object with a 'type'")
        kind = raw["type"]
        cls = self.registry.measures.get(kind)
        if cls is None:
            known = ", ".join(sorted(self.registry.measures))
            raise ServeError(400, f"measures[{i}].type: unknown measure {kind!r} "
                             f"(installed: {known})")
        # "label" is what describe() adds for the page, not a parameter: a measure
        # sent back as the app described it is the same measure.
        values = {k: v for k, v in raw.items() if k not in ("type", "label")}
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
            self._refuse_while_running()
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
        """Start the screening run of the project (see :func:`build_page_run`).

        Raises
        ------
        ServeError
            409 when a job of this project is under way; 400 for a rock
            count or seed out of range.
        """
        n, s = self._rocks_seed(rocks, seed)

        def work(job: Job) -> None:
            self.run = build_page_run(self.project, self.registry, n, s, job.progress)
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
        n, s = self._rocks_seed(rocks, seed)
        project = self.project
        if raws is not None:
            for i, raw in enumerate(raws):
                self.build_measure(raw, i)  # each measure's parameters, named for the page
            project = project.model_copy(update={"measures": [
                {k: v for k, v in r.items() if k != "label"} for r in raws]})
            try:
                # The measures placed on the section (fit, overlaps) before a job
                # starts; the check's run uses this plan.
                plan(project, self.registry)
            except ProjectError as exc:
                raise ServeError(400, placed_message(exc.message)) from None

        def work(job: Job) -> None:
            report = check(project, rocks=n, seed=s, progress=job.progress,
                           trajectories=DEFAULT_TRAJECTORIES, registry=self.registry)
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
        if self.project.design is None:
            raise ServeError(400, f"{self.path.name}: the project has no design: section to "
                             "optimise")
        if self.project.design.scenarios is not None:
            raise ServeError(400, f"{self.path.name}: design.scenarios: a design across "
                             "scenarios is optimised with rockfall-design optimise")
        n, s = self._rocks_seed(rocks, seed)
        project = self.project

        def work(job: Job) -> None:
            out = optimise(project, rocks=n, seed=s, progress=job.staged,
                           registry=self.registry)
            res = out.result
            job.result = res.summary()
            if res.best is not None:
                job.files["design.yaml"] = design_yaml(res.best, self.path.name,
                                                       res.search_rocks, res.looks,
                                                       res.marginal)
            # The report checks the chosen design again (for its figures): on request.
            job.files.update(lazy_files(out))

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
        if self.project.study is None:
            raise ServeError(400, f"{self.path.name}: the project has no study: section")
        n, s = self._rocks_seed(rocks, seed)
        project = self.project

        def work(job: Job) -> None:
            def progress(done: int, total: int, rocks_done: int) -> None:
                job.total = int(total)
                job.progress(done)

            res = study(project, rocks=n, seed=s, progress=progress, registry=self.registry,
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

            res = calibrate(project, rocks=n, bootstrap=b, seed=s, progress=on_done,
                            registry=self.registry)
            job.result = res.summary
            job.tables = calibration_tables(res)

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
        sources = library_comments(text)
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
                        "values": plain_json(m.model_dump(mode="json", exclude_none=True)),
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
        # A material of the project with that name but other values stays the
        # project's under a name of its own: the library's comes in as NAME
        # from LIBRARY.
        new = Material.model_validate(entry["values"])
        name = material
        if name in p.materials and p.materials[name] != new:
            name = f"{material} ({Path(lib['path']).stem})"
        with self.lock:
            self._refuse_while_running()
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
            self.project, self.run = project, None
            self.edits.append(f"segment {segment + 1}: {p.slope.materials[segment]} -> "
                              f"{name} from {lib['path']}")
        return {**self.describe(), "yaml": dump_yaml(project.resolved_dict())}

    # -- the project file -----------------------------------------------------------
    def _refuse_while_running(self) -> None:
        """409 while a job of this project runs (call with :attr:`lock` held)."""
        if self.job is not None and self.job.state == "running":
            raise ServeError(409, f"a {self.job.kind} of {self.id} is under way "
                             f"(job {self.job.id}); wait for it or cancel it first")

    def save(self, text: str, version: str) -> Path:
        """Validate ``text`` as the project and write it to the project file, and nowhere else.

        Parameters
        ----------
        text
            The project's YAML.
        version
            The version of the project file the page read
            (:func:`~rockfall_design.serve.guards.version_of`, as
            ``GET .../file`` gives it).

        Nothing is written unless the text is a valid project that names no
        file outside the directory, the file is still the one the page read
        and no job of the project runs; the file is replaced in one step,
        keeping its mode.

        Raises
        ------
        ServeError
            400 without a version or for a project that does not validate
            (its one-line message); 403 for a referenced file outside the
            directory; 409 when the file changed since the page read it, or
            while a job of this project runs; 507 when the disk is full.
        """
        target = self.path.resolve()
        project = self.validate(text, target)
        if not isinstance(version, str) or not version:
            raise ServeError(400, "version: expected the version of the project file the page "
                             "read (GET .../file gives it), so that Save overwrites no edit "
                             "made since")
        with self.lock:
            self._refuse_while_running()
            try:
                unchanged = same_version(target, version)
            except FileNotFoundError:
                unchanged = False
            if not unchanged:
                raise ServeError(409, f"{target.name} changed since the page read it (or was "
                                 "removed): reload it and make your edits again; nothing was "
                                 "written")
            write_atomically(target, text)
            self.project, self.run, self.edits = project, None, []
        return target

    def upload(self, name: str, text: str, replace: bool = False) -> Path:
        """Write an imported file (a section, observed stops, a library) beside the project.

        The text must be a surveyed section (CSV or DXF), observed stops
        (CSV) or a materials library (YAML); an existing file is replaced
        only when asked and only by a file of its own kind (observed stops
        by observed stops, never a project, a catalogue or another file by a
        library). Dotfiles and anything under a dot-folder are never written.

        Raises
        ------
        ServeError
            403 outside the project's directory or for a dotfile or
            dot-folder; 400 for another kind of file or text that is not a
            string; 409 when the file exists and ``replace`` is not set, or is
            of another kind; 507 when the disk is full.
        """
        if isinstance(name, str) and hidden_part(name) is not None:
            raise ServeError(403, f"path {name!r}: {hidden_part(name)!r} is hidden (a dotfile "
                             "or dot-folder): the app never writes there")
        target = inside(self.directory, name)
        if hidden_part(str(target.relative_to(self.directory))) is not None:
            raise ServeError(403, f"path {name!r} leads to a dotfile or dot-folder: the app "
                             "never writes there")
        if target.suffix.lower() not in UPLOAD_SUFFIXES:
            raise ServeError(400, f"path {name!r}: expected a file ending in "
                             f"{', '.join(UPLOAD_SUFFIXES)}")
        if not isinstance(text, str):
            raise ServeError(400, "text: expected the file's text as a string")
        kind = file_kind(target.name, text)
        if kind not in UPLOAD_KINDS:
            raise ServeError(400, f"{name}: the text is {kind}, not one of "
                             f"{'; '.join(UPLOAD_KINDS)}")
        if not target.parent.is_dir():
            raise ServeError(400, f"path {name!r}: no such directory in the project's directory")
        if target.resolve() == self.path.resolve():
            raise ServeError(400, f"{name} is the project file: save it from the editor")
        if target.exists():
            if not replace:
                raise ServeError(409, f"{name} exists already (send \"replace\": true to "
                                 "replace it)")
            old = self._existing_kind(target)
            if old != kind:
                raise ServeError(409, f"{name} holds {old}: an upload replaces only a file of "
                                 f"its own kind ({kind}); nothing was written")
        write_atomically(target, text)
        return target

    @staticmethod
    def _existing_kind(target: Path) -> str:
        if not target.is_file():
            return "directory or special file"
        if target.stat().st_size > MAX_BODY_BYTES:
            return "file larger than an upload may be"
        try:
            return file_kind(target.name, target.read_text(encoding="utf-8"))
        except UnicodeDecodeError:
            return "binary file"

    def validate(self, text: str, target: Path | None = None) -> Project:
        """The project in ``text``, validated as if it were the file ``target``.

        Raises
        ------
        ServeError
            403 when it names a file outside the project's directory; 400
            with the command line's one-line message when it is not valid.
        """
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


def load_entries(paths: Sequence[Path], registry: Registry) -> list[ProjectEntry]:
    """A :class:`ProjectEntry` per project file, with unique ids from the file names.

    Raises
    ------
    ProjectError
        A file is not a valid project (the command line's one-line message).
    """
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

"""Fixtures shared by the whole suite.

The suite mirrors the package: ``tests/engine``, ``tests/project``,
``tests/judge``, ``tests/optimiser``, ``tests/plugins``, ``tests/studies`` and
``tests/cli`` test the rooms of the same names; the tests at this level take
the product as a user meets it (the public API, the bundled projects, the
README, the notebook). Helpers that tests import live beside this file
(``engine_helpers``, ``plugin_helpers``); the plugin author's fixtures
(``tiny_slope``, ``rockfall_registry``) come from ``rockfall_design.testing``
through its pytest11 entry point, as they do for a plugin's own tests.
``tests/data/design_small.yaml`` (with its coarse catalogues) is a design
project that optimises in seconds, for the tests of what an optimisation
hands over (files, reports, interrupts, threads, the app) rather than of
what it designs.

Tests marked ``slow`` (end-to-end runs of the documentation's examples) are
left out of a plain run (``addopts`` in pyproject.toml); ``python -m pytest
-m slow`` runs them, as .ci/run does.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import re
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from rockfall_design.plugins import load_registry

try:  # file locks, to share a slow run between xdist workers (not on Windows)
    import fcntl
except ImportError:  # pragma: no cover
    fcntl = None

#: The repository: its projects/, examples/ and README.md.
ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="session")
def projects_dir() -> Path:
    """The bundled example projects (``projects/``)."""
    return ROOT / "projects"


@pytest.fixture(scope="module")
def registry():
    """The installed plugins, built-ins among them, once per module (a module may override it)."""
    reg = load_registry()
    assert {"fence", "wall", "ditch", "berm", "boulder_row"} <= set(reg.measures), reg.failures
    assert {"spang", "uni11211"} <= set(reg.safety_concepts), reg.failures
    return reg


@dataclass(frozen=True)
class OptimiseRun:
    """One ``rockfall-design optimise PROJECT --out OUT --report REPORT`` and what it left."""

    code: int
    terminal: str
    out: Path
    report: Path


@pytest.fixture(scope="session")
def optimised(tmp_path_factory: pytest.TempPathFactory) -> Callable[[Path], OptimiseRun]:
    """``optimise`` of a project with its own rocks and seed, run once per session.

    A bundled design takes half a minute to a minute and a half, and several
    slow tests read the same run (the one verdict of every face of
    tests/report/test_handin.py, the fresh-rocks guarantee of
    tests/optimiser/test_optimise.py): they share it. The tests only read its
    files; they must not change them. Under pytest-xdist those tests sit in
    different workers (``--dist loadscope`` keeps a module on one worker, not
    two modules), so the run is kept in the folder all workers of the session
    share, behind a file lock: the first worker to ask runs it, the others
    wait for it and read its files (one optimise of design_ditch_or_fence, half
    a minute to a minute, not two).

    It runs with the rock budget of 50,000 (``--max-rocks``; the default is
    400,000): what these tests check (one verdict on every face; the chosen
    design holds at other seeds with twice its deciding rocks) holds at any
    budget, and the default's larger decisions doubled the slow set's time
    (the fresh-seed checks alone 238 s quiet).
    """
    from rockfall_design.cli.program import main

    runs: dict[Path, OptimiseRun] = {}
    # The session's own folder: under xdist the workers' folders sit in one
    # folder of the session, which is theirs to share; without xdist the
    # session's folder itself (its parent holds earlier sessions' runs).
    base = tmp_path_factory.getbasetemp()
    shared = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base

    def optimise_once(project: Path, d: Path) -> OptimiseRun:
        done = d / "run.json"
        if done.is_file():
            kept = json.loads(done.read_text(encoding="utf-8"))
            return OptimiseRun(kept["code"], kept["terminal"], d / "out", d / "report")
        d.mkdir(exist_ok=True)
        term = io.StringIO()
        with contextlib.redirect_stdout(term):
            code = main(["optimise", str(project), "--max-rocks", "50000",
                         "--out", str(d / "out"), "--report", str(d / "report")])
        done.write_text(json.dumps({"code": code, "terminal": term.getvalue()}),
                        encoding="utf-8")
        return OptimiseRun(code, term.getvalue(), d / "out", d / "report")

    def run(project: Path) -> OptimiseRun:
        if project not in runs:
            d = shared / f"optimise-{project.stem}"
            if fcntl is None:  # no file locks here (Windows): a run per worker
                d = tmp_path_factory.mktemp(f"optimise-{project.stem}")
                runs[project] = optimise_once(project, d)
                return runs[project]
            with open(shared / f"optimise-{project.stem}.lock", "w") as lock:
                fcntl.flock(lock, fcntl.LOCK_EX)
                runs[project] = optimise_once(project, d)
        return runs[project]

    return run


@dataclass(frozen=True)
class PythonPageRun:
    """The block of docs/python.md, run as written, and the folder it ran in."""

    namespace: dict
    folder: Path


@pytest.fixture(scope="session")
def python_page_run(tmp_path_factory: pytest.TempPathFactory) -> PythonPageRun:
    """The Python page's block (docs/python.md, "From Python"), run once per session.

    It runs in a folder of its own in which ``projects`` leads to the bundled
    projects, as a reader runs it from the repository. Its optimisation of
    design_two_zones (seed 1) takes a minute: tests/test_api.py checks what the
    page promises and reads the same result as the issue's example rather than
    running it again (one module, so one xdist worker and one run).
    """
    text = (ROOT / "docs" / "python.md").read_text(encoding="utf-8")
    block = re.search(r"```python\n(.*?)```", text[text.index("# From Python"):], re.S)
    assert block, "no python block after '# From Python' in python.md"
    folder = tmp_path_factory.mktemp("python_page")
    (folder / "projects").symlink_to(ROOT / "projects")
    here = Path.cwd()
    os.chdir(folder)
    try:
        namespace: dict = {}
        exec(compile(block.group(1), "docs/python.md", "exec"), namespace)  # noqa: S102
    finally:
        os.chdir(here)
    return PythonPageRun(namespace, folder)


def _engine_is_cached() -> bool:
    """True if numba's cache holds the engine's batch kernel (no compile ahead)."""
    from rockfall_design.engine import ensemble, jit

    cache = getattr(ensemble._run_batch, "_cache", None)
    path = getattr(cache, "_cache_path", None)
    if not jit.CACHE or path is None:
        return False
    return any(Path(path).glob("ensemble._run_batch-*.nbi"))


def pytest_collection_finish(session: pytest.Session) -> None:
    """Compile the engine before the first test, saying so, if it is not cached yet.

    Otherwise the compilation (half a minute to a minute and a half) happens
    silently inside whichever test first runs a rock, its notice captured with
    that test's output. Here it is said on the terminal, timed, and done once.
    """
    if not session.items or session.config.option.collectonly or _engine_is_cached():
        return
    capture = session.config.pluginmanager.getplugin("capturemanager")
    with capture.global_and_fixture_disabled():
        sys.stderr.write("\ntests: the engine is not compiled yet for these sources; "
                         "compiling it before the first test...\n")
        sys.stderr.flush()
        t0 = time.perf_counter()
        import rockfall_design as rd

        rd.simulate(ROOT / "projects" / "standard_slope.yaml", rocks=1, seed=0)
        sys.stderr.write(f"tests: engine ready in {time.perf_counter() - t0:.0f} s\n")
        sys.stderr.flush()


@pytest.fixture(scope="session", autouse=True)
def _terminal_as_in_one_process() -> Iterator[None]:
    """A pytest-xdist worker's terminal as a plain run's: no COLUMNS or LINES of its own.

    xdist sets ``COLUMNS=80`` and ``LINES=24`` in every worker; the terminal
    report (report/terminal.py) takes a set ``COLUMNS`` as the user's wish and
    wraps at 80 where a pipe would get the content's own width, so the tests
    that read a printed panel saw other text on two workers than on one.
    """
    with pytest.MonkeyPatch.context() as mp:
        if os.environ.get("PYTEST_XDIST_WORKER"):
            mp.delenv("COLUMNS", raising=False)
            mp.delenv("LINES", raising=False)
        yield


@pytest.fixture(scope="session", autouse=True)
def _no_pdf_unless_asked() -> Iterator[None]:
    """report.pdf only in the tests that read it (tests/report/test_pdf.py).

    Each print starts a Chromium, seconds a report; the other tests of
    --report look at the HTML and Markdown. ``ROCKFALL_DESIGN_PDF=0``
    (docs/reports.md) reaches the commands run in subprocesses too.
    Session-scoped, so that it is in place before any fixture runs: pytest
    sets up a module's or the session's fixtures before a test's function-scoped
    autouse ones, and a function-scoped guard let the module-wide runs of
    ``--report`` (tests/report/test_handin.py, the ``optimised`` fixture) print
    a PDF no test read. tests/report/test_pdf.py turns it back on for itself.
    """
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("ROCKFALL_DESIGN_PDF", "0")
        yield

"""Fixtures shared by the whole suite.

The suite mirrors the package: ``tests/engine``, ``tests/project``,
``tests/judge``, ``tests/optimiser``, ``tests/plugins``, ``tests/studies`` and
``tests/cli`` test the rooms of the same names; the tests at this level take
the product as a user meets it (the public API, the bundled projects, the
README, the notebook). Helpers that tests import live beside this file
(``engine_helpers``, ``plugin_helpers``); the plugin author's fixtures
(``tiny_slope``, ``rockfall_registry``) come from ``rockfall_design.testing``
through its pytest11 entry point, as they do for a plugin's own tests.

Tests marked ``slow`` (end-to-end runs of the documentation's examples) are
left out of a plain run (``addopts`` in pyproject.toml); ``python -m pytest
-m slow`` runs them, as .ci/run does.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import pytest

from rockfall_design.plugins import load_registry

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


def _engine_is_cached() -> bool:
    """True if numba's cache holds the engine's batch kernel (no compile ahead)."""
    from rockfall_design.engine import _jit, ensemble

    cache = getattr(ensemble._run_batch, "_cache", None)
    path = getattr(cache, "_cache_path", None)
    if not _jit.CACHE or path is None:
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

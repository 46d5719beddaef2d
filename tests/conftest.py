"""Fixtures shared by the whole suite.

The suite mirrors the package: ``tests/engine``, ``tests/project``,
``tests/judge``, ``tests/optimise``, ``tests/plugins``, ``tests/study`` and
``tests/cli`` test the rooms of the same names; the tests at this level take
the product as a user meets it (the public API, the bundled projects, the
README, the notebook). Helpers that tests import live beside this file
(``engine_helpers``, ``plugin_helpers``); the plugin author's fixtures
(``tiny_slope``, ``rockfall_registry``) come from ``rockfall_design.testing``
through its pytest11 entry point, as they do for a plugin's own tests.
"""

from __future__ import annotations

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

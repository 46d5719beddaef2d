"""Fixtures of the browser app's tests: a copy of a bundled project in its own directory."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

pytest.importorskip("starlette", reason="rockfall-design serve needs the web extra")

#: The files design_two_zones.yaml reads (its catalogues).
TWO_ZONES_FILES = ("design_two_zones.yaml", "catalogue_products.yaml", "catalogue_costs.yaml")


@pytest.fixture(scope="module")
def project_copy(tmp_path_factory: pytest.TempPathFactory, projects_dir: Path) -> Path:
    """design_two_zones.yaml and its catalogues, copied into a directory of their own.

    The directory sits one level below a parent that holds a file too
    (``outside.txt``): what a request must never read or overwrite.
    """
    root = tmp_path_factory.mktemp("serve")
    (root / "outside.txt").write_text("not the project's\n")
    d = root / "project"
    d.mkdir()
    for name in TWO_ZONES_FILES:
        shutil.copy(projects_dir / name, d / name)
    return d / "design_two_zones.yaml"

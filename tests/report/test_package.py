"""The report room's face: the names it offers and the imports it leaves lazy."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

import rockfall_design.report as report
from rockfall_design.report import terminal

ROOT = Path(__file__).resolve().parents[2]

#: What ``from rockfall_design.report import X`` gave when it was one module,
#: and still gives: its ``__all__`` and the public helpers the commands share.
TERMINAL_NAMES = ("print_simulation", "print_check", "print_optimise", "alternatives_table",
                  "design_yaml", "plot_run", "plugins_table", "fitted_console",
                  "simulation_renderable", "check_renderable", "MAX_FILE_WIDTH")


@pytest.mark.parametrize("name", TERMINAL_NAMES)
def test_the_package_offers_the_terminal_names(name):
    assert getattr(report, name) is getattr(terminal, name)
    assert name in dir(report)


def test_star_import_gives_what_the_module_gave():
    names: dict[str, object] = {}
    exec("from rockfall_design.report import *", names)
    assert set(names) - {"__builtins__"} == set(terminal.__all__) == set(report.__all__)


def test_an_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'nothing_here'"):
        report.nothing_here  # noqa: B018


def _loaded_after(statement: str, modules: tuple[str, ...]) -> list[str]:
    code = (f"import sys\n{statement}\n"
            f"print(','.join(m for m in {modules!r} if m in sys.modules))")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    return [m for m in run.stdout.strip().split(",") if m]


def test_importing_the_package_loads_none_of_its_modules():
    """The package's names are imported on first use: rich, matplotlib, Jinja2 stay out."""
    heavy = ("rich", "matplotlib", "jinja2", "pandas", "rockfall_design.report.terminal",
             "rockfall_design.report.figures", "rockfall_design.report.documents",
             "rockfall_design.report.tables")
    assert _loaded_after("import rockfall_design.report", heavy) == []


def _public_definitions(module: object) -> set[str]:
    """The names a module's own source defines at its top level, leading underscore aside."""
    tree = ast.parse(Path(module.__file__).read_text(encoding="utf-8"))
    names: set[str] = set()
    for node in tree.body:
        if isinstance(node, ast.FunctionDef | ast.ClassDef):
            names.add(node.name)
        elif isinstance(node, ast.Assign):
            names.update(t.id for t in node.targets if isinstance(t, ast.Name))
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
    return {n for n in names if not n.startswith("_")}


def test_the_package_offers_every_public_name_of_the_terminal():
    assert _public_definitions(terminal) == set(TERMINAL_NAMES)


def _imported_modules(path: Path, package: str) -> set[str]:
    """The absolute names of the modules that the file at ``path`` imports from."""
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parent = package.split(".")[:len(package.split(".")) - node.level + 1]
                base = ".".join(parent + ([base] if base else []))
            names.add(base)
            names.update(f"{base}.{a.name}" for a in node.names)
        elif isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
    return names


def test_the_templates_are_package_data_where_the_loader_looks():
    """A wheel ships what package-data names: every template, beside documents.py."""
    import tomllib

    from rockfall_design.report import documents

    data = tomllib.loads((ROOT / "pyproject.toml").read_text())
    patterns = data["tool"]["setuptools"]["package-data"]["rockfall_design.report"]
    here = Path(documents.__file__).parent
    templates = sorted(p.relative_to(here) for p in (here / "templates").iterdir())
    assert [t.name for t in templates] == ["report.html.j2", "report.md.j2"]
    for t in templates:
        assert any(t.match(pattern) for pattern in patterns), t
    env = documents._environment(markdown=True)
    assert env.get_template("report.md.j2").filename == str(here / "templates" / "report.md.j2")


@pytest.mark.parametrize("module, not_loaded", [
    # A notebook's .plot(): matplotlib, but not the terminal's rich nor the reports' Jinja2.
    ("rockfall_design.report.figures", ("rich", "jinja2", "rockfall_design.report.terminal",
                                        "rockfall_design.report.documents")),
    # The documents draw their figures only when a report is written.
    ("rockfall_design.report.documents", ("matplotlib", "rich", "jinja2",
                                          "rockfall_design.report.figures")),
    ("rockfall_design.report.terminal", ("matplotlib", "jinja2", "pandas")),
])
def test_each_module_of_the_room_loads_only_its_own(module, not_loaded):
    assert _loaded_after(f"import {module}", not_loaded) == []

"""The report room's face: the names it offers and the imports it leaves lazy."""

from __future__ import annotations

import subprocess
import sys

import pytest

import rockfall_design.report as report
from rockfall_design.report import terminal

#: What ``from rockfall_design.report import X`` gave when it was one module,
#: and still gives: its ``__all__`` and the public helpers the commands share.
TERMINAL_NAMES = ("print_simulation", "print_check", "print_optimise", "alternatives_table",
                  "design_yaml", "plot_study", "plugins_table", "fitted_console",
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

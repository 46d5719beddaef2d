"""The output side: what a run shows the engineer, on the terminal and in files.

- :mod:`~rockfall_design.report.terminal`: the commands' terminal reports (rich);
- :mod:`~rockfall_design.report.figures`: matplotlib Figures, built without pyplot;
- :mod:`~rockfall_design.report.documents`: the HTML and Markdown reports (Jinja2,
  templates in ``report/templates``);
- :mod:`~rockfall_design.report.tables`: the tables that the terminal and the
  documents share (pandas).

They read result objects, never engine columns.

This package offers the names of the former module ``rockfall_design.report``
(the terminal's), as before: ``from rockfall_design.report import print_check``.
They are imported on first use (PEP 562), so that importing one module of the
room (``rockfall_design.report.figures`` for a notebook's ``.plot()``) loads
neither rich nor the others: each module keeps its own, lazy, imports.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover
    from .terminal import (  # noqa: F401  (the names __getattr__ offers, for type checkers)
        MAX_FILE_WIDTH,
        alternatives_table,
        check_renderable,
        design_yaml,
        fitted_console,
        plot_run,
        plugins_table,
        print_check,
        print_optimise,
        print_simulation,
        simulation_renderable,
    )

# As the former module's: what ``from rockfall_design.report import *`` gives.
__all__ = [
    "print_simulation",
    "print_check",
    "print_optimise",
    "alternatives_table",
    "design_yaml",
    "plot_run",
    "plugins_table",
]

#: The names of the terminal module offered here: its ``__all__`` and the
#: public helpers the commands share.
_TERMINAL = frozenset(__all__) | {"fitted_console", "simulation_renderable",
                                  "check_renderable", "MAX_FILE_WIDTH"}


def __getattr__(name: str) -> Any:
    if name not in _TERMINAL:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(import_module(".terminal", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | _TERMINAL)

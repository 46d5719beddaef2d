"""Plugins: loading them, and calling them safely.

Rooms:

* :mod:`~rockfall_design.plugins.manager`: find, load, check and register
  the plugins (:func:`load_registry`, :class:`Registry`);
* :mod:`~rockfall_design.plugins.contract`: what each plugin method may
  raise and must return, and the checks of a footprint;
* :mod:`~rockfall_design.plugins.proxy`: typed, guarded calls into plugin
  objects (:func:`guard`; :func:`call_plugin` for code written against it);
* :mod:`~rockfall_design.plugins.listing`: the registry as plain data
  (``plugins --json``).

The plugin author's manual is :mod:`rockfall_design.hookspecs`. Every name
this module had when it was one file is still importable from here.
"""

from __future__ import annotations

from typing import Any

from .contract import footprint_problem
from .listing import plugins_json
from .manager import (
    PluginFailure,
    PluginOrigin,
    Registry,
    UnknownNameError,
    blocked_provider,
    check_blocked_names,
    default_registry,
    is_real_interrupt,
    load_registry,
    plugin_code,
)
from .proxy import (
    Guard,
    GuardedConcept,
    GuardedCostModel,
    GuardedMeasure,
    call_plugin,
    guard,
)

__all__ = [
    "Guard",
    "GuardedConcept",
    "GuardedCostModel",
    "GuardedMeasure",
    "PluginFailure",
    "PluginOrigin",
    "Registry",
    "UnknownNameError",
    "blocked_provider",
    "call_plugin",
    "check_blocked_names",
    "default_registry",
    "footprint_problem",
    "guard",
    "is_real_interrupt",
    "load_registry",
    "plugin_code",
    "plugins_json",
    "plugins_table",
]


def __getattr__(name: str) -> Any:
    # The terminal's tables live with the other terminal output (report); rich
    # is imported only when they are drawn.
    if name == "plugins_table":
        from ..report.terminal import plugins_table

        return plugins_table
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

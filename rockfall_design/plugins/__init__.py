"""Plugins: loading them, and calling them safely.

Rooms:

* :mod:`~rockfall_design.plugins.discovery`: find, load, check and register
  the plugins (:func:`load_registry`);
* :mod:`~rockfall_design.plugins.manager`: the :class:`Registry` and the
  guard of plugin code;
* :mod:`~rockfall_design.plugins.contract`: what each plugin method may
  raise and must return, and the checks of a footprint;
* :mod:`~rockfall_design.plugins.proxy`: typed, guarded calls into plugin
  objects (:func:`guard`; :func:`call_plugin` for code written against it);
* :mod:`~rockfall_design.plugins.listing`: the registry as plain data
  (``plugins --json``).

The plugin author's manual is :mod:`rockfall_design.plugins.hookspecs`. Every name
this package offers is loaded on first use.
"""

from __future__ import annotations

from typing import Any

# Names are loaded on first use (PEP 562), so that importing a plugin base
# class (``plugins.measure`` and its siblings, which the public face imports)
# does not load the manager, pluggy and the entry points.
_WHERE = {
    "Guard": ".proxy",
    "GuardedConcept": ".proxy",
    "GuardedCostModel": ".proxy",
    "GuardedMeasure": ".proxy",
    "PluginFailure": ".manager",
    "PluginOrigin": ".manager",
    "Registry": ".manager",
    "UnknownNameError": ".manager",
    "blocked_provider": ".discovery",
    "call_plugin": ".proxy",
    "check_blocked_names": ".discovery",
    "default_registry": ".discovery",
    "footprint_problem": ".contract",
    "guard": ".proxy",
    "is_real_interrupt": ".manager",
    "load_registry": ".discovery",
    "plugin_code": ".manager",
    "plugins_json": ".listing",
}

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
]


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        from importlib import import_module

        value = getattr(import_module(_WHERE[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)

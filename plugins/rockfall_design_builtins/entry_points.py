"""One plugin object per built-in safety concept, so that each has an entry point of its own.

Every built-in measure, safety concept and cost model is registered by its
own entry point (pyproject.toml, group ``rockfall_design``), named as the
project file names it. So ``--block spang`` leaves out that concept and
nothing else, and a third party can replace one built-in by blocking it and
registering its own class of that name. The measures
(:mod:`rockfall_design_builtins.measures`) and the cost model
(:mod:`rockfall_design_builtins.costs.unit_prices`) are one module each,
registered as they are; the safety concepts ``spang``, ``uni11211``,
``onr24810`` and ``reliability`` still go through this module until they
are split the same way.

pluggy registers any object whose attributes are functions marked with
``@hookimpl`` (a module is only the most common such object). Each object
here carries one marked function: the registration hook of the module that
defines the built-in, filtered to that one class. The classes stay where
they are; this module only chooses among them.
"""

from __future__ import annotations

from collections.abc import Callable
from types import ModuleType

from rockfall_design import hookimpl

from . import safety, safety_onr24810, safety_reliability

__all__ = [
    "onr24810",
    "reliability",
    "spang",
    "uni11211",
]


class OneBuiltin:
    """A plugin object that registers one class of a built-in module.

    Parameters
    ----------
    module : module
        The module that defines the class and its registration hook.
    hook : str
        The hook's name, e.g. ``"rockfall_design_measures"``.
    name_attr : str
        The class attribute that names it (``"kind"`` or ``"name"``).
    name : str
        The one name to register.
    """

    def __init__(self, module: ModuleType, hook: str, name_attr: str, name: str) -> None:
        source: Callable[[], list[type]] = getattr(module, hook)

        def only_this_one() -> list[type]:
            return [cls for cls in source() if getattr(cls, name_attr, None) == name]

        only_this_one.__name__ = hook
        only_this_one.__qualname__ = f"{type(self).__name__}({name!r}).{hook}"
        only_this_one.__doc__ = f"The built-in {name!r} only (from {module.__name__})."
        # An instance attribute named as the hook: what pluggy looks for.
        setattr(self, hook, hookimpl(only_this_one))
        self.name = name

    def __repr__(self) -> str:
        return f"<built-in plugin {self.name!r}>"


def _concept(name: str, module: ModuleType = safety) -> OneBuiltin:
    return OneBuiltin(module, "rockfall_design_safety_concepts", "name", name)


spang = _concept("spang")
uni11211 = _concept("uni11211")
# One module each (DESIGN.md: one module per built-in).
onr24810 = _concept("onr24810", safety_onr24810)
reliability = _concept("reliability", safety_reliability)

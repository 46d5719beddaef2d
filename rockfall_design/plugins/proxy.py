"""Typed, guarded calls into plugin objects: the only way the core calls plugin code.

``guard(registry).measure(m).footprint(section)`` calls the measure's
``footprint`` as :func:`call_plugin` always did, and says in its signature
what it returns. Every call runs inside :func:`~.manager.plugin_code` (the
plugin's output goes to stderr; a real Ctrl-C is told apart from the
plugin's own ``KeyboardInterrupt``), contains anything the plugin raises,
``BaseException`` included, except the exceptions its contract lets through
(:mod:`.contract`), and checks what it returns. A fault is a
:class:`~rockfall_design.errors.PluginError` (exit code 3) whose one line
names the measure, safety concept or cost model, the distribution that
provides it, the method and the exception.

:func:`call_plugin` (method names as strings) stays for code written against
it; it is what the proxies call.
"""

from __future__ import annotations

import dataclasses
import reprlib
from typing import Any

import numpy as np

from ..errors import PluginError
from .concept import Check, SafetyConcept
from .contract import CONTRACTS, PLUGIN_NOUN, identify_plugin
from .cost_model import CostModel
from .manager import Registry, describe_exception, is_real_interrupt, plugin_code
from .measure import Barrier, ProfileEdit, ProtectiveMeasure, Quantity

#: numpy's message for a write into a read-only array.
_READ_ONLY = "read-only"


def _handed_arrays(args: tuple[Any, ...]) -> list[tuple[str, np.ndarray]]:
    """The numpy arrays in ``args`` and, one level down, in their dataclass fields.

    Named for messages: ``section.y``, ``MeasureResult.energy_kj``.
    """
    found: list[tuple[str, np.ndarray]] = []
    for i, arg in enumerate(args):
        if isinstance(arg, np.ndarray):
            found.append((f"argument {i + 1}", arg))
        elif dataclasses.is_dataclass(arg) and not isinstance(arg, type):
            owner, names = _fields_of(type(arg))
            for name in names:
                value = getattr(arg, name, None)
                if isinstance(value, np.ndarray):
                    found.append((f"{owner}.{name}", value))
    return found


#: Per dataclass handed to plugins: its name in messages and its field names.
_FIELDS: dict[type, tuple[str, tuple[str, ...]]] = {}


def _fields_of(cls: type) -> tuple[str, tuple[str, ...]]:
    """A dataclass's name for messages and its field names, looked up once per class.

    ``dataclasses.fields`` builds its list on every call; the optimiser hands
    a section or a measure's result to plugins about 100,000 times.
    """
    known = _FIELDS.get(cls)
    if known is None:
        owner = "section" if cls.__name__ == "Section" else cls.__name__
        known = _FIELDS[cls] = (owner, tuple(f.name for f in dataclasses.fields(cls)))
    return known


def _freeze(arrays: list[tuple[str, np.ndarray]]) -> None:
    """Make every array read-only, for good: the core only reads them after the call.

    For good, not for the call: two threads may hand the same section to
    plugins at once, and one thread's "put back" would open it under the
    other's plugin.
    """
    for _, array in arrays:
        if array.flags.writeable:
            array.flags.writeable = False


def call_plugin(registry: Registry, plugin: Any, method: str, *args: Any) -> Any:
    """Call plugin code from the core: every call into a plugin's class goes through here.

    Parameters
    ----------
    registry
        The registry the class came from, for the distribution that provides it.
    plugin
        A measure, safety concept or cost model: the class for ``"__init__"``,
        otherwise an instance.
    method
        ``"__init__"`` (instantiate the class with ``args``), or the name of
        the method: ``footprint``, ``design_properties``, ``quantities``,
        ``bill``, ``label`` (measures), ``checks`` (safety concepts), ``cost``,
        ``price``, ``missing_price`` (cost models).
    *args
        Passed on to the method.

    Returns
    -------
    Any
        What the method returned, checked against its contract.

    Raises
    ------
    ValueError
        From ``footprint`` (the measure does not fit on the section).
    KeyError or ValueError
        From ``cost`` and ``price`` (the catalogue has no price for the measure).
    PluginError
        Exit code 3: the method raised anything else, or returned what its
        contract does not allow. The one-line message names the measure,
        safety concept or cost model, the distribution that provides it, the
        method, and the exception (type, message and the plugin's line).
    """
    key, name = identify_plugin(plugin)
    contract = CONTRACTS[(key, method)]
    provider = registry.provider.get((key, name))
    who = f"{PLUGIN_NOUN[key]} {name!r}" + (f" (from {provider})" if provider else "")
    # The ground and the rocks' results are the core's: a plugin that wrote
    # into section.y would flatten the ground the engine then runs on.
    handed = _handed_arrays(args)
    _freeze(handed)
    try:
        with plugin_code():
            fn = plugin if method == "__init__" else getattr(plugin, method)
            value = fn(*args)
    except (*contract.raises, PluginError) as exc:
        if isinstance(exc, ValueError) and _READ_ONLY in str(exc) and handed:
            # Not "the measure does not fit": numpy refused a write.
            raise PluginError(
                f"{who} failed in {method}(): it wrote into an array it was handed "
                f"({', '.join(n for n, _ in handed)} are read-only); this is a bug in the "
                "plugin, not in the project") from exc
        # The contract's own exceptions mean something to the caller; a
        # PluginError comes from a nested call that already named its plugin.
        raise
    except BaseException as exc:
        # SystemExit, KeyboardInterrupt and the like are faults as well when
        # the plugin raises them; only a real Ctrl-C stops the run.
        if is_real_interrupt(exc):
            raise
        wrote = (f" (it wrote into an array it was handed: "
                 f"{', '.join(n for n, _ in handed)} are read-only)") if (
            isinstance(exc, ValueError) and _READ_ONLY in str(exc) and handed) else ""
        raise PluginError(
            f"{who} failed in {method}(): {describe_exception(exc)}{wrote}; "
            "this is a bug in the plugin, not in the project"
        ) from exc
    _check_returned(who, method, contract, value, plugin, args, handed)
    return value


def _check_returned(who: str, method: str, contract: Any, value: Any, plugin: Any,
                    args: tuple[Any, ...], handed: list[tuple[str, np.ndarray]]) -> None:
    """Refuse what a plugin's method did to its arrays or returned, against its contract.

    Raises
    ------
    PluginError
        The method made a handed array writeable again, returned a value of
        the wrong type, or one whose fields its contract refuses.
    """
    reopened = [n for n, array in handed if array.flags.writeable]
    if reopened:
        raise PluginError(
            f"{who}: {method}() made {', '.join(reopened)} writeable again: the arrays a "
            "plugin is handed are read-only; this is a bug in the plugin, not in the project")
    if contract.returns is not None and not contract.returns(value):
        shown = reprlib.repr(value)
        raise PluginError(
            f"{who}: {method}() returned {type(value).__name__} {shown}, "
            f"expected {contract.expected}; this is a bug in the plugin, not in the project"
        )
    why = contract.problem(value, plugin, args) if contract.problem is not None else None
    if why is not None:
        raise PluginError(
            f"{who}: {method}() returned {type(value).__name__} with {why}; "
            "this is a bug in the plugin, not in the project"
        )


# ---------------------------------------------------------------------------
# the typed proxies


class GuardedMeasure:
    """A measure whose every method call is guarded (see the module docstring).

    Parameters
    ----------
    registry : Registry
        The registry the measure's class came from (for the distribution
        named in an error).
    measure : ProtectiveMeasure
        The measure (an instance).
    """

    __slots__ = ("measure", "registry")

    def __init__(self, registry: Registry, measure: ProtectiveMeasure) -> None:
        self.registry = registry
        self.measure = measure

    def footprint(self, section: Any) -> Barrier | ProfileEdit:
        """The measure on ``section``: an obstacle at a station, or an edit of the ground.

        Raises
        ------
        ValueError
            The measure does not fit on the section (the project's fault, exit 2).
        PluginError
            Anything else raised, or a footprint the engine cannot use (exit 3).
        """
        return call_plugin(self.registry, self.measure, "footprint", section)

    def design_properties(self) -> dict[str, float]:
        """The measure's design properties (name to number, units in the names)."""
        return call_plugin(self.registry, self.measure, "design_properties")

    def quantities(self, section: Any) -> dict[str, float]:
        """The measure's quantities for costing on ``section`` (name to number)."""
        return call_plugin(self.registry, self.measure, "quantities", section)

    def bill(self, section: Any) -> list[Quantity]:
        """The measure's named quantities per running metre on ``section``, for pricing."""
        return call_plugin(self.registry, self.measure, "bill", section)

    def label(self) -> str:
        """The measure's one-line label for reports."""
        return call_plugin(self.registry, self.measure, "label")


class GuardedConcept:
    """A safety concept whose calls are guarded.

    Parameters
    ----------
    registry : Registry
    concept : SafetyConcept
        The concept (an instance).
    """

    __slots__ = ("concept", "registry")

    def __init__(self, registry: Registry, concept: SafetyConcept) -> None:
        self.registry = registry
        self.concept = concept

    def checks(self, result: Any) -> list[Check]:
        """The concept's checks of one measure's result (a ``MeasureResult``)."""
        return call_plugin(self.registry, self.concept, "checks", result)


class GuardedCostModel:
    """A cost model whose calls are guarded.

    Parameters
    ----------
    registry : Registry
    model : CostModel
        The cost model (an instance).
    """

    __slots__ = ("model", "registry")

    def __init__(self, registry: Registry, model: CostModel) -> None:
        self.registry = registry
        self.model = model

    def cost(self, *args: Any) -> float:
        """The cost of a measure (the arguments of :meth:`CostModel.cost`), a number >= 0.

        Raises
        ------
        KeyError or ValueError
            The catalogue has no price for the measure.
        """
        return call_plugin(self.registry, self.model, "cost", *args)

    def price(self, measure: ProtectiveMeasure, bill: list[Quantity],
              quantities: dict[str, float], length_m: float) -> float:
        """The cost of ``measure`` priced from its bill over ``length_m`` (m), a number >= 0.

        Raises
        ------
        KeyError or ValueError
            The catalogue has no price for a quantity of the bill.
        """
        return call_plugin(self.registry, self.model, "price", measure, bill, quantities,
                           length_m)

    def missing_price(self, measure: ProtectiveMeasure, bill: list[Quantity]) -> str | None:
        """Why the model cannot price ``bill`` (one line), or None if it can."""
        return call_plugin(self.registry, self.model, "missing_price", measure, bill)


class Guard:
    """Guarded access to the plugin objects of one registry: ``guard(registry)``.

    >>> g = guard(registry)                                # doctest: +SKIP
    >>> fence = g.instantiate(registry.measure("fence"), params)  # doctest: +SKIP
    >>> g.measure(fence).footprint(section)                # doctest: +SKIP
    """

    __slots__ = ("registry",)

    def __init__(self, registry: Registry) -> None:
        self.registry = registry

    def instantiate(self, cls: type[Any], *args: Any) -> Any:
        """An instance of a plugin's class (a measure, safety concept or cost model)."""
        return call_plugin(self.registry, cls, "__init__", *args)

    def measure(self, measure: ProtectiveMeasure) -> GuardedMeasure:
        """The guarded methods of ``measure``."""
        return GuardedMeasure(self.registry, measure)

    def concept(self, concept: SafetyConcept) -> GuardedConcept:
        """The guarded methods of a safety concept."""
        return GuardedConcept(self.registry, concept)

    def cost_model(self, model: CostModel) -> GuardedCostModel:
        """The guarded methods of a cost model."""
        return GuardedCostModel(self.registry, model)


def guard(registry: Registry) -> Guard:
    """Guarded, typed calls into the plugin objects of ``registry`` (see :class:`Guard`)."""
    return Guard(registry)

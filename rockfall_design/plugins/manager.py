"""The plugin manager's records: the registry, failures, origins, and running plugin code.

:class:`Registry` holds what the plugins provide (sorted, one class per
name) and :class:`PluginFailure` what failed to load; :func:`plugin_code`
is the guard every call into plugin code runs in (an interrupt raised there
is a real one only when the user sent it: :func:`is_real_interrupt`).
Finding and loading the plugins is :mod:`.discovery`; the calls of the core
into plugin objects go through the typed proxy of :mod:`.proxy`.
"""

from __future__ import annotations

import _signal
import contextlib
import difflib
import logging
import re
import sys
import threading
import traceback
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from ..errors import Interrupted
from .concept import SafetyConcept
from .cost_model import CostModel
from .measure import ProtectiveMeasure

log = logging.getLogger(__name__)

#: What a plugin name (a distribution or entry-point name) may contain.
NAME_RE = re.compile(r"[a-z0-9_-]+")


@dataclass(frozen=True)
class PluginFailure:
    """A plugin (or one class of it) that could not be used.

    Attributes
    ----------
    plugin : str
        The plugin's name (its entry-point name).
    distribution : str or None
        The distribution that ships it, None if unknown.
    reason : str
        One line: what went wrong.
    """

    plugin: str
    distribution: str | None
    reason: str


@dataclass(frozen=True)
class PluginOrigin:
    """Where a registered measure, safety concept or cost model comes from.

    Attributes
    ----------
    plugin : str
        The plugin's name (its entry-point name, or the name given to
        ``load_registry(extra_plugins=...)``).
    distribution : str or None
        The distribution that ships it; None for a plugin registered without
        one (``extra_plugins``).
    version : str or None
        That distribution's version; None if unknown.
    """

    plugin: str
    distribution: str | None
    version: str | None


class UnknownNameError(KeyError):
    """A measure kind, safety concept or cost model that is not registered.

    A :class:`KeyError` whose ``str()`` is the plain one-line message (with
    "did you mean" and the names that exist), not its repr.
    """

    def __init__(self, message: str, name: str, known: list[str]) -> None:
        super().__init__(message)
        self.message = message
        self.name = name
        self.known = known

    def __str__(self) -> str:
        return self.message


# (registry attribute, what a user calls it, hook, base class, name attribute, provider key)
SECTIONS: tuple[tuple[str, str, str, type, str, str], ...] = (
    ("measures", "measure kind", "rockfall_design_measures", ProtectiveMeasure, "kind",
     "measure"),
    ("safety_concepts", "safety concept", "rockfall_design_safety_concepts", SafetyConcept,
     "name", "safety"),
    ("cost_models", "cost model", "rockfall_design_cost_models", CostModel, "name", "cost"),
)
# What a class's example must not contain: the key the project file uses to choose it.
SELECTOR_KEY = {"measures": "type", "safety_concepts": "concept"}


@dataclass(frozen=True)
class Registry:
    """Everything the installed plugins provide, sorted by name.

    Attributes
    ----------
    measures : dict of str to type[ProtectiveMeasure]
        By ``kind``.
    safety_concepts : dict of str to type[SafetyConcept]
        By ``name``.
    cost_models : dict of str to type[CostModel]
        By ``name``.
    provider : dict of (str, str) to str
        ``("measure" | "safety" | "cost", name)`` -> name of the distribution
        that provides it (the plugin name where the distribution is unknown).
    failures : list of PluginFailure
        Plugins, hooks and classes that were left out, and why.
    blocked : list of str
        The names blocked by the caller (entry-point or distribution names).
    origins : dict of (str, str) to PluginOrigin
        Same keys as ``provider``: the plugin, distribution and version.
    """

    measures: dict[str, type[ProtectiveMeasure]] = field(default_factory=dict)
    safety_concepts: dict[str, type[SafetyConcept]] = field(default_factory=dict)
    cost_models: dict[str, type[CostModel]] = field(default_factory=dict)
    provider: dict[tuple[str, str], str] = field(default_factory=dict)
    failures: list[PluginFailure] = field(default_factory=list)
    blocked: list[str] = field(default_factory=list)
    origins: dict[tuple[str, str], PluginOrigin] = field(default_factory=dict)

    def measure(self, kind: str) -> type[ProtectiveMeasure]:
        """The measure class of ``kind``; :class:`UnknownNameError` (a KeyError) if none."""
        return self._lookup(self.measures, kind, "measure kind")

    def safety_concept(self, name: str) -> type[SafetyConcept]:
        """The safety concept ``name``; :class:`UnknownNameError` (a KeyError) if none."""
        return self._lookup(self.safety_concepts, name, "safety concept")

    def cost_model(self, name: str) -> type[CostModel]:
        """The cost model ``name``; :class:`UnknownNameError` (a KeyError) if none."""
        return self._lookup(self.cost_models, name, "cost model")

    def _lookup(self, table: dict[str, Any], name: str, what: str) -> Any:
        try:
            return table[name]
        except (KeyError, TypeError):
            pass
        known = sorted(table)
        msg = f"unknown {what} {name!r}"
        close = difflib.get_close_matches(str(name), known, n=3, cutoff=0.6)
        if close:
            msg += "; did you mean " + " or ".join(repr(c) for c in close) + "?"
        if known:
            msg += f" Known: {', '.join(known)}."
        else:
            msg += f"; no {what} is registered."
        if self.failures:
            n = len({f.plugin for f in self.failures})
            msg += (f" ({n} plugin{'s' if n != 1 else ''} failed to load; "
                    "see `rockfall-design plugins`.)")
        raise UnknownNameError(msg, str(name), known)


# ---------------------------------------------------------------------------
# loading


def one_line(text: object) -> str:
    """``text`` as one line: its whitespace (newlines too) collapsed to single spaces."""
    return " ".join(str(text).split())


def normalise_name(name: str) -> str:
    """PEP 503 normalisation, so that ``My_Plugin`` blocks ``my-plugin``."""
    return re.sub(r"[-_.]+", "-", name).lower()


def describe_exception(exc: BaseException) -> str:
    """``Type: message (file:line)`` with the innermost frame outside importlib."""
    text = f"{type(exc).__name__}: {one_line(exc)}" if str(exc) else type(exc).__name__
    frames = [f for f in traceback.extract_tb(exc.__traceback__)
              if not f.filename.startswith("<")]
    if frames:
        text += f" ({frames[-1].filename}:{frames[-1].lineno})"
    return text


def _raise_interrupted(signum: int, frame: Any) -> None:
    raise Interrupted(signum)


@contextlib.contextmanager
def plugin_code() -> Iterator[None]:
    """The block runs plugin code: its output goes to stderr, a real Ctrl-C is marked.

    - ``sys.stdout`` is stderr within the block, so that a plugin that
      prints cannot break ``--json`` (one JSON document on stdout).
    - Where Python's default SIGINT handler is in place (the program used
      as a library, on the main thread), it is swapped for one that raises
      :class:`~rockfall_design.errors.Interrupted`, as the command line's
      handler does. A real Ctrl-C is then told apart from a
      ``KeyboardInterrupt`` that the plugin raises itself: see
      :func:`is_real_interrupt`.
    """
    if threading.current_thread() is not threading.main_thread():
        # sys.stdout and the signal handlers are the process's: swapping them
        # from two threads at once could leave them swapped. (The program
        # calls plugins from the main thread only.)
        yield
        return
    # The C module's getsignal and signal: the signal module's wrappers turn
    # every handler into an enum member if they can (and a function fails that
    # slowly), 2 to 3 microseconds a call, and the optimiser makes 100,000
    # plugin calls. The same functions and handler objects, without the wrapping.
    swap = _signal.getsignal(_signal.SIGINT) is _signal.default_int_handler
    if swap:
        _signal.signal(_signal.SIGINT, _raise_interrupted)
    try:
        with contextlib.redirect_stdout(sys.stderr):
            yield
    finally:
        if swap:
            _signal.signal(_signal.SIGINT, _signal.default_int_handler)


def is_real_interrupt(exc: BaseException) -> bool:
    """Whether ``exc``, raised while plugin code ran, is a real signal, not the plugin's own."""
    return isinstance(exc, Interrupted)



"""Finding and loading the plugins: entry points, registration, the registry built.

:func:`load_registry` loads each entry point on its own (one broken plugin
cannot take the program down), checks its hooks (a misspelt or unmarked hook
is named), calls every hook implementation on its own, validates the classes
and refuses two claims of one name; :func:`default_registry` is the one the
commands use.
"""

from __future__ import annotations

import difflib
import functools
import importlib.metadata
import inspect
import logging
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from importlib.metadata import EntryPoint
from typing import Any

import pluggy
from pydantic import BaseModel, ValidationError

from ..errors import InputError, PluginError
from ..project.messages import did_you_mean
from . import hookspecs
from .manager import (
    NAME_RE,
    SECTIONS,
    SELECTOR_KEY,
    PluginFailure,
    PluginOrigin,
    Registry,
    describe_exception,
    is_real_interrupt,
    normalise_name,
    one_line,
    plugin_code,
)
from .measure import design_role

log = logging.getLogger(__name__)


def _dist_facts(ep: EntryPoint, known: dict[int, tuple[str | None, str | None]]
                ) -> tuple[str | None, str | None]:
    """The name and version of the distribution that declares ``ep``.

    ``dist.name`` and ``dist.version`` each parse the distribution's whole
    metadata file anew: three parses per entry point were two thirds of a
    command's plugin loading (25 ms; about 800 loads in the test suite). One
    parse per distribution here, kept in ``known`` (by the ``dist`` object,
    which the entry points of one distribution share) for one load.
    """
    dist = getattr(ep, "dist", None)
    if dist is None:
        return None, None
    if id(dist) not in known:
        try:
            meta = dist.metadata
            known[id(dist)] = (meta["Name"] or None, meta["Version"] or None)
        except Exception:  # pragma: no cover - broken metadata
            known[id(dist)] = (None, None)
    return known[id(dist)]


@dataclass
class _Plugin:
    name: str
    distribution: str | None
    version: str | None = None

    @property
    def provider(self) -> str:
        return self.distribution or self.name


def _validate_class(cls: Any, section: str, base: type, name_attr: str) -> str | None:
    """Why ``cls`` cannot be registered, or None if it can."""
    if not inspect.isclass(cls):
        return f"returned {cls!r}, which is not a class (return the class, not an instance)"
    if not issubclass(cls, base):
        return f"class {cls.__qualname__} is not a subclass of {base.__name__}"
    label = f"class {cls.__qualname__}"
    name = getattr(cls, name_attr, None)
    if not isinstance(name, str) or not name:
        return f"{label} has no {name_attr} (a non-empty string)"
    if not NAME_RE.fullmatch(name):
        return (f"{label} has {name_attr} {name!r}: use only lower-case letters, digits, "
                "'_' and '-'")
    params = getattr(cls, "Params", None)
    if not (inspect.isclass(params) and issubclass(params, BaseModel)):
        return f"{label} ({name_attr} {name!r}) has no Params (a pydantic model class)"
    if inspect.isabstract(cls):
        missing = ", ".join(sorted(getattr(cls, "__abstractmethods__", ())))
        return f"{label} ({name_attr} {name!r}) does not implement {missing}"
    example = getattr(cls, "example", None)
    if not isinstance(example, dict):
        return f"{label} ({name_attr} {name!r}) has no example (a dict of parameters)"
    selector = SELECTOR_KEY.get(section)
    if selector is not None and selector in example:
        return (f"{label} ({name_attr} {name!r}): example must not contain {selector!r} "
                "(it holds the parameters only)")
    try:
        with plugin_code():
            params.model_validate(example)
    except ValidationError as exc:
        errs = exc.errors()
        first = errs[0] if errs else {"loc": (), "msg": str(exc)}
        where = ".".join(str(p) for p in first.get("loc", ())) or "example"
        more = f" (and {len(errs) - 1} more)" if len(errs) > 1 else ""
        return (f"{label} ({name_attr} {name!r}): example does not validate against "
                f"Params: {where}: {one_line(first.get('msg', ''))}{more}")
    except BaseException as exc:  # a validator of the plugin's own that breaks
        if is_real_interrupt(exc):
            raise
        return (f"{label} ({name_attr} {name!r}): validating the example raised "
                f"{describe_exception(exc)}")
    if section == "measures":
        variables = getattr(cls, "design_variables", {})
        if not isinstance(variables, dict):
            return f"{label} (kind {name!r}): design_variables must be a dict"
        fields = set(params.model_fields)
        for var, bounds in variables.items():
            if var not in fields:
                return (f"{label} (kind {name!r}): design variable {var!r} is not a field "
                        f"of Params ({', '.join(sorted(fields))})")
            try:
                low, high = (float(b) for b in bounds)
            except (TypeError, ValueError):
                return (f"{label} (kind {name!r}): design variable {var!r} needs bounds "
                        f"(low, high), got {bounds!r}")
            # NaN: no default bound, the project (or the optimiser) gives it
            if not (math.isnan(low) or math.isnan(high) or low < high):
                return (f"{label} (kind {name!r}): design variable {var!r} has bounds "
                        f"({low:g}, {high:g}); low must be below high")
        for var in params.model_fields:
            try:
                design_role(params, var)  # the field's own declaration, if any
            except ValueError as exc:
                return f"{label} (kind {name!r}): {exc}"
    return None


def _entry_points(entry_points: Iterable[EntryPoint] | None
                  ) -> list[tuple[EntryPoint, str | None, str | None]]:
    """The entry points of the plugin group, each with its distribution's name and version.

    Sorted by entry-point name, distribution and value: the order of loading
    (and so of the messages) does not depend on the order of ``sys.path``.
    """
    if entry_points is None:
        entry_points = importlib.metadata.entry_points(group=hookspecs.ENTRY_POINT_GROUP)
    known: dict[int, tuple[str | None, str | None]] = {}
    eps = [(ep, *_dist_facts(ep, known)) for ep in entry_points
           if getattr(ep, "group", None) in (None, hookspecs.ENTRY_POINT_GROUP)]
    return sorted(eps, key=lambda e: (e[0].name, e[1] or "", e[0].value))


def load_registry(
    *,
    blocked: Iterable[str] = (),
    entry_points: Iterable[EntryPoint] | None = None,
    extra_plugins: Iterable[tuple[str, object]] = (),
) -> Registry:

    """Load the plugins and build a fresh :class:`Registry`.

    Parameters
    ----------
    blocked
        Entry-point or distribution names not to load (not even import).
    entry_points
        The entry points to load; by default those of the ``rockfall_design``
        group of every installed distribution.
    extra_plugins
        ``(name, module or object)`` pairs registered in addition, as if they
        came from an entry point (no distribution): for tests and embedding.

    Returns
    -------
    Registry
        Every valid class, sorted by name; everything that failed in
        ``failures``.

    Raises
    ------
    PluginError
        If two plugins (or two classes of one plugin) claim one measure kind,
        safety concept or cost-model name. The message names both providers.
    """
    loader = _Loader(blocked)
    for ep, dist_name, dist_version in _entry_points(entry_points):
        loader.register(ep.name, dist_name, ep.load, dist_version)
    for name, obj in extra_plugins:
        loader.register(str(name), None, lambda obj=obj: obj)
    return loader.registry()


class _Loader:
    """The steps of :func:`load_registry`: register each plugin on its own, then collect.

    Every failure is the plugin's own and is kept in :attr:`failures`; the
    other plugins still load.
    """

    def __init__(self, blocked: Iterable[str]) -> None:
        self.blocked_names = sorted(dict.fromkeys(str(b) for b in blocked))
        self.blocked_norm = {normalise_name(b) for b in self.blocked_names}
        self.pm = pluggy.PluginManager(hookspecs.PROJECT_NAME)
        self.pm.add_hookspecs(hookspecs)
        for name in self.blocked_names:
            self.pm.set_blocked(name)
        self.failures: list[PluginFailure] = []
        self.plugins: dict[str, _Plugin] = {}

    def fail(self, plugin: str, dist: str | None, reason: str) -> None:
        self.failures.append(PluginFailure(plugin, dist, one_line(reason)))

    def register(self, name: str, dist: str | None, obtain: Callable[[], object],
                 version: str | None = None) -> None:
        """Import one plugin (``obtain``) and register it, or note why not."""
        pm = self.pm
        if (normalise_name(name) in self.blocked_norm
                or (dist and normalise_name(dist) in self.blocked_norm)):
            pm.set_blocked(name)
            return
        if pm.has_plugin(name) or name in self.plugins:
            other = self.plugins.get(name)
            where = f" (by {other.provider})" if other is not None else ""
            self.fail(name, dist, f"plugin name {name!r} is already taken{where}; "
                      "rename the entry point")
            return
        try:
            with plugin_code():
                obj = obtain()
        except BaseException as exc:  # SystemExit at import time too
            if is_real_interrupt(exc):
                raise
            log.debug("plugin %s failed to import", name, exc_info=True)
            self.fail(name, dist, f"import failed: {describe_exception(exc)}")
            return
        try:
            if pm.register(obj, name=name) is None:  # blocked by name
                return
        except Exception as exc:
            if pm.get_plugin(name) is not None:  # pluggy may leave half a registration
                pm.unregister(name=name)
            if isinstance(exc, ValueError) and "already registered" in str(exc):
                reason = "the same object is already registered under another plugin name"
            else:
                reason = f"cannot register: {describe_exception(exc)}"
            self.fail(name, dist, reason)
            return
        why = self._hooks_problem(name, obj)
        if why:
            pm.unregister(name=name)
            self.fail(name, dist, why)
            return
        self.plugins[name] = _Plugin(name, dist, version)

    def _hooks_problem(self, name: str, obj: object) -> str:
        """Why a registered plugin's hooks are unusable (misspelt, unmarked, none), or ""."""
        pm = self.pm
        try:
            pm.check_pending()
        except pluggy.PluginValidationError:
            unknown = sorted(
                hname for hname, caller in vars(pm.hook).items()
                if not hname.startswith("_") and not caller.has_spec()
                and any(impl.plugin_name == name for impl in caller.get_hookimpls())
            )
            return f"unknown hook {', '.join(unknown)}{_hook_hint(unknown)}"
        impls = [impl for caller in pm.get_hookcallers(obj) or [] for impl in
                 caller.get_hookimpls() if impl.plugin_name == name]
        if impls:
            return ""
        unmarked = [h for h in _hook_names() if callable(getattr(obj, h, None))]
        if unmarked:
            return (f"{', '.join(unmarked)} not marked with @hookimpl "
                    "(from rockfall_design import hookimpl)")
        return f"implements no rockfall_design hook ({', '.join(_hook_names())})"

    def collect(self) -> dict[str, dict[str, list[tuple[_Plugin, type]]]]:
        """Every class each plugin's hooks return, per section and name (duplicates kept).

        Every hook implementation is called on its own, so that a failure is
        the plugin's own.
        """
        found: dict[str, dict[str, list[tuple[_Plugin, type]]]] = {}
        for section, _what, hook_name, base, name_attr, _key in SECTIONS:
            claims = found.setdefault(section, {})
            for impl in getattr(self.pm.hook, hook_name).get_hookimpls():
                plugin = self.plugins.get(impl.plugin_name)
                if plugin is None:  # pragma: no cover - registered outside register()
                    continue
                for cls in self._classes(plugin, impl, hook_name):
                    why = _validate_class(cls, section, base, name_attr)
                    if why is not None:
                        self.fail(plugin.name, plugin.distribution, f"{hook_name}: {why}")
                        continue
                    entries = claims.setdefault(getattr(cls, name_attr), [])
                    if not any(p is plugin and c is cls for p, c in entries):
                        entries.append((plugin, cls))
        return found

    def _classes(self, plugin: _Plugin, impl: Any, hook_name: str) -> list[Any]:
        """What one hook implementation returns (its classes), or [] with the failure noted."""
        if impl.hookwrapper or impl.wrapper:
            self.fail(plugin.name, plugin.distribution,
                      f"{hook_name} must be a plain hook, not a wrapper")
            return []
        try:
            with plugin_code():
                result = impl.function()
        except BaseException as exc:
            if is_real_interrupt(exc):
                raise
            log.debug("hook %s of plugin %s raised", hook_name, plugin.name, exc_info=True)
            self.fail(plugin.name, plugin.distribution,
                      f"{hook_name} raised {describe_exception(exc)}")
            return []
        if result is None:
            return []
        if not isinstance(result, list | tuple):
            self.fail(plugin.name, plugin.distribution,
                      f"{hook_name} returned {type(result).__name__}; return a list of classes")
            return []
        return list(result)

    def registry(self) -> Registry:
        """The registry of what was collected; two claims of one name are an error."""
        found = self.collect()
        duplicates = []
        for section, what, _hook, _base, _attr, _key in SECTIONS:
            for name, entries in sorted(found[section].items()):
                if len(entries) > 1:
                    who = sorted(
                        f"{p.name} (distribution {p.distribution}, class {c.__qualname__})"
                        if p.distribution else f"{p.name} (class {c.__qualname__})"
                        for p, c in entries
                    )
                    duplicates.append(f"{what} {name!r} is provided by both "
                                      + " and ".join(who))
        if duplicates:
            raise PluginError(
                "; ".join(duplicates) + ". Uninstall one of them, or block one with "
                "`--block PLUGIN`."
            )
        tables: dict[str, dict[str, type]] = {}
        provider: dict[tuple[str, str], str] = {}
        origins: dict[tuple[str, str], PluginOrigin] = {}
        for section, _what, _hook, _base, _attr, key in SECTIONS:
            tables[section] = {}
            for name, [(plugin, cls)] in sorted(found[section].items()):
                tables[section][name] = cls
                provider[(key, name)] = plugin.provider
                origins[(key, name)] = PluginOrigin(plugin.name, plugin.distribution,
                                                    plugin.version)
        return Registry(
            measures=tables["measures"],
            safety_concepts=tables["safety_concepts"],
            cost_models=tables["cost_models"],
            provider=provider,
            failures=sorted(self.failures,
                            key=lambda f: (f.plugin, f.distribution or "", f.reason)),
            blocked=self.blocked_names,
            origins=origins,
        )


def _hook_names() -> list[str]:
    return [section[2] for section in SECTIONS]


def _hook_hint(unknown: list[str]) -> str:
    for name in unknown:
        close = difflib.get_close_matches(name, _hook_names(), n=1, cutoff=0.6)
        if close:
            return f" (did you mean {close[0]}?)"
    return f" (known hooks: {', '.join(_hook_names())})"


@functools.lru_cache(maxsize=1)
def _default_registry() -> Registry:
    return load_registry()


def default_registry(blocked: Iterable[str] = ()) -> Registry:
    """The registry of the installed plugins, for the command line.

    Cached for the life of the process when nothing is blocked (clear it with
    ``default_registry.cache_clear()``); a fresh registry otherwise.
    """
    blocked = list(blocked)
    if blocked:
        return load_registry(blocked=blocked)
    return _default_registry()


def blocked_provider(registry: Registry, section: str, name: str) -> str | None:
    """The blocked distribution that provides measure kind (or concept, cost model) ``name``.

    Only for the message of a run that has already failed on an unknown
    name: the blocked plugins are loaded, guarded and apart from
    ``registry``, to say which of them provides it.

    Parameters
    ----------
    registry
        The registry of the run (its ``blocked`` names).
    section
        ``"measure"``, ``"safety"`` or ``"cost"``.
    name
        The unknown name.

    Returns
    -------
    str or None
        The distribution (or plugin) name, or None if no blocked plugin
        provides it (or none can be loaded).
    """
    blocked = {normalise_name(b) for b in registry.blocked}
    if not blocked:
        return None
    eps = [ep for ep, dist, _ in _entry_points(None)
           if normalise_name(ep.name) in blocked
           or (dist and normalise_name(dist) in blocked)]
    if not eps:
        return None
    try:
        found = load_registry(entry_points=eps)
    except PluginError:  # two blocked plugins claiming one name: say nothing
        return None
    return found.provider.get((section, name))


def check_blocked_names(names: Iterable[str]) -> None:
    """Refuse a ``--block`` name that no installed plugin has.

    A misspelt name would otherwise block nothing, silently.

    Parameters
    ----------
    names
        The names given to ``--block``: entry-point or distribution names
        (compared after PEP 503 normalisation).

    Raises
    ------
    InputError
        ``--block NAME: no installed plugin has this name (plugins: ...;
        distributions: ...)``, with "did you mean".
    """
    eps = _entry_points(None)
    plugins = sorted({ep.name for ep, _, _ in eps})
    dists = sorted({d for _, d, _ in eps if d})
    known = {normalise_name(n) for n in (*plugins, *dists)}
    for name in names:
        if normalise_name(name) not in known:
            hint = did_you_mean(name, [*plugins, *dists])
            raise InputError(
                f"--block {name}: no installed plugin has this name{hint} (plugins: "
                f"{', '.join(plugins) or 'none'}; distributions: {', '.join(dists) or 'none'})")


default_registry.cache_clear = _default_registry.cache_clear  # type: ignore[attr-defined]

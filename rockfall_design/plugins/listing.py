"""The registry as plain data: what ``rockfall-design plugins --json`` prints.

(The terminal's tables of the same are drawn by
:func:`rockfall_design.report.terminal.plugins_table`.)
"""

from __future__ import annotations

import math
from typing import Any

from .manager import SECTIONS, Registry, log
from .parameters import describe_parameters


def _parameter_names(cls: type) -> list[str]:
    params = cls.Params  # type: ignore[attr-defined]
    try:
        return list(params.model_json_schema().get("properties", {}))
    except Exception:  # a field type without a JSON schema
        return list(params.model_fields)


def parameter_list(cls: type) -> list[dict[str, Any]]:
    """The described parameters of a class; an empty list if its model cannot be read."""
    try:
        return describe_parameters(cls.Params)  # type: ignore[attr-defined]
    except Exception:  # pragma: no cover - a model pydantic itself cannot describe
        log.debug("cannot describe the parameters of %r", cls, exc_info=True)
        return []


def _design_variables(cls: type) -> list[dict[str, Any]]:
    """A measure's design variables as ``{name, low, high}``; NaN (the project's) as None."""
    out = []
    for name, bounds in (getattr(cls, "design_variables", None) or {}).items():
        low, high = (float(b) for b in bounds)
        out.append({"name": name,
                    "low": None if math.isnan(low) else low,
                    "high": None if math.isnan(high) else high})
    return out


def plugins_json(registry: Registry) -> dict[str, Any]:
    """The registry as plain JSON-able data (``rockfall-design plugins --json``).

    Each measure, safety concept and cost model has its name (``kind`` or
    ``name``), ``summary``, ``provider`` (the distribution, else the plugin
    name), ``plugin``, ``distribution`` and ``version`` (None without a
    distribution), ``parameter_names`` (the field names), and
    ``parameters``: one object per field of its ``Params`` with ``name``,
    ``type``, ``unit``, ``default``, ``required``, ``minimum``,
    ``maximum``, ``exclusive_minimum``, ``exclusive_maximum``, ``options``
    and ``description`` (see :func:`rockfall_design.plugins.parameters.describe_parameters`).
    A measure also has ``design_variables``: ``{name, low, high}`` with None
    for a bound the project supplies.
    """
    out: dict[str, Any] = {}
    for section, _what, _hook, _base, name_attr, key in SECTIONS:
        entries = []
        for name, cls in getattr(registry, section).items():
            origin = registry.origins.get((key, name))
            entry: dict[str, Any] = {
                name_attr: name,
                "summary": str(getattr(cls, "summary", "") or ""),
                "provider": registry.provider.get((key, name), ""),
                "plugin": origin.plugin if origin else None,
                "distribution": origin.distribution if origin else None,
                "version": origin.version if origin else None,
                "parameters": parameter_list(cls),
                "parameter_names": _parameter_names(cls),
            }
            if section == "measures":
                entry["design_variables"] = _design_variables(cls)
            entries.append(entry)
        out[section] = entries
    out["blocked"] = list(registry.blocked)
    out["failures"] = [
        {"plugin": f.plugin, "distribution": f.distribution, "reason": f.reason}
        for f in registry.failures
    ]
    return out

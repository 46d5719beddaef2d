"""What a plugin's parameters are: name, type, unit, default, bounds, options.

:func:`describe_parameters` reads a plugin's pydantic ``Params`` model and
returns one plain, JSON-ready dict per field; ``rockfall-design plugins
--json`` lists them. Nothing here runs plugin code except the model's own
default factories.

Where the unit comes from, first found wins:

1. the field's metadata, ``Field(..., json_schema_extra={"unit": "m"})``;
   ``{"unit": None}`` says explicitly that the parameter has no unit (a
   name, a flag);
2. the trailing parentheses of its description (``"height of the net above
   ground (m)"`` -> ``"m"``, ``"partial factor (-)."`` -> ``"-"``), as plugins
   written against the README's example give it;
3. otherwise None.

The description is the field's ``description``, or else the string literal
written right below the field in the class body (an attribute docstring,
as in the examples of ``hookspecs.py``).
"""

from __future__ import annotations

import ast
import enum
import inspect
import math
import textwrap
import types
import typing
from typing import Any, Literal

import annotated_types
from pydantic import BaseModel
from pydantic.fields import FieldInfo
from pydantic_core import PydanticUndefined

from .measure import design_role

__all__ = ["describe_parameters", "unit_from_description", "UNIT_KEY"]

#: The key of ``json_schema_extra`` that holds a parameter's unit.
UNIT_KEY = "unit"

#: Longest text in trailing parentheses still taken as a unit.
_MAX_UNIT_CHARS = 24

_JSON_TYPES: dict[type, str] = {
    bool: "boolean",
    int: "integer",
    float: "number",
    str: "string",
    dict: "object",
    list: "array",
    tuple: "array",
    set: "array",
    frozenset: "array",
    type(None): "null",
}


def unit_from_description(description: str | None) -> str | None:
    """The unit in the trailing parentheses of a description, or None.

    Parameters
    ----------
    description
        A field's description, e.g. ``"height of the net above ground (m)"``.

    Returns
    -------
    str or None
        The text inside the last, balanced pair of parentheses when the
        description ends with it (a final full stop is allowed), e.g. ``"m"``,
        ``"-"``, ``"currency/(kJ m)"``; None when it does not end so, or the
        text there is empty, longer than 24 characters or holds "e.g." or "i.e."
        (a remark, not a unit).

    Examples
    --------
    >>> unit_from_description("height of the net above ground (m)")
    'm'
    >>> unit_from_description("Partial factor on the energy (-).")
    '-'
    >>> unit_from_description("price per running metre") is None
    True
    """
    if not description:
        return None
    text = description.rstrip().rstrip(".").rstrip()
    if not text.endswith(")"):
        return None
    depth = 0
    for i in range(len(text) - 1, -1, -1):
        if text[i] == ")":
            depth += 1
        elif text[i] == "(":
            depth -= 1
            if depth == 0:
                unit = text[i + 1:-1].strip()
                if not 0 < len(unit) <= _MAX_UNIT_CHARS or "e.g." in unit or "i.e." in unit:
                    return None  # a remark in parentheses, not a unit
                return unit
    return None


def _attribute_docstrings(model: type[BaseModel]) -> dict[str, str]:
    """Field name -> the string literal right below it, over the model's classes."""
    found: dict[str, str] = {}
    for cls in reversed(model.__mro__):
        if not (isinstance(cls, type) and issubclass(cls, BaseModel)) or cls is BaseModel:
            continue
        try:
            source = textwrap.dedent(inspect.getsource(cls))
            body = ast.parse(source).body[0].body  # type: ignore[attr-defined]
        except (OSError, TypeError, SyntaxError, IndexError, AttributeError):
            continue
        for stmt, nxt in zip(body, body[1:], strict=False):
            if (isinstance(stmt, ast.AnnAssign) and isinstance(stmt.target, ast.Name)
                    and isinstance(nxt, ast.Expr) and isinstance(nxt.value, ast.Constant)
                    and isinstance(nxt.value.value, str)):
                found[stmt.target.id] = inspect.cleandoc(nxt.value.value)
    return found


def _strip_annotated(tp: Any) -> tuple[Any, list[Any]]:
    """(the type inside any ``Annotated[...]``, the metadata found on the way)."""
    meta: list[Any] = []
    while typing.get_origin(tp) is typing.Annotated:
        args = typing.get_args(tp)
        tp, meta = args[0], meta + list(args[1:])
    return tp, meta


def _alternatives(tp: Any) -> tuple[list[Any], list[Any]]:
    """(the members of a union, or ``[tp]``; metadata of their ``Annotated`` wrappers)."""
    tp, meta = _strip_annotated(tp)
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
        members: list[Any] = []
        for arg in typing.get_args(tp):
            inner, more = _alternatives(arg)
            members += inner
            meta += more
        return members, meta
    return [tp], meta


def _type_name(tp: Any) -> str:
    if tp is Any:
        return "any"
    origin = typing.get_origin(tp)
    if origin is Literal:
        names = dict.fromkeys(_type_name(type(v)) for v in typing.get_args(tp))
        return " | ".join(names)
    if inspect.isclass(tp) and issubclass(tp, enum.Enum):
        return " | ".join(dict.fromkeys(_type_name(type(m.value)) for m in tp))
    base = origin if origin is not None else tp
    if inspect.isclass(base):
        if issubclass(base, BaseModel):
            return "object"
        for py, name in _JSON_TYPES.items():
            if issubclass(base, py):
                return name
    return getattr(tp, "__name__", str(tp))


def _options(members: list[Any]) -> list[Any] | None:
    options: list[Any] = []
    for tp in members:
        if typing.get_origin(tp) is Literal:
            options += list(typing.get_args(tp))
        elif inspect.isclass(tp) and issubclass(tp, enum.Enum):
            options += [m.value for m in tp]
        elif tp is type(None):
            continue
        else:
            return None  # a free value besides the options: no closed list
    return options or None


def _jsonable(value: Any) -> Any:
    """A value for JSON: non-finite floats as strings ("inf", "nan"), the rest plain."""
    if isinstance(value, enum.Enum):
        value = value.value
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    if isinstance(value, bool | int | float | str) or value is None:
        return value
    if isinstance(value, dict):
        return {str(_jsonable(k)): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple | set | frozenset):
        return [_jsonable(v) for v in value]
    if isinstance(value, BaseModel):
        return _jsonable(value.model_dump(mode="python"))
    return repr(value)


def _bounds(metadata: list[Any]) -> dict[str, Any]:
    out: dict[str, Any] = {"minimum": None, "maximum": None,
                           "exclusive_minimum": None, "exclusive_maximum": None}
    flat: list[Any] = []
    for m in metadata:
        flat += list(m.metadata) if isinstance(m, FieldInfo) else [m]
    for m in flat:
        for attr, key in (("ge", "minimum"), ("le", "maximum"),
                          ("gt", "exclusive_minimum"), ("lt", "exclusive_maximum")):
            value = getattr(m, attr, None)
            if isinstance(m, annotated_types.BaseMetadata | annotated_types.GroupedMetadata) \
                    and value is not None and out[key] is None:
                out[key] = _jsonable(value)
    return out


def _unit(info: FieldInfo, description: str | None) -> str | None:
    extra = info.json_schema_extra
    if isinstance(extra, dict) and UNIT_KEY in extra:
        unit = extra[UNIT_KEY]
        return None if unit is None else str(unit)
    return unit_from_description(description)


def _design(model: type[BaseModel], name: str) -> dict[str, Any] | None:
    """The field's declared design role as JSON (see ``measures.design_role``), or None."""
    try:
        role = design_role(model, name)
    except ValueError:  # a malformed declaration: the registry reports the class
        return None
    if role is None:
        return None
    out: dict[str, Any] = {"role": role.role}
    if role.bounds is not None:
        out["bounds"] = _jsonable(list(role.bounds))
    if role.options is not None:
        out["options"] = _jsonable(list(role.options))
    return out


def describe_parameters(model: type[BaseModel]) -> list[dict[str, Any]]:
    """One JSON-ready dict per field of a plugin's ``Params`` model, in field order.

    Parameters
    ----------
    model
        The pydantic model (a measure's, safety concept's or cost model's
        ``Params``).

    Returns
    -------
    list of dict
        Each with ``name``; ``type`` (JSON-schema names joined by ``" | "``:
        ``"number"``, ``"string | null"``, ...); ``unit`` (see the module's
        docstring; None for none); ``default`` (None when ``required``;
        infinity and NaN as the strings ``"inf"``, ``"nan"``); ``required``;
        ``minimum``, ``maximum``, ``exclusive_minimum``, ``exclusive_maximum``
        (None where the field sets none); ``options`` (the values of a
        ``Literal`` or an ``Enum``, else None); ``description``; and ``design``
        (the design role the field declares in its metadata, as
        ``{"role": "range", "bounds": [low, high]}``, ``{"role": "options",
        "options": [...]}``, ``{"role": "catalogue"}``,
        ``{"role": "catalogue_height"}`` or ``{"role": "catalogue_capacity"}``;
        None for none).
    """
    docstrings: dict[str, str] | None = None
    out = []
    for name, info in model.model_fields.items():
        description = info.description
        if not description:
            if docstrings is None:
                docstrings = _attribute_docstrings(model)
            description = docstrings.get(name)
        members, nested_meta = _alternatives(info.annotation)
        required = info.is_required()
        default: Any = None
        if not required:
            if info.default is not PydanticUndefined:
                default = info.default
            elif info.default_factory is not None:
                try:
                    default = info.default_factory()  # type: ignore[call-arg]
                except Exception:  # a factory that needs the validated data
                    default = None
        entry: dict[str, Any] = {
            "name": name,
            "type": " | ".join(dict.fromkeys(_type_name(tp) for tp in members)),
            "unit": _unit(info, description),
            "default": _jsonable(default),
            "required": required,
            **_bounds(list(info.metadata) + nested_meta),
            "options": _jsonable(_options(members)),
            "description": description,
            "design": _design(model, name),
        }
        out.append(entry)
    return out

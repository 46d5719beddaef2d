"""Messages: one line per problem, ``file:line: key.path: message``.

How a value is described ("got string 'abc'"), "did you mean" for near
misses, where a key path is in the file (line and dotted key), and how a
pydantic error (of a core section or of a plugin's parameters, whose
strictness is checked here by walking the model's annotations) becomes one
line of a :class:`~rockfall_design.errors.ProjectError`.
"""

import contextlib
import contextvars
import difflib
import math
import types
import typing
from collections.abc import Iterator, Mapping, Sequence
from typing import Annotated, Any, Literal, Union

from pydantic import BaseModel, ValidationError
from pydantic_core import PydanticCustomError

from ..errors import ProjectError

# --------------------------------------------------------------------------------------
# Values described, "did you mean", and a validator's error with its place
# --------------------------------------------------------------------------------------

ERROR_TYPE = "rockfall_project"


def fail(message: str, subpath: tuple = ()) -> PydanticCustomError:
    """An error to raise from a validator.

    ``subpath`` is appended to the location pydantic reports, so a model-level
    check can point at the field (or list item) it is about.
    """
    return PydanticCustomError(ERROR_TYPE, "{message}", {"message": message, "subpath": subpath})


def fmt(value: Any) -> str:
    """A number as the user would write it (``1`` rather than ``1.0``)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value):
            return ".nan"
        if math.isinf(value):
            return ".inf" if value > 0 else "-.inf"
        return format(value, ".12g")
    return str(value)


#: False while data from a file that the project names (a catalogue, a price
#: file) is checked: the path may point at any file, so its values are not
#: repeated in messages, only its file, line and key path.
_QUOTE_VALUES: contextvars.ContextVar[bool] = contextvars.ContextVar("quote", default=True)


@contextlib.contextmanager
def unquoted() -> Iterator[None]:
    """Within the block, :func:`describe` names a value's type, never the value."""
    token = _QUOTE_VALUES.set(False)
    try:
        yield
    finally:
        _QUOTE_VALUES.reset(token)


def describe(value: Any) -> str:
    """A short, one-line description of a YAML value for "got ..." messages."""
    if value is None:
        return "null"
    if not _QUOTE_VALUES.get() and isinstance(value, bool | int | float | str):
        return "a boolean" if isinstance(value, bool) else (
            "a string" if isinstance(value, str) else "a number")
    if isinstance(value, bool):
        return f"{fmt(value)} (a boolean)"
    if isinstance(value, int | float):
        return fmt(value)
    if isinstance(value, str):
        text = value if len(value) <= 40 else value[:37] + "..."
        return f"string {text!r}"
    if isinstance(value, list | tuple):
        return f"a list of {len(value)} item{'s' if len(value) != 1 else ''}"
    if isinstance(value, dict):
        return "a mapping"
    return f"a value of type {type(value).__name__}"


def did_you_mean(word: str, candidates: Any) -> str:
    matches = difflib.get_close_matches(word, [str(c) for c in candidates], n=1)
    return f"; did you mean {matches[0]!r}?" if matches else ""


#: key path -> (1-based line, node kind: "map" | "seq" | "scalar")
Lines = dict[tuple, tuple[int, str]]


def key_text(path: tuple, lines: Lines) -> str:
    """Dotted key path as the user sees it: ``rocks.release[1].x``."""
    shown = getattr(lines, "shown", None)
    if shown is not None:
        # One section of a corridor: the key as written in the file
        # (``sections[1].slope...``), see project/corridor.py.
        return key_text(shown(path), lines.file_lines)  # type: ignore[attr-defined]
    text = ""
    prefix: tuple = ()
    for element in path:
        parent = lines.get(prefix)
        if parent is not None and parent[1] == "seq" and isinstance(element, int):
            text += f"[{element}]"
        elif parent is None and isinstance(element, int) and not isinstance(element, bool):
            text += f"[{element}]"
        else:
            text += f".{element}" if text else str(element)
        prefix += (element,)
    return text


def yaml_path(loc: tuple, lines: Lines) -> tuple:
    """Drop list indices that normalisation added (a single zone or material name
    stored as a list): an int under a YAML mapping or scalar that is not one of its keys."""
    path: tuple = ()
    for element in loc:
        parent = lines.get(path)
        if (
            isinstance(element, int)
            and not isinstance(element, bool)
            and parent is not None
            and parent[1] in ("map", "scalar")
            and path + (element,) not in lines
        ):
            continue
        path += (element,)
    return path


def line_of(path: tuple, lines: Lines) -> int | None:
    """Line of ``path`` or of its nearest ancestor present in the file."""
    for end in range(len(path), -1, -1):
        hit = lines.get(path[:end])
        if hit is not None:
            return hit[0]
    return None


# --------------------------------------------------------------------------------------
# pydantic errors -> one line
# --------------------------------------------------------------------------------------

_BOUNDS = {
    "greater_than": (">", "gt"),
    "greater_than_equal": (">=", "ge"),
    "less_than": ("<", "lt"),
    "less_than_equal": ("<=", "le"),
}


def error_message(error: dict) -> str:
    """The plain-language message of one pydantic validation error (its type and context)."""
    kind = error["type"]
    ctx = error.get("ctx") or {}
    value = error.get("input")
    if kind == ERROR_TYPE:
        return str(ctx["message"])
    if kind == "missing":
        return "required key is missing"
    if kind == "extra_forbidden":
        return "unknown key"
    if kind in _BOUNDS:
        op, name = _BOUNDS[kind]
        # integer fields carry integer bounds (ge=1), float fields float bounds (gt=0.0)
        bound = ctx[name]
        noun = (
            "an integer" if isinstance(bound, int) and not isinstance(bound, bool) else "a number"
        )
        # (In a file the project names, the value is not repeated.)
        got = f", got {describe(value)}" if _QUOTE_VALUES.get() else ""
        return f"expected {noun} {op} {fmt(ctx[name])}{got}"
    if kind == "too_short":
        if isinstance(value, str):
            return "must not be empty"
        return f"expected at least {ctx.get('min_length')} item(s), got {ctx.get('actual_length')}"
    if kind == "too_long":
        return f"expected at most {ctx.get('max_length')} item(s), got {ctx.get('actual_length')}"
    if kind in ("dict_type", "model_type", "model_attributes_type"):
        return f"expected a mapping of key: value, got {describe(value)}"
    if kind in ("list_type", "tuple_type"):
        return f"expected a list, got {describe(value)}"
    return str(error.get("msg", kind))


def to_project_error(
    exc: ValidationError, source: str, lines: Lines, model: type[BaseModel]
) -> ProjectError:
    located = []
    for order, error in enumerate(exc.errors()):
        loc = tuple(error["loc"])
        ctx = error.get("ctx") or {}
        if error["type"] == ERROR_TYPE:
            loc += tuple(ctx.get("subpath", ()))
        prefix = ""
        if loc and loc[-1] == "[key]":  # a bad mapping key, e.g. a material named 1
            loc = loc[:-1]
            prefix = "invalid key: "
        path = yaml_path(loc, lines)
        line = line_of(path, lines)
        if error["type"] == "missing":
            message = _missing_message(_navigate(model, loc)[1], loc)
        else:
            message = prefix + error_message(error)
        located.append((line if line is not None else 0, order, path, line, message))
    _, _, path, line, message = min(located, key=lambda item: item[:2])
    return ProjectError(source, line, key_text(path, lines), message)


# --------------------------------------------------------------------------------------
# Plugin parameters: strictness by annotation, and pydantic errors -> one line
# --------------------------------------------------------------------------------------

_UNION_ORIGINS = (Union, types.UnionType)
_SEQUENCE_ORIGINS = (list, tuple, set, frozenset, Sequence)
_MAPPING_ORIGINS = (dict, Mapping)


def annotation_options(annotation: Any) -> list[Any]:
    """The alternatives of an annotation: ``Annotated`` unwrapped, unions flattened."""
    origin = typing.get_origin(annotation)
    if origin is Annotated:
        return annotation_options(typing.get_args(annotation)[0])
    if origin in _UNION_ORIGINS:
        return [option for arg in typing.get_args(annotation) for option in annotation_options(arg)]
    return [annotation]


def _is_model(option: Any) -> bool:
    return isinstance(option, type) and issubclass(option, BaseModel)


def _accepts(options: list[Any]) -> set[str]:
    """Which plain YAML kinds the alternatives accept: any, bool, number, str."""
    kinds = set()
    for option in options:
        origin = typing.get_origin(option)
        if option is bool:
            kinds.add("bool")
        elif option in (int, float):
            kinds.add("number")
        elif option is str:
            kinds.add("str")
        elif origin is Literal:
            for value in typing.get_args(option):
                kinds.add(
                    "bool"
                    if isinstance(value, bool)
                    else "str"
                    if isinstance(value, str)
                    else "number"
                )
        elif option is type(None) or _is_model(option):
            continue
        elif origin in _SEQUENCE_ORIGINS or origin in _MAPPING_ORIGINS:
            continue
        elif option in (list, tuple, dict, set, frozenset):
            continue
        else:  # Any, enums, custom types: left to pydantic
            kinds.add("any")
    return kinds


def _field_of(model: type[BaseModel], key: Any) -> Any:
    """The FieldInfo of ``key`` (a field name or alias) in ``model``, or None."""
    for name, info in model.model_fields.items():
        if key == name or (info.alias is not None and key == info.alias):
            return info
    return None


def strict_problems(annotation: Any, value: Any, loc: tuple, problems: list) -> None:
    """Append ``(loc, message, 1)`` for values pydantic's lax mode would wrongly accept."""
    if isinstance(value, float) and not math.isfinite(value):
        problems.append((loc, f"must be finite, got {fmt(value)}", 1))
        return
    options = annotation_options(annotation)
    kinds = _accepts(options)
    if isinstance(value, bool):
        if "number" in kinds and not kinds & {"bool", "any"}:
            problems.append((loc, f"expected a number, got {describe(value)}", 1))
        return
    if isinstance(value, str):
        if not kinds & {"str", "any"}:
            if "number" in kinds:
                problems.append((loc, f"expected a number, got {describe(value)}", 1))
            elif "bool" in kinds:
                problems.append((loc, f"expected true or false, got {describe(value)}", 1))
        return
    if isinstance(value, int | float):
        if "bool" in kinds and not kinds & {"number", "any", "str"}:
            problems.append((loc, f"expected true or false, got {describe(value)}", 1))
        return
    if isinstance(value, Mapping):
        model = next((o for o in options if _is_model(o)), None)
        mapping = next((o for o in options if typing.get_origin(o) in _MAPPING_ORIGINS), None)
        for key, item in value.items():
            if model is not None:
                info = _field_of(model, key)
                inner = Any if info is None else info.annotation
            elif mapping is not None:
                inner = (typing.get_args(mapping) or (Any, Any))[-1]
            else:
                inner = Any
            strict_problems(inner, item, loc + (key,), problems)
        return
    if isinstance(value, list | tuple):
        sequence = next((o for o in options if typing.get_origin(o) in _SEQUENCE_ORIGINS), None)
        args = typing.get_args(sequence) if sequence is not None else ()
        for i, item in enumerate(value):
            if typing.get_origin(sequence) is tuple and args and args[-1] is not Ellipsis:
                inner = args[i] if i < len(args) else Any
            else:
                inner = args[0] if args else Any
            strict_problems(inner, item, loc + (i,), problems)


def _navigate(model: type[BaseModel], loc: tuple) -> tuple[tuple, Any, Any]:
    """Follow a pydantic error location through the model's annotations.

    Returns the location without union tags (``'float'``,
    ``"literal['a']"``), the model owning the last key (or None) and the
    annotation at the location (``Any`` where it cannot be followed).
    """
    clean: tuple = ()
    annotation: Any = model
    owner: Any = None
    for element in loc:
        options = annotation_options(annotation)
        model_option = next((o for o in options if _is_model(o)), None)
        mapping = next((o for o in options if typing.get_origin(o) in _MAPPING_ORIGINS), None)
        sequence = next((o for o in options if typing.get_origin(o) in _SEQUENCE_ORIGINS), None)
        if isinstance(element, str) and model_option is not None:
            owner = model_option
            info = _field_of(model_option, element)
            annotation = Any if info is None else info.annotation
            clean += (element,)
        elif mapping is not None:
            annotation = (typing.get_args(mapping) or (Any, Any))[-1]
            owner = None
            clean += (element,)
        elif isinstance(element, int) and sequence is not None:
            args = typing.get_args(sequence)
            if typing.get_origin(sequence) is tuple and args and args[-1] is not Ellipsis:
                annotation = args[element] if element < len(args) else Any
            else:
                annotation = args[0] if args else Any
            owner = None
            clean += (element,)
        elif len(options) > 1 and isinstance(element, str):
            continue  # a union member's tag, e.g. ('spin', 'float')
        else:
            annotation = Any
            owner = None
            clean += (element,)
    return clean, owner, annotation


_NUMBER_ERRORS = {"float_type", "float_parsing", "int_type", "int_parsing"}


def param_problems(model: type[BaseModel], errors: list[Any]) -> list[tuple[tuple, str, int]]:
    """Pydantic errors of a plugin model -> (location, one-line message, rank).

    The rank is 0 for an unknown key, reported before anything else, 1
    otherwise. A value that fits no member of a union (pydantic reports one
    error per member) gives one message naming every alternative.
    """
    problems = []
    done: set[tuple] = set()
    for error in errors:
        if error["loc"] and error["loc"][-1] == "[key]":  # e.g. a height key 'abc'
            key_loc, _, _ = _navigate(model, tuple(error["loc"][:-1]))
            problems.append((key_loc, "invalid key: " + _param_message(model, error)[1], 1))
            continue
        loc, owner, annotation = _navigate(model, tuple(error["loc"]))
        options = annotation_options(annotation)
        if len(options) > 1 and len(error["loc"]) > len(loc):  # an error of a union member
            if loc in done:
                continue
            done.add(loc)
            problems.append((loc, _union_message(options, error.get("input")), 1))
            continue
        loc, message = _param_message(model, error)
        problems.append((loc, message, 0 if error["type"] == "extra_forbidden" else 1))
    return problems


def _union_message(options: list[Any], value: Any) -> str:
    """ "expected a number or one of rolling, got ..." for a value that fits no alternative."""
    wanted: list[str] = []
    choices: list[Any] = []
    for option in options:
        origin = typing.get_origin(option)
        if origin is Literal:
            choices.extend(typing.get_args(option))
            continue
        if option in (int, float):
            text = "a number"
        elif option is bool:
            text = "true or false"
        elif option is str:
            text = "a string"
        elif option is type(None):
            text = "null"
        elif _is_model(option) or origin in _MAPPING_ORIGINS or option is dict:
            text = "a mapping"
        elif origin in _SEQUENCE_ORIGINS or option in (list, tuple):
            text = "a list"
        else:
            text = getattr(option, "__name__", str(option))
        if text not in wanted:
            wanted.append(text)
    if choices:
        wanted.append("one of " + ", ".join(fmt(c) for c in choices))
    hint = did_you_mean(value, choices) if isinstance(value, str) and choices else ""
    return f"expected {' or '.join(wanted)}, got {describe(value)}{hint}"


def _missing_message(owner: Any, loc: tuple) -> str:
    """"required key is missing", with what the key holds (its field's description)."""
    info = _field_of(owner, loc[-1]) if owner is not None and loc else None
    about = ""
    if info is not None and info.description:
        about = f" ({info.description.split('. ')[0].strip().rstrip('.')})"
    return f"required key is missing{about}"


def _param_message(model: type[BaseModel], error: Any) -> tuple[tuple, str]:
    kind = error["type"]
    value = error.get("input")
    loc, owner, annotation = _navigate(model, tuple(error["loc"]))
    if kind == "extra_forbidden" and loc:
        key = loc[-1]
        fields = list(owner.model_fields) if owner is not None else []
        listing = f"; expected one of {', '.join(fields)}" if fields else ""
        hint = (did_you_mean(key, fields) if isinstance(key, str) else "") or listing
        return loc, f"unknown key {key!r}{hint}"
    if kind == "missing":
        if loc and isinstance(loc[-1], int):
            return loc[:-1], f"expected more items: item {loc[-1]} is missing"
        return loc, _missing_message(owner, loc)
    if kind == "finite_number":
        return loc, f"must be finite, got {describe(value)}"
    if kind in _NUMBER_ERRORS or kind == "int_from_float":
        noun = "an integer" if kind.startswith("int") else "a number"
        return loc, f"expected {noun}, got {describe(value)}"
    if kind in ("bool_type", "bool_parsing"):
        return loc, f"expected true or false, got {describe(value)}"
    if kind in ("string_type", "string_sub_type"):
        return loc, f"expected a string, got {describe(value)}"
    if kind == "literal_error":
        choices = [
            v
            for o in annotation_options(annotation)
            if typing.get_origin(o) is Literal
            for v in typing.get_args(o)
        ]
        if choices:
            hint = did_you_mean(value, choices) if isinstance(value, str) else ""
            listing = ", ".join(fmt(c) for c in choices)
            return loc, f"expected one of {listing}, got {describe(value)}{hint}"
        return loc, f"expected {error['ctx']['expected']}, got {describe(value)}"
    if kind in ("value_error", "assertion_error"):
        message = str(error.get("msg", ""))
        for prefix in ("Value error, ", "Assertion failed, "):
            message = message.removeprefix(prefix)
        return loc, message
    return loc, error_message(error)

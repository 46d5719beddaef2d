"""Fields: the strict scalar types every section is made of, and the base model.

Numbers must be finite YAML numbers, booleans true or false, strings
strings; unknown keys are rejected with "did you mean". The plugin sections
(``measures:``, ``safety:``) and the plugin parts of the design section are
kept raw here, as plain data with finite numbers, until their plugins are
loaded.
"""

import math
import re
from collections.abc import Callable
from typing import Annotated, Any

from pydantic import (
    AfterValidator,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    model_validator,
)
from pydantic_core import PydanticCustomError

from .inputs import strip_controls
from .messages import describe, did_you_mean, fail, fmt

# --------------------------------------------------------------------------------------
# Strict scalars and the base model
# --------------------------------------------------------------------------------------


def as_number(value: Any, subpath: tuple = ()) -> float:
    """``value`` as a finite float; bools, strings and None are rejected."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise fail(f"expected a number, got {describe(value)}", subpath)
    try:
        number = float(value)
    except OverflowError:
        raise fail("number is too large", subpath) from None
    if not math.isfinite(number):
        raise fail(f"must be finite, got {fmt(number)}", subpath)
    return number


def as_integer(value: Any) -> int:
    """``value`` as an int; integral floats (``1000.0``) are accepted, bools are not."""
    if isinstance(value, float) and not isinstance(value, bool):
        if not math.isfinite(value):
            raise fail(f"must be finite, got {fmt(value)}")
        if value.is_integer():
            return int(value)
    if isinstance(value, bool) or not isinstance(value, int):
        raise fail(f"expected an integer, got {describe(value)}")
    return value


def _as_string(value: Any) -> str:
    if not isinstance(value, str):
        raise fail(f"expected a string, got {describe(value)}")
    return value


def _as_bool(value: Any) -> bool:
    if not isinstance(value, bool):
        raise fail(f"expected true or false, got {describe(value)}")
    return value


def as_list(value: Any) -> list:
    """``value`` as a list (a tuple converted); anything else is a validation error."""
    if isinstance(value, tuple):
        return list(value)
    if not isinstance(value, list):
        raise fail(f"expected a list, got {describe(value)}")
    return value


def number_pair(what: str) -> Callable[[Any], tuple[float, float]]:
    """Validator for a ``[a, b]`` pair of finite numbers, ``what`` naming it in messages."""

    def check(value: Any) -> tuple[float, float]:
        if not isinstance(value, list | tuple) or len(value) != 2:
            raise fail(f"expected a pair {what}, got {describe(value)}")
        return (as_number(value[0], (0,)), as_number(value[1], (1,)))

    return check


def choice(*options: str) -> Callable[[Any], str]:
    """Validator for one of the strings ``options``, with "did you mean" on a near miss."""

    def check(value: Any) -> str:
        if value not in options or not isinstance(value, str):
            hint = did_you_mean(value, options) if isinstance(value, str) else ""
            raise fail(f"expected one of {', '.join(options)}, got {describe(value)}{hint}")
        return value

    return check


def none_as_empty(value: Any) -> Any:
    """An empty section (``analysis:`` with nothing under it) means "all defaults"."""
    return {} if value is None else value


Number = Annotated[float, BeforeValidator(as_number)]
Integer = Annotated[int, BeforeValidator(as_integer)]
String = Annotated[str, BeforeValidator(_as_string)]
Boolean = Annotated[bool, BeforeValidator(_as_bool)]
#: Text shown to people (a project's name): control characters, which would
#: steer the terminal (window title, clear screen), removed; one line.
Title = Annotated[String, AfterValidator(strip_controls)]
#: Free text of several lines (a description): control characters removed.
Prose = Annotated[String, AfterValidator(lambda s: strip_controls(s, lines=True))]
#: Newlines, tabs and the characters :func:`strip_controls` removes: none of
#: them belongs in a name, a label or a currency.
_NOT_ONE_LINE = re.compile("[\x00-\x1f\x7f-\x9f\u2028\u2029\u202a-\u202e\u2066-\u2069]")


def one_line(value: Any, subpath: tuple = ()) -> Any:
    """``value`` if it is not text, or text of one line without control characters.

    A name, a label or a currency from a file is shown in tables, headings
    and figures: a newline there would start a heading of its own in
    report.md, and a control character steer the terminal. Refused at the
    key, not silently changed: the file says something else than intended.
    """
    if isinstance(value, str) and _NOT_ONE_LINE.search(value):
        raise fail("expected one line of text without control characters (a newline, a "
                    "tab, an escape), got " + describe(value), subpath)
    return value


def lines_of_text(value: Any, where: tuple = ()) -> None:
    """Every key and text in ``value`` one line without control characters (:func:`one_line`).

    A cost catalogue's currency and product names are shown in headings,
    tables and figures: a newline there wrote a heading of its own into
    report.md.
    """
    if isinstance(value, dict):
        for key, item in value.items():
            one_line(key, (*where, key))
            lines_of_text(item, (*where, key))
    elif isinstance(value, list):
        for j, item in enumerate(value):
            lines_of_text(item, (*where, j))
    else:
        one_line(value, where)


#: Text of one line without control characters (a name, a label, a currency).
Label = Annotated[String, AfterValidator(one_line)]
Fraction = Annotated[Number, Field(ge=0.0, le=1.0)]
NonNegative = Annotated[Number, Field(ge=0.0)]
Positive = Annotated[Number, Field(gt=0.0)]


class SectionModel(BaseModel):
    """Base of every section: unknown keys are rejected with "did you mean"."""

    model_config = ConfigDict(extra="forbid", validate_default=False)

    @model_validator(mode="before")
    @classmethod
    def _check_mapping_and_keys(cls, data: Any) -> Any:
        if isinstance(data, cls):
            return data
        if not isinstance(data, dict):
            raise fail(f"expected a mapping of key: value, got {describe(data)}")
        fields = list(cls.model_fields)
        for key in data:
            if key not in cls.model_fields:
                if isinstance(key, str):
                    hint = did_you_mean(key, fields) or f"; expected one of {', '.join(fields)}"
                else:
                    hint = f"; keys must be names, expected one of {', '.join(fields)}"
                raise fail(f"unknown key {key!r}{hint}", (key,))
        return data


# --------------------------------------------------------------------------------------
# Plugin sections: measures and safety, kept raw until the plugins are loaded
# --------------------------------------------------------------------------------------


def plugin_data(value: Any, subpath: tuple = (), *, number_keys: bool = False) -> Any:
    """Plain YAML data for a plugin, checked and copied.

    Accepts null, booleans, strings, integers, finite floats, lists and
    mappings with string keys (recursively); NaN and infinities, non-string
    keys and other YAML types (``!!binary``, ``!!set``) are rejected at the
    offending node. With ``number_keys``, finite numbers are accepted as keys
    too (a price table by height, ``{2: 350, 3: 420}``).
    """
    if value is None or isinstance(value, bool | str | int):
        return value
    if isinstance(value, float):
        if not math.isfinite(value):
            raise fail(f"must be finite, got {fmt(value)}", subpath)
        return value
    if isinstance(value, list | tuple):
        return [plugin_data(item, subpath + (i,), number_keys=number_keys)
                for i, item in enumerate(value)]
    if isinstance(value, dict):
        copied = {}
        for key, item in value.items():
            number = isinstance(key, int | float) and not isinstance(key, bool)
            if number and number_keys:
                if not math.isfinite(key):
                    raise fail(f"keys must be finite, got {fmt(key)}", subpath + (key,))
            elif not isinstance(key, str):
                raise fail(f"keys must be names, got {describe(key)}", subpath + (key,))
            copied[key] = plugin_data(item, subpath + (key,), number_keys=number_keys)
        return copied
    raise fail(f"unsupported value: {describe(value)}", subpath)



def check_typed_item(item: Any, i: int, expected: str) -> None:
    """An entry of ``measures:`` or ``design.candidates``: a mapping with a string ``type``."""
    if not isinstance(item, dict):
        raise fail(f"expected {expected}, got {describe(item)}", (i,))
    if "type" not in item:
        raise fail("required key 'type' is missing (the kind of measure, e.g. fence)", (i,))
    kind = item["type"]
    if not isinstance(kind, str):
        raise fail(f"expected the name of a measure type, got {describe(kind)}", (i, "type"))
    if not kind.strip():
        raise fail("must not be empty (the kind of measure, e.g. fence)", (i, "type"))

def parse_measures(value: Any) -> list[dict[str, Any]]:
    """``measures:``: a list of mappings, each with a non-empty string ``type``."""
    if value is None:
        return []
    if not isinstance(value, list | tuple):
        raise fail(f"expected a list of measures (mappings with a type), got {describe(value)}")
    measures = []
    for i, item in enumerate(value):
        check_typed_item(item, i, "a measure (a mapping such as {type: fence, x: 70, ...})")
        measures.append(plugin_data(item, (i,)))
    return measures


DEFAULT_CONCEPT = "spang"


def parse_safety(value: Any) -> dict[str, Any]:
    """``safety:``: a mapping with a string ``concept`` (default spang), listed first."""
    if value is None:
        return {"concept": DEFAULT_CONCEPT}
    if not isinstance(value, dict):
        raise fail(
            f"expected a mapping (concept: NAME and its parameters), got {describe(value)}"
        )
    concept = value.get("concept", DEFAULT_CONCEPT)
    if not isinstance(concept, str):
        raise fail(
            f"expected the name of a safety concept, got {describe(concept)}", ("concept",)
        )
    if not concept.strip():
        raise fail("must not be empty (the name of a safety concept, e.g. spang)", ("concept",))
    rest = plugin_data({k: v for k, v in value.items() if k != "concept"})
    return {"concept": concept, **rest}


def plain_copy(value: Any, what: str) -> Any:
    """:func:`plugin_data` for data a program passes in: problems are a ValueError (a bug)."""
    try:
        return plugin_data(value)
    except PydanticCustomError as exc:
        where = "".join(f"[{p!r}]" for p in (exc.context or {}).get("subpath", ()))
        raise ValueError(f"{what}{where}: {exc.message()}") from None

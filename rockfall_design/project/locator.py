"""Locator: where the nodes of some YAML data are, and plugin parameters checked there.

A :class:`Locator` makes ``file:line: key.path: message`` errors for a key
path, and validates a plugin's parameters with its model, strictly, the
problem located in the file; :func:`params_problem` does the same for data
that is not in a file.
"""

import contextlib
import sys
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from pydantic import BaseModel, ValidationError

from ..errors import Interrupted, PluginError, ProjectError
from .messages import (
    describe,
    did_you_mean,
    key_text,
    line_of,
    param_problems,
    strict_problems,
    unquoted,
    yaml_path,
)


class Locator:
    """Where the nodes of some YAML data are: a file, its line map and a key prefix.

    The project file has one (:attr:`.Project.locator`); so has each part of
    the design section that may come from another file: the product
    catalogue (:attr:`.Design.products_locator`) and the cost model's
    parameters (:attr:`.Design.costs_locator`). Key paths given to the methods
    are relative to the data's root; the prefix locates that root in its
    file (``("design", "products")`` for an inline catalogue, ``()`` for a
    catalogue file). Errors read ``file:line: key.path: message``.

    Parameters
    ----------
    source
        The file as the user named it.
    lines
        Key path -> (line, node kind), from the YAML loader.
    prefix
        Key path of the data's root in that file.
    """

    def __init__(
        self, source: str, lines: dict, prefix: Sequence[str | int] = (), *, quote: bool = True
    ) -> None:
        self.source = source
        self._lines = lines
        self.prefix = tuple(prefix)
        #: False for a file the project names: its values are not quoted in messages.
        self.quote = quote

    def __repr__(self) -> str:
        return f"Locator({self.source!r}, prefix={self.prefix!r})"

    def line(self, path: Sequence[str | int]) -> int | None:
        """Line of ``path`` (or of its nearest existing ancestor); None if unknown."""
        return line_of(yaml_path(self.prefix + tuple(path), self._lines), self._lines)

    def error_at(self, path: Sequence[str | int], message: str) -> ProjectError:
        """A :class:`ProjectError` at ``path`` (see :meth:`.Project.error_at`)."""
        full = yaml_path(self.prefix + tuple(path), self._lines)
        return ProjectError(
            self.source, line_of(full, self._lines), key_text(full, self._lines), message
        )

    def unknown_name(
        self, path: Sequence[str | int], name: Any, candidates: Iterable[str], what: str
    ) -> ProjectError:
        """An unknown name with "did you mean" (see :meth:`.Project.unknown_name`)."""
        names = [str(c) for c in candidates]
        hint = did_you_mean(name, names) if isinstance(name, str) else ""
        available = f" (available: {', '.join(names)})" if names else " (none available)"
        return self.error_at(path, f"unknown {what} {name!r}{hint}{available}")

    def validate_params(
        self,
        path: Sequence[str | int],
        model: type[BaseModel],
        data: Any,
        *,
        drop: Iterable[str] = (),
    ) -> BaseModel:
        """Validate plugin parameters at ``path`` (see :meth:`.Project.validate_params`)."""
        path = tuple(path)
        if not isinstance(data, Mapping):
            raise self.error_at(path, f"expected a mapping of key: value, got {describe(data)}")
        dropped = set(drop)
        data = {key: value for key, value in data.items() if key not in dropped}
        with contextlib.nullcontext() if self.quote else unquoted():
            instance, problems = _check_params(model, data)
        if instance is not None:
            return instance
        # unknown keys first (a misspelt key also makes a required one "missing"),
        # then the problem earliest in the file
        located = []
        for order, (loc, message, rank) in enumerate(problems):
            full = yaml_path(self.prefix + path + loc, self._lines)
            line = line_of(full, self._lines)
            located.append((rank, line if line is not None else 0, order, full, message))
        *_, full, message = min(located, key=lambda item: item[:3])
        raise ProjectError(
            self.source, line_of(full, self._lines), key_text(full, self._lines), message
        )


def _check_params(
    model: type[BaseModel], data: Mapping[str, Any]
) -> tuple[BaseModel | None, list[tuple[tuple, str, int]]]:
    """``(instance, [])`` if ``data`` is valid for ``model``, else ``(None, problems)``."""
    problems: list[tuple[tuple, str, int]] = []  # (location, message, rank)
    strict_problems(model, data, (), problems)
    try:
        # A plugin's validators are plugin code: what they print goes to stderr.
        with contextlib.redirect_stdout(sys.stderr):
            instance = model.model_validate(data)
    except ValidationError as exc:
        problems.extend(param_problems(model, exc.errors()))
    except BaseException as exc:
        # pydantic turns a validator's ValueError or AssertionError into a
        # validation error; anything else is a bug in the plugin's model
        # (SystemExit too), unless it is a real Ctrl-C.
        if isinstance(exc, Interrupted):
            raise
        raise PluginError(
            f"the parameter model {model.__module__}.{model.__qualname__} failed while "
            f"validating: {type(exc).__name__}: {exc}; this is a bug in the plugin, "
            "not in the project"
        ) from exc
    else:
        if not problems:
            return instance, []
    return None, problems


def params_problem(model: type[BaseModel], data: Mapping[str, Any]) -> tuple[tuple, str] | None:
    """The first problem of plugin parameters ``data`` for ``model``, or None if valid.

    The same strict checks and one-line messages as
    :meth:`.Project.validate_params`, for data that is not in a file (the
    optimiser's candidates): unknown keys first, then pydantic's order.

    Returns
    -------
    tuple of (key path, message) or None
        e.g. ``(("width",), "expected a number > 0, got -1")``.
    """
    return validated_params(model, data)[1]


def validated_params(model: type[BaseModel], data: Mapping[str, Any]
                     ) -> tuple[BaseModel | None, tuple[tuple, str] | None]:
    """``(instance, None)`` for valid plugin parameters, else ``(None, first problem)``.

    :func:`params_problem` with the instance it validated, for a caller that
    builds the measure (the optimiser builds thousands: validating twice
    cost a quarter of building one).
    """
    instance, problems = _check_params(model, dict(data))
    if not problems:
        return instance, None
    loc, message, _ = min(problems, key=lambda item: item[2])
    return None, (loc, message)

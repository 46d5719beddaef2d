"""The numbers a run takes from its caller: one set of bounds and messages.

The command line (``--rocks``, ``--seed``, ``--workers``, ``--bootstrap``)
and the Python API (``rocks=``, ``seed=``, ``workers=``, ``bootstrap=``)
check them here, so that both refuse the same values with the same words:
``simulate(p, rocks=2.5)`` is "rocks: expected a whole number, got 2.5", as
``--rocks 2.5`` is "argument --rocks: expected a whole number, got '2.5'".
Light on purpose: the command line imports it to parse its options.
"""

from __future__ import annotations

import numbers
import operator
from typing import Any

from .errors import InputError

__all__ = [
    "DEFAULT_FLAT_DEG",
    "DEFAULT_TOLERANCE_M",
    "MAX_BOOTSTRAP",
    "MAX_ROCKS",
    "ArgumentError",
    "ArgumentTypeError",
    "bounds_problem",
    "whole_number",
]

#: Most rocks of one run (as ``rockfall_design.project.MAX_ROCKS``, here
#: without importing pydantic for every ``--help``).
MAX_ROCKS = 1_000_000_000
#: Most bootstrap replicates of a calibration.
MAX_BOOTSTRAP = 2000

# The defaults of ``section`` (rockfall_design.terrain), here so that its
# --help says them without importing the terrain room.
#: Vertical tolerance (m) of the simplified section: 5 cm, well below the
#: roughness heights calibrated for talus (Bourrier et al. 2009 report
#: 0.1-0.5 m) and below the vertical accuracy of airborne LiDAR DEMs (USGS
#: 3DEP quality level 2: 10 cm RMSE). ILLUSTRATIVE as a default; state yours.
DEFAULT_TOLERANCE_M = 0.05
#: Below this slope (deg) the ground counts as flat and the fall line ends:
#: rocks come to rest on slopes below about 5-10 deg (rolling friction of
#: 0.1-0.2, e.g. Dorren 2003), so a path that reaches 3 deg has left the
#: slope. ILLUSTRATIVE default; set it per project.
DEFAULT_FLAT_DEG = 3.0


class ArgumentError(InputError, ValueError):
    """A number given to an API function that the command line would refuse too.

    Exit code 2 (an :class:`~rockfall_design.errors.InputError`). Also a
    :class:`ValueError`, as Python's convention has it for an argument of
    the right type with a wrong value (numpy's ``AxisError`` is a
    ``ValueError`` and an ``IndexError`` alike): a user's ``except
    ValueError`` catches ``simulate(p, rocks=2.5)`` and ``seed=-1``.

    Attributes
    ----------
    key : str
        The keyword argument, e.g. ``"rocks"``.
    problem : str
        What is wrong with it, in the command line's words.
    """

    def __init__(self, key: str, problem: str) -> None:
        super().__init__(f"{key}: {problem}")
        self.key = key
        self.problem = problem


class ArgumentTypeError(ArgumentError, TypeError):
    """An argument that is not a number at all (``rocks="10"``, ``seed=True``, ``None``).

    A :class:`TypeError` too, as Python raises for a wrong type; still an
    :class:`ArgumentError` (so a ``ValueError`` and an ``InputError``, exit
    code 2), so that one ``except`` catches every refused argument.
    """


def bounds_problem(value: int, low: int, high: int | None, what: str) -> str | None:
    """What is wrong with the whole number ``value`` for ``low <= value <= high``, or None.

    Parameters
    ----------
    value : int
    low, high : int
        The bounds (``high`` None: no upper bound).
    what : str
        What the number is ("number", "seed", "number of workers").
    """
    if value < low:
        return f"expected a {what} >= {low}, got {value}"
    if high is not None and value > high:
        return f"expected a {what} <= {high:,}, got {value:,}"
    return None


def whole_number(value: Any, key: str, low: int, high: int | None = None,
                 what: str = "number") -> int:
    """``value`` as an int, if it is a whole number (not a bool, float or text) within bounds.

    Parameters
    ----------
    value
        What the caller gave: an int or numpy integer.
    key : str
        The keyword it was given as, for the message.
    low, high, what
        As :func:`bounds_problem`.

    Raises
    ------
    ArgumentError
        ``KEY: expected a whole number, got VALUE`` for a real number that is
        not whole, or a bound's message (a ``ValueError`` too).
    ArgumentTypeError
        The same words for a value that is not a number (text, None, a
        boolean): a ``TypeError`` too.
    """
    if isinstance(value, bool):
        raise ArgumentTypeError(key, f"expected a whole number, got {value!r} (a boolean)")
    try:
        number = operator.index(value)  # int and numpy integers; not 2.5, "10" or 10.0
    except TypeError:
        # A real number that is not whole (2.5, 10.0) is a wrong value; anything
        # else ("10", None, a list) a wrong type.
        kind = ArgumentError if isinstance(value, numbers.Real) else ArgumentTypeError
        raise kind(key, f"expected a whole number, got {value!r}") from None
    problem = bounds_problem(number, low, high, what)
    if problem is not None:
        raise ArgumentError(key, problem)
    return number

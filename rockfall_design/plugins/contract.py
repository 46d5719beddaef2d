"""What plugin methods may raise and must return: the checks of their results.

Every call of the core into a plugin object is checked here after it
returns (by :mod:`rockfall_design.plugins.proxy`): the type of the value,
and for a footprint every number the engine will use, so that a plugin's
bug is reported as the plugin's, by name, before it can reach the engine.
"""

from __future__ import annotations

import inspect
import math
import numbers
import reprlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .concept import Check
from .manager import SECTIONS
from .measure import Barrier, BarrierBehaviour, ProfileEdit, Quantity


def _is_number(value: Any) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _is_number_dict(value: Any) -> bool:
    # NaN is never a property or a quantity; infinity is allowed, since a
    # measure may state "no capacity given" as capacity_kj = inf (see Barrier).
    return isinstance(value, dict) and all(
        isinstance(k, str) and _is_number(v) and not math.isnan(v) for k, v in value.items()
    )


def _is_cost(value: Any) -> bool:
    return _is_number(value) and math.isfinite(value) and value >= 0


def _is_bill(value: Any) -> bool:
    # A bill is priced as amount x unit price: an amount must be a finite number >= 0.
    return isinstance(value, list) and all(
        isinstance(q, Quantity) and isinstance(q.name, str) and q.name
        and isinstance(q.unit, str) and _is_number(q.amount) and math.isfinite(q.amount)
        and q.amount >= 0 and (q.product is None or isinstance(q.product, str))
        and (q.size is None or (_is_number(q.size) and math.isfinite(q.size)))
        for q in value)


def _is_check_list(value: Any) -> bool:
    return isinstance(value, list) and all(isinstance(c, Check) for c in value)


@dataclass(frozen=True)
class _Contract:
    """What one plugin method may raise by contract, and what it must return.

    Attributes
    ----------
    raises : tuple of exception types
        Exceptions that are part of the contract: they reach the caller as
        they are, and the caller gives them their documented meaning.
    returns : callable or None
        Whether a returned value is acceptable (None: anything is).
    expected : str
        What ``returns`` accepts, for the error message.
    """

    raises: tuple[type[Exception], ...] = ()
    returns: Callable[[Any], bool] | None = None
    expected: str = ""
    #: ``problem(value, plugin, args)``: what is wrong with an accepted value's
    #: content (one line), or None.
    problem: Callable[[Any, Any, tuple], str | None] | None = None


_NUMBER_DICT = _Contract((), _is_number_dict, "a dict of str to number (not NaN)")

#: (provider key, method) -> contract; ``__init__`` is the class being instantiated.
CONTRACTS: dict[tuple[str, str], _Contract] = {
    ("measure", "__init__"): _Contract(),
    # ValueError: the measure does not fit on the section (bad input, exit 2).
    ("measure", "footprint"): _Contract(
        (ValueError,), lambda v: isinstance(v, Barrier | ProfileEdit),
        "a Barrier or a ProfileEdit", lambda v, m, args: footprint_problem(v, m, *args)),
    ("measure", "design_properties"): _NUMBER_DICT,
    ("measure", "quantities"): _NUMBER_DICT,
    ("measure", "bill"): _Contract((), _is_bill, "a list of Quantity (a name, a unit, an "
                                   "amount that is a finite number >= 0)"),
    ("measure", "label"): _Contract((), lambda v: isinstance(v, str), "a str"),
    ("safety", "__init__"): _Contract(),
    ("safety", "checks"): _Contract((), _is_check_list, "a list of Check"),
    ("cost", "__init__"): _Contract(),
    # KeyError or ValueError: no price for this measure (the optimiser skips the design).
    ("cost", "cost"): _Contract((KeyError, ValueError), _is_cost, "a finite number >= 0"),
    ("cost", "price"): _Contract((KeyError, ValueError), _is_cost, "a finite number >= 0"),
    ("cost", "missing_price"): _Contract((), lambda v: v is None or isinstance(v, str),
                                         "a str or None"),
}

#: Provider key -> the noun a message uses for such a plugin.
PLUGIN_NOUN = {"measure": "measure", "safety": "safety concept", "cost": "cost model"}


def identify_plugin(plugin: Any) -> tuple[str, str]:
    """``(provider key, name)`` of a measure, safety concept or cost model (class or object)."""
    cls = plugin if inspect.isclass(plugin) else type(plugin)
    known = _IDENTIFIED.get(cls)
    if known is not None:
        return known
    for _section, _what, _hook, base, name_attr, key in SECTIONS:
        if issubclass(cls, base):
            found = key, str(getattr(cls, name_attr, "?"))
            # Once per class: every call into a plugin names it, about 100,000
            # in one optimise. (A class's name attribute is read once; the
            # registry keeps the name it was registered under anyway.)
            _IDENTIFIED[cls] = found
            return found
    raise TypeError(f"{cls.__qualname__} is not a measure, safety concept or cost model")


#: ``identify_plugin``'s answers by class.
_IDENTIFIED: dict[type, tuple[str, str]] = {}


def _number(value: Any, name: str, low: float, high: float = math.inf, *,
            low_open: bool = False, allow_inf: bool = False) -> str | None:
    """Why ``value`` is not a real number in [low, high] (or (low, high]), or None."""
    if not _is_number(value):
        return f"{name} = {reprlib.repr(value)}: expected a number"
    v = float(value)
    if math.isnan(v) or (math.isinf(v) and not (allow_inf and v > 0)):
        return f"{name} = {v}: expected a finite number"
    if v < low or (low_open and v == low) or v > high:
        bounds = f"{'>' if low_open else '>='} {low:g}" + (
            f" and <= {high:g}" if math.isfinite(high) else "")
        return f"{name} = {v:g}: expected a number {bounds}"
    return None


def _x_problem(x: float, name: str, measure: Any, section: Any) -> str | None:
    """A station outside the section is the plugin's fault when the measure's own x is inside.

    (When the measure's ``x`` is outside too, it is the project's:
    :func:`~rockfall_design.judge.evaluation.place_measures` says so.)
    """
    x0, x1 = float(section.x[0]), float(section.x[-1])
    if x0 <= x <= x1:
        return None
    own = getattr(getattr(measure, "params", None), "x", None)
    if _is_number(own) and x0 <= float(own) <= x1:
        return (f"{name} = {x:g} m: outside the section ({x0:g} to {x1:g} m), although the "
                f"measure's x = {float(own):g} m is on it")
    return None


def _mel_problem(fp: Barrier) -> str | None:
    """What is wrong with a barrier's optional SEL/MEL figures (NaN: not given), or None."""
    for name in ("sel_kj", "elongation_sel_m", "elongation_mel_m"):
        value = getattr(fp, name)
        if _is_number(value) and math.isnan(float(value)):
            continue
        why = _number(value, name, 0.0, low_open=True)
        if why:
            return why
    if not math.isnan(float(fp.sel_kj)) and not fp.sel_kj < fp.capacity_kj:
        return (f"sel_kj = {fp.sel_kj:g}: expected it below capacity_kj = {fp.capacity_kj:g} "
                "(the SEL is a fraction of the MEL)")
    return None


def footprint_problem(fp: Barrier | ProfileEdit, measure: Any, section: Any) -> str | None:
    """What is wrong with a footprint's fields, or None: every value the engine will use.

    A barrier needs a finite ``x`` on the section, a finite ``height_m`` > 0
    (a NaN height would catch every rock), ``capacity_kj`` >= 0 (``inf``
    for none given), a :class:`BarrierBehaviour`, ``restitution`` in 0..1,
    ``gap_m`` >= 0 and ``spacing_m`` > 0 with the gap no wider than the
    spacing, ``slope_cos`` in (0, 1], and SEL/MEL figures that are NaN (not
    given) or > 0, the SEL below the capacity. A profile edit needs a
    finite stretch ``x_start`` < ``x_end``,
    points of shape (k, 2), k >= 2, finite, x strictly increasing from
    ``x_start`` to ``x_end`` and meeting the ground there, a finite catch
    range ``catch_from`` <= ``catch_to`` on the section, and a material
    name or None.
    """
    if isinstance(fp, Barrier):
        return _barrier_problem(fp, measure, section)
    return _edit_problem(fp, measure, section)


def _barrier_problem(fp: Barrier, measure: Any, section: Any) -> str | None:
    """What is wrong with a barrier's fields, or None (see :func:`footprint_problem`)."""
    why = (_number(fp.x, "x", -math.inf)
           or _number(fp.height_m, "height_m", 0.0, low_open=True)
           or _number(fp.capacity_kj, "capacity_kj", 0.0, allow_inf=True))
    if why:
        return why
    b = fp.behaviour
    if isinstance(b, bool) or not isinstance(b, int) or b not in set(BarrierBehaviour):
        names = ", ".join(m.name for m in BarrierBehaviour)
        return f"behaviour = {reprlib.repr(b)}: expected a BarrierBehaviour ({names})"
    why = (_number(fp.restitution, "restitution", 0.0, 1.0)
           or _number(fp.gap_m, "gap_m", 0.0)
           or _number(fp.spacing_m, "spacing_m", 0.0, low_open=True))
    if why:
        return why
    why = (_number(fp.slope_cos, "slope_cos", 0.0, 1.0, low_open=True)
           or _mel_problem(fp))
    if why:
        return why
    if fp.gap_m > fp.spacing_m:
        return (f"gap_m = {fp.gap_m:g} wider than spacing_m = {fp.spacing_m:g}: "
                "the gaps lie between the blocks")
    return _x_problem(float(fp.x), "x", measure, section)


def _edit_problem(fp: ProfileEdit, measure: Any, section: Any) -> str | None:
    """What is wrong with a profile edit's fields, or None (see :func:`footprint_problem`)."""
    why = (_number(fp.x_start, "x_start", -math.inf)
           or _number(fp.x_end, "x_end", -math.inf)
           or _number(fp.catch_from, "catch_from", -math.inf)
           or _number(fp.catch_to, "catch_to", -math.inf))
    if why:
        return why
    if not fp.x_start < fp.x_end:
        return f"x_start = {fp.x_start:g} not below x_end = {fp.x_end:g}"
    if not fp.catch_from <= fp.catch_to:
        return f"catch_from = {fp.catch_from:g} above catch_to = {fp.catch_to:g}"
    if fp.material is not None and (not isinstance(fp.material, str) or not fp.material):
        return f"material = {reprlib.repr(fp.material)}: expected a material name or None"
    return _edit_points_problem(fp, measure, section)


def _edit_points_problem(fp: ProfileEdit, measure: Any, section: Any) -> str | None:
    """What is wrong with a profile edit's points against its stretch and the ground, or None."""
    try:
        points = np.asarray(fp.points, dtype=float)
    except (TypeError, ValueError):
        return f"points = {reprlib.repr(fp.points)}: expected an array of [x, y] (m)"
    if points.ndim != 2 or points.shape[1] != 2 or points.shape[0] < 2:
        return f"points of shape {points.shape}: expected (k, 2) with k >= 2"
    if not np.isfinite(points).all():
        return "points that are not all finite"
    if not (np.diff(points[:, 0]) > 0).all():
        return "points whose x does not increase strictly"
    scale = max(1.0, float(np.abs(points).max()))
    tol = 1e-9 * scale
    if abs(points[0, 0] - fp.x_start) > tol or abs(points[-1, 0] - fp.x_end) > tol:
        return (f"points from x = {points[0, 0]:g} to {points[-1, 0]:g} m: expected them to "
                f"run from x_start = {fp.x_start:g} to x_end = {fp.x_end:g} m")
    x0, x1 = float(section.x[0]), float(section.x[-1])
    for name, x in (("x_start", fp.x_start), ("x_end", fp.x_end)):
        why = _x_problem(float(x), name, measure, section)
        if why:
            return why
    if x0 <= fp.x_start and fp.x_end <= x1:  # else place_measures reports the project's x
        ground = np.interp([fp.x_start, fp.x_end], section.x, section.y)
        off = np.abs(points[[0, -1], 1] - ground)
        if (off > 1e-6 * max(1.0, float(np.abs(ground).max()))).any():
            return (f"points that do not meet the ground at x_start and x_end (y = "
                    f"{points[0, 1]:g} and {points[-1, 1]:g} m, ground {ground[0]:g} and "
                    f"{ground[1]:g} m)")
        if fp.catch_from < x0 or fp.catch_to > x1:
            return (f"catch range [{fp.catch_from:g}, {fp.catch_to:g}] m: outside the "
                    f"section ({x0:g} to {x1:g} m)")
    return None

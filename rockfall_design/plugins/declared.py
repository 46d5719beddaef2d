"""What a measure's plugin declares about its design variables.

:func:`declared_design` reads a measure class: which of its ``Params`` fields
take the catalogue product, one of the product's heights and its energy class,
and which are free variables with default bounds or options. The declarations
are in each field's metadata (``json_schema_extra={"design": ...}``, parsed by
:func:`~rockfall_design.plugins.measure.design_role`); a plugin that declares nothing
keeps the conventions of plugins written before declarations existed (fields
named ``product``, ``height``, ``capacity_kj``; ``design_variables`` bounds).
:mod:`rockfall_design.judge.design_spec` resolves a project's candidates with them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from .measure import design_role

__all__ = ["DeclaredDesign", "declared_design"]

#: The conventional field names of the catalogue roles, for plugins that declare none.
_CONVENTIONAL = {"catalogue": "product", "catalogue_height": "height",
                 "catalogue_capacity": "capacity_kj"}


@dataclass(frozen=True)
class DeclaredDesign:
    """A measure class's design variables, as its plugin declares them.

    Attributes
    ----------
    product, height, capacity : str or None
        The fields that take the catalogue product, one of its heights (m)
        and its energy class (kJ); None where the measure has none (all None
        for a measure without catalogue products).
    ranges : dict of str to (float, float)
        Free continuous variables and their default bounds (declared in the
        field's metadata).
    options : dict of str to tuple
        Free discrete variables and their default options.
    fallback_bounds : dict of str to (float, float)
        ``design_variables`` bounds: used for a required parameter the
        candidate does not give (plugins written before declarations).
    """

    product: str | None = None
    height: str | None = None
    capacity: str | None = None
    ranges: dict[str, tuple[float, float]] = field(default_factory=dict)
    options: dict[str, tuple[Any, ...]] = field(default_factory=dict)
    fallback_bounds: dict[str, tuple[float, float]] = field(default_factory=dict)


def declared_design(cls: Any) -> DeclaredDesign:
    """What measure class ``cls`` declares about its design variables.

    Parameters
    ----------
    cls
        A measure class (its ``Params`` and ``design_variables``).

    Returns
    -------
    DeclaredDesign

    Raises
    ------
    ValueError
        If a declaration is malformed, a catalogue role is declared twice, or
        a height or capacity role is declared without a product field (a
        fault of the plugin).
    """
    model = cls.Params
    fields = model.model_fields
    roles = {name: design_role(model, name) for name in fields}
    ranges: dict[str, tuple[float, float]] = {}
    options: dict[str, tuple[Any, ...]] = {}
    catalogue: dict[str, str] = {}
    for name, role in roles.items():
        if role is None:
            continue
        if role.role == "range":
            assert role.bounds is not None
            ranges[name] = role.bounds
        elif role.role == "options":
            assert role.options is not None
            options[name] = role.options
        else:
            if role.role in catalogue:
                raise ValueError(f"{model.__name__}: fields {catalogue[role.role]!r} and "
                                 f"{name!r} both declare design role {role.role!r}")
            catalogue[role.role] = name
    # Today's convention for what is not declared: a field's name gives its role.
    for role_name, conventional in _CONVENTIONAL.items():
        if role_name not in catalogue and conventional in fields \
                and roles.get(conventional) is None:
            catalogue[role_name] = conventional
    if "catalogue" not in catalogue:
        declared = [n for n, r in roles.items() if r is not None and r.role.startswith("catalogue")]
        if declared:
            raise ValueError(f"{model.__name__}: field {declared[0]!r} declares a catalogue role "
                             "but no field declares design role 'catalogue' (the product)")
        catalogue = {}
    fallback: dict[str, tuple[float, float]] = {}
    for name, bounds in (getattr(cls, "design_variables", {}) or {}).items():
        low, high = (float(b) for b in bounds)
        if math.isfinite(low) and math.isfinite(high):
            fallback[name] = (low, high)
    return DeclaredDesign(
        product=catalogue.get("catalogue"),
        height=catalogue.get("catalogue_height"),
        capacity=catalogue.get("catalogue_capacity"),
        ranges=ranges,
        options=options,
        fallback_bounds=fallback,
    )

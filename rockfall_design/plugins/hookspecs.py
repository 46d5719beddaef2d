"""Hook specifications: the plugin author's manual.

A rockfall-design plugin adds protective measures, safety concepts or cost
models. It is an ordinary Python module that defines one or more of the hook
functions below, each marked with :data:`hookimpl`, and returns *classes*
from them. The built-in fence, wall, ditch, ... are plugins of exactly this
kind (``rockfall_design_builtins``); they get no special treatment.

Current routes and older routes
-------------------------------
Some parts of the contract have two routes: the current one, and an older
one kept so that plugins written against it keep working, unchanged and
without warnings. New plugins should take the current route. Each route says
the rockfall-design version it dates from ("since 0.1.0": every route below
is in 0.1.0); an older route is removed only in a release whose notes say
so, and not before 1.0. The same list is in the plugin guide,
``docs/plugins.md`` (a test keeps the two alike):

- **Design variables.** Current (since 0.1.0): each field declares its
  role, ``json_schema_extra={"design": ...}``. Kept for plugins written
  before declarations (no removal before 1.0): a required field the
  candidate does not give is searched within ``design_variables``, and
  fields named ``product``, ``height`` and ``capacity_kj`` are catalogue choices.
- **What a measure takes.** Current (since 0.1.0): ``bill(section)``, a list
  of ``Quantity``. Kept for plugins written before bills (no removal before
  1.0): ``quantities(section)`` alone, billed as one running metre named
  after the measure's ``kind``.
- **Pricing.** Current (since 0.1.0): ``CostModel.price(measure, bill,
  quantities, length_m)``. Kept for cost models written before bills (no
  removal before 1.0): ``CostModel.cost(measure, quantities, length_m)``,
  which the default ``price`` calls.
- **Units of parameters.** Current (since 0.1.0): the field's metadata,
  ``Field(..., json_schema_extra={"unit": "m"})``. Kept for plugins written
  before unit metadata (no removal before 1.0): the trailing parentheses of
  the description, ``"height of the net (m)"``.

How a plugin is found
---------------------
Through the entry-point group ``rockfall_design``. In the ``pyproject.toml``
of the distribution that ships the plugin::

    [project.entry-points.rockfall_design]
    myplugin = "my_package.module"

Once that distribution is installed (``pip install .``), every run of
``rockfall-design`` imports ``my_package.module`` and registers the module
object with pluggy under the name ``myplugin`` (the entry-point name). The
hooks are then called once each, when the registry of measures, safety
concepts and cost models is built at start-up, and never again: the classes
they return are resolved to plain objects before any rock falls, so nothing
in the per-rock loop goes through a plugin hook.

``rockfall-design plugins`` lists what was found, which distribution
provides each name, and every plugin that failed to load (``--json`` for a
machine-readable listing). A plugin that raises on import, implements a
misspelt hook (``rockfall_design_measure`` instead of
``rockfall_design_measures``), raises from a hook or returns an invalid class
is reported by name with a one-line reason, and the other plugins still load.
Two plugins that register the same measure ``kind`` (or the same safety
concept / cost model ``name``) are an error that names both: the program
stops with exit code 3 (``ExitCode.PLUGIN_FAULT``) rather than guess.

What a plugin may import
------------------------
From rockfall-design, only the public API: the names exported by the
``rockfall_design`` package itself (``from rockfall_design import ...``),
which are :data:`hookimpl`, the contracts :class:`ProtectiveMeasure`,
:class:`SafetyConcept` and :class:`CostModel` with their parameter bases
:class:`~.measure.MeasureParams`, :class:`~.concept.SafetyParams` and
:class:`~.cost_model.CostParams`, and the data they exchange
(:class:`~.measure.Barrier`, :class:`~.measure.BarrierBehaviour`,
:class:`~.measure.ProfileEdit`, :class:`~.measure.MeasureResult`, :class:`~.measure.Outcome`,
:class:`~.concept.Check`, :class:`~.measure.Quantity`). Everything else
(``rockfall_design.engine``, ``project``,
``plugins``, ...) is internal and may change in any release. Other libraries
(numpy, pydantic, ...) are fine as dependencies of the plugin's own
distribution.

How to block a plugin
---------------------
Block it by its entry-point name or its distribution name:
``rockfall-design plugins --block myplugin`` shows the registry without it
(the module is not even imported), and ``load_registry(blocked=["myplugin"])``
does the same in Python. To remove it for good, uninstall its distribution.
A project that needs a blocked plugin's measure type fails at that type's
line (exit code 2), naming the plugin: "measure type 'catch_net' is provided
by rockfall-catchnet, which is blocked (--block)". To say so, and only then,
after the run has already failed, the blocked plugins are loaded (guarded)
apart from the run's registry.

Rules for every registered class
--------------------------------
* ``kind`` (measures) or ``name`` (safety concepts, cost models): non-empty,
  lower case, only ``a-z``, ``0-9``, ``_`` and ``-``; unique across all
  installed plugins.
* ``summary``: one line shown by ``rockfall-design plugins``.
* ``Params``: a pydantic model, subclass of :class:`~.measure.MeasureParams`,
  :class:`~.concept.SafetyParams` or :class:`~.cost_model.CostParams`; put units in field names
  (``height_m``, ``capacity_kj``) and in each field's metadata,
  ``Field(2.0, gt=0, json_schema_extra={"unit": "m"})`` (``{"unit": None}``
  for a name or a flag). Without that metadata the unit is read from the
  trailing parentheses of the description (``"height of the net (m)"``).
  ``rockfall-design plugins --json`` lists every field with its type, unit,
  default, bounds and options.
* ``example``: a complete, valid parameter set (``Params(**example)`` must
  succeed); for a measure without ``type``, for a safety concept without
  ``concept``.
* Measures only: ``design_variables`` maps names of ``Params`` fields to
  default (low, high) bounds with low < high; ``nan`` for a bound that the
  project (or the optimiser) must supply, e.g. a station range. A field's
  own design declaration (below) takes precedence.
* Measures only: ``default_prices`` (optional) maps the names of the
  measure's own quantities (see "Costs by quantities") to prices the cost
  catalogue uses when it has none of its own.
* The class must implement every abstract method of its base.

A class that breaks a rule is reported as a failure of its plugin (naming
the class) and left out; the plugin's other classes still load.

Design variables: what the optimiser may choose
-----------------------------------------------
``rockfall-design optimise`` builds its search space from what each
measure's ``Params`` declares, plus the ranges the project's
``design.candidates`` give; it never special-cases a measure or parameter by
name. A field declares its role in its metadata, under the key ``"design"``
of ``json_schema_extra`` (beside ``"unit"``):

``{"design": {"bounds": [low, high]}}``
    A free continuous design variable (a ``float`` field). The optimiser
    searches it within these bounds unless the candidate fixes it
    (``spacing: 2.0``), gives its own range (``spacing: [1, 4]``) or options.
``{"design": {"options": [a, b, ...]}}``
    A free discrete design variable: one of these values.
``{"design": "options"}``
    A free discrete variable over every value of the field's ``Literal``
    (or ``Enum``) type.
``{"design": "catalogue"}``
    The catalogue product (a ``str`` field): the optimiser picks it among
    the products of the measure's type in ``design.products``; the
    candidate may restrict them (``product: [RX-100, RX-250]`` for a field
    named ``product``, ``{options: [...]}`` for any name).
``{"design": "catalogue_height"}``
    One of the heights (m) the chosen product comes in.
``{"design": "catalogue_capacity"}``
    The chosen product's energy class (``capacity_kj`` of the catalogue, kJ).

A product's other catalogue keys that name fields of ``Params`` (a wall's
``thickness``) are set from it too. A candidate must not give what the
product sets. Example::

    class RingNetParams(MeasureParams):
        height: float = Field(gt=0, json_schema_extra={
            "unit": "m", "design": {"bounds": [1.0, 6.0]}})
        rings: int = Field(2, ge=1, le=4, json_schema_extra={
            "unit": None, "design": {"options": [1, 2, 3, 4]}})

Kept for plugins written before declarations (older route; current:
declarations, since 0.1.0): plugins without declarations keep the older
conventions: a field
named ``product`` is the catalogue product, ``height`` its height and
``capacity_kj`` its energy class (unless those fields declare another role),
and a *required* field the candidate does not give is searched within its
``design_variables`` bounds. ``rockfall-design plugins --json`` lists each
parameter's declaration under ``design``.

Costs by quantities
-------------------
A measure reports what it takes per running metre of slope as a bill:
``bill(section)`` returns a list of :class:`~.measure.Quantity` (``name``, ``amount``
per running metre, ``unit``, optional ``product`` and ``size``), e.g.
``Quantity("embankment_fill_m3", 18.5, "m3")``. The built-ins bill
``fence``/``wall`` (one running metre of their product at their height),
``excavation_m3``, ``fill_m3`` and ``block_m3``; a plugin may invent any
name, and ship default prices for its names in ``default_prices``
(``{"embankment_fill_m3": 35.0}``, currency per unit), which the project's
cost catalogue overrides (``prices: {embankment_fill_m3: 30}`` for the
built-in ``unit_prices``). The default ``bill`` names the ``quantities()``
dict through ``bill_from(quantities)``, and the default ``bill_from`` bills
one running metre named after the measure's ``kind``: a measure written
before bills existed (``quantities`` alone: the older route, kept) is
priced as before (``other_per_m`` of ``unit_prices``).

A cost model prices a bill in ``price(measure, bill, quantities, length_m)``
(current route, since 0.1.0); the default calls the older
``cost(measure, quantities, length_m)`` (kept for cost models written before
bills). Before
any search, ``missing_price(measure, bill)`` is asked, with a sample design
of every candidate, whether each quantity has a price at all: a str (the
reason) makes the design section an error at ``design.costs`` naming the
candidate, the quantity and the catalogue (bad input, exit code 2). The
default says nothing (None).

When plugin code fails at run time
----------------------------------
The program calls into a plugin's classes at set-up and once per design (each
candidate design of the optimiser included), never per rock: the
constructors, a measure's ``footprint``, ``design_properties``,
``quantities``, ``bill`` and ``label``, a safety concept's ``checks`` and a
cost model's ``price`` (by default ``cost``) and ``missing_price``. Every
such call goes through one guard (``rockfall_design.plugins.call_plugin``).
Only two exceptions are part of the contract:

* ``footprint`` raises ``ValueError``: the measure does not fit on the
  section. ``check`` shows the message at the measure's key path (bad input,
  exit code 2); the optimiser counts the design as infeasible.
* ``cost`` or ``price`` raises ``KeyError`` or ``ValueError``: the catalogue
  has no price for the measure. The optimiser skips the design and reports
  why.

Anything else raised (``SystemExit`` and ``KeyboardInterrupt`` included:
only a real Ctrl-C, a signal the process receives, stops the run as an
interrupt), and a return value of the wrong kind, is a fault of the plugin:
the run stops with exit code 3 (``ExitCode.PLUGIN_FAULT``) and one line
naming the measure kind, safety concept or cost model, the distribution that
provides it, the method and the exception (type, message, file:line). The
same at load time leaves the plugin out, reported by
``rockfall-design plugins``. What must come back: ``footprint`` a
:class:`~.measure.Barrier` or :class:`~.measure.ProfileEdit`; ``design_properties`` and
``quantities`` a dict of str to number, never NaN (``inf`` is allowed, e.g.
"no capacity given"); ``bill`` a list of :class:`~.measure.Quantity` with finite
amounts >= 0; ``label`` a str; ``checks`` a list of :class:`~.concept.Check`;
``cost`` and ``price`` a finite number >= 0; ``missing_price`` a str or None.

Every field of a footprint is checked before the engine sees it
(``rockfall_design.plugins.footprint_problem``): a :class:`~.measure.Barrier` needs a
finite ``x`` on the section, ``height_m`` > 0, ``capacity_kj`` >= 0 (``inf``
for none given), a :class:`~.measure.BarrierBehaviour`, ``restitution`` in 0..1,
``gap_m`` >= 0 and ``spacing_m`` > 0 with the gap no wider than the
spacing; a :class:`~.measure.ProfileEdit` a finite stretch ``x_start`` < ``x_end``,
``points`` of shape (k, 2), k >= 2, finite, x strictly increasing from
``x_start`` to ``x_end`` and meeting the ground at both, a finite catch range
``catch_from`` <= ``catch_to`` on the section and a ``material`` name or
None. A bad field is a fault of the plugin (exit code 3), not of the
project; a station off the section is the project's only when the measure's
own ``x`` is off it too.

While plugin code runs, ``sys.stdout`` is the program's stderr: what a
plugin prints never mixes with ``--json`` output. (Output written to file
descriptor 1 directly, from C code say, is not redirected.)

A measure's ``design_properties()`` and ``label()`` are asked for by the
program before any safety concept or report sees the measure, so a measure
that fails there is named itself, not the concept that reads
``result.measure.design_properties()``. Keep these methods deterministic and
free of side effects: they may be called several times per design.
"""

from __future__ import annotations

import pluggy

from .concept import SafetyConcept
from .cost_model import CostModel
from .measure import ProtectiveMeasure

__all__ = [
    "ENTRY_POINT_GROUP",
    "PROJECT_NAME",
    "hookimpl",
    "hookspec",
    "rockfall_design_cost_models",
    "rockfall_design_measures",
    "rockfall_design_safety_concepts",
]

#: Name of the pluggy project; hook functions are prefixed ``rockfall_design_``.
PROJECT_NAME = "rockfall_design"
#: Entry-point group through which plugins are found.
ENTRY_POINT_GROUP = "rockfall_design"

#: Marks the hook specifications below (for rockfall-design itself).
hookspec = pluggy.HookspecMarker(PROJECT_NAME)
#: Marks a plugin's hook implementations: ``@hookimpl`` above each hook function.
hookimpl = pluggy.HookimplMarker(PROJECT_NAME)


@hookspec
def rockfall_design_measures() -> list[type[ProtectiveMeasure]]:
    """Register protective measures (fences, walls, ditches, ...).

    Called once, at start-up, when the registry is built (before the project
    file is validated, since its ``measures[].type`` refers to the kinds
    registered here); never per rock, never per candidate design.

    Returns
    -------
    list of type[ProtectiveMeasure]
        The measure *classes* (not instances) this plugin provides, in any
        order; the registry sorts them by ``kind``. An empty list (or None)
        registers nothing.

    Notes
    -----
    * ``kind`` is the ``type:`` of the project file. It must be unique across
      all installed plugins: two plugins with the same ``kind`` stop the
      program with an error naming both.
    * Required class attributes: ``kind``, ``summary``, ``Params`` (a
      :class:`~.measure.MeasureParams` subclass; every measure has the station ``x``
      in m) and ``example`` (a valid parameter set *without* ``type``).
      ``design_variables`` (name -> (low, high)) lists what the optimiser
      may vary; a field's ``json_schema_extra={"design": ...}`` declares its
      role more precisely (see "Design variables" above).
    * Implement ``footprint(section)`` (a :class:`~.measure.Barrier` at a station, or
      a :class:`~.measure.ProfileEdit` of the ground), ``design_properties()`` (the
      ``height_m``, ``capacity_kj`` and/or ``width_m`` that safety concepts
      check) and, for costing, ``bill(section)`` (named quantities, see
      "Costs by quantities" above) or ``quantities(section)``.
    * The program instantiates the class itself, with validated parameters:
      ``Measure(Measure.Params(**fields_without_type))``.
    * Raise ``ValueError`` from ``footprint`` when the measure does not fit
      on the section (the message is shown to the user). Any other exception
      from the measure is a plugin fault (exit code 3); see "When plugin code
      fails at run time" above.

    Examples
    --------
    A light net fence, ``type: post_fence`` in a project file:

    .. code-block:: python

        from rockfall_design import (
            Barrier,
            BarrierBehaviour,
            MeasureParams,
            ProtectiveMeasure,
            hookimpl,
        )


        class PostFenceParams(MeasureParams):
            height_m: float = 2.0
            capacity_kj: float = 100.0


        class PostFence(ProtectiveMeasure):
            kind = "post_fence"
            summary = "Light post-and-mesh net fence for small rocks"
            Params = PostFenceParams
            example = {"x": 70.0, "height_m": 2.0, "capacity_kj": 100.0}
            design_variables = {"x": (10.0, 120.0), "height_m": (1.0, 4.0)}

            def footprint(self, section):
                p = self.params
                return Barrier(x=p.x, height_m=p.height_m, capacity_kj=p.capacity_kj,
                               behaviour=BarrierBehaviour.NET)

            def design_properties(self):
                return {"height_m": self.params.height_m,
                        "capacity_kj": self.params.capacity_kj}


        @hookimpl
        def rockfall_design_measures():
            return [PostFence]
    """


@hookspec
def rockfall_design_safety_concepts() -> list[type[SafetyConcept]]:
    """Register safety concepts (how rock statistics become design checks).

    Called once, at start-up, when the registry is built; never per rock.
    The project chooses one concept with ``safety: {concept: NAME, ...}``.

    Returns
    -------
    list of type[SafetyConcept]
        The concept *classes* (not instances) this plugin provides, in any
        order; the registry sorts them by ``name``. An empty list (or None)
        registers nothing.

    Notes
    -----
    * ``name`` must be unique across all installed plugins; two plugins with
      the same name stop the program with an error naming both.
    * Required class attributes: ``name``, ``summary``, ``Params`` (a
      :class:`~.concept.SafetyParams` subclass: targets and partial factors with
      documented defaults) and ``example`` (a valid parameter set *without*
      ``concept``).
    * Implement ``checks(result)``: given the :class:`~.measure.MeasureResult` of one
      measure (passing heights in m, energies in kJ, reaches in m, of the
      rocks that met it), return a list of :class:`~.concept.Check`; an empty list when
      the concept has nothing to check for that kind of measure. Read the
      measure's properties with ``result.measure.design_properties()``.
      Anything but a list of :class:`~.concept.Check`, or an exception, is a plugin
      fault (exit code 3).

    Examples
    --------
    Energy capacity against the largest energy with a partial factor,
    ``safety: {concept: max_energy, factor: 1.5}`` in a project file:

    .. code-block:: python

        from rockfall_design import Check, SafetyConcept, SafetyParams, hookimpl


        class MaxEnergyParams(SafetyParams):
            factor: float = 1.5
            "Partial factor on the largest energy (-)."


        class MaxEnergy(SafetyConcept):
            name = "max_energy"
            summary = "Capacity >= factor x the largest energy of any rock"
            Params = MaxEnergyParams
            example = {"factor": 1.5}

            def checks(self, result):
                capacity = result.measure.design_properties().get("capacity_kj")
                if capacity is None:
                    return []
                if len(result.energy_kj) == 0:
                    return [Check("energy_factor", None, 1.0, True,
                                  detail="no rock met the measure")]
                design_kj = self.params.factor * float(max(result.energy_kj))
                value = capacity / design_kj
                return [Check("energy_factor", value, 1.0, value >= 1.0,
                              detail=f"{capacity:g} kJ / {design_kj:g} kJ")]


        @hookimpl
        def rockfall_design_safety_concepts():
            return [MaxEnergy]
    """


@hookspec
def rockfall_design_cost_models() -> list[type[CostModel]]:
    """Register cost models (how the quantities of a measure are priced).

    Called once, at start-up, when the registry is built; never per rock and
    never per candidate design of the optimiser (it calls the ``cost`` method
    of an instance it made once).

    Returns
    -------
    list of type[CostModel]
        The cost-model *classes* (not instances) this plugin provides, in any
        order; the registry sorts them by ``name``. An empty list (or None)
        registers nothing.

    Notes
    -----
    * ``name`` must be unique across all installed plugins; two plugins with
      the same name stop the program with an error naming both.
    * Required class attributes: ``name``, ``summary``, ``Params`` (a
      :class:`~.cost_model.CostParams` subclass: the catalogue of unit prices, units in
      the field names) and ``example`` (a valid parameter set).
    * Implement ``cost(measure, quantities, length_m)``: the cost of
      ``measure`` over ``length_m`` metres of slope, from its
      ``quantities`` per running metre; or, to price named quantities,
      ``price(measure, bill, quantities, length_m)`` (and optionally
      ``missing_price(measure, bill)``), see "Costs by quantities" above.
      Raise ``KeyError`` or ``ValueError`` when the catalogue has no price
      for that measure (the optimiser skips the design and says why);
      return a finite number >= 0 otherwise. Any other exception is a
      plugin fault (exit code 3).

    Examples
    --------
    A price per running metre plus a price per kJ of capacity per metre:

    .. code-block:: python

        from rockfall_design import CostModel, CostParams, hookimpl


        class UnitRateParams(CostParams):
            per_m: float = 400.0
            "Price per running metre of slope (currency/m)."
            per_kj_per_m: float = 0.5
            "Price per kJ of capacity per running metre (currency/(kJ m))."


        class UnitRate(CostModel):
            name = "unit_rate"
            summary = "Price per metre plus price per kJ of capacity"
            Params = UnitRateParams
            example = {"per_m": 400.0, "per_kj_per_m": 0.5}

            def cost(self, measure, quantities, length_m):
                p = self.params
                rate = p.per_m + p.per_kj_per_m * quantities.get("capacity_kj", 0.0)
                return rate * length_m


        @hookimpl
        def rockfall_design_cost_models():
            return [UnitRate]
    """

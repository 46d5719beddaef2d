"""The built-in safety concepts: ``spang``, ``uni11211``, ``onr24810`` and ``reliability``.

Ordinary plugins, one module each (:mod:`.spang`, :mod:`.uni11211`,
:mod:`.onr24810`, :mod:`.reliability`): each uses only the public
``rockfall_design`` API and the public helpers beside it (:mod:`.shared`:
statistics with their order-statistic bounds; :mod:`.checks`: checks built
from them; :mod:`.limit_states`: the partial-factor limit states), and is
registered by its own entry point of the ``rockfall_design`` group, exactly
as a third party's concept would be. This package registers nothing; it
only names the classes, so that ``from rockfall_design_builtins.safety
import SpangConcept`` keeps working.

``spang`` and ``uni11211`` turn a :class:`~rockfall_design.MeasureResult` -- the passing
heights, speeds, energies, masses, radii and reaches of the rocks that met one
measure -- into :class:`~rockfall_design.Check` objects, one per design
property the measure declares (``height_m``, ``capacity_kj``, ``width_m``;
see ``ProtectiveMeasure.design_properties``):

* ``spang`` -- the safety factors of Spang & Rautenstrauch (1988): provided
  height, capacity and width divided by the critical height, the design
  energy and the reach of the rocks (each the concept's statistic);
* ``uni11211`` -- the limit-state check of UNI 11211-4 for net fences, with
  partial factors on the trajectory, the slope survey, the block volume and
  unit weight, and the product's energy capacity.

Both also check the braking distance of a fence whose catalogue product gives
its maximum elongation in the MEL test (``max_elongation_m``): the protected
zone must not start within it (``braking_distance``).

Conventions shared by both (``onr24810`` and ``reliability`` say theirs):

* a design property that is absent or not finite (e.g. ``capacity_kj = inf``,
  "no capacity given") is not checked;
* if no rock met the measure, every check has ``value = None`` and
  ``ok = True`` ("no rock reached the measure");
* if the demand is zero (every passing height, energy or reach is 0), the
  factor is undefined: ``value = None``, ``ok = True``;
* percentiles are ``numpy.percentile`` with linear interpolation between
  order statistics (Hyndman & Fan type 7), over the rocks that met the
  measure, each rock counted once;
* every check also carries ``bound``: its value with the one-sided upper
  confidence bound (``confidence``, default 0.95; distribution-free, from
  order statistics) of each percentile in place of the percentile, and
  ``ok_with_confidence``. A sample too small to bound a percentile gives
  ``bound = None`` and ``ok_with_confidence = False``, and the detail says how
  many rocks it needs. The ``max`` statistic is the sample's own maximum:
  it has no distribution-free bound, grows with the sample, and is its own
  ``bound``.

Units: m, m/s, kg, kJ.
"""

from .checks import braking_check, factor_check, gamma_d_field, limit_check, reach_check
from .onr24810 import Onr24810Concept
from .reliability import ReliabilityConcept, life_probability
from .shared import design_mass
from .spang import SpangConcept
from .uni11211 import Uni11211Concept

__all__ = [
    "Onr24810Concept",
    "ReliabilityConcept",
    "SpangConcept",
    "Uni11211Concept",
    "braking_check",
    "design_mass",
    "factor_check",
    "gamma_d_field",
    "life_probability",
    "limit_check",
    "reach_check",
]

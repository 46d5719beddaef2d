"""rockfall-design: rockfall trajectories and the least-cost design of protection.

The public API is what this module exports:

- for engineers: :func:`load_project`, :func:`simulate`, :func:`check` and
  :func:`optimise`, whose results carry ``.summary`` (the dict of the
  command's ``--json``), pandas DataFrames (``.rocks``, ``.stations``,
  ``.crossings``, ``.measures``, ``.alternatives``) and matplotlib Figures
  (``.plot()``) built without touching matplotlib's backend;
- for plugin authors: the hook marker, the contracts of measures, safety
  concepts and cost models, and the plain data they exchange with the program.

>>> import rockfall_design as rd
>>> p = rd.load_project("projects/design_two_zones.yaml")   # doctest: +SKIP
>>> r = rd.optimise(p, rocks=2000, seed=1)                  # doctest: +SKIP
>>> r.best, r.alternatives, r.plot()                        # doctest: +SKIP
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("rockfall-design")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"

# The submodule rockfall_design.optimise shares its name with the function
# optimise below. Importing a submodule for the first time sets the package's
# attribute of that name to the module, so it is imported here first: the
# function then takes the name for good, and later imports of the submodule
# (``from rockfall_design.optimise import ...``) find it in sys.modules.
from . import optimise as _optimise_module  # noqa: F401  isort: skip
from .api import (
    CheckResult,
    OptimiseResult,
    SimulationResult,
    check,
    load_project,
    optimise,
    simulate,
)
from .costs import CostModel, CostParams
from .hookspecs import hookimpl
from .judge.bounds import (
    fraction_upper_bound,
    quantile_upper_bound,
    rocks_to_bound_quantile,
    rocks_to_show_fraction,
)
from .measures import (
    Barrier,
    BarrierBehaviour,
    MeasureParams,
    MeasureResult,
    Outcome,
    ProfileEdit,
    ProtectiveMeasure,
)
from .safety import Check, SafetyConcept, SafetyParams

__all__ = [
    "__version__",
    "hookimpl",
    "load_project",
    "simulate",
    "check",
    "optimise",
    "SimulationResult",
    "CheckResult",
    "OptimiseResult",
    "Barrier",
    "BarrierBehaviour",
    "Check",
    "CostModel",
    "CostParams",
    "MeasureParams",
    "MeasureResult",
    "Outcome",
    "ProfileEdit",
    "ProtectiveMeasure",
    "SafetyConcept",
    "SafetyParams",
    "fraction_upper_bound",
    "quantile_upper_bound",
    "rocks_to_bound_quantile",
    "rocks_to_show_fraction",
]

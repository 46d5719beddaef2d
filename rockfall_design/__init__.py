"""rockfall-design: rockfall trajectories and the least-cost design of protection.

The public API for plugin authors is what this module exports: the hook
marker, the contracts of measures, safety concepts and cost models, and the
plain data they exchange with the program.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("rockfall-design")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"

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

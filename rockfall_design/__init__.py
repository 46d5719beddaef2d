"""rockfall-design: rockfall trajectories and the least-cost design of protection.

The public API is what this module exports:

- for engineers: :func:`load_project`, :func:`simulate`, :func:`check`,
  :func:`optimise` and :func:`study` (a parametric study), whose results
  carry ``.summary`` (the dict of the command's ``--json``), pandas
  DataFrames (``.rocks``, ``.stations``, ``.crossings``, ``.measures``,
  ``.alternatives``, ``.scenarios``, ``.sensitivity``) and matplotlib Figures
  (``.plot()``) built without touching matplotlib's backend;
- for plugin authors: the hook marker, the contracts of measures, safety
  concepts and cost models, and the plain data they exchange with the program.

>>> import rockfall_design as rd
>>> p = rd.load_project("projects/design_two_zones.yaml")   # doctest: +SKIP
>>> r = rd.optimise(p, rocks=2000, seed=1)                  # doctest: +SKIP
>>> r.best, r.alternatives, r.plot()                        # doctest: +SKIP
"""

from importlib import import_module
from typing import TYPE_CHECKING, Any

from .plugins.concept import Check, DesignBlock, DesignValue, SafetyConcept, SafetyParams
from .plugins.cost_model import CostModel, CostParams
from .plugins.hookspecs import hookimpl
from .plugins.measure import (
    Barrier,
    BarrierBehaviour,
    MeasureParams,
    MeasureResult,
    Outcome,
    ProfileEdit,
    ProtectiveMeasure,
    Quantity,
    Stand,
)
from .version import __version__

# The engineer's functions and the statistics helpers are imported on first
# use (PEP 562), so that importing the package, or a module of it such as
# rockfall_design.testing (which pytest loads in every run through its
# pytest11 entry point), does not import the engine, numba, scipy and pandas.
_LAZY: dict[str, str] = {
    **dict.fromkeys(("check", "load_project", "optimise", "simulate", "study", "calibrate",
                     "compare", "run_corridor"), ".api"),
    **dict.fromkeys(("CheckResult", "OptimiseResult", "SimulationResult"), ".results"),
    **dict.fromkeys(("CalibrationResult", "ComparisonResult"), ".calibration.calibration_result"),
    "StudyResult": ".studies.study_result",
    **dict.fromkeys(("Corridor", "load_corridor"), ".project"),
    **dict.fromkeys(("fraction_lower_bound", "fraction_upper_bound", "quantile_lower_bound",
                     "quantile_upper_bound", "quantile_with_bounds",
                     "rocks_to_bound_quantile", "rocks_to_show_fraction"), ".judge.bounds"),
}

if TYPE_CHECKING:  # pragma: no cover
    from .api import (
        calibrate,
        check,
        compare,
        load_project,
        optimise,
        run_corridor,
        simulate,
        study,
    )
    from .calibration.calibration_result import CalibrationResult, ComparisonResult
    from .judge.bounds import (
        fraction_lower_bound,
        fraction_upper_bound,
        quantile_lower_bound,
        quantile_upper_bound,
        quantile_with_bounds,
        rocks_to_bound_quantile,
        rocks_to_show_fraction,
    )
    from .project import Corridor, load_corridor
    from .results import CheckResult, OptimiseResult, SimulationResult
    from .studies.study_result import StudyResult


def __getattr__(name: str) -> Any:
    where = _LAZY.get(name)
    if where is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(import_module(where, __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


__all__ = [
    "__version__",
    "hookimpl",
    "load_project",
    "load_corridor",
    "Corridor",
    "simulate",
    "check",
    "optimise",
    "study",
    "calibrate",
    "compare",
    "run_corridor",
    "SimulationResult",
    "CheckResult",
    "OptimiseResult",
    "StudyResult",
    "CalibrationResult",
    "ComparisonResult",
    "Barrier",
    "BarrierBehaviour",
    "Check",
    "DesignBlock",
    "DesignValue",
    "CostModel",
    "CostParams",
    "MeasureParams",
    "MeasureResult",
    "Outcome",
    "ProfileEdit",
    "ProtectiveMeasure",
    "Quantity",
    "SafetyConcept",
    "SafetyParams",
    "Stand",
    "fraction_upper_bound",
    "fraction_lower_bound",
    "quantile_lower_bound",
    "quantile_upper_bound",
    "quantile_with_bounds",
    "rocks_to_bound_quantile",
    "rocks_to_show_fraction",
]

"""Parametric studies: scenarios of a project, run as independent tasks, and sensitivity.

- :mod:`.paths`: :func:`with_values`, a project with inputs set by their path
  in the project file (``materials.talus.restitution``), validated again;
- :mod:`.scenarios`: the scenarios of a ``study:`` section (grid or Latin
  hypercube), each with its values and its own rock seed.

The engineer's entry point is :func:`rockfall_design.study` (the function of
the public API, which shares its name with this package).
"""

from .paths import PathError, check_study, parse_path, with_values
from .scenarios import Scenario, scenario_seed, scenarios

__all__ = [
    "PathError",
    "Scenario",
    "check_study",
    "parse_path",
    "scenario_seed",
    "scenarios",
    "with_values",
]

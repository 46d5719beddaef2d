"""Parametric studies: scenarios of a project, run as independent tasks, and sensitivity.

- :mod:`.paths`: :func:`with_values`, a project with inputs set by their path
  in the project file (``materials.talus.restitution``), validated again;
  :func:`check_study`, every path and value of a ``study:`` section checked;
- :mod:`.sampling`: the scenarios of a ``study:`` section (grid or Latin
  hypercube), each with its values and its own rock seed; named for how the
  points are drawn (``sampling`` in ``study --json``), not ``scenarios.py``:
  a submodule of that name would be bound to the package's name
  ``scenarios`` when imported, which holds the function :func:`scenarios`
  (so the import order here decided which of the two the name held);
- :mod:`.runner`: the scenarios as tasks, and the task (one ``simulate``
  run); not ``run.py``, which would read as the package's
  :mod:`rockfall_design.run` room;
- :mod:`.executors`: tasks in-process, on a local process pool or on Dask
  (:mod:`._warm` is what the pool's forkserver imports first);
- :mod:`.scenario_result`: :class:`~.scenario_result.ScenarioResult`, what
  one scenario found;
- :mod:`.sensitivity`: which input moves each design value (main-effect
  ranges; RBD-FAST indices of SALib for a sampled study);
- :mod:`.study_result`: :class:`.StudyResult` (JSON, tables, figures, report),
  named as :mod:`.scenario_result` beside it;
- :mod:`.scenario_checks`: designs checked across the scenarios (``check
  --scenarios``);
- :mod:`.corridor`: a corridor's result, its sections' JSON objects and the
  totals over them;
- :mod:`~rockfall_design.cli.study_command`: the ``rockfall-design study`` command.

The engineer's entry point is :func:`rockfall_design.study` (the function of
the public API, which shares its name with this package).
"""

from typing import TYPE_CHECKING, Any

from .paths import PathError, check_study, parse_path, with_values
from .sampling import Scenario, scenario_seed, scenarios

if TYPE_CHECKING:  # pragma: no cover
    from .study_result import StudyResult


def __getattr__(name: str) -> Any:
    if name == "StudyResult":  # with pandas and matplotlib behind it: on first use
        from .study_result import StudyResult

        return StudyResult
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "PathError",
    "Scenario",
    "StudyResult",
    "check_study",
    "parse_path",
    "scenario_seed",
    "scenarios",
    "with_values",
]

"""Parametric studies: scenarios of a project, run as independent tasks, and sensitivity.

- :mod:`.paths`: :func:`with_values`, a project with inputs set by their path
  in the project file (``materials.talus.restitution``), validated again;
  :func:`check_study`, every path and value of a ``study:`` section checked;
- :mod:`.scenarios`: the scenarios of a ``study:`` section (grid or Latin
  hypercube), each with its values and its own rock seed;
- :mod:`.run`: the scenarios as tasks, and the task (one ``simulate`` run);
- :mod:`.executors`: tasks in-process, on a local process pool or on Dask;
- :mod:`.sensitivity`: which input moves each design value (main-effect
  ranges; RBD-FAST indices of SALib for a sampled study);
- :mod:`.result`: :class:`StudyResult` (JSON, tables, figures, report);
- :mod:`.command`: the ``rockfall-design study`` command.

The engineer's entry point is :func:`rockfall_design.study` (the function of
the public API, which shares its name with this package). The names below
are imported on first use, so that the command line's ``--help`` does not
import pydantic and numpy.
"""

from importlib import import_module
from typing import TYPE_CHECKING, Any

_LAZY = {
    "PathError": ".paths",
    "check_study": ".paths",
    "parse_path": ".paths",
    "with_values": ".paths",
    "Scenario": ".scenarios",
    "scenario_seed": ".scenarios",
    "scenarios": ".scenarios",
    "StudyResult": ".result",
}

if TYPE_CHECKING:  # pragma: no cover
    from .paths import PathError, check_study, parse_path, with_values
    from .result import StudyResult
    from .scenarios import Scenario, scenario_seed, scenarios


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
    "PathError",
    "Scenario",
    "StudyResult",
    "check_study",
    "parse_path",
    "scenario_seed",
    "scenarios",
    "with_values",
]

"""The numeric core: exact event-to-event rockfall trajectories.

Pure numerics over arrays (numpy and numba). Nothing here imports pluggy,
pydantic, rich or pandas; the rest of the package builds on this.
"""

# First: it decides where numba caches compiled code, before numba is imported.
from . import _jit  # noqa: F401, I001
from .core import STATUS_NAMES, G
from .ensemble import (
    EngineSettings,
    EnsembleResult,
    Material,
    Releases,
    Section,
    barrier_table,
    rock_mass,
    run_ensemble,
)

__all__ = [
    "G",
    "STATUS_NAMES",
    "EngineSettings",
    "EnsembleResult",
    "Material",
    "Releases",
    "Section",
    "barrier_table",
    "rock_mass",
    "run_ensemble",
]

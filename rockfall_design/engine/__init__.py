"""The numeric core: exact event-to-event rockfall trajectories.

Pure numerics over arrays (numpy and numba). Nothing here imports pluggy,
pydantic, rich or pandas; the rest of the package builds on this.
"""

from pathlib import Path

# jit first: it decides where numba caches compiled code, before numba is imported.
from . import ensemble, jit  # noqa: I001
from .columns import STATUS_NAMES, G
from .ensemble import run_ensemble
from .problem import (
    EngineSettings,
    EnsembleResult,
    Material,
    Releases,
    Section,
    barrier_table,
    rock_mass,
)

# Before anything loads from numba's cache: drop it if any engine source changed.
jit.drop_stale_cache(ensemble._run_batch, Path(__file__).resolve().parent)

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

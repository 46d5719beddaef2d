"""Imported by the forkserver of a study's process pool: the engine loaded once, before any fork.

A worker of the pool is forked from the forkserver; what the forkserver has
imported and loaded, every worker has at no cost. Importing this module
imports the engine and runs two rocks on one thread, which loads numba's
cached machine code (about a second per process otherwise, paid by every
worker). One thread, so that the forkserver runs no thread when it forks.
"""

import os

from ..engine.batching import THREADS_ENV

os.environ[THREADS_ENV] = "1"

from ..project import load_project_text  # noqa: E402
from ..run.simulation import simulate  # noqa: E402
from . import runner as _run  # noqa: E402, F401  (the task's module, unpickled by reference)

_TINY = """
name: warm-up
slope: {points: [[0, 10], [10, 0], [20, 0]], materials: ground}
materials: {ground: {restitution: 0.3, friction: 0.5, rolling_resistance: 0.3}}
rocks: {count: 2, radius: 0.3, release: {x: 1}}
analysis: {stations: [15], envelope_points: 5}
"""

try:
    simulate(load_project_text(_TINY, "<warm-up>"), rocks=2, seed=0)
except Exception:  # noqa: BLE001 - a failed warm-up costs the workers time, nothing else:
    pass  # each loads the engine on its first scenario, and reports any error there

"""The batch kernel's first compile, shared between two processes.

The kernel (``ensemble._run_batch``) calls two large independent parts: the
rock's event loop (``rock.simulate_rock`` and the impact, contact, flight,
drag and barrier functions under it) and the centre path's sweep
(``ensemble._path``, ``profile.every_piece_units`` and the profile functions
under them), each about two fifths of the first compile, the kernel's own
typing, lowering and optimisation of the whole the last fifth. numba compiles
in one thread per process, so on a machine of two cores or more the sweep is
compiled by a helper process (:func:`.jit.compile_in_helper`) while this
process compiles the event loop; the kernel's compile then loads the sweep
from the cache the helper filled. The machine code is the same; what the
user waits for is about three fifths of the compile.

Each part is compiled for exactly the argument types the kernel calls it
with, made here from the kernel's own arguments as ``_run_batch`` makes them;
a test holds that the kernel's compile compiles neither part again.
"""

from __future__ import annotations

import pickle
from pathlib import Path
from typing import Any

import numpy as np

from . import columns, jit
from .profile import every_piece_units, no_units
from .records import N_WORK, RockOut
from .rock import simulate_rock

HELPER = r"""
import pickle, sys
sys.path.insert(0, {root!r})
from rockfall_design.engine import jit, ensemble, profile
ground, r, max_chord, elems = pickle.load(sys.stdin.buffer)
units = profile.no_units()
for disp, args in ((ensemble._path, (ground, r, max_chord, elems, units)),
                   (profile.every_piece_units, (ground.x, ground.y, max_chord))):
    with jit.as_callee():
        disp.compile(tuple(disp.typeof_pyval(a) for a in args))
"""
"""The helper's program: compile the sweep for the kernel's types, into the shared cache."""


def sweep_args(path_fn: Any, args0: tuple) -> list[tuple[Any, tuple]]:
    """The sweep's functions and arguments of their types as the kernel calls them."""
    ground, _, _, elems, _, max_chord = args0[:6]
    r = float(args0[9][0, 0])  # a radius (float64), as rel[i, REL_R]
    return [(path_fn, (ground, r, max_chord, elems, no_units())),
            (every_piece_units, (ground.x, ground.y, max_chord))]


def event_loop_args(args0: tuple) -> tuple:
    """``simulate_rock``'s arguments of the types ``_run_batch`` calls it with."""
    (_, path0, _, _, settings, _, _, _, _, rel, resume, stations, bars, out) = args0
    ns = stations.x.shape[0]
    rock_out = RockOut(np.empty(ns), np.empty(ns), out.grid_v[0], out.cross[0],
                       np.empty((0, columns.N_TRAJ_COLS)), out.bar_out[0], out.bar_rec[0],
                       out.srec[0], out.srng[0], np.zeros(N_WORK))
    return (path0, settings, rel[0], np.empty(1, dtype=np.uint64), stations, bars, rock_out,
            resume.mask[0], resume.states[0])


def start(path_fn: Any, args0: tuple) -> None:
    """Before the kernel's first compile: its sweep in a helper, its event loop here.

    Parameters
    ----------
    path_fn : numba dispatcher
        ``ensemble._path``.
    args0 : tuple
        The kernel's arguments for its first batch (at least one rock).

    Does nothing for a part already compiled or cached; where no helper can
    be started, the kernel's compile compiles the sweep itself, as before.
    """
    sweep = [(d, a) for d, a in sweep_args(path_fn, args0) if jit.will_compile(d, a)]
    if sweep:
        ground, _, _, elems, _, max_chord = args0[:6]
        payload = pickle.dumps((ground, sweep[0][1][1], max_chord, elems))
        root = str(Path(__file__).resolve().parents[2])
        jit.compile_in_helper([d for d, _ in sweep], HELPER.format(root=root), payload)
    rock_args = event_loop_args(args0)
    if jit.will_compile(simulate_rock, rock_args):
        # For the kernel, which optimises it with the rest (jit.optimise_once).
        with jit.as_callee():
            simulate_rock.compile(tuple(simulate_rock.typeof_pyval(a) for a in rock_args))

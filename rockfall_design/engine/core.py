"""Event-to-event motion of a rigid sphere on the centre path (PHYSICS.md).

The rock is in one of two modes:

* FLIGHT: a parabola, solved exactly for the next contact with the centre
  path (one quadratic per piece walked);
* CONTACT: rolling, sliding, or rolling with sliding on one straight piece
  of the centre path, with constant accelerations between events (end of the
  piece, speed reaching zero, slip reaching zero, spin reaching zero), all
  closed forms. Rolling resistance opposes the spin whether or not the
  contact slips, and no event ever has zero length (see ``_contact_accel``).

Impacts apply Newton restitution with Coulomb friction and spin (``spang``) or
the lumped-mass law (``rn_rt``). There is no time step anywhere.

All functions are compiled with numba and take plain arrays. Sign conventions:
x downslope, y up, angular velocity ``w`` counter-clockwise positive; a rock
rolling towards +x without slip has ``w = -v / r``.

The engine is split by job; this module gathers their names for the code and
tests that import them from here:

* ``columns``: codes and column layouts of the plain tables;
* ``flight``: the next landing of a parabola on the centre path;
* ``impact``: restitution, friction and spin at an impact;
* ``contact``: rolling and sliding between events;
* ``barriers``: what a barrier does to a rock that reaches it;
* ``recording``: station passages, event states and restart states;
* ``rock``: one rock's event loop (:func:`simulate_rock`).
"""

from __future__ import annotations

# Re-exports only: every name below is used by the importers of this module.
# ruff: noqa: F401
from .barriers import _barrier_hit, _meet
from .columns import *  # noqa: F403
from .columns import STATUS_NAMES, G
from .contact import SLIP_TOL, _contact_accel, _start_from_rest
from .flight import _unit_tangent, locate, next_landing, path_height
from .impact import _collide, _draw, impact
from .recording import _record, _record_restart, _traj_row
from .rock import simulate_rock

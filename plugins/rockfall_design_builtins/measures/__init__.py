"""The built-in protective measures: fence, wall, boulder row, ditch, berm, forest.

Ordinary plugins, one module each (:mod:`.fence`, :mod:`.wall`,
:mod:`.boulder_row`, :mod:`.ditch`, :mod:`.berm`, :mod:`.protection_forest`,
with what they share in
:mod:`.shared`): each uses only the public ``rockfall_design`` API and is
registered by its own entry point of the ``rockfall_design`` group, exactly
as a third party's measure would be. This package registers nothing; it
only names the classes, so that ``from rockfall_design_builtins.measures
import Fence`` keeps working.

Three measures are barriers (:class:`~rockfall_design.Barrier`), which stand
at a station and leave the ground as it is:

* ``fence`` -- flexible net (:attr:`~rockfall_design.BarrierBehaviour.NET`);
* ``wall`` -- rigid wall of gabions or concrete (:attr:`~rockfall_design.BarrierBehaviour.RIGID`);
* ``boulder_row`` -- a row of cubic blocks with gaps
  (:attr:`~rockfall_design.BarrierBehaviour.BLOCKS`).

Three are edits of the ground (:class:`~rockfall_design.ProfileEdit`), which the
engine splices into the section before the rocks run:

* ``ditch`` -- a trapezoidal catch ditch dug into the slope;
* ``berm`` -- a horizontal bench cut into the slope, with a cut face above it;
* ``protection_forest`` -- a managed stand of trees on a stretch, the ground
  kept as it is (a :class:`~rockfall_design.Stand` on the edit).

The engine, not the measure, applies the catch conditions; each class
documents the condition that its footprint asks for. All lengths are in m,
angles in degrees, energies in kJ, densities in kg/m^3.
"""

from .berm import Berm, BermParams
from .boulder_row import BoulderRow, BoulderRowParams
from .ditch import Ditch, DitchParams
from .fence import Fence, FenceParams, residual_height_category
from .protection_forest import ProtectionForest, ProtectionForestParams
from .shared import SectionLike, cut_and_fill
from .wall import Wall, WallParams

__all__ = [
    "Berm",
    "BermParams",
    "BoulderRow",
    "BoulderRowParams",
    "Ditch",
    "DitchParams",
    "Fence",
    "FenceParams",
    "ProtectionForest",
    "ProtectionForestParams",
    "SectionLike",
    "Wall",
    "WallParams",
    "cut_and_fill",
    "residual_height_category",
]

"""Moved: the tables are now :mod:`rockfall_design.report.tables`.

This module stays so that ``from rockfall_design.tables import ...`` in users'
scripts and notebooks keeps working: it hands on the public names of
:mod:`rockfall_design.report.tables`, which new code imports instead.
"""

# Exactly the new module's __all__, so the two cannot drift apart.
from .report.tables import *  # noqa: F403
from .report.tables import __all__  # noqa: F401

"""Moved: the figures are now :mod:`rockfall_design.report.figures`.

This module stays so that ``from rockfall_design.figures import ...`` in users'
scripts and notebooks keeps working: it hands on the public names of
:mod:`rockfall_design.report.figures`, which new code imports instead.
"""

# Exactly the new module's __all__, so the two cannot drift apart.
from .report.figures import *  # noqa: F403
from .report.figures import __all__  # noqa: F401
from .report.figures import figure_svg as figure_svg  # public, though never in __all__

"""Moved: the HTML and Markdown reports are now :mod:`rockfall_design.report.documents`.

This module stays so that ``from rockfall_design.documents import ...`` in
users' scripts and notebooks keeps working: it hands on the public names of
:mod:`rockfall_design.report.documents`, which new code imports instead.
"""

# Exactly the new module's __all__, so the two cannot drift apart.
from .report.documents import *  # noqa: F403
from .report.documents import __all__  # noqa: F401

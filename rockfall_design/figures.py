"""Moved: the figures are now :mod:`rockfall_design.report.figures`.

This module stays so that ``from rockfall_design.figures import ...`` in users'
scripts and notebooks keeps working: it hands on the public names of
:mod:`rockfall_design.report.figures`, which new code imports instead.
"""

from .report.figures import (
    CAPTIONS,
    DEFAULT_MIN_ROCKS_ENVELOPE,
    FIGURE_FORMATS,
    RockfallFigure,
    alternatives_figure,
    envelopes_figure,
    margins_figure,
    no_stop_reason,
    profile_figure,
    save_figures,
    stops_figure,
    study_figures,
)
from .report.figures import figure_svg as figure_svg  # public, though never in __all__

__all__ = [
    "RockfallFigure",
    "FIGURE_FORMATS",
    "CAPTIONS",
    "DEFAULT_MIN_ROCKS_ENVELOPE",
    "profile_figure",
    "envelopes_figure",
    "stops_figure",
    "alternatives_figure",
    "margins_figure",
    "study_figures",
    "save_figures",
    "no_stop_reason",
]

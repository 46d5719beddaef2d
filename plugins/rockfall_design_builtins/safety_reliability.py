"""The old import path of the ``reliability`` concept, kept so that it keeps working.

The concept lives in :mod:`rockfall_design_builtins.safety.reliability`,
registered by its own entry point; this module registers nothing.
"""

from .safety.reliability import ReliabilityConcept, life_probability

__all__ = ["ReliabilityConcept", "life_probability"]

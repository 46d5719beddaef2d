"""Tests of rockfall_design.optimiser."""

"""Tests of rockfall_design.engine."""

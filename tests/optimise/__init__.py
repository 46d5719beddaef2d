"""Tests of rockfall_design.optimise."""

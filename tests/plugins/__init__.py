"""Tests of rockfall_design.plugins."""

"""Tests of rockfall_design.trial."""

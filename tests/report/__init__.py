"""Tests of rockfall_design.report."""

"""Tests of rockfall_design.project."""

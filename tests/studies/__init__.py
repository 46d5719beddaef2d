"""Tests of rockfall_design.studies."""

"""Tests of rockfall_design.study."""

"""Tests of rockfall_design.judge."""

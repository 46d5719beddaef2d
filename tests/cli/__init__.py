"""Tests of the command line (rockfall_design.cli.program)."""

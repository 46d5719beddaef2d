"""The optimiser weighs a protection forest against a fence (design_forest_or_fence.yaml)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rockfall_design.cli.program import main

PROJECTS = Path(__file__).resolve().parents[2] / "projects"


@pytest.mark.slow  # an optimisation with a ground edit per forest geometry: minutes on one core
def test_optimise_weighs_a_forest_against_a_fence(capsys):
    """Both families are searched; the chosen one holds on fresh rocks and is reported."""
    code = main(["optimise", str(PROJECTS / "design_forest_or_fence.yaml"), "--json"])
    s = json.loads(capsys.readouterr().out)
    assert code == 0, s
    names = {a["name"] for a in s["alternatives"]}
    assert {"fence", "protection_forest"} <= names, names
    assert s["best"] is not None and s["best"]["holds_on_fresh_rocks"] is True
    chosen = s["best"]["name"]
    assert chosen in {"fence", "protection_forest"}
    print(f"optimise chose {chosen} at {s['best']['cost']:,.0f}")

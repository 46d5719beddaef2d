"""The bundled terrain example end to end: a corridor designed from a DEM, back on the map."""

from __future__ import annotations

import json
from pathlib import Path

import pyogrio
import pytest

from rockfall_design.cli.program import main

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "terrain" / "corridor.yaml"


@pytest.mark.slow
def test_the_bundled_terrain_corridor_is_designed_and_mapped(tmp_path, capsys):
    out = tmp_path / "results"
    # What is checked here is the corridor's way from the DEM to the map, not the
    # designs: a last look of 20,000 rocks instead of 400,000 gives every section a
    # design in 14 s instead of 60-90 s (2026-11-28).
    code = main(["optimise", str(EXAMPLE), "--out", str(out), "--plot", str(out), "--json",
                 "--max-rocks", "20000"])
    summary = json.loads(capsys.readouterr().out)
    assert code == 0
    assert summary["totals"]["sections"] >= 10
    assert summary["totals"]["ok"]
    meta, _, geometry, fields = pyogrio.raw.read(out / "measures.gpkg")
    assert meta["geometry_type"] == "LineString"
    assert "25832" in meta["crs"]
    names = list(meta["fields"])
    for key in ("type", "product", "height_m", "capacity_kj", "cost", "section", "station_m"):
        assert key in names
    assert sum(b["road"]["length_m"] for b in summary["sections"]) == pytest.approx(562.05,
                                                                                  abs=0.1)
    sections = {b["name"] for b in summary["sections"]}
    assert set(fields[names.index("section")]) == sections  # a measure in every section
    assert len(geometry) == sum(len(b["best"]["measures"]) for b in summary["sections"])
    assert (out / "map.png").stat().st_size > 10_000

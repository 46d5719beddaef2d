"""examples/section_from_points.py: a section cut from terrain points, ready for a project,
and the whole way from map points to `compare`."""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
from numpy.testing import assert_allclose

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _module():
    spec = importlib.util.spec_from_file_location("section_from_points",
                                                  EXAMPLES / "section_from_points.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _terrain(rng: np.random.Generator) -> np.ndarray:
    """Scan-like points of a slope falling east, 0.6 m per m, flat beyond e = 60 m,
    with a 5 m tall shrub beside the trace and one on it."""
    e = rng.uniform(0, 100, 20_000)
    n = rng.uniform(-20, 20, 20_000)
    z = 100 - 0.6 * np.minimum(e, 60.0)
    z[(np.abs(n - 8) < 1) & (np.abs(e - 30) < 3)] += 5.0   # off the corridor
    shrub = (np.abs(n) < 2) & (np.abs(e - 41) < 0.5)
    z[shrub & (rng.random(len(e)) < 0.3)] += 3.0           # a few returns from a shrub
    return np.column_stack([e, n, z])


def test_a_section_follows_the_ground_under_the_trace():
    mod = _module()
    pts = _terrain(np.random.default_rng(1))
    trace = np.array([[0.0, 0.0], [100.0, 0.0]])
    x, y, used = mod.section(pts, trace, corridor=2.0, step=2.0)
    assert 0 < used < len(pts)
    assert np.all(np.diff(x) > 0)
    assert_allclose(x[:3], [1.0, 3.0, 5.0])
    # the median keeps the ground, not the shrub; the point off the corridor is not used
    assert_allclose(y, 100 - 0.6 * np.minimum(x, 60.0), atol=0.7)
    assert mod.materials_at(np.array([0.0, 10.0, 70.0]), "soil", [(60.0, "floor")]) == \
        ["soil", "soil", "floor"]


def test_too_few_points_are_refused(tmp_path):
    (tmp_path / "t.xyz").write_text("0 30 100\n10 30 94\n")
    (tmp_path / "trace.csv").write_text("e,n\n0,0\n100,0\n")
    run = subprocess.run([sys.executable, str(EXAMPLES / "section_from_points.py"),
                          str(tmp_path / "t.xyz"), str(tmp_path / "trace.csv"),
                          str(tmp_path / "s.csv")], capture_output=True, text=True)
    assert run.returncode == 2 and "too few" in run.stderr
    assert not (tmp_path / "s.csv").exists()


def test_from_map_points_to_compare(tmp_path, capsys):
    """Terrain points and deposit points in map coordinates become a project whose
    section and stops `compare` reads: the way docs/calibration.md shows for a site."""
    from rockfall_design.cli.program import main

    rng = np.random.default_rng(2)
    pts = _terrain(rng)
    np.savetxt(tmp_path / "terrain.xyz", pts, fmt="%.3f", header="E N Z")
    (tmp_path / "trace.csv").write_text("e,n\n0,0\n100,0\n")
    run = subprocess.run([sys.executable, str(EXAMPLES / "section_from_points.py"),
                          str(tmp_path / "terrain.xyz"), str(tmp_path / "trace.csv"),
                          str(tmp_path / "section.csv"), "--step", "5", "--material", "slope",
                          "--zone", "60", "floor"], capture_output=True, text=True, check=True)
    assert "section points" in run.stderr
    rows = (tmp_path / "section.csv").read_text().splitlines()
    assert rows[0] == "x,y,material" and rows[1].endswith(",slope") and rows[-1].endswith(",")
    e = rng.uniform(62, 90, 12)
    n = rng.uniform(-5, 5, 12)
    dep = "E,N,mass\n" + "".join(f"{a:.2f},{b:.2f},{200:.0f}\n" for a, b in zip(e, n, strict=True))
    (tmp_path / "deposits.csv").write_text(dep)
    subprocess.run([sys.executable, str(EXAMPLES / "stops_from_points.py"),
                    str(tmp_path / "deposits.csv"), str(tmp_path / "trace.csv"),
                    str(tmp_path / "stops.csv"), "--e", "E", "--n", "N", "--mass", "mass",
                    "--corridor", "10"], check=True, capture_output=True)
    (tmp_path / "site.yaml").write_text("""\
name: site from map points
slope: {csv: section.csv}
materials:
  slope: {restitution: 0.3, friction: 0.6, rolling_resistance: 0.4}
  floor: {restitution: 0.25, friction: 0.6, rolling_resistance: 0.6}
rocks:
  count: 40
  seed: 5
  volume: 0.1
  release: {x: [3, 5], height: 0.5}
""")
    code = main(["compare", str(tmp_path / "site.yaml"), "--observed",
                 str(tmp_path / "stops.csv"), "--json"])
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    assert out["fit"]["observed"]["count"] == 12

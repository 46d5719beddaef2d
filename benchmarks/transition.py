"""How the answer moves with engine.v_contact: it should not (docs/PHYSICS.md).

    python benchmarks/transition.py [--rocks 2000] [--seed 5] [--projects a.yaml ...]

For each project (by default the steep-to-flat section of issue 35 and the
bundled projects whose grounds are all ``spang`` or ``rough_soft``), the same
rocks are run at v_contact = 2, 1, 0.5, 0.25, 0.1 and 0.05 m/s, and this prints
the median stop position and, at each analysis station, the 95th percentiles
of the passing height and of the energy, each with its two-sided 95 %
distribution-free interval (order statistics, rockfall_design.judge.bounds),
and whether every figure's interval overlaps that of the smallest setting.
``rn_rt`` grounds depend on v_contact by their law (docs/PHYSICS.md, "Not for
rn_rt"); give such a project with ``--projects`` to see by how much.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import rockfall_design as rd  # noqa: E402
from rockfall_design.judge.bounds import quantile_with_bounds  # noqa: E402

SETTINGS = (2.0, 1.0, 0.5, 0.25, 0.1, 0.05)
DEFAULT_PROJECTS = ("projects/standard_slope.yaml", "projects/design_two_zones.yaml",
                    "projects/study_talus.yaml")

STEEP_TO_FLAT = """\
name: Steep to flat
description: A 35 degree soil slope onto flat hard ground (issue 35).
slope:
  points: [[0, 60], [10, 58], [70, 16], [75, 15], [250, 15]]
  materials: [soil, soil, soil, hard]
materials:
  soil: {restitution: 0.3, friction: 0.6, rolling_resistance: 0.7, roughness_deg: 4}
  hard: {restitution: 0.5, friction: 0.5, rolling_resistance: 1.0, roughness_deg: 8}
rocks:
  count: 2000
  seed: 3
  volume: {lognormal: [0.3, 0.6]}
  release: {x: [2, 8], height: 16, velocity: [0.5, 0]}
analysis: {stations: [40, 72]}
protect: {x: 200}
"""
"""Issue 35's steep-to-flat case: soil rolling resistance 0.7, hard ground 1.0."""


def _with_v_contact(text: str, v_contact: float) -> str:
    """The project text with ``engine.v_contact`` set (appended or replaced)."""
    lines = [ln for ln in text.splitlines() if not ln.startswith("engine:")]
    return "\n".join(lines) + f"\nengine: {{v_contact: {v_contact}}}\n"


def figures(text: str, base: Path, v_contact: float, rocks: int, seed: int
            ) -> dict[str, tuple[float, float | None, float | None]]:
    """Median stop (m) and station p95 height (m) and energy (kJ), each with its interval."""
    with tempfile.NamedTemporaryFile("w", suffix=".yaml", dir=base, delete=False) as f:
        f.write(_with_v_contact(text, v_contact))
    try:
        res = rd.simulate(f.name, rocks=rocks, seed=seed, trajectories=0)
    finally:
        Path(f.name).unlink()
    out = {}
    end_x = res.rocks["end_x_m"].to_numpy()
    out["median end x (m)"] = quantile_with_bounds(end_x, 0.5, 0.975)
    cross = res.crossings
    for x, grp in cross[cross["crossed"]].groupby("station_x_m"):
        for col, unit in (("passing_height_m", "m"), ("energy_kj", "kJ")):
            key = f"p95 {col.split('_')[0]} at {x:g} ({unit})"
            out[key] = quantile_with_bounds(grp[col].to_numpy(), 0.95, 0.975)
    return out


def _overlap(a: tuple, b: tuple) -> bool:
    """Whether two (value, lower, upper) intervals overlap (an open end overlaps)."""
    lo_a = -np.inf if a[1] is None else a[1]
    hi_a = np.inf if a[2] is None else a[2]
    lo_b = -np.inf if b[1] is None else b[1]
    hi_b = np.inf if b[2] is None else b[2]
    return lo_a <= hi_b and lo_b <= hi_a


def report(name: str, text: str, base: Path, rocks: int, seed: int) -> bool:
    """Print one project's table; True if every figure agrees with the smallest setting's."""
    rows = {vc: figures(text, base, vc, rocks, seed) for vc in SETTINGS}
    ref = rows[SETTINGS[-1]]
    print(f"\n{name} ({rocks} rocks, seed {seed})")
    ok = True
    for key in ref:
        print(f"  {key}")
        for vc in SETTINGS:
            v, lo, hi = rows[vc].get(key, (np.nan, None, None))
            agree = key in rows[vc] and _overlap(rows[vc][key], ref[key])
            ok &= agree or vc > 0.5
            lo = np.nan if lo is None else lo
            hi = np.nan if hi is None else hi
            print(f"    v_contact {vc:5.2f}: {v:9.2f}  [{lo:9.2f}, {hi:9.2f}]  "
                  f"{'ok' if agree else 'DIFFERS'}")
    print(f"  every figure from 0.05 to 0.5 m/s within the intervals: {ok}")
    return ok


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rocks", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--projects", nargs="*", default=list(DEFAULT_PROJECTS))
    args = ap.parse_args(argv)
    ok = report("steep to flat", STEEP_TO_FLAT, ROOT / "projects", args.rocks, args.seed)
    for p in args.projects:
        path = (ROOT / p) if not Path(p).is_absolute() else Path(p)
        ok &= report(path.name, path.read_text(), path.parent, args.rocks, args.seed)
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())

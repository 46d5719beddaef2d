"""Where the rocks of projects/benchmark.yaml stop under each roughness convention.

    python benchmarks/roughness.py [--rocks 20000] [--pyrockfall-python PATH]

Conventions, each on the benchmark's rn_rt talus:

* ``gauss``: rockfall-design's ``roughness_deg: 5``, the normal tilted by
  N(0, 5 deg) either way;
* ``height``: ``roughness_height_m: 0.1`` (and ``roughness_deg: 0``), the
  normal tilted against the motion by U(0, atan(0.1 / 0.5)) = U(0, 11.3 deg),
  the one-sided convention of PlatRock and PyRockfall (PHYSICS.md, Options);
* ``none``: no roughness.

The same three in PyRockfall 0.1.2 (benchmarks/_pyrockfall_case.py) if an
interpreter with it is given. No peer publishes statistics for this slope, so
the comparison is with what PyRockfall gives on it. The two models differ in
more than roughness (PyRockfall: lumped mass, sliding stepped in time, no
rolling resistance), so compare the shift each convention causes within one
model rather than the absolute stops across models.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
PROJECT = ROOT / "projects" / "benchmark.yaml"
QS = (5, 25, 50, 75, 95, 99)


def ours(convention: str, rocks: int) -> dict[str, float]:
    from rockfall_design.engine.columns import STOPPED
    from rockfall_design.project import load_project_text
    from rockfall_design.run.simulation import run_in_memory

    text = PROJECT.read_text()
    if convention == "height":
        text = text.replace("roughness_deg: 5", "roughness_deg: 0\n    roughness_height_m: 0.1")
    elif convention == "none":
        text = text.replace("roughness_deg: 5", "roughness_deg: 0")
    run = run_in_memory(load_project_text(text, str(PROJECT)), rocks=rocks)
    r = run.result
    x = r.x_end[r.status == STOPPED]
    return {"stopped": int(x.size), **{f"p{q}": float(np.percentile(x, q)) for q in QS},
            "beyond_150": float(np.mean(r.max_x >= 150.0))}


def peer(python: str, convention: str, rocks: int) -> dict[str, float] | None:
    script = ROOT / "benchmarks" / "_pyrockfall_case.py"
    try:
        out = subprocess.run([python, str(script), str(rocks), convention], check=True,
                             capture_output=True, text=True).stdout
    except (OSError, subprocess.CalledProcessError) as err:
        print(f"PyRockfall run failed: {err}", file=sys.stderr)
        return None
    p = json.loads(out)
    return {"stopped": p["stopped_on_section"],
            **{f"p{q}": p["stop_x_percentiles"][str(q)] for q in QS}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rocks", type=int, default=20_000)
    ap.add_argument("--pyrockfall-python", default=None)
    args = ap.parse_args()
    head = "  ".join(f"{'p' + str(q):>7s}" for q in QS)
    print(f"stop x (m) of the rocks at rest, {args.rocks:,} rocks")
    print(f"{'model':16s} {'convention':10s} {'stopped':>8s}  {head}")
    for conv in ("gauss", "height", "none"):
        rows = [("rockfall-design", ours(conv, args.rocks))]
        if args.pyrockfall_python:
            p = peer(args.pyrockfall_python, conv, args.rocks)
            if p is not None:
                rows.append(("PyRockfall 0.1.2", p))
        for name, s in rows:
            vals = "  ".join(f"{s['p' + str(q)]:7.1f}" for q in QS)
            print(f"{name:16s} {conv:10s} {s['stopped']:>8,d}  {vals}")


if __name__ == "__main__":
    main()

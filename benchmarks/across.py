"""Designs across scenarios: speed, and whether the chosen design holds in every scenario.

    python benchmarks/across.py [--project projects/design_two_zones.yaml] [--seed 11]
                                [--rocks 1500] [--no-check] [--across-only]

Adds a study of three scenarios to a bundled design project (the restitution
of its first material at 0.9x, 1x and 1.1x its value, a grid) with
``design.scenarios: all``, and prints

* the wall time of ``optimise`` across the scenarios (warm: numba compiled
  first) and of the single-scenario optimiser on the project as written, the
  designs screened, the exact runs, the rocks simulated, and the chosen
  designs and costs;
* the binding scenario and its margin;
* the chosen design checked as an engineer would, ``check design.yaml
  --scenarios`` with the rocks that decided it and with twice as many
  (the seed of each check given): in how many scenarios it holds on the
  point values and with confidence (skipped with ``--no-check``).

``--rocks`` sets the search rocks of both optimisations (default: the
project's ``rocks.count``), and ``--across-only`` skips the one of the
project as written, for a quick look at several seeds.

Figures are from one run on this machine; run it again to compare.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from rockfall_design.api import optimise
from rockfall_design.plugins import load_registry
from rockfall_design.project import dump_yaml, load_project, load_project_text

ROOT = Path(__file__).resolve().parents[1]


def _study_project(path: Path, directory: Path) -> Path:
    """The project with a study of its first material's restitution and design.scenarios."""
    project = load_project(path)
    data = project.resolved_dict()
    name, material = next(iter(data["materials"].items()))
    e = float(material["restitution"])
    values = [round(min(1.0, f * e), 4) for f in (0.9, 1.0, 1.1)]
    data["study"] = {"vary": {f"materials.{name}.restitution": values}, "scenarios": "grid"}
    data["design"]["scenarios"] = "all"
    out = directory / "across.yaml"
    out.write_text(dump_yaml(data))
    load_project_text(out.read_text(), str(out))  # valid as written
    return out


def _check(design: Path, rocks: int, seed: int) -> dict:
    out = subprocess.run(
        [sys.executable, "-m", "rockfall_design", "check", str(design), "--scenarios",
         "--rocks", str(rocks), "--seed", str(seed), "--json"],
        capture_output=True, text=True, check=False)
    return json.loads(out.stdout)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--project", type=Path, default=ROOT / "projects" /
                        "design_two_zones.yaml")
    parser.add_argument("--seed", type=int, default=None)
    parser.add_argument("--rocks", type=int, default=None,
                        help="search rocks of both optimisations (default: the project's)")
    parser.add_argument("--across-only", action="store_true",
                        help="only the optimisation across the scenarios (no warm-up: its "
                             "wall time then includes numba's compile, if not cached)")
    parser.add_argument("--no-check", action="store_true",
                        help="skip the check of the chosen design (two runs per scenario)")
    args = parser.parse_args()
    registry = load_registry()
    with tempfile.TemporaryDirectory() as tmp:
        tmpdir = Path(tmp)
        path = _study_project(args.project, tmpdir)
        runs = []
        if not args.across_only:
            single = load_project(args.project)
            optimise(single, rocks=200, seed=1, registry=registry)  # compile numba first
            t0 = time.perf_counter()
            one = optimise(single, rocks=args.rocks, seed=args.seed, registry=registry)
            runs.append(("as written", one, time.perf_counter() - t0))
        across_project = load_project(path)
        t0 = time.perf_counter()
        across = optimise(across_project, rocks=args.rocks, seed=args.seed,
                          registry=registry)
        runs.append(("across 3 scenarios", across, time.perf_counter() - t0))
        for label, res, wall in runs:
            s = res.summary
            best = res.best
            chosen = "none" if best is None else f"{best['name']} {best['cost']:,.0f}"
            print(f"{label:>20}: {wall:6.1f} s, {s['designs_evaluated']:,} designs screened, "
                  f"{s['exact_evaluations']} exact runs, {s['rocks_simulated']:,} rocks "
                  f"simulated; chosen: {chosen}")
        block = across.summary["scenarios"]
        if across.best is None or block["binding"] is None:
            print("no design holds across the scenarios:", across.summary["reason"])
            return
        b = block["binding"]
        print(f"binding scenario {b['index']} {b['values']}: margin {100 * b['margin']:+.1f} % "
              f"at {b['binds_at']}")
        if args.no_check:
            return
        from rockfall_design.cli.scenario_commands import across_design_yaml

        design = tmpdir / "design.yaml"
        design.write_text(across_design_yaml(across.result, path, across_project))
        decided = int(across.summary["rocks"])
        for rocks, seed in ((decided, across.seed), (2 * decided, 977)):
            c = _check(design, rocks, seed)
            print(f"check --scenarios, {rocks:,} rocks, run seed {seed}: holds in "
                  f"{c['holds_in']} of {c['of']} (with confidence in "
                  f"{c['holds_with_confidence_in']}); binding {c['binding']['index']}, margin "
                  f"{100 * (c['binding']['margin'] or 0):+.1f} %")


if __name__ == "__main__":
    main()

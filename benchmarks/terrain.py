"""Speed of a corridor along a road cut from a DEM: 50 sections, here and on Dask.

    python benchmarks/terrain.py [--sections 50] [--rocks 300] [--skip-optimise]

Takes the bundled example (examples/terrain/corridor.yaml: a SYNTHETIC DEM,
see examples/terrain/README.txt; no real DEM is bundled) with its spacing
set so that the road gives ``--sections`` sections, and times, once each:

1. loading it: every section's fall line traced up from the road, cut from
   the DEM, its materials from the cover polygons, its release zones;
2. ``simulate`` of every section in this process (``--workers 1``);
3. ``simulate`` on the local process pool (``--workers 2``);
4. ``simulate`` on a local Dask cluster (``distributed.LocalCluster``,
   two worker processes of one thread, ``--scheduler``);
5. ``optimise`` of the corridor (its sections one after the other in this
   process, as a corridor's optimise runs), unless ``--skip-optimise``.

The example's 300 rocks a section (600 at most for a decision) are the
fewest with which its sections' designs are admitted: at 200 (400) no
section's design can be shown to hold at 95 % and optimise finds none.

Each run is checked to give every section's rocks. The engine is compiled
before timing. Figures move by 10-50 % on a shared machine.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import re
import tempfile
import time
from pathlib import Path

import numpy as np

from rockfall_design.cli.program import main as cli
from rockfall_design.project import load_corridor
from rockfall_design.terrain.dem import read_dem
from rockfall_design.terrain.road import read_road

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "terrain"


def project_for(sections: int, rocks: int, folder: Path) -> Path:
    """The example with absolute paths, ``rocks`` rocks and ``sections`` sections."""
    dem = read_dem(EXAMPLE / "valley_dem.tif")
    road = read_road(EXAMPLE / "road.gpkg", dem.crs_wkt)
    length = float(np.hypot(*np.diff(road, axis=0).T).sum())
    spacing = length / sections * (1 + 1e-6)
    text = (EXAMPLE / "corridor.yaml").read_text()
    text = re.sub(r"spacing_m: \S+", f"spacing_m: {spacing:.6f}", text)
    text = re.sub(r"count: \d+", f"count: {rocks}", text)
    text = re.sub(r"max_rocks: \d+", f"max_rocks: {2 * rocks}", text)
    for name in ("valley_dem.tif", "road.gpkg", "cover.gpkg"):
        text = text.replace(f" {name}", f" {EXAMPLE / name}")
    text = text.replace("../../projects/", f"{ROOT / 'projects'}/")
    path = folder / "corridor50.yaml"
    path.write_text(text)
    return path


def timed(argv: list[str]) -> tuple[float, dict]:
    """Seconds of one command, and its JSON."""
    out = io.StringIO()
    start = time.perf_counter()
    with contextlib.redirect_stdout(out):
        code = cli(argv + ["--json"])
    seconds = time.perf_counter() - start
    if code not in (0, 1):
        raise SystemExit(f"{' '.join(argv)}: exit code {code}")
    return seconds, json.loads(out.getvalue())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sections", type=int, default=50)
    ap.add_argument("--rocks", type=int, default=300)
    ap.add_argument("--skip-optimise", action="store_true")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        path = project_for(args.sections, args.rocks, Path(folder))
        start = time.perf_counter()
        corridor = load_corridor(path)
        load_s = time.perf_counter() - start
        n = len(corridor.sections)
        points = [len(s.project.slope.points) for s in corridor.sections]
        print(f"corridor: {n} sections, {args.rocks} rocks each, section points "
              f"{min(points)}-{max(points)}; loaded (traced, cut, materials) in {load_s:.1f} s "
              f"({load_s / n * 1000:.0f} ms a section)")
        timed(["simulate", str(path), "--workers", "1", "--rocks", "20"])  # warm up
        rows = []
        for label, extra in (("this process (--workers 1)", ["--workers", "1"]),
                             ("local pool (--workers 2)", ["--workers", "2"])):
            seconds, out = timed(["simulate", str(path)] + extra)
            assert out["totals"]["rocks"] == n * args.rocks
            rows.append((label, seconds))
        import distributed  # the study extra; only here

        with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                      dashboard_address=None) as cluster:
            seconds, out = timed(["simulate", str(path), "--scheduler", cluster.scheduler_address])
            assert out["totals"]["rocks"] == n * args.rocks
            rows.append(("local Dask cluster (2 workers)", seconds))
        for label, seconds in rows:
            print(f"simulate on {label}: {seconds:.1f} s ({seconds / n:.2f} s a section)")
        if not args.skip_optimise:
            seconds, out = timed(["optimise", str(path)])
            ok = sum(1 for b in out["sections"] if b.get("best"))
            cost = out["totals"]["cost"]
            print(f"optimise (sections one after the other): {seconds:.1f} s "
                  f"({seconds / n:.2f} s a section); {ok} of {n} sections with a design"
                  + (f", total {cost:,.0f} {out['totals']['currency']}"
                     if cost is not None and not math.isnan(cost) else ""))


if __name__ == "__main__":
    main()

"""projects/benchmark.yaml in PyRockfall 0.1.2, for benchmarks/engine.py and roughness.py.

Run by those scripts in a separate interpreter that has ``pyrockfall==0.1.2``
installed (a benchmarks-only dependency: it pulls in tensorflow, open3d and
more, so it stays out of rockfall-design's own environment):

    python benchmarks/_pyrockfall_case.py ROCKS {gauss|height|none} [SEED]

Prints one JSON line: wall time (s) of the run alone and of the whole
process, rocks/s, the resident peak (MiB) and statistics of where the rocks
end (x of the end points, m).

The case, as close as PyRockfall's lumped-mass model allows: the slope's
polyline, Rn ~ N(0.35, 0.05) in [0, 1], Rt = 0.85, friction angle
atan(0.58 +- 0.05), rocks of 1387.5 kg (r = 0.5 m, 2650 kg/m^3) released at
x = 1 m just above the ground with (0.6, -0.8) m/s. Roughness: ``gauss``
tilts the normal by N(0, 5 deg) (rockfall-design's ``roughness_deg: 5``),
``height`` by U(0, atan(h / r)) degrees, positive (counter-clockwise, i.e.
against a rock moving towards +x, the sense of PyRockfall's examples), with
h = ``ROUGHNESS_HEIGHT_M``.
"""

from __future__ import annotations

import json
import resource
import sys
import time

T_START = time.perf_counter()

import numpy as np  # noqa: E402

POINTS = [[0, 100], [30, 60], [60, 30], [80, 20], [120, 15], [200, 12]]
ROUGHNESS_HEIGHT_M = 0.1
RADIUS_M = 0.5
DENSITY = 2650.0
# PyRockfall steps slides in time (10 ms) and stops at maxIter steps (default
# 1000, which cuts most paths here short); 0 lifts the limit.
MAX_ITER = 0


def main() -> None:
    import pyrockfall as pr
    from pyrockfall import stats

    n = int(sys.argv[1])
    convention = sys.argv[2]
    seed = int(sys.argv[3]) if len(sys.argv) > 3 else 42
    mass = 4.0 / 3.0 * np.pi * RADIUS_M**3 * DENSITY
    if convention == "gauss":
        rough = stats.Normal(0.0, 5.0)
    elif convention == "height":
        rough = stats.Uniform(0.0, float(np.degrees(np.arctan(ROUGHNESS_HEIGHT_M / RADIUS_M))))
    else:
        rough = 0.0
    mat = pr.Material(
        name="talus",
        normalRestitution=stats.Truncate(stats.Normal(0.35, 0.05), lower=0.0, upper=1.0),
        tangentialRestitution=0.85,
        frictionAngle=stats.Truncate(
            stats.Normal(float(np.degrees(np.arctan(0.58))), 2.5), lower=0.0, upper=60.0
        ),
        roughness=rough,
    )
    slope = pr.Slope(pr.Geometry(np.array(POINTS, dtype=float)), materials=mat)
    rock = pr.Rock(name="block", mass=mass, density=DENSITY)
    y0 = 100.0 - 40.0 / 30.0 * 1.0
    seeder = pr.Seeder(np.array([1.0, y0 + 0.05]), rocks=[rock])
    seeder.numberOfRocks = n
    seeder.translationalVelocity = [0.6, -0.8]
    analysis = pr.Analysis()
    analysis.slope = slope
    analysis.seeders = [seeder]
    analysis.useSpecificSeed = True
    analysis.specificSeed = seed
    analysis.maxIter = MAX_ITER
    t0 = time.perf_counter()
    analysis.run()
    run_s = time.perf_counter() - t0
    end_x = np.asarray(analysis.trajectories.endpoints)[0].ravel()
    end_x = end_x[np.isfinite(end_x)]
    inside = end_x[end_x < POINTS[-1][0] - 1e-6]
    out = {
        "rocks": n,
        "convention": convention,
        "run_s": run_s,
        "process_s": time.perf_counter() - T_START,
        "rocks_per_s_run": n / run_s,
        "peak_rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "stopped_on_section": int(inside.size),
        "stop_x_percentiles": {
            str(q): float(np.percentile(inside, q)) if inside.size else None
            for q in (5, 25, 50, 75, 95, 99)
        },
    }
    sys.stdout.write(json.dumps(out) + "\n")


if __name__ == "__main__":
    main()

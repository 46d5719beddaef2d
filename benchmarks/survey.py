"""Engine speed against the number of survey points (issue 27, item 8).

    python benchmarks/survey.py [--rocks 20000] [--points 1000 10000 100000]
                                [--noise 0.01] [--threads 1] [--varying-rocks 20]
                                [--sigma 0.2] [--size-step 0.005]
    PYTHONPATH=OTHER_TREE python benchmarks/survey.py   # the same for another engine

The standard slope (the 6 vertices of projects/benchmark.yaml and its rn_rt
talus) against noisy surveys of the same slope: n points evenly spaced in x,
heights with N(0, noise) errors, all measured in the same run. For each:

* the centre path of one radius (made once per run for rocks of one size);
* rocks of one radius (0.5 m, as the project): the run's wall time (centre
  path included), events per second, and the ratio to the 6-point section;
  then the same without the one making of the centre path (what a run of
  many more rocks tends to);
* rocks of sizes uniform in [0.3, 0.7] m: each rock has a centre path of its
  own (``--varying-rocks``, 0 to skip), made from the ground elements (segment
  offsets, vertex arcs) that the path of some radius in [0.3, 0.7] m can lie on
  (found once per run): how many of the survey's elements those are, the time
  to find them, and the time of one rock's path from them against that from
  every element. The 6-point row of this column runs 2,000 rocks (20 take a
  millisecond, too short to time); its rate is the one the others are set
  against;
* rocks of lognormal size (issue 34, item 9): ``--rocks`` rocks of radius
  0.5 m times exp(N(0, ``--sigma``)) (0.2: a volume's sigma of 0.6, as
  projects/quarry_road.yaml), rounded to size classes of relative step
  ``--size-step`` as a project's run rounds them on a survey
  (``run.releases.size_classes``): the run's wall time (every class's centre
  path included), events per second and their ratio to those of the rocks of
  one size on the same section (the issue's aim: within 3 times), and the
  same ratio of events per CPU second (the two runs again, one after the
  other: on a shared machine the wall times move with its load);
* for those rocks, how much of its own path a rock comes near: of the 1 m
  windows of the slope it travels over, the share in which it touches the
  ground or flies within its radius + 0.1 m of the window's highest point
  (what a path made only where the rock goes would still have to make).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from rockfall_design.engine import Material, Releases, Section, columns, run_ensemble
from rockfall_design.engine.records import Ground, Path

try:
    from rockfall_design.engine.ensemble import rock_path as _rock_path
except ImportError:  # an engine from before issue 27 (PYTHONPATH=OTHER_TREE, to compare)
    from rockfall_design.engine.profile import centre_path

    def _rock_path(ground, r, max_chord):  # noqa: D103 - the same work, older names
        px, py, pseg = centre_path(ground.x, ground.y, np.arange(ground.x.size - 1), r,
                                   max_chord)
        return Path(px, py, pseg, ground.seg_mat, ground.mats)

try:
    from rockfall_design.engine.profile import element_codes, path_elements
except ImportError:  # before the paths of rocks of several sizes were made from fewer elements
    element_codes = path_elements = None

try:
    from rockfall_design.run.releases import size_classes
except ImportError:  # an engine from before size classes: every size exact
    def size_classes(radius, step):  # noqa: D103 - the radii as they are
        return np.asarray(radius, dtype=float).copy()

EVERY = np.empty(0, dtype=np.int64)


def rock_path(ground, r, max_chord, elems=EVERY):
    """The engine's centre path of radius r (from the elements ``elems``, where it takes them)."""
    try:
        return _rock_path(ground, r, max_chord, elems)
    except TypeError:  # an engine whose rock_path takes every segment
        return _rock_path(ground, r, max_chord)

STANDARD = np.array([(0, 100), (30, 60), (60, 30), (80, 20), (120, 15), (200, 12)], float)
TALUS = Material(impact_model="rn_rt", restitution=0.35, tangential_restitution=0.85,
                 friction=0.58, rolling_resistance=0.3, roughness_deg=5.0,
                 sd_restitution=0.05, sd_friction=0.05, sd_rolling_resistance=0.02)


def section(points: int, noise: float, seed: int = 0) -> Section:
    """The standard slope (``points`` 0 or 6) or a noisy survey of it with ``points`` points."""
    if points <= len(STANDARD):
        x, y = STANDARD[:, 0].copy(), STANDARD[:, 1].copy()
    else:
        rng = np.random.default_rng(seed)
        x = np.linspace(0.0, 200.0, points)
        y = np.interp(x, STANDARD[:, 0], STANDARD[:, 1]) + rng.normal(0.0, noise, points)
    return Section(x, y, np.zeros(x.size - 1, dtype=np.int64), (TALUS,))


def releases(n: int, radius: np.ndarray | float) -> Releases:
    """n rocks released as in projects/benchmark.yaml."""
    return Releases(radius=np.broadcast_to(np.asarray(radius, dtype=float), (n,)).copy(),
                    density=2650.0, x=np.full(n, 1.0), height=np.zeros(n),
                    vx=np.full(n, 0.6), vy=np.full(n, -0.8), spin=np.zeros(n),
                    spin_rolling=np.zeros(n, dtype=bool))


def timed(sec: Section, rel: Releases, threads: int) -> tuple[float, int]:
    """Wall time (s) and events of one run."""
    t0 = time.perf_counter()
    res = run_ensemble(sec, rel, key=7, threads=threads)
    return time.perf_counter() - t0, res.events_total


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rocks", type=int, default=20_000)
    ap.add_argument("--points", type=int, nargs="+", default=[1000, 10_000, 100_000])
    ap.add_argument("--noise", type=float, default=0.01, help="sd of the survey heights (m)")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--varying-rocks", type=int, default=20)
    ap.add_argument("--sigma", type=float, default=0.2,
                    help="sd of ln(radius) of the lognormal rocks (0 to skip them)")
    ap.add_argument("--size-step", type=float, default=0.005,
                    help="relative step of their size classes")
    args = ap.parse_args()
    cases = [6, *args.points]
    # Compiled and warm before anything is timed.
    run_ensemble(section(6, 0.0), releases(2, [0.4, 0.5]), key=1, threads=1)
    warm = section(300, 0.01)
    run_ensemble(warm, releases(2, [0.4, 0.5]), key=1, threads=1)
    rock_path(Ground(warm.x, warm.y, warm.segment_material, warm.material_table()), 0.5,
              np.radians(5.0), _every(warm.x.size))
    print(f"{args.rocks:,} rocks of 0.5 m and {args.varying_rocks:,} of U(0.3, 0.7) m on each "
          f"section, {args.threads} thread(s), survey noise {args.noise} m")
    print(f"{'points':>8} {'path pieces':>11} {'centre path':>12} {'run (one size)':>15} "
          f"{'events/s':>12} {'vs 6 pts':>8} {'w/o path':>12} {'vs 6 pts':>8}   "
          f"{'sizes varying':>14} {'events/s':>10} {'vs 6 pts':>8}")
    base = None
    base_v = None
    details = []
    lognormal = []
    g = np.random.default_rng(0)
    for pts in cases:
        sec = section(pts, args.noise)
        ground = Ground(sec.x, sec.y, sec.segment_material, sec.material_table())
        t0 = time.perf_counter()
        # The engine's path of one size: on a survey, from every element by survey_path.
        path = rock_path(ground, 0.5, np.radians(5.0), _every(pts) if pts > 256 else EVERY)
        t_path = time.perf_counter() - t0
        t, ev = timed(sec, releases(args.rocks, 0.5), args.threads)
        rate = ev / t
        # The events alone: the run less one making of the centre path.
        bare = ev / max(t - t_path, 1e-9) if pts > 256 else rate
        base = base or rate
        line = (f"{pts:>8,} {path.px.size - 1:>11,} {t_path * 1e3:>10.1f} ms {t:>13.3f} s "
                f"{rate:>12,.0f} {base / rate:>7.1f}x {bare:>12,.0f} {base / bare:>7.1f}x")
        if args.varying_rocks:
            nv = args.varying_rocks if pts > len(STANDARD) else max(args.varying_rocks, 2000)
            tv, evv = timed(sec, releases(nv, g.uniform(0.3, 0.7, nv)), args.threads)
            base_v = base_v or evv / tv
            line += f"   {tv:>12.3f} s {evv / tv:>10,.0f} {base_v / (evv / tv):>7.1f}x"
            if path_elements is not None and pts > 256:
                details.append((pts, *_pruned(ground)))
        print(line, flush=True)
        if args.sigma > 0:
            lognormal.append((pts, rate, *_lognormal(sec, args)))
    if lognormal:
        print(f"\n{args.rocks:,} rocks of lognormal radius (median 0.5 m, sigma {args.sigma}) "
              f"in size classes of step {args.size_step}, against as many of 0.5 m")
        print(f"{'points':>8} {'classes':>8} {'run':>10} {'events/s':>12} "
              f"{'one size':>12} {'ratio':>6} {'per CPU s':>10}")
        for pts, rate, classes, tl, evl, cpu_ratio in lognormal:
            print(f"{pts:>8,} {classes:>8,} {tl:>8.3f} s {evl / tl:>12,.0f} {rate:>12,.0f} "
                  f"{rate / (evl / tl):>5.1f}x {cpu_ratio:>9.1f}x")
    if args.varying_rocks:
        print("\nrocks of U(0.3, 0.7) m: the share of the 1 m windows each travels over "
              "that it comes near (touches, or flies within r + 0.1 m of the highest point)")
        for pts in args.points:
            shares = _windows_near(section(pts, args.noise), args.varying_rocks)
            print(f"{pts:>8,} points: median {np.median(shares):.0%} "
                  f"({shares.min():.0%} to {shares.max():.0%}) of {shares.size} rocks")
    if details:
        print("\nrocks of U(0.3, 0.7) m: the elements (segment offsets, vertex arcs) their "
              "paths can lie on, found once per run")
        print(f"{'points':>8} {'elements kept':>16} {'found in':>10} {'path of 0.45 m':>15} "
              f"{'from every element':>19}")
        for pts, kept, t_find, t_kept, t_all in details:
            print(f"{pts:>8,} {kept:>8,} ({kept / (2 * pts - 1):>4.0%}) {t_find * 1e3:>7.1f} ms "
                  f"{t_kept * 1e3:>12.2f} ms {t_all * 1e3:>16.2f} ms")


def _lognormal(sec: Section, args: argparse.Namespace) -> tuple[int, float, int, float]:
    """Size classes of ``args.rocks`` lognormal radii and the run's wall time (s), events
    and events per CPU second against those of as many rocks of 0.5 m (CPU time: what the
    work costs, whatever else the machine runs)."""
    g = np.random.default_rng(2)
    radius = size_classes(0.5 * np.exp(args.sigma * g.standard_normal(args.rocks)),
                          args.size_step if sec.x.size > 256 else 0.0)
    rates = []
    for rel in (releases(args.rocks, 0.5), releases(args.rocks, radius)):
        c0 = time.process_time()
        t, ev = timed(sec, rel, args.threads)
        rates.append(ev / max(time.process_time() - c0, 1e-9))
    return int(np.unique(radius).size), t, ev, rates[0] / rates[1]


def _every(points: int) -> np.ndarray:
    """Every element of a ground of ``points`` vertices (or segment, for an older engine)."""
    return element_codes(points) if element_codes is not None else np.arange(points - 1)


def _windows_near(sec: Section, n: int, width: float = 1.0) -> np.ndarray:
    """Per rock of U(0.3, 0.7) m: the share of the ``width`` windows it travels over that it
    comes near (a contact in it, or a flight within r + 0.1 m of its highest ground point).

    Flights are sampled every 5 cm between their recorded ends (the engine
    records a rock's state at each event).
    """
    rel = releases(n, np.random.default_rng(1).uniform(0.3, 0.7, n))
    res = run_ensemble(sec, rel, key=7, threads=1, n_trajectories=n,
                       max_trajectory_points=200_000)
    x0 = sec.x[0]
    nwin = int(np.ceil((sec.x[-1] - x0) / width))
    top = np.full(nwin, -np.inf)
    np.maximum.at(top, np.minimum(((sec.x - x0) / width).astype(int), nwin - 1), sec.y)
    c = columns
    shares = []
    for i, t in enumerate(res.trajectories):
        r = rel.radius[i]
        near = np.zeros(nwin, dtype=bool)
        for a, b in zip(t[:-1], t[1:], strict=False):
            if a[c.T_MODE] == c.CONTACT:
                lo = int((min(a[c.T_X], b[c.T_X]) - r - x0) / width)
                hi = int((max(a[c.T_X], b[c.T_X]) + r - x0) / width)
                near[max(lo, 0):min(hi, nwin - 1) + 1] = True
                continue
            ts = np.linspace(0.0, b[c.T_T] - a[c.T_T],
                             max(int(abs(b[c.T_X] - a[c.T_X]) / 0.05), 2))
            xs = a[c.T_X] + a[c.T_VX] * ts
            ys = a[c.T_Y] + a[c.T_VY] * ts - 0.5 * c.G * ts ** 2
            w = np.clip(((xs - x0) / width).astype(int), 0, nwin - 1)
            near[w[ys - top[w] < 1.01 * r + 0.1]] = True
        travelled = int((res.max_x[i] - x0) / width) + 1
        shares.append(near[:travelled].sum() / max(travelled, 1))
    return np.array(shares)


def _pruned(ground: Ground) -> tuple[int, float, float, float]:
    """Elements kept for radii in [0.3, 0.7] m, time to find them, and one path (0.45 m) from
    them and from every element (s, best of 3)."""
    chord = np.radians(5.0)
    t0 = time.perf_counter()
    kept = path_elements(ground.x, ground.y, 0.3, 0.7, chord)
    t_find = time.perf_counter() - t0
    every = element_codes(ground.x.size)

    def best(s: np.ndarray) -> float:
        times = []
        for _ in range(3):
            t = time.perf_counter()
            rock_path(ground, 0.45, chord, s)
            times.append(time.perf_counter() - t)
        return min(times)

    return kept.size, t_find, best(kept), best(every)


if __name__ == "__main__":
    main()

"""Which inputs one profile's stops pin down, and which decide a second profile.

docs/calibration.md, "A real site", "Why P2 is not predicted": a
one-at-a-time sensitivity of the level shares of two profiles (the Authume
P1 and P2 projects that ``examples/authume_quarry.py --law rough_soft``
writes) to each input of the first profile's ``calibrate: fit:``, each set
to the low end, the middle and the high end of its range while the others
stay at the project's values. An input that moves the calibrated profile's
shares by less than the observations' Wilson intervals can tell apart is
not pinned down by them; if it moves the second profile's shares, the
prediction of the second depends on what the first leaves open.

For each run it prints each level's share, the median stop, and at the
``--stations`` of the second profile the share of the rocks that passed
and their median speed::

    python examples/authume_sensitivity.py authume_P1.yaml stops_P1.csv \\
        authume_P2.yaml stops_P2.csv --rocks 500 --stations 23 30

Both projects take the observed masses as ``compare`` does (a lognormal
fitted to each profile's blocks).
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rockfall_design.calibration.distances import level_shares, stop_positions
from rockfall_design.calibration.fit import FitProblem, problem_for
from rockfall_design.calibration.observations import (
    Observations,
    read_observations,
    size_distribution,
    size_limits,
)
from rockfall_design.project import load_project
from rockfall_design.run.simulation import run_in_memory
from rockfall_design.studies.paths import with_values


@dataclass
class Profile:
    """One profile: its fit problem (project, base, levels) and its observed blocks."""

    name: str
    problem: FitProblem
    observed: Observations
    seed: int
    fit: dict[str, tuple[float, float]]


def load(name: str, project_path: Path, observed_path: Path, rocks: int,
         stations: tuple[float, ...] = ()) -> Profile:
    """The profile's project with the observed sizes, and ``stations`` (m) to record at."""
    project = load_project(project_path)
    obs = read_observations(observed_path, project.slope.x_range,
                            size_limits(project.rocks.density))
    levels = project.calibrate.levels if project.calibrate is not None else {}
    problem = problem_for(project, {}, levels=levels, rocks=rocks,
                          sizes=size_distribution(obs))
    if stations:
        problem.base.setdefault("analysis", {})["stations"] = list(stations)
    fit = dict(project.calibrate.fit) if project.calibrate is not None else {}
    return Profile(name, problem, obs, int(project.rocks.seed), fit)


def summary(p: Profile, values: dict[str, float], rocks: int) -> str:
    """One run of profile ``p`` at ``values``: level shares, median stop, passages."""
    run = run_in_memory(with_values(p.problem.project, values, base=p.problem.base),
                        rocks=rocks, seed=p.seed)
    r = run.result
    stops = stop_positions(r.x_end, r.status, p.problem.x_range)
    shares = level_shares(p.observed.x, stops, p.problem.levels)
    cells = " ".join(f"{s.name} {s.simulated_share:.2f}{'' if s.consistent else '*'}"
                     for s in shares)
    text = f"{p.name}: {cells}; median {np.median(stops):.1f} m"
    if r.stations.size:
        speed = run.crossing_arrays()["velocity_ms"]
        for j, xs in enumerate(r.stations):
            v = speed[:, j][np.isfinite(speed[:, j])]
            med = f"{np.median(v):.1f} m/s" if v.size else "-"
            text += f"; at {xs:g} m {v.size / r.n:.2f} passed, median {med}"
    return text


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("project", type=Path, help="the calibrated profile's project (its fit:)")
    ap.add_argument("observed", type=Path, help="that profile's observed stops")
    ap.add_argument("other", type=Path, help="the second profile's project")
    ap.add_argument("other_observed", type=Path, help="the second profile's observed stops")
    ap.add_argument("--rocks", type=int, default=500, help="simulated rocks per run")
    ap.add_argument("--stations", type=float, nargs="*", default=(),
                    help="stations of the second profile to report passages at (m)")
    args = ap.parse_args(argv)

    first = load("P1", args.project, args.observed, args.rocks)
    second = load("P2", args.other, args.other_observed, args.rocks, tuple(args.stations))
    sys.stdout.write("* : outside the observed share's 95 % Wilson interval\n")
    sys.stdout.write(f"project values\n  {summary(first, {}, args.rocks)}\n"
                     f"  {summary(second, {}, args.rocks)}\n")
    for path, (lo, hi) in first.fit.items():
        for value in (lo, 0.5 * (lo + hi), hi):
            values = {path: value}
            sys.stdout.write(f"{path} = {value:g}\n  {summary(first, values, args.rocks)}\n"
                             f"  {summary(second, values, args.rocks)}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

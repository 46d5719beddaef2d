"""Predict a profile with each bootstrap refit of a calibration, and the size effect.

docs/calibration.md, "A real site": after ``calibrate authume_P1.yaml
--bootstrap N --out cal``, this runs profile P2's project once with the best
fit and once with each refit's values (``cal/replicates.csv``), with the
block masses drawn as ``compare`` draws them (a lognormal fitted to the
observed masses), and prints for each run the share of the stops on each
level of the project's ``calibrate:`` section against the observed share's
Wilson interval; then the Spearman rank correlation of mass and stop station,
on the simulated rocks (one that left the section counted at its end) and on
the observed blocks. Issue 35's figures follow for each run: the share of
the stops on the bench (the level ``--bench``) and below it (from the
bench's end to the section's end; a rock that left the section is on
neither, as in the fit) against the observed shares' 95 % Wilson intervals,
and a last line counts the refits that put both inside, and those whose
Spearman correlation exceeds 0.15::

    python examples/authume_refits.py authume_P2_calibrated.yaml stops_P2.csv \\
        --replicates cal/replicates.csv --rocks 1000

The project's materials library (``calibrated_materials.yaml``) gives the
values of everything not in ``replicates.csv``.
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

import numpy as np
from scipy.stats import spearmanr

from rockfall_design.calibration.distances import level_shares, stop_positions
from rockfall_design.calibration.fit import problem_for
from rockfall_design.calibration.observations import (
    read_observations,
    size_distribution,
    size_limits,
)
from rockfall_design.engine.columns import STOPPED
from rockfall_design.project import load_project
from rockfall_design.run.simulation import run_in_memory
from rockfall_design.studies.paths import with_values


def refits(path: Path | None) -> list[tuple[str, dict[str, float]]]:
    """The runs: the project as it is, then each refit's values (path -> value).

    Replicate 0 of ``replicates.csv`` is the best fit (the project's values
    after ``--save-materials``) and is not run twice.
    """
    runs: list[tuple[str, dict[str, float]]] = [("best fit", {})]
    if path is None:
        return runs
    with open(path, newline="", encoding="utf-8") as fh:
        for row in csv.DictReader(fh):
            if row["replicate"] == "0":  # the best fit itself, run first already
                continue
            values = {k: float(v) for k, v in row.items() if k.startswith("materials.")}
            runs.append((f"refit {row['replicate']}", values))
    return runs


#: Issue 35's threshold of the predicted mass-runout Spearman correlation.
SPEARMAN_MIN = 0.15


def cells(shares: list) -> str:
    """Each level's simulated share, (observed share, Wilson interval), OUT if outside."""
    return "; ".join(f"{s.name} {s.simulated_share:.2f} ({s.observed_share:.2f}, "
                     f"{s.low:.2f}..{s.high:.2f}){'' if s.consistent else ' OUT'}"
                     for s in shares)


def bench_and_below(observed: np.ndarray, stops: np.ndarray,
                    levels: dict[str, tuple[float, float]], bench: str,
                    last: float) -> list:
    """The bench's share and the share below it (bench end to ``last``, m), with Wilson."""
    lo, hi = levels[bench]
    return level_shares(observed, stops, {bench: (lo, hi), "below": (hi, last)})


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("project", type=Path, help="the profile's project (its calibrate: levels)")
    ap.add_argument("observed", type=Path, help="the profile's observed stops (x, mass_kg)")
    ap.add_argument("--replicates", type=Path, help="a calibration's replicates.csv")
    ap.add_argument("--rocks", type=int, default=1000, help="simulated rocks per run")
    ap.add_argument("--seed", type=int, help="seed (default: the project's rocks.seed)")
    ap.add_argument("--bench", default="bench",
                    help="the level whose share, and the share below it, are counted "
                    "(default bench)")
    args = ap.parse_args(argv)

    project = load_project(args.project)
    obs = read_observations(args.observed, project.slope.x_range,
                            size_limits(project.rocks.density))
    levels = project.calibrate.levels if project.calibrate is not None else {}
    problem = problem_for(project, {}, levels=levels, rocks=args.rocks,
                          sizes=size_distribution(obs))
    seed = int(project.rocks.seed if args.seed is None else args.seed)
    rho_obs = spearmanr(obs.size, obs.x) if obs.size is not None else None
    if args.bench not in levels:
        sys.stderr.write(f"{args.project}: no level {args.bench!r} under calibrate.levels "
                         f"(there: {', '.join(levels)})\n")
        return 2
    both = rho_ok = runs = 0
    for name, values in refits(args.replicates):
        run = run_in_memory(with_values(problem.project, values, base=problem.base),
                            rocks=args.rocks, seed=seed).result
        stops = stop_positions(run.x_end, run.status, problem.x_range)
        shares = level_shares(obs.x, stops, problem.levels)
        inside = sum(s.consistent for s in shares)
        # Every rock, a rock that left the section at the section's end (as
        # the fit counts it); the count of those stopped on it is shown.
        stopped = run.status == STOPPED
        rho = spearmanr(run.mass, stops) if np.ptp(stops) > 0 else None
        corr = ("n/a" if rho is None else
                f"{rho.statistic:+.2f} (p {rho.pvalue:.2g}, {int(stopped.sum())} stopped)")
        pair = bench_and_below(obs.x, stops, levels, args.bench, problem.x_range[1])
        sys.stdout.write(f"{name}: {inside}/{len(shares)} levels inside; {cells(shares)}; "
                         f"median stop {np.median(stops):.1f} m; Spearman mass-runout "
                         f"{corr}\n  issue 35: {cells(pair)}\n")
        if name != "best fit":
            runs += 1
            both += all(s.consistent for s in pair)
            rho_ok += rho is not None and rho.statistic > SPEARMAN_MIN
    if runs:
        sys.stdout.write(f"refits: {both} of {runs} put both the {args.bench} and the below "
                         f"shares inside their Wilson intervals; {rho_ok} of {runs} have a "
                         f"Spearman mass-runout above {SPEARMAN_MIN}\n")
    if rho_obs is not None:
        sys.stdout.write(f"observed: Spearman mass-runout {rho_obs.statistic:+.2f} "
                         f"(p {rho_obs.pvalue:.2g}, {obs.n} blocks)\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

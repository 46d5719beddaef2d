"""Coverage of the optimiser's sequential rule, in full (the suite runs a fast version).

    python benchmarks/sequential.py [--reps 4000] [--max-rocks N]

For a design whose true residual fraction sits exactly on the target (the
hardest case for both errors), it simulates the optimiser's looks
(:func:`rockfall_design.judge.sequential.plan_looks`: 0.1 % allowed,
3,000 rocks to the default ``design.max_rocks``, 95 %) and prints the share
of runs in which some look admits it and in which some look rejects it,
each with its Clopper-Pearson 99 % interval, for the spent schedule and for
the naive rule that uses the fixed-sample bounds at every look. Both shares
of the spent schedule must stay below 5 %.
"""

from __future__ import annotations

import argparse

import numpy as np

from rockfall_design.judge.bounds import fraction_lower_bound, fraction_upper_bound
from rockfall_design.judge.sequential import plan_looks
from rockfall_design.project.schema import DEFAULT_MAX_ROCKS


def _run(sizes, p, conf, reps, rng):
    steps = np.diff((0,) + tuple(sizes))
    admits = rejects = 0
    for _ in range(reps):
        counts = np.cumsum(rng.binomial(steps, p))
        adm = any(fraction_upper_bound(int(x), n, conf) <= p for n, x in zip(sizes, counts,
                                                                              strict=True))
        rej = any(fraction_lower_bound(int(x), n, conf) > p for n, x in zip(sizes, counts,
                                                                             strict=True))
        admits += adm
        rejects += rej
    return admits, rejects


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=4000)
    ap.add_argument("--max-rocks", type=int, default=DEFAULT_MAX_ROCKS,
                    help="the last look (default: design.max_rocks's default)")
    args = ap.parse_args()
    rng = np.random.default_rng(20261124)
    for allowed, first in ((0.001, 3000), (0.01, 600), (0.05, 200)):
        looks = plan_looks(first, args.max_rocks, 0.95, allowed)
        print(f"allowed {100 * allowed:g} %: looks {looks.sizes}, each at "
              f"{100 * looks.look_confidence:.3f} %")
        for label, conf in (("spent", looks.look_confidence), ("naive", 0.95)):
            a, r = _run(looks.sizes, allowed, conf, args.reps, rng)
            for what, k in (("admits", a), ("rejects", r)):
                lo = fraction_lower_bound(k, args.reps, 0.99)
                hi = fraction_upper_bound(k, args.reps, 0.99)
                print(f"  {label:5s} {what:7s} {k / args.reps:7.4f}  "
                      f"(99 % interval {lo:.4f} to {hi:.4f}; limit 0.05)")


if __name__ == "__main__":
    main()

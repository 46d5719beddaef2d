"""The sequential rule keeps its errors below 1 - confidence over all its looks.

Simulated looks at a design whose true residual fraction or true percentile
sits exactly on its target (the hardest case for both errors): across many
repetitions, the share of runs in which *any* look admits (a design that
does not hold) or *any* look rejects (one that holds) stays below
``1 - confidence`` with its own Clopper-Pearson margin. A naive rule that
looks at the fixed-sample bounds at every look is shown to exceed it, so the
test can see the difference. The full version is benchmarks/sequential.py.
"""

from __future__ import annotations

import numpy as np
import pytest

from rockfall_design.judge.bounds import (
    fraction_lower_bound,
    fraction_upper_bound,
    quantile_lower_bound,
    quantile_upper_bound,
)
from rockfall_design.judge.sequential import LookSchedule, plan_looks


def _fraction_errors(looks: LookSchedule, p: float, conf: float, reps: int,
                     rng: np.random.Generator) -> tuple[int, int]:
    """Runs in which some look admits, and in which some look rejects, at true fraction p."""
    admits = rejects = 0
    steps = np.diff((0,) + looks.sizes)
    for _ in range(reps):
        counts = np.cumsum(rng.binomial(steps, p))
        adm = rej = False
        for n, x in zip(looks.sizes, counts, strict=True):
            adm |= fraction_upper_bound(int(x), n, conf) <= p
            rej |= fraction_lower_bound(int(x), n, conf) > p
        admits += adm
        rejects += rej
    return admits, rejects


def test_plan_looks_divides_the_error_over_its_looks():
    looks = plan_looks(3000, 50_000, 0.95, 0.001)
    assert looks.sizes[-1] == 50_000 and len(looks) <= looks.spent_over
    assert looks.look_confidence == pytest.approx(1 - 0.05 / looks.spent_over)
    # the first look can show the target with no rock reaching, at the look's confidence
    assert fraction_upper_bound(0, looks.sizes[0], looks.look_confidence) <= 0.001
    assert all(b > a for a, b in zip(looks.sizes, looks.sizes[1:], strict=False))
    one = plan_looks(400, 400, 0.95)
    assert one.sizes == (400,) and one.look_confidence == pytest.approx(0.95)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_fraction_errors_stay_below_alpha_at_every_look(seed):
    conf, p, reps = 0.9, 0.02, 400
    looks = plan_looks(200, 3200, conf)
    rng = np.random.default_rng(seed)
    admits, rejects = _fraction_errors(looks, p, looks.look_confidence, reps, rng)
    limit = reps * (1 - conf)
    # each error's upper Clopper-Pearson bound (99 %) is compatible with <= 1 - conf
    assert fraction_lower_bound(admits, reps, 0.99) <= 1 - conf, (admits, limit)
    assert fraction_lower_bound(rejects, reps, 0.99) <= 1 - conf, (rejects, limit)


def test_the_naive_rule_that_looks_again_inflates_the_error():
    """Looking at every look with the fixed-sample bounds admits too often: the test can see it."""
    conf, p, reps = 0.9, 0.02, 400
    looks = plan_looks(200, 3200, conf)
    rng = np.random.default_rng(11)
    admits, _ = _fraction_errors(looks, p, conf, reps, rng)  # no spending
    assert fraction_lower_bound(admits, reps, 0.99) > 1 - conf


@pytest.mark.parametrize("seed", [4, 5])
def test_percentile_errors_stay_below_alpha_at_every_look(seed):
    conf, q, reps = 0.9, 0.9, 300
    looks = plan_looks(100, 1600, conf)
    c = looks.look_confidence
    rng = np.random.default_rng(seed)
    true_q = float(np.log(1 / (1 - q)))  # exponential(1): the 90 % quantile
    admits = rejects = 0
    for _ in range(reps):
        x = rng.exponential(1.0, looks.sizes[-1])
        adm = rej = False
        for n in looks.sizes:
            up = quantile_upper_bound(x[:n], q, c)
            low = quantile_lower_bound(x[:n], q, c)
            adm |= up is not None and up <= true_q
            rej |= low is not None and low > true_q
        admits += adm
        rejects += rej
    assert fraction_lower_bound(admits, reps, 0.99) <= 1 - conf
    assert fraction_lower_bound(rejects, reps, 0.99) <= 1 - conf

"""How sure a study's sensitivity is: lower bounds, the joint bounds, and the effect's interval."""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np
import pytest
from scipy import stats

import rockfall_design as rd
from rockfall_design.cli.program import main
from rockfall_design.judge.bounds import (
    fraction_bounds,
    fraction_lower_bound,
    fraction_upper_bound,
    quantile_index_table,
    quantile_indices,
    quantile_lower_bound,
    quantile_lower_index,
    quantile_upper_bound,
    quantile_upper_index,
)
from rockfall_design.project import load_project_text
from rockfall_design.studies.scenario_result import BoundsLadder, ScenarioBounds, ScenarioResult
from rockfall_design.studies.sensitivity import LADDER, effect_interval, joint_bounds

from .test_study import RUNOUT

#: A large effect (ten times the rock volume) and a small one (a friction step).
VOLUME_FRICTION = RUNOUT + ("  vary:\n    materials.talus.friction: [0.55, 0.6]\n"
                            "    rocks.volume: [0.3, 3.0]\n")
#: An input that moves nothing: the restitution of a material no segment uses.
NULL_INPUT = RUNOUT.replace("materials:\n", "materials:\n  unused: {restitution: 0.3, "
                            "friction: 0.5}\n") + (
    "  vary:\n    materials.unused.restitution: [0.2, 0.4]\n    rocks.volume: [0.5, 2.0]\n")
ENERGY = "measures[0] x=160 energy_kj p95"


def _study(text: str, rocks: int, seed: int) -> Any:
    return rd.study(load_project_text(text, "runout.yaml"), rocks=rocks, seed=seed, workers=1)


def _entry(result, target: str, parameter: str) -> dict:
    return next(e for e in result.summary["sensitivity"]
                if e["target"] == target and e["parameter"] == parameter)


# ---- the bounds of one sample ----------------------------------------------------------------


@pytest.mark.parametrize(("n", "q", "c"), [(1, 0.95, 0.9), (20, 0.95, 0.95), (59, 0.95, 0.95),
                                           (200, 0.99, 0.95), (1000, 0.95, 0.999),
                                           (10_000, 0.99, 1 - 0.05 / 24)])
def test_the_lower_index_is_the_largest_order_statistic_below_the_quantile_at_c(n, q, c):
    k = quantile_lower_index(n, q, c)
    r = np.arange(1, n + 1)
    ok = stats.binom.sf(r - 1, n, q) >= c  # P[x_(r) <= quantile] >= P[Binomial(n, q) >= r]
    assert k == (int(r[ok].max()) - 1 if ok.any() else None)


def test_the_table_of_indices_is_the_one_index_at_a_time():
    rng = np.random.default_rng(3)
    levels = [0.9, 0.95, *(1 - 0.05 / (2 * k) for k in LADDER)]
    ns = [0, 1, 2, 7, 60, 300, 2_000, 9_999, 250_000]
    qs = [0.95, 0.99, 0.95, 0.5, 0.95, 0.99, float(rng.uniform(0.01, 0.99)), 0.95, 0.99]
    lower = quantile_index_table(ns, qs, levels, "lower")
    upper = quantile_index_table(ns, qs, levels, "upper")
    for row, (n, q) in enumerate(zip(ns, qs, strict=True)):
        for col, c in enumerate(levels):
            want_low = quantile_lower_index(n, q, c) if n else None
            want_up = quantile_upper_index(n, q, c) if n else None
            assert lower[row, col] == (-1 if want_low is None else want_low)
            assert upper[row, col] == (-1 if want_up is None else want_up)
        assert np.array_equal(quantile_indices(n, q, levels, "upper"), upper[row])


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_both_quantile_bounds_hold_at_least_as_often_as_stated(seed):
    # 2,000 samples of 150 exponential values: how often does each bound hold for p95?
    rng = np.random.default_rng(seed)
    true = -math.log(0.05)
    samples = rng.exponential(size=(2_000, 150))
    low = np.array([quantile_lower_bound(s, 0.95, 0.9) for s in samples])
    high = np.array([quantile_upper_bound(s, 0.95, 0.9) for s in samples])
    # at least 90 % each by construction (more: the order statistics are discrete);
    # 2,000 trials put a binomial sd of 0.7 % on the share
    assert (low <= true).mean() > 0.87 and (high >= true).mean() > 0.87
    assert ((low <= true) & (true <= high)).mean() > 0.77  # two-sided at 2c - 1 = 0.8


def test_clopper_pearson_lower_bounds():
    assert fraction_lower_bound(0, 100, 0.95) == 0.0
    assert fraction_lower_bound(100, 100, 0.95) == pytest.approx(0.05 ** (1 / 100))
    assert fraction_lower_bound(10, 100, 0.95) == pytest.approx(stats.beta.ppf(0.05, 10, 91))
    assert fraction_lower_bound(10, 100, 0.95) < 0.1 < fraction_upper_bound(10, 100, 0.95)
    levels = [0.9, 0.99, 0.9999]
    for x, n in ((0, 50), (7, 50), (50, 50), (3, 0)):
        lo, hi = fraction_bounds(x, n, levels)
        assert lo == pytest.approx([fraction_lower_bound(x, n, c) for c in levels])
        assert hi == pytest.approx([fraction_upper_bound(x, n, c) for c in levels])


# ---- the interval of an effect, by hand ---------------------------------------------------------


def test_the_effect_interval_on_hand_made_numbers():
    keys = ["a", "a", "b", "b"]
    # level a: bounds [1, 2] and [2, 3], means L = 1.5, U = 2.5; level b: [5, 7], [6, 8]: 5.5, 7.5
    low, high = effect_interval(keys, [1, 2, 5, 6], [2, 3, 7, 8])
    assert high == pytest.approx(7.5 - 1.5)
    assert low == pytest.approx(5.5 - 2.5)
    # overlapping levels (a: L 1.5, U 3.5; b: L 2, U 4): the effect may be 0
    assert effect_interval(keys, [1, 2, 1.5, 2.5], [3, 4, 3.5, 4.5]) == (0.0, 4.0 - 1.5)
    # three levels: the largest gap between a level's lower and another's upper mean
    low, high = effect_interval([0, 1, 2], [10, 0, 4], [12, 1, 6])
    assert (low, high) == (10 - 1, 12 - 0)
    # a scenario without a bound, or a single level: no interval
    assert effect_interval(keys, [1, None, 5, 6], [2, 3, 7, 8]) is None
    assert effect_interval(keys, [1, 2, 5, math.nan], [2, 3, 7, 8]) is None
    assert effect_interval(["a"] * 3, [1, 2, 3], [2, 3, 4]) is None


def test_the_effect_interval_holds_whenever_every_scenario_interval_does():
    rng = np.random.default_rng(7)
    for _ in range(300):
        keys = list(rng.integers(0, 3, size=9))
        if len(set(keys)) < 2:
            continue
        true = rng.normal(size=9) * rng.uniform(0, 3)
        lower = true - rng.uniform(0, 1, size=9)
        upper = true + rng.uniform(0, 1, size=9)
        means = [true[[k == key for k in keys]].mean() for key in dict.fromkeys(keys)]
        effect = max(means) - min(means)
        low, high = effect_interval(keys, lower, upper)
        assert low - 1e-12 <= effect <= high + 1e-12


def test_the_joint_bounds_take_the_first_rung_not_below_the_number_of_scenarios():
    def result(c: float, value: float) -> ScenarioResult:
        rungs = list(LADDER)
        return _bounded(c, BoundsLadder(rungs, lower={"t": [value - k for k in rungs]},
                                        upper={"t": [value + k for k in rungs]}))

    joint = joint_bounds([result(0.95, 100.0 * i) for i in range(9)])  # 9 scenarios: rung 12
    assert joint.confidence == 0.95
    assert joint.scenario_confidence == pytest.approx(1 - 0.05 / 12)
    assert [b["t"] for b in joint.lower] == [100.0 * i - 12 for i in range(9)]
    assert [b["t"] for b in joint.upper] == [100.0 * i + 12 for i in range(9)]
    assert joint_bounds([result(0.95, 0.0), result(0.9, 0.0)]).confidence == 0.9
    assert joint_bounds([result(0.95, 0.0), _bounded(0.95, BoundsLadder([], {}, {}))]) is None
    assert joint_bounds([]) is None


def _bounded(confidence: float, ladder: BoundsLadder) -> ScenarioResult:
    """A scenario's result with nothing but its bounds."""
    return ScenarioResult(0, 0, 0, 0, "", [], {}, ScenarioBounds(confidence, {}, {}, ladder))


def test_the_joint_bounds_are_at_k_itself_when_the_scenarios_were_bounded_for_it():
    # A study's tasks know k: each scenario is bounded for k alone, no rounding up.
    def result(value: float) -> ScenarioResult:
        return _bounded(0.95, BoundsLadder([9], lower={"t": [value - 1]},
                                           upper={"t": [value + 1]}))

    joint = joint_bounds([result(10.0 * i) for i in range(9)])
    assert joint.scenario_confidence == pytest.approx(1 - 0.05 / 9)
    assert [b["t"] for b in joint.upper] == [10.0 * i + 1 for i in range(9)]


# ---- on a study ---------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", [1, 2])
def test_more_rocks_narrow_the_interval(seed):
    few, many = _study(VOLUME_FRICTION, 250, seed), _study(VOLUME_FRICTION, 2000, seed)
    widths = []
    # the bare slope's residual: the fence holds every rock, the residual with it is 0
    for target in (ENERGY, "x=160 passing_height_m p95", "x=200 residual, bare slope"):
        for parameter in ("rocks.volume", "materials.talus.friction"):
            a, b = _entry(few, target, parameter), _entry(many, target, parameter)
            if a["effect_low"] is None:
                continue
            widths.append(a["effect_high"] - a["effect_low"])
            # eight times the rocks: about a third of the width (order statistics)
            assert b["effect_high"] - b["effect_low"] < 0.75 * widths[-1], (target, parameter)
    assert len(widths) >= 4


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_wide_rock_volume_range_is_resolved_from_the_noise(seed):
    result = _study(VOLUME_FRICTION, 300, seed)
    volume = _entry(result, ENERGY, "rocks.volume")
    friction = _entry(result, ENERGY, "materials.talus.friction")
    assert volume["resolved"] and volume["effect_low"] > 0
    assert volume["effect_low"] <= volume["effect"] <= volume["effect_high"]
    # a step of friction moves it too little to tell from 300 rocks: not resolved
    assert friction["effect_low"] == 0 and not friction["resolved"]
    assert volume["effect_low"] > friction["effect_high"]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_an_input_that_moves_nothing_is_not_resolved(seed):
    result = _study(NULL_INPUT, 1000, seed)
    entries = [e for e in result.summary["sensitivity"]
               if e["parameter"] == "materials.unused.restitution"]
    # 8 design values at stations and the fence, the residual with the fence in place and
    # the bare slope's beside it
    assert len(entries) == 10 and any(e["effect"] > 0 for e in entries)  # the noise
    assert {"x=200 residual", "x=200 residual, bare slope"} <= {e["target"] for e in entries}
    # with 1,000 rocks every design value is bounded, and none is moved beyond the noise
    assert all(e["effect_low"] == 0 and not e["resolved"] for e in entries)


def test_the_same_rocks_give_an_unresolved_zero_effect_by_construction():
    result = _study(NULL_INPUT + "  seeds: common\n", 300, 4)
    for e in result.summary["sensitivity"]:
        if e["parameter"] == "materials.unused.restitution":
            assert e["effect"] == 0 and not e["resolved"]
            assert e["effect_low"] in (0, None)


def test_too_few_rocks_give_no_interval_and_no_resolution():
    result = _study(VOLUME_FRICTION, 40, 1)  # 40 rocks bound no p99 at 1 - 0.05 / 8 a side
    entries = [e for e in result.summary["sensitivity"] if e["target"].endswith(" p99")]
    assert entries
    for e in entries:
        assert e["effect_low"] is None and e["effect_high"] is None and not e["resolved"]


def test_the_json_keeps_its_keys_and_gains_the_bounds():
    result = _study(VOLUME_FRICTION, 300, 2)
    s = result.summary
    json.dumps(s, allow_nan=False)
    assert s["sensitivity_confidence"] == 0.95
    # ranked unit-free (issue 25): the design values by their largest relative effect,
    # each design value's inputs by the raw effect, which stays beside it
    ranked = s["sensitivity"]
    targets = list(dict.fromkeys(e["target"] for e in ranked))
    assert [e["target"] for e in ranked] == sorted((e["target"] for e in ranked),
                                                   key=targets.index)
    tops = [max(e["relative_effect"] for e in ranked if e["target"] == t) for t in targets]
    assert tops == sorted(tops, reverse=True)
    for t in targets:
        effects = [e["effect"] for e in ranked if e["target"] == t]
        assert effects == sorted(effects, reverse=True)
    for e in s["sensitivity"]:
        assert {"parameter", "target", "effect", "unit", "low", "high", "effect_low",
                "effect_high", "resolved"} <= set(e)
    for block in s["scenarios"]:
        bounds = block["bounds"]
        assert set(bounds) == {"confidence", "upper", "lower", "joint"}  # the ladder stays out
        assert bounds["joint"]["confidence"] == pytest.approx(1 - 0.05 / 4)
        for name, up in bounds["upper"].items():
            low = bounds["lower"][name]
            if up is not None and low is not None:
                assert low <= up
            jl, ju = bounds["joint"]["lower"][name], bounds["joint"]["upper"][name]
            if ju is not None:  # a wider interval: each side at 1 - 0.05 / 8
                assert ju >= up and jl <= low


def test_a_scenario_bounds_are_the_order_statistics_of_its_rocks():
    result = _study(VOLUME_FRICTION, 300, 2)
    block = result.summary["scenarios"][3]
    project = load_project_text(VOLUME_FRICTION, "runout.yaml")
    from rockfall_design.run.simulation import simulate
    from rockfall_design.studies import with_values

    run = simulate(with_values(project, block["values"]), rocks=300, seed=block["seed"])
    energy = run.crossing_arrays()["energy_j"][:, list(run.stations).index(160.0)]
    energy = energy[np.isfinite(energy)] / 1e3
    bounds = block["bounds"]
    assert bounds["upper"][ENERGY] == quantile_upper_bound(energy, 0.95, 0.95)
    assert bounds["lower"][ENERGY] == quantile_lower_bound(energy, 0.95, 0.95)
    assert result.results[3].bounds.ladder.scenarios == [4]  # k itself, alone
    side = 1 - (1 - 0.95) / 8  # four scenarios: each side of each at 1 - (1 - c) / (2k)
    assert bounds["joint"]["upper"][ENERGY] == quantile_upper_bound(energy, 0.95, side)
    assert bounds["joint"]["lower"][ENERGY] == quantile_lower_bound(energy, 0.95, side)
    # The residual of the project as it stands: with its measures, where it has any.
    residual = block.get("protect_with_measures") or block["protect"]
    reaching, rocks = residual["reaching"], block["rocks"]
    assert bounds["lower"]["x=200 residual"] == pytest.approx(
        fraction_lower_bound(reaching, rocks, 0.95))


def test_the_safety_concepts_confidence_sets_the_sensitivitys():
    text = VOLUME_FRICTION.replace("study:\n", "safety: {concept: spang, confidence: 0.9}\n"
                                   "study:\n")
    result = _study(text, 300, 1)
    assert result.summary["sensitivity_confidence"] == 0.9
    assert result.summary["scenarios"][0]["bounds"]["joint"]["confidence"] == pytest.approx(
        1 - 0.1 / 4)
    assert set(result.sensitivity["confidence"]) == {0.9}


def test_report_csv_and_tornado_show_what_is_not_resolved(tmp_path, capsys):
    path = tmp_path / "vf.yaml"
    path.write_text(VOLUME_FRICTION)
    assert main(["study", str(path), "--rocks", "300", "--seed", "1", "--workers", "1",
                 "--out", str(tmp_path / "out")]) == 0
    out = capsys.readouterr().out
    assert "effect at 95 %" in out and "not resolved from Monte Carlo noise" in out
    assert " *" in out
    import pandas as pd

    table = pd.read_csv(tmp_path / "out" / "sensitivity.csv")
    assert {"effect_low", "effect_high", "resolved", "confidence"} <= set(table.columns)
    assert table["resolved"].any() and not table["resolved"].all()
    scenarios = pd.read_csv(tmp_path / "out" / "scenarios.csv")
    assert f"{ENERGY} lower" in scenarios.columns and f"{ENERGY} upper" in scenarios.columns

    from matplotlib.container import ErrorbarContainer

    fig = _study(VOLUME_FRICTION, 300, 1).plot_tornado()
    assert any(isinstance(c, ErrorbarContainer) for ax in fig.axes for c in ax.containers)

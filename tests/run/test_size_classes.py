"""Size classes on a survey (issue 34, item 9): rounding, records and statistics.

On a slope of more than 256 points, rocks of varying size are rounded to a
geometric grid of radii (``rocks.size_step``, default 0.5 %), so that rocks
of one class share one centre path. Here: each class radius is within half a
step of the drawn one; sections of few points, rocks of one size and a step
of 0 are left as drawn; the step is recorded; and the run's statistics
(p50/p95/p99 of energy and passing height at stations, of the stop
positions) agree with those of the exact sizes within their confidence
bounds on a dense survey, at more than one seed, while the same comparison
does see radii 15 % too large.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rockfall_design.engine import run_ensemble
from rockfall_design.engine.ensemble import SHARED_PATH_VERTICES
from rockfall_design.judge.bounds import quantile_with_bounds
from rockfall_design.project import load_project_text
from rockfall_design.project.schema import DEFAULT_SIZE_STEP, MAX_SIZE_STEP, SURVEY_POINTS
from rockfall_design.run.releases import (
    draw_releases,
    engine_key,
    section_from_project,
    size_classes,
)
from rockfall_design.run.simulation import run_in_memory

#: The standard slope (projects/benchmark.yaml's vertices), resampled as a noisy survey.
STANDARD = np.array([(0, 100), (30, 60), (60, 30), (80, 20), (120, 15), (200, 12)], float)


def survey_yaml(points: int, size: str, step: str = "", noise: float = 0.01,
                seed: int = 0) -> str:
    """A project on the standard slope surveyed at ``points`` points (1 cm noise)."""
    if points <= len(STANDARD):
        xy = STANDARD
    else:
        x = np.linspace(0.0, 200.0, points)
        y = (np.interp(x, STANDARD[:, 0], STANDARD[:, 1])
             + np.random.default_rng(seed).normal(0.0, noise, points))
        xy = np.column_stack([x, y])
    pts = ", ".join(f"[{float(a)!r}, {float(b)!r}]" for a, b in xy)
    return f"""name: dense survey
slope:
  points: [{pts}]
  materials: talus
materials:
  talus:
    impact_model: rn_rt
    restitution: 0.35
    tangential_restitution: 0.85
    friction: 0.58
    rolling_resistance: 0.3
    roughness_deg: 5
    scatter: {{restitution: 0.05, friction: 0.05, rolling_resistance: 0.02}}
rocks:
  count: 1000
  seed: 1
  {size}
{step}  release:
    x: [1, 3]
    velocity: [0.6, -0.8]
analysis:
  stations: [45, 75]
"""


LOGNORMAL = "radius: {lognormal: [0.45, 0.3]}"


def test_the_projects_threshold_is_the_engines():
    assert SURVEY_POINTS == SHARED_PATH_VERTICES


@settings(max_examples=200, deadline=None)
@given(r=st.floats(0.01, 25.0), step=st.floats(1e-4, MAX_SIZE_STEP))
def test_a_class_radius_is_within_half_a_step_of_the_drawn_one(r, step):
    rc = float(size_classes(np.array([r]), step)[0])
    assert abs(rc / r - 1.0) <= step / 2.0
    # The class is one number: every radius of it gives the same bits.
    assert size_classes(np.array([rc]), step)[0] == rc
    assert size_classes(np.array([r]), 0.0)[0] == r


def test_the_default_step_moves_a_radius_by_at_most_a_quarter_per_cent():
    r = np.exp(np.random.default_rng(5).uniform(np.log(0.01), np.log(25.0), 200_000))
    rel = size_classes(r, DEFAULT_SIZE_STEP) / r - 1.0
    assert np.abs(rel).max() <= 0.0025
    # The mass: by at most 1.005 ** 1.5 - 1 = 0.751 %.
    assert np.abs((1.0 + rel) ** 3 - 1.0).max() <= 1.005 ** 1.5 - 1.0 + 1e-12 < 0.00752
    # And rounds as often up as down: no bias in the sizes.
    assert abs(np.mean(np.log1p(rel))) < 2e-5


def test_sizes_are_rounded_on_a_survey_only_and_only_where_they_vary():
    survey = load_project_text(survey_yaml(400, LOGNORMAL))
    assert survey.size_step == DEFAULT_SIZE_STEP
    r = draw_releases(survey, 5_000, 3).radius
    exact = draw_releases(load_project_text(survey_yaml(400, LOGNORMAL, "  size_step: 0\n")),
                          5_000, 3).radius
    assert np.array_equal(r, size_classes(exact, DEFAULT_SIZE_STEP))
    assert np.unique(r).size < np.unique(exact).size == exact.size
    # A few points, or one size: as drawn, whatever the step.
    few = load_project_text(survey_yaml(6, LOGNORMAL, "  size_step: 0.01\n"))
    assert few.size_step == 0.0
    assert np.unique(draw_releases(few, 500, 3).radius).size == 500
    fixed = load_project_text(survey_yaml(400, "radius: 0.4"))
    assert fixed.size_step == 0.0 and (draw_releases(fixed, 10, 3).radius == 0.4).all()
    coarse = load_project_text(survey_yaml(400, LOGNORMAL, "  size_step: 0.02\n"))
    assert coarse.size_step == 0.02


def test_the_step_is_in_the_run_record_and_summary_where_sizes_were_rounded():
    survey = load_project_text(survey_yaml(400, LOGNORMAL))
    record = survey.resolved_dict()["rocks"]
    assert record["size_step"] == DEFAULT_SIZE_STEP
    # The record loads back to the same project (and hash).
    again = load_project_text(survey_yaml(400, LOGNORMAL, "  size_step: 0.005\n"))
    assert again.resolved_hash() == survey.resolved_hash()
    assert run_in_memory(survey, rocks=20, seed=2).summary()["size_step"] == DEFAULT_SIZE_STEP
    exact = load_project_text(survey_yaml(400, LOGNORMAL, "  size_step: 0\n"))
    assert exact.resolved_dict()["rocks"]["size_step"] == 0
    assert exact.resolved_hash() != survey.resolved_hash()
    assert "size_step" not in run_in_memory(exact, rocks=20, seed=2).summary()
    # A section of few points records nothing new: its record and hash are as before.
    few = load_project_text(survey_yaml(6, LOGNORMAL))
    assert "size_step" not in few.resolved_dict()["rocks"]
    assert "size_step" not in json.dumps(run_in_memory(few, rocks=20, seed=2).summary())


def test_rocks_of_one_class_run_as_they_would_alone():
    """The engine's grouping by size changes no rock: each as in a run of its own."""
    survey = load_project_text(survey_yaml(400, LOGNORMAL))
    whole = run_in_memory(survey, rocks=300, seed=4).result
    some = [7, 150, 299]
    for i in some:
        alone = run_in_memory(survey, rocks=i + 1, seed=4).result
        assert alone.radius[i] == whole.radius[i]
        for name in ("x_end", "y_end", "max_x", "n_events", "status"):
            assert getattr(alone, name)[i] == getattr(whole, name)[i], name
        assert np.array_equal(alone.grid_energy[i], whole.grid_energy[i], equal_nan=True)


def test_threads_and_batches_change_nothing_on_a_survey_of_size_classes():
    survey = load_project_text(survey_yaml(400, LOGNORMAL))
    section, rel = section_from_project(survey), draw_releases(survey, 400, 6)
    common = dict(key=engine_key(6), stations=[45.0, 75.0], n_trajectories=3)
    one = run_ensemble(section, rel, threads=1, **common)
    two = run_ensemble(section, rel, threads=2, batch_size=7, **common)
    for name in ("status", "x_end", "y_end", "n_events", "crossings", "grid_energy"):
        assert np.array_equal(getattr(one, name), getattr(two, name), equal_nan=True), name
    for a, b in zip(one.trajectories, two.trajectories, strict=True):
        assert np.array_equal(a, b)


# ---- the statistics of size classes against exact sizes --------------------------

QUANTILES = (0.5, 0.95, 0.99)
#: Family-wise level of one comparison of two runs: at most this chance that
#: runs of the same distribution are called different at some quantity.
FAMILY_ALPHA = 0.01


def _samples(project, rocks: int, seed: int) -> dict[str, np.ndarray]:
    """The compared quantities of a run: energy and passing height at each station, stops."""
    run = run_in_memory(project, rocks=rocks, seed=seed)
    r = run.result
    out = {}
    for j, x in enumerate(r.stations):
        out[f"energy at {x:g} m"] = run.crossing_arrays()["energy_j"][:, j]
        out[f"passing height at {x:g} m"] = run.crossing_arrays()["passing_height_m"][:, j]
    out["stop x"] = run.rest_positions()[0]
    return {k: v[np.isfinite(v)] for k, v in out.items()}


def _differences(a: dict[str, np.ndarray], b: dict[str, np.ndarray]) -> list[str]:
    """The quantiles of ``a`` and ``b`` whose confidence intervals do not overlap.

    Each interval is a distribution-free two-sided one (order statistics,
    ``judge.bounds``) at level ``1 - FAMILY_ALPHA / (2 m)`` for ``m``
    comparisons: two intervals of samples of one distribution miss each other
    only if one misses the quantile, so the chance of any difference when
    there is none is at most ``FAMILY_ALPHA`` (Bonferroni). The two runs share
    their seed, which makes them alike where their rocks are (positively
    correlated), so the test is conservative; the control with radii 15 %
    larger shows that it still sees a change of that size.
    """
    m = len(a) * len(QUANTILES)
    side = 1.0 - FAMILY_ALPHA / (4.0 * m)  # one side of a two-sided interval
    found = []
    for key in a:
        for q in QUANTILES:
            va, lo_a, up_a = quantile_with_bounds(a[key], q, side)
            vb, lo_b, up_b = quantile_with_bounds(b[key], q, side)
            assert None not in (lo_a, up_a, lo_b, up_b), (key, q, a[key].size, b[key].size)
            if up_a < lo_b or up_b < lo_a:
                found.append(f"{key} p{q * 100:g}: {va:.4g} [{lo_a:.4g}, {up_a:.4g}] vs "
                             f"{vb:.4g} [{lo_b:.4g}, {up_b:.4g}]")
    return found


def _compare(seed: int, rocks: int, points: int) -> None:
    classes = load_project_text(survey_yaml(points, LOGNORMAL))
    exact = load_project_text(survey_yaml(points, LOGNORMAL, "  size_step: 0\n"))
    a, b = _samples(classes, rocks, seed), _samples(exact, rocks, seed)
    assert min(v.size for v in a.values()) > 0.5 * rocks  # most rocks pass and stop
    assert _differences(a, b) == []
    # The control: the same comparison sees radii 15 % too large (masses 52 %); at
    # 2,000 rocks in 4 to 5 of its 15 quantiles at seeds 1 to 3 (radii 10 % too
    # large: in 1 to 3).
    bigger = load_project_text(survey_yaml(points, LOGNORMAL.replace("0.45", "0.5175")))
    assert _differences(_samples(bigger, rocks, seed), b)


@pytest.mark.parametrize("seed", [1, 2])
def test_size_classes_keep_the_statistics_of_exact_sizes(seed):
    """p50/p95/p99 of energy and passing height at two stations and of the stop positions:
    2,000 rocks on a 600-point survey, classes against exact sizes, at two seeds."""
    _compare(seed, 2_000, 600)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [3, 4])
def test_size_classes_keep_the_statistics_of_exact_sizes_heavier(seed):
    """The same with 10,000 rocks on a 2,000-point survey, at two more seeds.

    Each seed is three runs of 10,000 rocks on the long survey (about 25 s of
    CPU); seeds 5 and 6 passed too (2026-11-28) and were dropped to keep CI
    inside its time: with seeds 1 and 2 above the claim is checked at four.
    """
    _compare(seed, 10_000, 2_000)


def test_a_survey_threshold_of_more_than_256_points():
    at = load_project_text(survey_yaml(SURVEY_POINTS, LOGNORMAL))
    above = load_project_text(survey_yaml(SURVEY_POINTS + 1, LOGNORMAL))
    assert at.size_step == 0.0 and above.size_step == DEFAULT_SIZE_STEP
    assert math.isclose(above.size_step, 0.005)

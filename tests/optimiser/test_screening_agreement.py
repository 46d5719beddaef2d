"""Screening and exact evaluation judge alike: one judgement, and a documented margin.

For every bundled design project and random designs from its design space,
the screening (:meth:`Screening.screen`, on the table of bare-slope passages
and resumed ground-edit runs) is compared with the exact run of the same
rocks with the measures in place (:func:`evaluate_design`):

* the screening never admits a design that the exact run does not admit
  (with the confidence bounds, ``design.max_rocks`` set to the rocks run so
  that admission is on this sample alone);
* a design that the exact run admits is admitted by the screening or left
  to the exact decision (``near``: it passes with rocks whose paths the
  screening approximates, or misses within the margin);
* where the screening approximates no rock, the two agree exactly: the same
  verdict and the same number of rocks reaching the protected zone.
"""

from __future__ import annotations

import re
import zlib
from pathlib import Path

import numpy as np
import pytest

from rockfall_design.judge.design_spec import resolve_design
from rockfall_design.judge.evaluation import evaluate_design
from rockfall_design.judge.placing import build_concept
from rockfall_design.optimiser import STATION_STEP_M, Screening
from rockfall_design.plugins import load_registry
from rockfall_design.project import load_project_text

from ..plugin_helpers import install_embankment_example

PROJECTS = Path(__file__).resolve().parents[2] / "projects"
ROCKS = 400
DESIGNS = 100  # per project: a few hundred in all



def _project(name: str):
    text = (PROJECTS / name).read_text()
    for cat in ("catalogue_products.yaml", "catalogue_costs.yaml"):
        text = text.replace(cat, str(PROJECTS / cat))
    text = text.replace("  max_measures:", f"  max_rocks: {ROCKS}\n  max_measures:")
    # Targets that a few hundred rocks can show with confidence, so that both
    # verdicts occur among the random designs: 5 % may reach the protected
    # zone, p95 design values (p99 needs 299 rocks at a measure to be bounded).
    text = re.sub(r"residual: \{fraction: [0-9.]+\}", "residual: {fraction: 0.05}", text)
    text = text.replace("statistic: p99", "statistic: p95")
    return load_project_text(text, name, base_dir=PROJECTS)  # its block survey, say


def _random_params(cand, rng: np.random.Generator) -> dict:
    lo, hi = cand.x_range
    k = int(rng.integers(0, int((hi - lo) / STATION_STEP_M) + 1))
    params: dict = {"x": float(lo + k * STATION_STEP_M)}
    if cand.products:
        prod = cand.products[int(rng.integers(len(cand.products)))]
        params[cand.product_field] = prod.name
        if cand.height_field is not None:
            params[cand.height_field] = prod.heights[int(rng.integers(len(prod.heights)))]
    for name, opts in cand.options.items():
        params[name] = opts[int(rng.integers(len(opts)))]
    for name, (a, b) in cand.ranges.items():
        params[name] = float(a + 0.25 * int(rng.integers(0, int((b - a) / 0.25) + 1)))
    return params


@pytest.mark.parametrize("name", sorted(p.name for p in PROJECTS.glob("design_*.yaml")))
def test_screening_never_admits_what_the_exact_run_rejects(registry, name, tmp_path,
                                                           monkeypatch):
    if name == "design_embankment.yaml":  # its candidate is the example plugin's
        install_embankment_example(tmp_path, monkeypatch)
        registry = load_registry()
    project = _project(name)
    spec = resolve_design(project, registry)
    concept = build_concept(project, registry)
    allowed = spec.residual_fraction if spec.residual_fraction is not None else (
        (spec.residual_count or 0) / ROCKS)
    project = project.model_copy(update={"protect": project.protect.model_copy(
        update={"allowed_fraction": allowed})})
    seed = project.rocks.seed
    screen = Screening(project, registry, spec, concept, rocks=ROCKS, seed=seed)
    rng = np.random.default_rng(zlib.crc32(name.encode()))
    judged = exact_agree = admitted = 0
    for _ in range(DESIGNS * 3):
        if judged >= DESIGNS:
            break
        size = int(rng.integers(1, spec.max_measures + 1))
        cis = rng.integers(len(spec.candidates), size=size)
        try:
            measures = screen.measures([(int(ci), _random_params(spec.candidates[ci], rng))
                                        for ci in cis])
        except ValueError:
            continue
        sr = screen.screen(measures)
        if sr.reason:  # does not fit (overlap, a ditch too narrow): not a design
            continue
        ev = evaluate_design(project, registry, measures, concept, rocks=ROCKS, seed=seed)
        judged += 1
        exact = ev.holds_with_confidence
        assert not (sr.feasible and not exact), (
            f"screening admits what the exact run rejects: {sr.labels}: {ev.failures()}")
        assert not (exact and not (sr.feasible or sr.near)), (
            f"the exact run admits what the screening rejects outside its margin: {sr.labels}")
        admitted += exact
        if not sr.approximate:
            # Judged without approximation: the same rocks through, the same verdict.
            assert sr.residual == ev.protect["reaching"], sr.labels
            assert sr.feasible is exact, sr.labels
            exact_agree += 1
    assert judged >= DESIGNS // 2, "too few random designs fit to compare anything"
    assert exact_agree > 0
    assert 0 < admitted < judged, "both verdicts occur, or the comparison says little"

"""Synthetic recovery: what passing heights and a second profile pin down (issue 35 item 5).

Observations are simulated by the engine from known soil values (restitution
0.3, rolling resistance 0.4) on the quarry site of the suite, and on a
second profile of the same site; the two values are fitted back. Each test
runs two calibrations of 8 bootstrap replicates at 100 rocks per evaluation
(about a minute on a shared core), so it is marked slow; the figures are in
docs/calibration.md ("Observations other than stops", "Several profiles").
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rockfall_design.calibration.uncertainty import FittedParameter
from rockfall_design.project import load_project, load_project_text

from .calibration_helpers import SITE
from .test_observation_sets import HEAD, P2

TRUTH = {"materials.soil.restitution": 0.3, "materials.soil.rolling_resistance": 0.4}
FIT = ("  fit:\n    materials.soil.restitution: [0.05, 0.7]\n"
       "    materials.soil.rolling_resistance: [0.05, 1.2]\n")
TAIL = "  levels: {bench: [20.5, 29], floor: [29, 107]}\n  rocks: 100\n  bootstrap: 8\n"
#: Where the blocks that bounce off the bench are still in the air above the floor.
STATION = 35.0


def _observed(text: str, name: str, seed: int, n: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """``n`` stops and the passing heights at :data:`STATION` simulated at the truth.

    The profile runs with the site's materials (SITE's soil and rock), as a
    calibration over profiles runs it.
    """
    from rockfall_design.calibration.distances import stop_positions
    from rockfall_design.calibration.fit import problem_for
    from rockfall_design.run.simulation import run_in_memory
    from rockfall_design.studies.paths import with_values

    problem = problem_for(load_project_text(text, name), {})
    base = {**problem.base, "analysis": {**problem.base["analysis"], "stations": [STATION]}}
    site = load_project_text(SITE, "site.yaml").resolved_dict()["materials"]
    base["materials"] = {**base["materials"], **site}
    run = run_in_memory(with_values(problem.project, TRUTH, base=base), rocks=n,
                        seed=10_000 + seed)
    heights = run.crossing_arrays()["passing_height_m"][:, 0]
    return (stop_positions(run.result.x_end, run.result.status, problem.x_range),
            heights[np.isfinite(heights)])


def _write(path: Path, column: str, values: np.ndarray) -> None:
    path.write_text(f"{column}\n" + "".join(f"{v:.3f}\n" for v in values))


def _fit(directory: Path, section: str, seed: int) -> dict[str, FittedParameter]:
    from rockfall_design.calibration.procedure import run_calibration

    (directory / "site.yaml").write_text(HEAD + section + FIT + TAIL)
    result = run_calibration(load_project(directory / "site.yaml"), seed=seed)
    return {p.path: p for p in result.parameters}


def _width(p: FittedParameter) -> float:
    return p.high - p.low


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_passing_heights_pin_down_what_stops_alone_leave_open(tmp_path, seed):
    stops, heights = _observed(SITE, "site.yaml", seed)
    assert heights.size >= 30  # most blocks pass the station
    _write(tmp_path / "stops.csv", "x", stops)
    _write(tmp_path / "marks.csv", "height_m", heights)
    alone = _fit(tmp_path, "calibrate:\n  observed: stops.csv\n", seed)
    both = _fit(tmp_path, "calibrate:\n  observed:\n    - stops.csv\n    - {kind: "
                f"passing_heights, x: {STATION:g}, file: marks.csv}}\n", seed)
    e, rr = TRUTH
    # Stops alone leave the restitution open over more than a quarter of its range
    # (measured 28 to 43 % at seeds 1-3); the heights narrow it at least threefold
    # (measured six- to tenfold) and the rolling resistance's at least twofold.
    assert alone[e].width_share > 0.25
    assert _width(both[e]) < _width(alone[e]) / 3
    assert _width(both[rr]) < _width(alone[rr]) / 2
    # With the heights, both best values near the truth (measured within 0.003 and 0.02).
    assert both[e].value == pytest.approx(TRUTH[e], abs=0.02)
    assert both[rr].value == pytest.approx(TRUTH[rr], abs=0.05)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_two_profiles_fitted_together_recover_the_shared_values(tmp_path, seed):
    stops, _ = _observed(SITE, "site.yaml", seed)
    stops_p2, _ = _observed(P2, "p2.yaml", seed)
    _write(tmp_path / "stops.csv", "x", stops)
    _write(tmp_path / "stops_p2.csv", "x", stops_p2)
    (tmp_path / "p2.yaml").write_text(P2)
    both = _fit(tmp_path, "calibrate:\n  profiles: {P2: p2.yaml}\n  observed:\n    - stops.csv\n"
                "    - {file: stops_p2.csv, profile: P2, levels: {bench: [30, 44]}}\n", seed)
    for path, truth in TRUTH.items():
        p = both[path]
        # Pinned down (stops of the quarry alone leave the restitution open over 28
        # to 43 % of its range), and near the truth: measured within 0.028 of it.
        # The rough intervals of 8 replicates are not asserted to cover it: at seed 2
        # the restitution's (0.315 .. 0.349) misses 0.3 (docs/calibration.md).
        assert p.identified, p
        assert p.width_share < 0.15, p
        assert p.value == pytest.approx(truth, abs=0.05), p

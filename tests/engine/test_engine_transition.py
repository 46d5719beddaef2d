"""The answer does not depend on engine.v_contact (docs/PHYSICS.md, "The transition").

The same rocks at v_contact 0.02 and 0.2 m/s, a decade apart: the median stop
and the 95th percentiles of passing height and energy at the stations agree
within their two-sided 95 % order-statistic intervals, and the share of rocks
past the last station within its Clopper-Pearson interval, at two seeds, on
issue 35's steep-to-flat section (soil rolling resistance 0.7, hard ground
1.0: without the hop criterion its median stop moves from 78.2 m to 89.9 m
as v_contact goes from 2 to 0.02 m/s, 1,000 rocks, seed 5) with spang,
rough_soft and rn_rt grounds, and on a bundled project (quarry_road).
benchmarks/transition.py prints the full table, with the criterion and
without it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

import rockfall_design as rd
from rockfall_design.judge.bounds import (
    fraction_lower_bound,
    fraction_upper_bound,
    quantile_with_bounds,
)

ROCKS = 600
SETTINGS = (0.02, 0.2)
PROJECTS = Path(__file__).resolve().parents[2] / "projects"

STEEP_TO_FLAT = """\
name: Steep to flat
description: A 35 degree soil slope onto flat hard ground (issue 35).
slope:
  points: [[0, 60], [10, 58], [70, 16], [75, 15], [250, 15]]
  materials: [soil, soil, soil, hard]
materials:
  soil: {soil}
  hard: {hard}
rocks:
  count: 10
  seed: 3
  volume: {{lognormal: [0.3, 0.6]}}
  release: {{x: [2, 8], height: 16, velocity: [0.5, 0]}}
analysis: {{stations: [40, 72, 100]}}
protect: {{x: 200}}
"""
SPANG = ("{restitution: 0.3, friction: 0.6, rolling_resistance: 0.7, roughness_deg: 4}",
         "{restitution: 0.5, friction: 0.5, rolling_resistance: 1.0, roughness_deg: 8}")
ROUGH_SOFT = ("{impact_model: rough_soft, restitution: 0.28, friction: 0.6, "
              "rolling_resistance: 0.25, obstacle_height_m: 0.05, drag_speed_ms: 6, "
              "roughness_deg: 4}",
              "{impact_model: rough_soft, restitution: 0.43, friction: 0.55, "
              "rolling_resistance: 0.1, obstacle_height_m: 0.05, roughness_deg: 8}")
RN_RT = ("{impact_model: rn_rt, restitution: 0.3, tangential_restitution: 0.8, "
         "friction: 0.6, rolling_resistance: 0.7, roughness_deg: 4}",
         "{impact_model: rn_rt, restitution: 0.5, tangential_restitution: 0.85, "
         "friction: 0.5, rolling_resistance: 1.0, roughness_deg: 8}")


def _with_v_contact(text: str, vc: float) -> str:
    data = yaml.safe_load(text)
    data["engine"] = {**data.get("engine", {}), "v_contact": vc}
    return yaml.safe_dump(data)


def _figures(path: Path, seed: int) -> dict[str, tuple]:
    """Median stop, station p95 height and energy, share past the last station: with bounds."""
    res = rd.simulate(path, rocks=ROCKS, seed=seed, trajectories=0)
    out = {"median end x": quantile_with_bounds(res.rocks["end_x_m"].to_numpy(), 0.5, 0.975)}
    cross = res.crossings[res.crossings["crossed"]]
    for x, grp in cross.groupby("station_x_m"):
        for col in ("passing_height_m", "energy_kj"):
            out[f"p95 {col} at {x:g}"] = quantile_with_bounds(grp[col].to_numpy(), 0.95, 0.975)
    last = float(res.crossings["station_x_m"].max())
    past = res.rocks["max_x_m"].to_numpy() > last
    k, n = int(past.sum()), past.size
    out[f"share past {last:g}"] = (k / n, *(bound(k, n, 0.975) for bound in
                                            (fraction_lower_bound, fraction_upper_bound)))
    return out


def _overlap(a: tuple, b: tuple) -> bool:
    """Whether two (value, lower, upper) intervals share a point (None: an open end)."""
    lows = [v for v in (a[1], b[1]) if v is not None]
    highs = [v for v in (a[2], b[2]) if v is not None]
    return max(lows, default=-np.inf) <= min(highs, default=np.inf)


def _agree(tmp_path: Path, text: str, seed: int) -> None:
    rows = []
    for vc in SETTINGS:
        path = tmp_path / f"p{vc}.yaml"
        path.write_text(_with_v_contact(text, vc))
        rows.append(_figures(path, seed))
    small, large = rows
    assert small.keys() == large.keys()
    for key in small:
        assert _overlap(small[key], large[key]), (key, small[key], large[key])


@pytest.mark.parametrize("grounds", [SPANG, ROUGH_SOFT, RN_RT], ids=["spang", "rough_soft",
                                                                       "rn_rt"])
@pytest.mark.parametrize("seed", [5, 6])
def test_a_decade_of_v_contact_gives_the_same_answer(tmp_path, grounds, seed):
    _agree(tmp_path, STEEP_TO_FLAT.format(soil=grounds[0], hard=grounds[1]), seed)


@pytest.mark.parametrize("seed", [5, 6])
def test_a_bundled_project_does_not_depend_on_v_contact(tmp_path, seed):
    text = (PROJECTS / "quarry_road.yaml").read_text()
    _agree(tmp_path, text, seed)

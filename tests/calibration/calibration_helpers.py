"""The small quarry site the calibration tests fit (few rocks: seconds per calibration)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: A vegetated slope, a rock wall, a bench, a second wall and the quarry floor.
SITE = """\
name: site
slope:
  points: [[0, 40], [20, 25.47], [20.5, 11.47], [28.5, 11.3], [29, 2.3], [107, 2.0]]
  materials: [soil, rock, rock, rock, soil]
materials:
  soil: {restitution: 0.3, friction: 0.6, rolling_resistance: 0.4, roughness_deg: 4}
  rock: {restitution: 0.5, friction: 0.5, rolling_resistance: 0.15, roughness_deg: 8}
  unused: {restitution: 0.4, friction: 0.5}
rocks:
  count: 100
  seed: 1
  volume: 0.3
  release: {x: [1, 3], height: 0.5, velocity: [0.5, 0]}
calibrate:
  observed: stops.csv
  fit:
    materials.soil.restitution: [0.05, 0.7]
  levels: {bench: [20.5, 29], floor: [29, 107]}
  rocks: 100
  bootstrap: 8
"""

#: The value the observations are simulated with.
TRUTH = 0.3


def observed_stops(n: int, seed: int, value: float = TRUTH) -> np.ndarray:
    """``n`` stops simulated by the engine on SITE with soil restitution ``value``."""
    from rockfall_design.calibration.fit import problem_for, simulated_stops
    from rockfall_design.project import load_project_text

    project = load_project_text(SITE, "site.yaml")
    problem = problem_for(project, {}, rocks=n)
    return simulated_stops(problem, {"materials.soil.restitution": value}, 10_000 + seed)


def write_site(directory: Path, stops: np.ndarray, section: str | None = None) -> Path:
    """SITE (its calibrate: section replaced by ``section``) and stops.csv in ``directory``."""
    text = SITE if section is None else SITE.split("calibrate:")[0] + section
    (directory / "site.yaml").write_text(text)
    (directory / "stops.csv").write_text("x\n" + "".join(f"{x:.3f}\n" for x in stops))
    return directory / "site.yaml"

"""Roughness as a height (PHYSICS.md "Options"): a one-sided tilt up to atan(h_r / r)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from rockfall_design.engine import Material, columns
from rockfall_design.engine.impact import impact
from rockfall_design.engine.rng import next_uniform
from rockfall_design.errors import InputError
from rockfall_design.project import load_project_text
from rockfall_design.run.releases import section_from_project

from ..engine_helpers import one_rock, run_one, section

ROOT = Path(__file__).resolve().parents[2]


def _impact(v, n, w, r, tilt_max, seed=12345, model=columns.MODEL_RN_RT):
    rng = np.array([seed], dtype=np.uint64)
    return np.array(impact(v[0], v[1], w, n[0], n[1], r, model, 0.6, 0.8, 0.4, False,
                                9.144, 0.0, rng, tilt_max))


@pytest.mark.parametrize("direction", [1.0, -1.0])
@pytest.mark.parametrize("model", [columns.MODEL_SPANG, columns.MODEL_RN_RT])
def test_height_tilts_the_normal_against_the_motion(direction, model):
    """The impact equals one on a normal turned by U * atan(h_r / r) against v_t."""
    r, h = 0.5, 0.2
    tilt_max = np.arctan(h / r)
    a = np.radians(20.0)
    n = np.array([np.sin(a), np.cos(a)])
    t = np.array([n[1], -n[0]])
    v = direction * 6.0 * t - 3.0 * n
    out = _impact(v, n, -1.0, r, tilt_max, model=model)
    u = next_uniform(np.array([12345], dtype=np.uint64))
    th = direction * u * tilt_max  # counter-clockwise turns n towards -t
    m = np.array([np.cos(th) * n[0] - np.sin(th) * n[1], np.sin(th) * n[0] + np.cos(th) * n[1]])
    ref = _impact(v, m, -1.0, r, 0.0, model=model)
    assert_allclose(out, ref, rtol=1e-12)
    # Against the motion: the normal leans towards where the rock comes from.
    assert np.dot(m - n, t) * direction < 0


def test_tilt_is_uniform_on_zero_to_atan_h_over_r():
    """Tilt angles over many impacts: within [0, atan(h_r / r)], mean half of it."""
    r, h = 0.8, 0.3
    tilt_max = np.arctan(h / r)
    n = np.array([0.0, 1.0])
    ths = []
    for seed in range(2000):
        # Elastic rn_rt impact: the outgoing velocity is the mirror image of the
        # incoming one about the tilted plane, so the tilt can be read back.
        rng = np.array([seed * 7919 + 1], dtype=np.uint64)
        vx, vy, _ = impact(3.0, -2.0, 0.0, n[0], n[1], r, columns.MODEL_RN_RT, 1.0, 1.0, 0.0,
                                False, 9.144, 0.0, rng, tilt_max)
        # The normal bisects the change of velocity.
        dv = np.array([vx - 3.0, vy + 2.0])
        ths.append(np.arctan2(-dv[0], dv[1]))
    ths = np.array(ths)
    assert ths.min() >= 0.0 and ths.max() <= tilt_max * (1 + 1e-12)
    assert_allclose(ths.mean(), tilt_max / 2, rtol=0.05)
    assert ths.max() > 0.95 * tilt_max


def test_larger_rocks_feel_the_ground_smoother():
    """The same h_r stops small rocks sooner than large ones, relative to no roughness."""
    mat0 = Material(restitution=0.4, friction=0.5, rolling_resistance=0.1)
    math_ = Material(restitution=0.4, friction=0.5, rolling_resistance=0.1, roughness_height_m=0.2)
    pts = [[0, 60], [60, 20], [200, 10]]
    reach = {}
    for r in (0.2, 2.0):
        for name, mat in (("smooth", mat0), ("rough", math_)):
            res = run_one(section(pts, mat), one_rock(r=r, x=1.0, h=3.0, vx=2.0, n=30), key=2)
            reach[r, name] = np.mean(res.max_x)
    ratio_small = reach[0.2, "rough"] / reach[0.2, "smooth"]
    ratio_large = reach[2.0, "rough"] / reach[2.0, "smooth"]
    assert ratio_small < ratio_large <= 1.0 + 1e-9


def _project(extra: str):
    text = (ROOT / "projects" / "standard_slope.yaml").read_text()
    return load_project_text(text.replace("roughness_deg: 5", "roughness_deg: 5" + extra),
                             "p.yaml")


def test_project_file_takes_roughness_height():
    p = _project("\n    roughness_height_m: 0.15")
    assert p.materials["talus"].roughness_height_m == 0.15
    sec = section_from_project(p)
    assert sec.material_table()[0, columns.M_ROUGH_H] == 0.15
    assert _project("").materials["talus"].roughness_height_m == 0.0


@pytest.mark.parametrize(
    "value, message",
    [("-0.1", "expected a number >= 0"), ("30", "expected a number <= 25"),
     ("high", "expected a number")],
)
def test_project_file_rejects_bad_roughness_height(value, message):
    with pytest.raises(InputError) as err:
        _project(f"\n    roughness_height_m: {value}")
    text = str(err.value)
    assert "materials.talus.roughness_height_m" in text and message in text
    assert "\n" not in text

"""The impact law against published reference cases and hand calculations."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from rockfall_design.engine import columns, impact

RTOL = 1e-10


def _impact(vx, vy, w, r, model, e, mu, rt=1.0, vscale=False, k=9.144):
    rng = np.zeros(1, dtype=np.uint64)
    return impact.impact(vx, vy, w, 0.0, 1.0, r, model, e, rt, mu, vscale, k, 0.0, rng)


@pytest.mark.parametrize("theta_deg", np.arange(5.0, 86.0, 5.0))
def test_chung_ooi_2011_test4_oblique_impact(theta_deg):
    """Oblique impact of a sphere on a rigid plane, constant speed, varying angle.

    Source: Chung, Y. C. & Ooi, J. Y. (2011), "Benchmark tests for verifying
    discrete element modelling codes at particle impact level", Granular
    Matter 13, 643-656, Test No. 4: aluminium oxide sphere, radius 2.5 mm,
    3.9 m/s, e = 0.98, mu = 0.092, no initial spin, incident angle theta 5 to
    85 degrees measured from the normal of the plane (v_n = v cos theta,
    v_t = v sin theta, as the benchmark's set-up in the DEM codes that run
    it). Their rigid-body solution: the contact slips throughout when
    tan theta > 7/2 mu (1 + e), i.e. theta > 32.52 deg, with tangential
    restitution v_t'/v_t = 1 - mu (1 + e) / tan theta = 1 - 0.18216 / tan theta
    and spin 5/2 mu (1 + e) v_n / r; below it the sphere leaves rolling,
    v_t'/v_t = 5/7, spin 5/7 v_t / r.
    """
    v, r, e, mu = 3.9, 0.0025, 0.98, 0.092
    th = np.radians(theta_deg)
    vt, vn = v * np.sin(th), v * np.cos(th)
    vx, vy, w = _impact(vt, -vn, 0.0, r, columns.MODEL_SPANG, e, mu)
    switch = np.degrees(np.arctan(3.5 * mu * (1 + e)))
    assert_allclose(switch, 32.52, atol=5e-3)
    assert_allclose(vy, e * vn, rtol=RTOL)
    if theta_deg > switch:
        et = 1.0 - 0.18216 / np.tan(th)
        spin = 2.5 * mu * (1 + e) * vn / r
    else:
        et = 5.0 / 7.0
        spin = 5.0 / 7.0 * vt / r
    assert_allclose(vx / vt, et, rtol=RTOL)
    # Clockwise (negative) spin for a sphere moving towards +x.
    assert_allclose(-w, spin, rtol=RTOL)


@pytest.mark.parametrize("model", [columns.MODEL_SPANG, columns.MODEL_RN_RT])
def test_pfeiffer_bowen_velocity_scaling_hand_calculation(model):
    """Velocity-scaled normal restitution, by hand.

    Source: Pfeiffer, T. J. & Bowen, T. D. (1989), "Computer simulation of
    rockfalls", Bulletin of the Association of Engineering Geologists 26(1),
    135-146 (as used in CRSP): e_eff = e / (1 + (|v_n| / K)^2), K = 9.144 m/s.
    v_n = -10 m/s and Rn = 0.35: e_eff = 0.35 / (1 + (10 / 9.144)^2)
    = 0.159381, so v_n' = 1.59381 m/s.
    """
    vx, vy, w = _impact(0.0, -10.0, 0.0, 0.5, model, 0.35, 0.5, rt=0.85, vscale=True)
    assert_allclose(vy, 1.59381, atol=5e-6)
    assert_allclose(vy, 10.0 * 0.35 / (1.0 + (10.0 / 9.144) ** 2), rtol=RTOL)
    assert vx == 0.0 and w == 0.0

"""The literature as the prior: a regularised fit moves what the stops see, keeps the rest.

Issue 35: ``fit: auto`` weighs each fitted input's distance from its class's
value (the range as +-2 sd) against the criterion, on the scale of the
criterion's own sampling noise (rockfall_design/calibration/prior.py).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import rockfall_design as rd
from rockfall_design.calibration.prior import (
    HELD_BY_PRIOR_SHARE,
    PRIOR_SIGMAS,
    criterion_noise,
    posterior_shares,
    prior_centres,
    prior_penalty,
    prior_sds,
)
from rockfall_design.calibration.terms import Term

from .calibration_helpers import SITE, TRUTH, observed_stops, write_site


def test_the_penalty_is_zero_at_the_class_value_and_two_sds_at_each_end():
    low, high, centre = [0.0, 0.02], [0.2, 0.4], [0.05, 0.1]
    assert prior_penalty(centre, centre, low, high) == 0.0
    # Either end of either range: PRIOR_SIGMAS sds, whichever side is wider.
    for theta in ([0.0, 0.1], [0.2, 0.1], [0.05, 0.02], [0.05, 0.4]):
        assert prior_penalty(theta, centre, low, high) == pytest.approx(PRIOR_SIGMAS**2)
    # A value at the end of its range: that side adds nothing (the bound holds it).
    assert prior_penalty([0.0], [0.0], [0.0], [1.0]) == 0.0


@settings(max_examples=60, deadline=None)
@given(c=st.floats(0.0, 1.0), a=st.floats(0.0, 1.0), b=st.floats(0.0, 1.0))
def test_the_penalty_grows_with_the_distance_from_the_class_value(c, a, b):
    near, far = sorted([abs(a - c), abs(b - c)])
    for sign in (-1.0, 1.0):
        t_near, t_far = np.clip(c + sign * near, 0, 1), np.clip(c + sign * far, 0, 1)
        p_near = prior_penalty([t_near], [c], [0.0], [1.0])
        p_far = prior_penalty([t_far], [c], [0.0], [1.0])
        assert 0.0 <= p_near <= p_far + 1e-12


def test_the_prior_sds_are_a_quarter_of_each_side_of_the_range():
    # The class value 0.1 in 0.02 .. 0.4: 0.02 below (0.04 of the range: 0.2 / 2 ...).
    sd = prior_sds([0.0, 0.9], [0.1, 0.1], [0.02, 0.02], [0.4, 0.4])
    c = (0.1 - 0.02) / 0.38
    assert sd == pytest.approx([c / 2, (1 - c) / 2])


def test_the_centres_are_the_project_values_and_must_lie_in_their_ranges():
    base = {"materials": {"soil": {"restitution": 0.3}}}
    path = "materials.soil.restitution"
    assert prior_centres(base, {path: (0.1, 0.5)}) == (0.3,)
    with pytest.raises(ValueError, match="inside the range"):
        prior_centres(base, {path: (0.4, 0.5)})
    with pytest.raises(ValueError, match="inside the range"):
        prior_centres(base, {"materials.rock.restitution": (0.1, 0.5)})


def test_the_criterion_noise_is_that_of_a_right_model_and_shrinks_with_more_blocks():
    rng = np.random.default_rng(4)
    terms = [Term("stops", levels={"a": (0.0, 5.0), "b": (5.0, 20.0)})]
    few, many = rng.normal(5, 3, 20), rng.normal(5, 3, 400)
    s_few = criterion_noise([few], terms, "energy", [4.0], 500, 1, terms[0].levels)
    s_many = criterion_noise([many], terms, "energy", [4.0], 500, 1, terms[0].levels)
    assert 0.0 < s_many < s_few
    assert s_few == criterion_noise([few], terms, "energy", [4.0], 500, 1, terms[0].levels)
    # Observation sets: the weighted sum of the terms, the same noise for one set.
    assert criterion_noise([few], terms, "energy", [4.0], 500, 1) == pytest.approx(s_few)


def test_posterior_shares_see_a_curved_input_a_flat_one_and_a_ridge():
    sigma = np.array([0.1, 0.1, 0.1])

    def f(u):  # input 0 well seen, input 1 not at all, input 2 not
        return 100.0 * ((u[0] - 0.5) / 0.1) ** 2

    shares = posterior_shares(f, [0.5, 0.5, 0.5], sigma, noise=1.0)
    assert shares[0] < 0.1 and shares[1] == pytest.approx(1.0) and shares[2] == pytest.approx(1)

    def ridge(u):  # only the sum of inputs 0 and 1 is seen
        return 1e4 * ((u[0] + u[1] - 1.0) / 0.1) ** 2

    shares = posterior_shares(ridge, [0.5, 0.5, 0.5], sigma, noise=1.0)
    # Each of the two keeps half its prior variance: the ridge's direction is the prior's.
    assert shares[:2] == pytest.approx([2**-0.5, 2**-0.5], abs=0.01)
    assert shares[2] == pytest.approx(1.0)


def _site_with_class_value(tmp_path, value: float, fit: str, bootstrap: int = 4):
    text = SITE.replace("soil: {restitution: 0.3,", f"soil: {{restitution: {value},")
    section = (f"calibrate:\n  observed: stops.csv\n  fit: {fit}\n  levels: {{bench: "
               f"[20.5, 29], floor: [29, 107]}}\n  rocks: 80\n  bootstrap: {bootstrap}\n")
    path = write_site(tmp_path, observed_stops(40, seed=1), section)
    path.write_text(text.split("calibrate:")[0] + section)
    return path


def test_what_the_stops_see_moves_away_from_the_class_value(tmp_path):
    # The class says 0.45, the stops were made with 0.3: the fit follows the stops.
    site = _site_with_class_value(tmp_path, 0.45, "{materials.soil.restitution: [0.05, 0.7]}")
    result = rd.calibrate(site, workers=1, prior=True)
    (p,) = result.parameters
    assert abs(p.value - TRUTH) < 0.1 and p.value < 0.4
    assert p.prior_share is not None and p.prior_share < HELD_BY_PRIOR_SHARE
    method = result.summary["method"]["prior"]
    assert method["modes"] == {"materials.soil.restitution": 0.45} and method["noise"] > 0
    unregularised = rd.calibrate(site, workers=1, prior=False, bootstrap=0)
    assert unregularised.summary["method"]["prior"] is None
    assert unregularised.parameters[0].prior_share is None


def test_what_the_stops_do_not_see_stays_at_the_class_value_and_is_flagged(tmp_path):
    # A material on no segment: unregularised its refits go anywhere; with the
    # prior they stay at its value, and the flag says the prior holds it.
    site = _site_with_class_value(
        tmp_path, 0.3, "{materials.unused.restitution: [0.05, 0.7]}", bootstrap=6)
    result = rd.calibrate(site, workers=1, prior=True)
    (p,) = result.parameters
    assert p.value == pytest.approx(0.4, abs=0.02) and p.sd < 0.02
    assert p.held_by_prior and p.identified is False
    assert any("held near its class's value by the prior" in w
               for w in result.summary["warnings"])


def test_the_screen_leaves_out_what_the_stops_cannot_see_and_says_so(tmp_path):
    fit = "{materials.soil.restitution: [0.05, 0.7], materials.unused.restitution: [0.05, 0.7]}"
    site = _site_with_class_value(tmp_path, 0.45, fit, bootstrap=0)
    result = rd.calibrate(site, workers=1, prior=True)
    assert [p.path for p in result.parameters] == ["materials.soil.restitution"]
    screen = {s["path"]: s for s in result.summary["method"]["screen"]}
    assert screen["materials.unused.restitution"]["kept"] is False
    assert screen["materials.unused.restitution"]["effect"] == 0.0  # on no segment
    assert screen["materials.soil.restitution"]["kept"] is True
    assert any(w.startswith("materials.unused.restitution: left out of the fit and kept at "
                            "its class's value 0.4") for w in result.warnings)
    assert result.calibrated_project().materials["unused"].restitution == 0.4
    every = rd.calibrate(site, workers=1, prior=True, screen=False)
    assert len(every.parameters) == 2 and every.summary["method"]["screen"] is None

"""Tests of the embankment, written the way a plugin author tests a plugin.

They use ``rockfall_design.testing`` (its fixtures come with rockfall-design)
and need the plugin installed: ``python -m pip install ./examples/rockfall-embankment``.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from numpy.testing import assert_allclose
from rockfall_embankment import Embankment, fill_area

from rockfall_design import Quantity
from rockfall_design.testing import assert_catches, assert_passes_over

#: On the tiny slope's flat runout (20 < x < 60 m).
EMBANKMENT = {"type": "embankment", "x": 35.0, "height": 3.0}


def flat(x0: float = 0.0, x1: float = 100.0) -> SimpleNamespace:
    """A flat section at y = 0, as a measure sees one (x, y)."""
    return SimpleNamespace(x=np.array([x0, x1]), y=np.array([0.0, 0.0]))


def test_parameters_validate_and_declare_their_design_roles(tiny_slope):
    tiny_slope(EMBANKMENT)  # validated as a project would be
    fields = Embankment.Params.model_fields
    assert fields["height"].json_schema_extra["design"] == {"bounds": [1.5, 6.0]}
    assert fields["uphill_face_deg"].json_schema_extra["design"] == {"bounds": [55.0, 75.0]}
    with pytest.raises(Exception, match="height"):
        tiny_slope({**EMBANKMENT, "height": -1.0})


def test_geometry_and_fill_on_flat_ground():
    m = Embankment(Embankment.Params(x=10.0, height=3.0, crest_width=2.0,
                                     uphill_face_deg=60.0, downhill_face_deg=35.0))
    fp = m.footprint(flat())
    run_up, run_down = 3.0 / math.tan(math.radians(60.0)), 3.0 / math.tan(math.radians(35.0))
    assert_allclose(fp.points, [[10.0, 0.0], [10.0 + run_up, 3.0], [12.0 + run_up, 3.0],
                                [12.0 + run_up + run_down, 0.0]], atol=1e-12)
    assert (fp.catch_from, fp.catch_to) == (4.0, pytest.approx(12.0 + run_up))
    # a trapezoid: crest plus the two faces' triangles
    area = 3.0 * 2.0 + 0.5 * 3.0 * run_up + 0.5 * 3.0 * run_down
    q = m.quantities(flat())
    assert_allclose(q["fill_m3_per_m"], area)
    assert m.bill(flat()) == [Quantity("embankment_fill_m3", q["fill_m3_per_m"], "m3")]
    assert_allclose(m.design_properties()["width_m"], 6.0 + run_up + 2.0)


def test_fill_on_a_slope_is_the_area_between_the_grounds():
    xs, ys = np.array([0.0, 50.0, 100.0]), np.array([10.0, 0.0, 0.0])
    points = np.array([[40.0, 2.0], [45.0, 6.0], [60.0, 0.0]])
    # by hand: the polygon (40, 2) (45, 6) (60, 0) (50, 0) back to (40, 2)
    poly = np.array([[40.0, 2.0], [45.0, 6.0], [60.0, 0.0], [50.0, 0.0]])
    shoelace = 0.5 * abs(np.dot(poly[:, 0], np.roll(poly[:, 1], -1))
                         - np.dot(poly[:, 1], np.roll(poly[:, 0], -1)))
    assert_allclose(fill_area(xs, ys, points), shoelace)


def test_it_does_not_fit_where_the_ground_is_steeper_than_its_downhill_face():
    steep = SimpleNamespace(x=np.array([0.0, 100.0]), y=np.array([100.0, 0.0]))  # 45 deg
    with pytest.raises(ValueError, match="never meets the ground"):
        Embankment(Embankment.Params(x=20.0, height=3.0)).footprint(steep)


def test_it_stops_slow_rocks_and_high_rocks_fly_over():
    assert_catches(EMBANKMENT, speed=8.0, height=1.0)      # strikes the face, stays in front
    assert_catches(EMBANKMENT, speed=5.0, height=0.25)     # rolls into the face
    assert_passes_over(EMBANKMENT, speed=15.0, height=4.5)  # clears the 3 m crest

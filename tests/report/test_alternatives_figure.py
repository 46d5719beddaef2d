"""alternatives.png with five families: every label whole, the cost axis readable, and the
binding check the one nearest its target whichever way its relation runs."""

from __future__ import annotations

from rockfall_design.report.design_figures import alternatives_figure


def _check(name, value, target, relation, unit="m"):
    return {"name": name, "value": value, "target": target, "relation": relation,
            "unit": unit, "ok": True}


FIVE = [
    {"name": "fence 113-280 m", "cost": 285_000.0, "feasible": True, "residual": 4,
     "checks": [_check("design_height", 2.15, 2.75, "<="),
                _check("braking_distance", 10.14, 36.0, "<="),
                _check("design_energy", 2000.0, 4166.0, "<=", "kJ")]},
    {"name": "fence 25-92 m", "cost": None, "feasible": False,
     "reason": "rocks released below x = 92 m never meet a barrier in 25-92 m"},
    {"name": "2 x fence 25-92 m", "cost": None, "feasible": False, "reason": "no design"},
    {"name": "fence 25-92 m + fence 113-280 m", "cost": 312_500.0, "feasible": True,
     "residual": 0, "checks": [_check("height_factor", 2.2, 2.0, ">=", "-"),
                               _check("failure_probability", 0.05, 0.2, "<=", "-")]},
    {"name": "2 x fence 113-280 m", "cost": 401_000.0, "feasible": True, "residual": 1,
     "checks": [_check("failure_probability", 0.19, 0.2, "<=", "-")]},
]


def _texts(fig):
    return [t.get_text() for ax in fig.axes for t in ax.texts]


def test_the_binding_check_is_the_nearest_to_its_target_on_either_side():
    fig = alternatives_figure(FIVE, best="fence 113-280 m", currency="EUR", title="Two zones")
    notes = _texts(fig)
    # 2.15 of 2.75 m (22 % slack) binds, not the braking distance (72 % slack).
    assert any("binding: design_height 2.15/2.75" in t for t in notes), notes
    # A factor's slack is value/target - 1 (10 %), a probability's 1 - value/target (75 %).
    assert any("binding: height 2.20/2.00" in t for t in notes), notes
    assert any("binding: failure_probability 0.19/0.20" in t for t in notes), notes


def test_five_families_have_their_names_whole_and_a_readable_cost_axis():
    fig = alternatives_figure(FIVE, best="fence 113-280 m", currency="EUR", title="Two zones")
    bars = fig.axes[0]
    names = [t.get_text() for t in bars.get_yticklabels()]
    assert names[0] == "* fence 113-280 m" and len(names) == 5
    assert "fence 25-92 m + fence 113-280 m" in names
    fig.canvas.draw()
    labels = [t for t in bars.get_xticklabels() if t.get_text()]
    assert 2 <= len(labels) <= 4 and bars.get_xlabel() == "cost (thousand EUR)"
    # No two tick labels overlap on the drawn figure.
    boxes = sorted((t.get_window_extent() for t in labels), key=lambda b: b.x0)
    assert all(a.x1 < b.x0 for a, b in zip(boxes, boxes[1:], strict=False))

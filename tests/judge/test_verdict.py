"""The verdict: four states from a check summary, and no vacuous "holds"."""

from __future__ import annotations

import json
import textwrap

import pytest

from rockfall_design.cli.program import main
from rockfall_design.judge.bounds import fraction_upper_bound
from rockfall_design.judge.verdict import (
    FAILS,
    HOLDS_ON_POINT_VALUES,
    HOLDS_WITH_CONFIDENCE,
    STATES,
    UNTESTED,
    DesignVerdict,
    residual_rocks,
    verdict_of,
    verdict_of_scenarios,
    verdict_of_sections,
)


def check(name="height_factor", value=2.5, target=2.0, ok=True, bound=2.2, owc=True,
          rocks_needed=None, unit="-"):
    return {"name": name, "value": value, "target": target, "ok": ok, "unit": unit,
            "detail": "", "bound": bound, "ok_with_confidence": owc,
            "rocks_needed": rocks_needed}


def summary(checks=None, met=100, protect=None, rocks=1000):
    measures = [] if checks is None else [
        {"type": "fence", "label": "fence at x = 50 m", "met": met, "checks": checks}]
    out = {"rocks": rocks, "confidence": 0.95, "measures": measures}
    if protect is not None:
        out["protect"] = protect
    return out


def protect(reaching=0, n=1000, allowed=0.01):
    upper = fraction_upper_bound(reaching, n, 0.95)
    return {"x": 100.0, "reaching": reaching, "fraction": reaching / n, "upper_fraction": upper,
            "allowed_fraction": allowed, "ok": reaching / n <= allowed,
            "ok_with_confidence": upper <= allowed}


def test_every_check_with_its_bound_holds_with_confidence():
    v = verdict_of(summary([check()], protect=protect(0, 1000, 0.01)))
    assert v.state == HOLDS_WITH_CONFIDENCE and v.with_confidence and v.holds
    assert v.headline.startswith("Holds with confidence: ") and "95 %" in v.headline
    assert v.details == () and v.untested == ()


def test_a_check_that_holds_on_its_point_value_only_says_what_would_settle_it():
    # value 2.5 against 2.0, bound 1.5: the bound is 1.0 from the value, the value 0.5
    # from the target; the bound shrinks as 1/sqrt(n): 1000 * (1.0 / 0.5)**2 rocks.
    v = verdict_of(summary([check(bound=1.5, owc=False)]))
    assert v.state == HOLDS_ON_POINT_VALUES and v.holds and not v.with_confidence
    assert v.rocks_needed == 4000
    assert "about 4,000 rocks would settle it" in v.headline
    assert "height_factor 2.50 meets its target 2.00" in v.details[0]


def test_a_sample_too_small_to_bound_scales_the_rocks_it_needs_by_the_share_met():
    v = verdict_of(summary([check(bound=None, owc=False, rocks_needed=59)], met=10))
    assert v.state == HOLDS_ON_POINT_VALUES and v.rocks_needed == 5900
    assert "cannot be bounded yet" in v.details[0]


def test_a_residual_of_zero_allowed_is_never_settled_and_says_what_to_write():
    v = verdict_of(summary([check()], protect=protect(0, 1000, 0.0)))
    assert v.state == HOLDS_ON_POINT_VALUES and v.rocks_needed is None
    assert "no number of rocks" in v.headline
    assert "e.g. 0.001" in v.details[0] and "2,995 rocks" in v.details[0]


def test_a_failing_check_says_what_fails_and_by_how_much():
    v = verdict_of(summary([check(value=1.5, ok=False, bound=1.7, owc=False)],
                           protect=protect(30, 1000, 0.01)))
    assert v.state == FAILS and not v.holds
    assert v.headline == "Fails: 2 requirements miss their targets on 1,000 rocks."
    assert "height_factor 1.50 misses its target 2.00 by 0.50 (25 % of the target)" \
        in v.details[0]
    assert "30 of 1,000 rocks (3 %) reach" in v.details[1] and "20 rocks too many" in v.details[1]


def test_nothing_to_check_is_untested_not_holds():
    v = verdict_of(summary(None))
    assert v.state == UNTESTED and not v.holds
    assert v.headline.startswith("Untested: no measure and no protected zone")
    w = verdict_of(summary([check(value=None, bound=None, owc=None)], met=0))
    assert w.state == UNTESTED and w.untested == ("fence at x = 50 m",)


def test_a_measure_no_rock_meets_is_listed_as_untested_under_any_verdict():
    s = summary([check()], protect=protect(0, 1000, 0.01))
    s["measures"].append({"type": "ditch", "label": "ditch at x = 90 m", "met": 0,
                          "checks": [check(value=None, bound=None, owc=None)]})
    v = verdict_of(s)
    assert v.state == HOLDS_WITH_CONFIDENCE and v.untested == ("ditch at x = 90 m",)
    assert any("ditch at x = 90 m: untested" in d for d in v.details)


@pytest.mark.parametrize("reaching, n, allowed", [(0, 500, 0.001), (3, 4000, 0.002),
                                                  (10, 2000, 0.01)])
def test_the_rocks_that_settle_a_residual_are_the_fewest_at_the_observed_rate(reaching, n,
                                                                             allowed):
    need = residual_rocks(reaching, n, allowed, 0.95)
    rate = reaching / n

    def bound(m):
        return fraction_upper_bound(int(-(-rate * m // 1)), m, 0.95)

    assert bound(need) <= allowed < bound(need - 1)


def test_scenarios_and_sections_take_their_weakest_state():
    sure = summary([check()])
    loose = summary([check(bound=1.5, owc=False)])
    bad = summary([check(value=1.0, ok=False)])
    assert verdict_of_scenarios([sure, sure, bad], required=2).state == HOLDS_WITH_CONFIDENCE
    assert verdict_of_scenarios([sure, loose, bad], required=2).state == HOLDS_ON_POINT_VALUES
    assert verdict_of_scenarios([sure, bad, bad], required=2).state == FAILS
    assert verdict_of_scenarios([summary(None)] * 2, required=2).state == UNTESTED
    parts = [("north", verdict_of(sure)), ("south", verdict_of(loose))]
    v = verdict_of_sections(parts)
    assert v.state == HOLDS_ON_POINT_VALUES and "south" in v.headline
    assert DesignVerdict.from_dict(v.as_dict()) == v
    assert v.state in STATES


FLAT = """\
name: flat
slope:
  points: [[0, 40], [60, 0], [200, 0]]
  materials: ground
materials:
  ground: {restitution: 0.3, friction: 0.6, rolling_resistance: 0.5}
rocks:
  count: 40
  seed: 3
  radius: 0.3
  release: {x: [1, 3], height: 1}
"""


def _write(tmp_path, extra):
    path = tmp_path / "p.yaml"
    path.write_text(FLAT + textwrap.dedent(extra))
    return path


def test_check_of_nothing_is_untested_exit_1(tmp_path, capsys):
    """Issue 27 item 3: no measure and no protected zone is not "holds"."""
    code = main(["check", str(_write(tmp_path, "")), "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 1
    assert next(iter(out)) == "verdict" and out["verdict"]["state"] == UNTESTED
    assert out["ok"] is False and out["holds_with_confidence"] is False


def test_a_fence_no_rock_reaches_is_untested(tmp_path, capsys):
    path = _write(tmp_path, "measures: [{type: fence, x: 199, height: 3, capacity_kj: 500}]\n")
    code = main(["check", str(path), "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 1 and out["verdict"]["state"] == UNTESTED
    assert out["verdict"]["untested_measures"] == [out["measures"][0]["label"]]
    main(["check", str(path)])
    text = capsys.readouterr().out
    assert text.splitlines()[1].strip("│ ").startswith("Untested: no rock of 40 reached")


def test_an_allowed_fraction_of_zero_is_one_warning_line_at_load(tmp_path, capsys):
    path = _write(tmp_path, """\
        protect: {x: 150, allowed_fraction: 0}
        measures: [{type: fence, x: 100, height: 3, capacity_kj: 5000}]
        """)
    main(["check", str(path), "--json"])
    err = capsys.readouterr().err.splitlines()
    warned = [line for line in err if "allowed_fraction" in line]
    assert len(warned) == 1
    assert warned[0].startswith(f"rockfall-design: warning: {path}:12: protect.allowed_fraction:")
    assert "never hold with confidence" in warned[0] and "allowed_fraction: 0.001" in warned[0]
    # A fraction that can be shown says nothing.
    path.write_text(path.read_text().replace("allowed_fraction: 0", "allowed_fraction: 0.01"))
    main(["check", str(path), "--json"])
    assert "allowed_fraction" not in capsys.readouterr().err


def test_check_scenarios_of_nothing_is_untested_not_holds_in_every_scenario(tmp_path, capsys):
    """Issue 27 item 3: check --scenarios with no measures held "in 2 of 2"."""
    path = _write(tmp_path, """\
        study:
          vary:
            materials.ground.friction: [0.5, 0.7]
          scenarios: grid
        """)
    code = main(["check", str(path), "--scenarios", "--workers", "1", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 1 and out["ok"] is False and out["holds_in"] == 0
    assert out["verdict"]["state"] == UNTESTED
    assert all(s["verdict"]["state"] == UNTESTED for s in out["scenarios"])

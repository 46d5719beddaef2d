"""Observations beyond stops (issue 35 item 5): kinds, profiles, their terms and checks."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rockfall_design.errors import ProjectError
from rockfall_design.project import load_project, load_project_text

from .calibration_helpers import SITE

HEAD = SITE.split("calibrate:")[0]
FIT = "  fit: {materials.soil.restitution: [0.05, 0.7]}\n"

#: A second profile of the same site: a slope onto a bench reached by sliding,
#: a wall and a floor; the soil and rock are the site's (by name), its own
#: ``gravel`` only it has.
P2 = """\
name: site P2
slope:
  points: [[0, 30], [30, 13], [44, 12], [44.5, 3], [100, 2]]
  materials: [soil, gravel, rock, soil]
materials:
  soil: {restitution: 0.9, friction: 0.6, rolling_resistance: 0.1}
  rock: {restitution: 0.5, friction: 0.5, rolling_resistance: 0.15, roughness_deg: 8}
  gravel: {restitution: 0.25, friction: 0.6, rolling_resistance: 0.6, roughness_deg: 4}
rocks:
  count: 100
  seed: 7
  volume: 0.3
  release: {x: [1, 3], height: 0.5, velocity: [0.5, 0]}
"""


def _project(section: str, name: str = "site.yaml"):
    return load_project_text(HEAD + section, name)


@pytest.mark.parametrize("section, where, words", [
    ("calibrate:\n  observed:\n    - {kind: hights, x: 25, values: [1, 2, 3, 4, 5]}\n" + FIT,
     "calibrate.observed[0].kind", "expected one of stops, passing_heights, speeds"),
    ("calibrate:\n  observed:\n    - stops.csv\n    - {kind: speeds, values: [1, 2, 3, 4, 5]}\n"
     + FIT, "calibrate.observed[1].x", "needs x"),
    ("calibrate:\n  observed:\n    - {file: a.csv, values: [1, 2, 3, 4, 5]}\n" + FIT,
     "calibrate.observed[0].file", "either file"),
    ("calibrate:\n  observed:\n    - {file: a.csv, x: 3}\n" + FIT,
     "calibrate.observed[0].x", "stops have no station"),
    ("calibrate:\n  observed:\n    - stops.csv\n    - {kind: speeds, x: 3, values: [1, 2, 3, "
     "4, 5], measured: normal}\n" + FIT, "calibrate.observed[1].measured", "passing_heights"),
    ("calibrate:\n  observed:\n    - {file: a.csv, profile: P3}\n" + FIT,
     "calibrate.observed[0].profile", "no profile 'P3'"),
    ("calibrate:\n  profiles: {P2: p2.yaml}\n  observed: [a.csv]\n" + FIT,
     "calibrate.profiles.P2", "has no observation"),
    ("calibrate:\n  observed:\n    - {kind: speeds, x: 30, values: [1, 2, 3, 4, 5]}\n" + FIT,
     "calibrate.observed", "project's own section"),
    ("calibrate:\n  observed:\n    - stops.csv\n    - {kind: speeds, x: 300, values: [1, 2, 3, "
     "4, 5]}\n" + FIT, "calibrate.observed[1].x", "outside the slope section"),
    ("calibrate:\n  observed:\n    - stops.csv\n    - {kind: speeds, x: 30, valus: [1]}\n" + FIT,
     "calibrate.observed[1].valus", "did you mean 'values'"),
    ("calibrate:\n  observed:\n    - stops.csv\n    - {kind: speeds, x: 30, weight: 0, values: "
     "[1, 2, 3, 4, 5]}\n" + FIT, "calibrate.observed[1].weight", "> 0, got 0"),
    ("calibrate:\n  observed: 3\n" + FIT, "calibrate.observed", "or a list of observation"),
])
def test_a_bad_observation_set_is_one_line_at_its_key(section, where, words):
    with pytest.raises(ProjectError) as err:
        _project(section)
    text = str(err.value)
    assert "\n" not in text
    assert f": {where}:" in text and words in text, text


def test_the_single_file_form_keeps_its_record():
    one = _project("calibrate:\n  observed: stops.csv\n" + FIT).resolved_dict()["calibrate"]
    listed = _project("calibrate:\n  observed: [stops.csv]\n" + FIT).resolved_dict()
    assert one["observed"] == "stops.csv" and "profiles" not in one
    assert listed["calibrate"] == one
    many = _project("calibrate:\n  observed:\n    - stops.csv\n    - {kind: speeds, x: 30, "
                    "values: [1, 2, 3, 4, 5]}\n" + FIT).resolved_dict()["calibrate"]
    assert [e["kind"] for e in many["observed"]] == ["stops", "speeds"]


@pytest.mark.parametrize("text, line, column, words", [
    ("height\n1\n", 1, "height_m", "did you mean 'height'"),
    ("height_m\n1\n-2\n", 3, "height_m", ">= 0"),
    ("height_m\n1\n2\nabc\n", 4, "height_m", "expected a number"),
    ("height_m\n1\n2\n150\n", 4, "height_m", "other units"),
    ("height_m\n1\n2\n", 3, "height_m", "at least 5"),
    ("", 1, "", "empty"),
])
def test_a_bad_file_of_heights_is_one_line_at_its_place(text, line, column, words):
    from rockfall_design.calibration.sets import parse_passages, passage_limit

    project = _project("calibrate:\n  observed: stops.csv\n" + FIT)
    limit = passage_limit(project, 30.0, "passing_heights")
    with pytest.raises(ProjectError) as err:
        parse_passages(text, "marks.csv", "passing_heights", limit)
    assert str(err.value).startswith(f"marks.csv:{line}: {column}")
    assert words in str(err.value)


def test_the_free_fall_bound_of_a_passage():
    from rockfall_design.calibration.sets import passage_limit

    project = _project("calibrate:\n  observed: stops.csv\n" + FIT)
    # From 40 m down to 2.3 m at x = 30, plus the 0.5 m release clearance and
    # the head of 0.5 m/s with the rolling share: 38.2 m + 0.018 m.
    h = passage_limit(project, 30.0, "passing_heights")
    assert h == pytest.approx(40 - np.interp(30, [29, 107], [2.3, 2.0]) + 0.5
                              + 1.4 * 0.25 / (2 * 9.81))
    assert passage_limit(project, 30.0, "speeds") == pytest.approx(np.sqrt(2 * 9.81 * h))


def test_inline_values_are_checked_at_their_item(tmp_path):
    from rockfall_design.calibration.sets import read_site

    (tmp_path / "stops.csv").write_text("x\n" + "".join(f"{30 + i}\n" for i in range(6)))
    (tmp_path / "site.yaml").write_text(HEAD + "calibrate:\n  observed:\n    - stops.csv\n"
                                        "    - {kind: speeds, x: 30, values: [5, 6, 7, 99, "
                                        "5]}\n" + FIT)
    with pytest.raises(ProjectError) as err:
        read_site(load_project(tmp_path / "site.yaml"))
    assert "calibrate.observed[1].values[3]: 99 m/s is more than any rock" in str(err.value)


def test_a_missing_profile_file_is_named_at_its_key(tmp_path):
    from rockfall_design.calibration.sets import read_site

    (tmp_path / "site.yaml").write_text(HEAD + "calibrate:\n  profiles: {P2: nothere.yaml}\n"
                                        "  observed:\n    - stops.csv\n    - {file: s2.csv, "
                                        "profile: P2}\n" + FIT)
    with pytest.raises(ProjectError) as err:
        read_site(load_project(tmp_path / "site.yaml"))
    assert "calibrate.profiles.P2: no profile file" in str(err.value)


@settings(max_examples=30, deadline=None)
@given(obs=st.lists(st.floats(0.0, 10.0), min_size=5, max_size=30),
       sim=st.lists(st.floats(0.0, 10.0), min_size=0, max_size=30),
       w=st.floats(0.1, 10.0))
def test_a_passage_term_is_nonnegative_zero_on_itself_and_linear_in_its_weight(obs, sim, w):
    from rockfall_design.calibration.terms import Term, passage_term, sets_objective

    o, s = np.asarray(obs), np.asarray(sim)
    t = passage_term(o, s, "energy", 0.5)
    assert t >= 0 and np.isfinite(t)
    assert passage_term(o, o, "energy", 0.5) == pytest.approx(0.0, abs=1e-9)
    one = sets_objective([o], [s], [Term("speeds", 0, 0, "velocity_ms", 1.0)], "energy", [0.5])
    many = sets_objective([o], [s], [Term("speeds", 0, 0, "velocity_ms", w)], "energy", [0.5])
    assert many == pytest.approx(w * one)


def _stops(directory, name="stops.csv", start=40.0):
    (directory / name).write_text("x\n" + "".join(f"{start + 1.5 * i:.1f}\n" for i in range(12)))


def test_heights_and_speeds_are_fitted_and_reported(tmp_path, capsys):
    from rockfall_design.cli import main

    _stops(tmp_path)
    (tmp_path / "marks.csv").write_text("height_m,note\n" + "".join(
        f"{h},tree {i}\n" for i, h in enumerate([0.6, 0.9, 1.4, 0.7, 2.1, 0.8])))
    (tmp_path / "site.yaml").write_text(
        HEAD + "calibrate:\n  observed:\n    - stops.csv\n"
        "    - {kind: passing_heights, x: 35, file: marks.csv, weight: 2}\n"
        "    - {kind: speeds, x: 50, values: [6, 7.5, 8, 9, 7, 6.5]}\n"
        + FIT + "  rocks: 40\n  bootstrap: 2\n")
    assert main(["calibrate", str(tmp_path / "site.yaml"), "--json", "--out",
                 str(tmp_path / "cal")]) == 0
    out = json.loads(capsys.readouterr().out)
    kinds = [(s["kind"], s["x"], s["weight"]) for s in out["sets"]]
    assert kinds == [("stops", None, 1.0), ("passing_heights", 35.0, 2.0), ("speeds", 50.0, 1.0)]
    heights = out["sets"][1]
    assert heights["count"] == 6 and 0 < heights["passed_share"] <= 1
    assert heights["fit"]["simulated"]["count"] == round(heights["passed_share"] * 40)
    # calibrated.yaml names the same sets, from where it is written, and reruns.
    again = load_project(tmp_path / "cal" / "calibrated.yaml")
    assert [e.kind for e in again.calibrate.entries] == ["stops", "passing_heights", "speeds"]
    assert again.calibrate.entries[1].file == "../marks.csv"
    library = " ".join((tmp_path / "cal" / "materials.yaml").read_text().split())
    assert "passing heights (vertical) at x = 35 m from" in library
    # compare without --observed: every set, each with its verdict.
    assert main(["compare", str(tmp_path / "cal" / "calibrated.yaml"), "--rocks", "60"]) == 0
    shown = " ".join(capsys.readouterr().out.split())
    assert "observation sets" in shown and "NOT consistent" in shown
    assert main(["compare", str(tmp_path / "cal" / "calibrated.yaml"), "--rocks", "60",
                 "--json"]) == 0
    cmp = json.loads(capsys.readouterr().out)
    assert [s["kind"] for s in cmp["sets"]] == ["stops", "passing_heights", "speeds"]
    assert cmp["consistent"] == all(s["consistent"] for s in cmp["sets"])


def test_the_list_form_of_one_file_fits_as_the_single_file_form(tmp_path):
    from rockfall_design.calibration.procedure import run_calibration

    _stops(tmp_path)
    values = []
    for observed in ("stops.csv", "[{file: stops.csv}]"):
        (tmp_path / "site.yaml").write_text(HEAD + f"calibrate:\n  observed: {observed}\n"
                                            + FIT + "  rocks: 30\n  bootstrap: 0\n")
        values.append(run_calibration(load_project(tmp_path / "site.yaml")).values)
    assert values[0] == values[1]


def test_two_profiles_share_their_materials_by_name(tmp_path, capsys):
    from rockfall_design.calibration.procedure import run_calibration
    from rockfall_design.cli import main

    _stops(tmp_path)
    _stops(tmp_path, "stops_p2.csv", 30.0)
    (tmp_path / "p2.yaml").write_text(P2)
    (tmp_path / "site.yaml").write_text(
        HEAD + "calibrate:\n  profiles: {P2: p2.yaml}\n  observed:\n    - stops.csv\n"
        "    - {file: stops_p2.csv, profile: P2, levels: {bench: [30, 44]}}\n"
        "  fit:\n    materials.soil.restitution: [0.05, 0.7]\n"
        "    materials.gravel.rolling_resistance: [0.1, 1.0]\n  rocks: 30\n  bootstrap: 0\n")
    result = run_calibration(load_project(tmp_path / "site.yaml"))
    (p2,) = result.problem.others
    # The site's soil (0.3), not P2's own (0.9); P2's gravel added to the site's.
    assert p2.base["materials"]["soil"]["restitution"] == 0.3
    assert result.problem.base["materials"]["gravel"]["rolling_resistance"] == 0.6
    assert [s.profile for s in result.sets] == [None, "P2"]
    assert [lv.name for lv in result.sets[1].levels] == ["bench"]
    assert main(["calibrate", str(tmp_path / "site.yaml"), "--out", str(tmp_path / "cal"),
                 "--bootstrap", "0", "--json"]) == 0
    capsys.readouterr()
    again = load_project(tmp_path / "cal" / "calibrated.yaml")
    assert again.calibrate.profiles == {"P2": "../p2.yaml"}
    assert "gravel" in again.materials
    # compare without --observed predicts both profiles, each set with its verdict.
    from rockfall_design.calibration.procedure import run_comparison

    cmp = run_comparison(again, None, rocks=30)
    assert [(s.profile, s.kind) for s in cmp.sets] == [(None, "stops"), ("P2", "stops")]
    assert cmp.consistent == all(s.consistent for s in cmp.sets)


def test_fit_auto_takes_every_profile_s_materials(tmp_path):
    from rockfall_design.calibration.procedure import fit_ranges
    from rockfall_design.calibration.sets import read_site

    ranges = "ranges: {restitution: [0.1, 0.6], rolling_resistance: [0.1, 1.0]}"
    head = HEAD.replace("roughness_deg: 4}", f"roughness_deg: 4, {ranges}}}").replace(
        "roughness_deg: 8}", f"roughness_deg: 8, {ranges}}}")
    _stops(tmp_path)
    _stops(tmp_path, "stops_p2.csv", 30.0)
    (tmp_path / "p2.yaml").write_text(P2.replace("roughness_deg: 4}",
                                                 f"roughness_deg: 4, {ranges}}}"))
    (tmp_path / "site.yaml").write_text(
        head + "calibrate:\n  profiles: {P2: p2.yaml}\n  observed:\n    - stops.csv\n"
        "    - {file: stops_p2.csv, profile: P2}\n  fit: auto\n")
    project = load_project(tmp_path / "site.yaml")
    assert "materials.gravel.restitution" not in project.calibrate.fit
    fit = fit_ranges(project, read_site(project))
    assert list(fit) == [f"materials.{m}.{k}" for m in ("soil", "rock", "gravel")
                         for k in ("restitution", "rolling_resistance")]


def test_the_report_has_a_table_of_the_sets(tmp_path):
    from rockfall_design.calibration.procedure import run_comparison

    _stops(tmp_path)
    (tmp_path / "site.yaml").write_text(
        HEAD + "calibrate:\n  observed:\n    - stops.csv\n"
        "    - {kind: speeds, x: 50, values: [6, 7.5, 8, 9, 7, 6.5]}\n" + FIT)
    result = run_comparison(load_project(tmp_path / "site.yaml"), None, rocks=40)
    result.save_report(tmp_path / "rep")
    text = (tmp_path / "rep" / "report.md").read_text()
    assert "Observation sets" in text and "speeds at x = 50 m" in text


def test_the_bootstrap_resamples_every_set_each_on_its_own(monkeypatch):
    from rockfall_design.calibration import uncertainty
    from rockfall_design.calibration.fit import FitOutcome

    seen = []

    def fake_fit(problem, observed, seed, diagnose=False):
        seen.append(observed)
        return FitOutcome({}, 0.0, 0, np.zeros(1), ())

    monkeypatch.setattr(uncertainty, "fit", fake_fit)
    stops, heights = np.arange(10.0), np.arange(100.0, 107.0)
    uncertainty.run_replicate(uncertainty.ReplicateTask(None, stops, 3, 5))
    uncertainty.run_replicate(uncertainty.ReplicateTask(None, (stops, heights), 3, 5))
    single, (first, second) = seen
    # The first set draws as the single-file form did; the second, its own values.
    assert np.array_equal(single, first)
    assert second.size == 7 and set(second) <= set(heights)
    assert not np.array_equal(np.sort(second), heights)  # a resample, not the set itself


@pytest.mark.parametrize("entry, where", [
    ("{file: stops.csv, levels: {far: [200, 300]}}", "calibrate.observed[0].levels.far"),
    ("{file: stops.csv}\n  levels: {far: [200, 300]}", "calibrate.levels.far"),
])
def test_a_level_off_its_section_is_named_where_it_is_given(tmp_path, entry, where):
    from rockfall_design.calibration.procedure import run_calibration

    _stops(tmp_path)
    (tmp_path / "site.yaml").write_text(HEAD + f"calibrate:\n  observed:\n    - {entry}\n"
                                        + FIT + "  rocks: 30\n  bootstrap: 0\n")
    with pytest.raises(ProjectError) as err:
        run_calibration(load_project(tmp_path / "site.yaml"))
    assert f": {where}: level [200, 300] lies outside" in str(err.value)

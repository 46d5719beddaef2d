"""The design block (``rocks.design_block``): from a block survey or a return period.

A survey's percentile carries its order-statistic bounds into ``m_d`` of
``uni11211`` and ``E_d`` of ``onr24810``; a return period's block is
:math:`V_T = (a T)^{1/b}`; bad input is one line naming file, line and key.
"""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from rockfall_design.errors import ProjectError
from rockfall_design.judge.bounds import quantile_with_bounds
from rockfall_design.judge.design_block import design_block_of
from rockfall_design.judge.evaluation import evaluate
from rockfall_design.project import load_project, load_project_text
from rockfall_design.project.design_block import parse_block_survey

ROOT = Path(__file__).resolve().parents[2]

# Level ground; rocks launched 10 m above it meet a fence at x = 6 m.
FLIGHT = """
name: flight
slope:
  points: [[-20, 0], [300, 0]]
  materials: ground
materials:
  ground: {{restitution: 0.3, friction: 0.5, rolling_resistance: 0.4}}
rocks:
  count: 80
  seed: 3
  radius: 0.3
  density: 2500
  release: {{x: 0, height: 10, velocity: [5, 0], spin: 2}}
{block}
measures:
  - {{type: fence, x: 6, height: 5.0, capacity_kj: 5000, max_elongation_m: 5.5,
     elongation_sel_m: 3.6, residual_height_fraction: 0.6}}
protect: {{x: 30}}
safety: {{concept: {concept}}}
"""

SURVEY = "block,volume_m3\n" + "".join(f"B{i},{0.01 * i:.2f}\n" for i in range(1, 201))


def _project(tmp_path: Path, block: str, concept: str = "uni11211",
             survey: str | None = SURVEY) -> Path:
    if survey is not None:
        (tmp_path / "blocks.csv").write_text(survey, encoding="utf-8")
    path = tmp_path / "p.yaml"
    text = FLIGHT.format(block=textwrap.indent(textwrap.dedent(block).strip(), "  "),
                         concept=concept)
    path.write_text(text, encoding="utf-8")
    return path


def _check(ev, name):
    (c,) = [c for c in ev.checks[0] if c.name == name]
    return c


def test_a_survey_percentile_is_the_design_mass_of_uni11211(registry, tmp_path):
    path = _project(tmp_path, "design_block: {survey: blocks.csv, percentile: 98}")
    ev = evaluate(load_project(path), registry)
    volumes = 0.01 * np.arange(1, 201)
    point, lower, upper = quantile_with_bounds(volumes, 0.98, 0.95)
    energy = _check(ev, "design_energy")
    (m_d,) = [d for d in energy.design_values if d.symbol == "m_d"]
    assert_allclose(m_d.value, point * 2500 * 1.02)
    assert_allclose(m_d.bound, upper * 2500 * 1.02)
    assert "design block" in m_d.meaning and "rocks.design_block" in energy.detail
    assert "p98 of the 200 block volumes of survey blocks.csv" in energy.detail
    # The bound of E_d takes the block's upper bound: it is above the value.
    assert energy.bound > energy.value


def test_without_a_design_block_the_simulated_masses_are_used(registry, tmp_path):
    ev = evaluate(load_project(_project(tmp_path, "")), registry)
    energy = _check(ev, "design_energy")
    (m_d,) = [d for d in energy.design_values if d.symbol == "m_d"]
    mass = 4 / 3 * math.pi * 0.3**3 * 2500
    assert_allclose(m_d.value, mass * 1.02)
    assert "simulated rocks" in energy.detail and "design_block" not in energy.detail


def test_onr24810_takes_the_design_block_at_the_rocks_speeds(registry, tmp_path):
    path = _project(tmp_path, "design_block: {survey: blocks.csv, percentile: 98}",
                    "onr24810")
    ev = evaluate(load_project(path), registry)
    energy = _check(ev, "design_energy")
    speeds = ev.results[0].velocity_ms
    block = design_block_of(load_project(path), 0.95)
    expected = 1.1 * np.percentile(0.5 * block.mass_kg * speeds**2 / 1000.0, 99)
    assert_allclose(energy.value, expected)
    assert "rocks.design_block" in energy.detail


def test_a_return_period_gives_the_power_law_volume(registry, tmp_path):
    path = _project(tmp_path, "design_block: {return_period_years: 100, "
                    "frequency: {a: 0.5, b: 0.8}}", survey=None)
    block = design_block_of(load_project(path), 0.95)
    volume = (0.5 * 100) ** (1 / 0.8)
    assert_allclose(block.mass_kg, volume * 2500)
    assert block.lower_kg == block.upper_kg == block.mass_kg
    assert "return period 100 years" in block.source
    ev = evaluate(load_project(path), registry)
    assert "return period 100 years" in _check(ev, "design_energy").detail


@settings(max_examples=40, deadline=None)
@given(st.floats(0.01, 100.0), st.floats(1.0, 1e4), st.floats(0.2, 2.0))
def test_the_return_period_block_is_exceeded_once_in_its_period(a, period, b):
    """N(>V_T) = a V_T^-b = 1/T: the block is exceeded once a return period on average."""
    text = FLIGHT.format(block=f"  design_block: {{return_period_years: {period!r}, "
                         f"frequency: {{a: {a!r}, b: {b!r}}}}}", concept="uni11211")
    spec = load_project_text(text, "p.yaml").rocks.design_block
    v = spec.return_period_volume_m3
    assert_allclose(a * v ** (-b) * period, 1.0, rtol=1e-9)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(0.001, 50.0), min_size=1, max_size=300))
def test_a_survey_reads_back_every_block(values):
    text = "id,volume_m3,note\n" + "".join(f"{i},{v!r},x\n" for i, v in enumerate(values))
    quantity, read = parse_block_survey(text, "s.csv")
    assert quantity == "volume" and read == values


def _error(path: Path) -> str:
    with pytest.raises(ProjectError) as info:
        load_project(path)
    text = str(info.value)
    assert "\n" not in text
    return text


def test_a_missing_survey_file_is_an_error_at_its_key(tmp_path):
    path = _project(tmp_path, "design_block: {survey: nowhere.csv, percentile: 98}")
    text = _error(path)
    line = path.read_text().splitlines().index("  design_block: {survey: nowhere.csv, "
                                                "percentile: 98}") + 1
    assert text.startswith(f"{path}:{line}: rocks.design_block.survey: cannot read the block "
                           "survey"), text


@pytest.mark.parametrize("survey, line, key, words", [
    ("block,size\nB1,0.2\n", 1, "", "no column volume_m3 (m3) or mass_kg (kg)"),
    ("volume_m3,mass_kg\n0.2,500\n", 1, "mass_kg", "give only one of volume_m3 and mass_kg"),
    ("block,volume_m3\nB1,0.2\nB2,abc\n", 3, "volume_m3", "expected a number, got 'abc'"),
    ("block,volume_m3\nB1,0.2\nB2,-1\n", 3, "volume_m3", "expected a size > 0, got -1"),
    ("block,volume_m3\nB1,0.2\nB2\n", 3, "", "expected 2 cells"),
    ("block,volume_m3\n", 1, "volume_m3", "no block below the header row"),
])
def test_a_bad_survey_names_file_line_and_column(tmp_path, survey, line, key, words):
    path = _project(tmp_path, "design_block: {survey: blocks.csv, percentile: 98}",
                    survey=survey)
    text = _error(path)
    where = f"{tmp_path / 'blocks.csv'}:{line}: " + (f"{key}: " if key else "")
    assert text.startswith(where) and words in text, text


@pytest.mark.parametrize("block, key, words", [
    ("{survey: blocks.csv, percentile: 100}", "percentile", "expected a number < 100, got 100"),
    ("{survey: blocks.csv, percentile: 0}", "percentile", "expected a number > 0, got 0"),
    ("{survey: blocks.csv}", "percentile", "give the percentile"),
    ("{return_period_years: 100}", "frequency", "give the design block"),
    ("{survey: blocks.csv, percentile: 98, return_period_years: 50, frequency: {a: 1, b: 1}}",
     "return_period_years", "not both"),
])
def test_a_bad_design_block_names_its_key(tmp_path, block, key, words):
    text = _error(_project(tmp_path, f"design_block: {block}"))
    assert f"rocks.design_block.{key}: " in text and words in text, text


def test_a_survey_too_small_to_bound_its_percentile_says_how_many_blocks(registry, tmp_path):
    survey = "volume_m3\n" + "".join(f"{0.1 * i:.1f}\n" for i in range(1, 41))
    path = _project(tmp_path, "design_block: {survey: blocks.csv, percentile: 98}",
                    survey=survey)
    with pytest.raises(ProjectError) as info:
        evaluate(load_project(path), registry)
    text = str(info.value)
    assert "rocks.design_block.percentile: 40 surveyed blocks cannot bound" in text
    assert "at least 149 blocks" in text


def test_a_concept_that_uses_no_design_block_refuses_one(registry, tmp_path):
    path = _project(tmp_path, "design_block: {survey: blocks.csv, percentile: 98}", "spang")
    with pytest.raises(ProjectError) as info:
        evaluate(load_project(path), registry)
    assert "rocks.design_block: the safety concept 'spang' designs on the simulated" in str(
        info.value)


def test_the_bundled_quarry_designs_on_its_synthetic_survey():
    project = load_project(ROOT / "projects" / "design_quarry.yaml")
    spec = project.rocks.design_block
    assert spec.survey == "quarry_blocks.csv" and spec.quantity == "volume"
    assert len(spec.blocks) == 240
    block = design_block_of(project, 0.95)
    assert block.lower_kg < block.mass_kg < block.upper_kg
    assert "quarry_blocks.csv" in block.source


def test_the_check_report_shows_the_survey_and_the_design_block_used(tmp_path):
    """design_quarry's survey with a fence: the report lists the blocks, the check names them.

    The report's text, rendered without its figures, which say nothing of the
    block (check's whole report, figures and all, is written by the command
    in tests/report/test_handin.py and printed in test_pdf.py).
    """
    import rockfall_design as rd
    from rockfall_design.report.documents import render_markdown, report_context

    for name in ("quarry_blocks.csv", "catalogue_products.yaml", "catalogue_costs.yaml"):
        (tmp_path / name).write_text((ROOT / "projects" / name).read_text(encoding="utf-8"))
    text = (ROOT / "projects" / "design_quarry.yaml").read_text(encoding="utf-8")
    text = text[:text.index("design:")] + (
        "measures:\n  - {type: fence, x: 100, height: 5.0, capacity_kj: 5000, "
        "max_elongation_m: 7.8, residual_height_fraction: 0.6}\n")
    path = tmp_path / "quarry.yaml"
    path.write_text(text, encoding="utf-8")
    page = render_markdown(report_context(rd.check(path, rocks=300), {}))
    assert "Block survey" in page and "240 block volumes (m3) in the table" in page
    assert "design mass: the design block (rocks.design_block)" in page
    assert "p98 of the 240 block volumes of survey quarry_blocks.csv" in page

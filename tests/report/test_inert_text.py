"""Text from input files is inert everywhere (issue 34 item 6).

A newline or a control character in a name, a label or a currency is
refused at its key (``file:line: key: ...``), before any run; a ``$`` in a
name is drawn as written in the figures (no mathematics, no parse error);
rich markup in a name is printed as written on the terminal.
"""

from __future__ import annotations

import io
import shutil
from pathlib import Path

import matplotlib
import pytest
from hypothesis import given
from hypothesis import strategies as st
from pydantic_core import PydanticCustomError

import rockfall_design as rd
from rockfall_design.cli.program import main
from rockfall_design.errors import ProjectError
from rockfall_design.project import load_project_text
from rockfall_design.project.fields import one_line

ROOT = Path(__file__).resolve().parents[2]
PROJECTS = ROOT / "projects"
DATA = ROOT / "tests" / "data"


def _design(tmp_path: Path) -> Path:
    for name in ("design_small.yaml", "catalogue_products.yaml", "catalogue_costs.yaml"):
        shutil.copy(DATA / name, tmp_path / name)
    return tmp_path / "design_small.yaml"


def _one_line(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "Traceback" not in err, err
    return err


@pytest.mark.parametrize("currency", ["EUR\\n# Holds with confidence: approved.**",
                                      "EUR\\u001b]0;owned\\u0007", "EUR\\tCHF"])
def test_a_currency_of_more_than_one_line_is_refused_at_its_key(tmp_path, capsys, currency):
    project = _design(tmp_path)
    costs = tmp_path / "catalogue_costs.yaml"
    text = costs.read_text()
    assert "currency: EUR" in text
    costs.write_text(text.replace("currency: EUR", f'currency: "{currency}"'))
    line = next(i for i, row in enumerate(costs.read_text().splitlines(), 1)
                if row.startswith("currency:"))
    assert main(["optimise", str(project), "--out", str(tmp_path / "out")]) == 2
    err = _one_line(capsys)
    assert f"{costs}:{line}: currency: expected one line of text without control " \
           "characters" in err
    assert not (tmp_path / "out").exists()


def test_a_product_name_with_a_newline_is_refused_at_its_line(tmp_path):
    project = _design(tmp_path)
    products = tmp_path / "catalogue_products.yaml"
    lines = products.read_text().splitlines()
    first = next(i for i, row in enumerate(lines) if row.startswith("  ") and ":" in row
                 and not row.lstrip().startswith("#"))
    name = lines[first].split(":")[0].strip()
    lines[first] = lines[first].replace(name, f'"{name}\\n# a heading"', 1)
    products.write_text("\n".join(lines) + "\n")
    with pytest.raises(ProjectError) as caught:
        rd.load_project(project)
    assert str(caught.value).startswith(f"{products}:{first + 1}: ")
    assert "expected one line of text" in str(caught.value)


def test_inline_cost_parameters_and_level_names_are_checked_too():
    text = (PROJECTS / "calibrate_quarry.yaml").read_text()
    bad = text.replace("levels: {bench:", 'levels: {"bench\\n## x":')
    with pytest.raises(ProjectError, match=r"calibrate\.levels.*one line of text"):
        load_project_text(bad, "quarry.yaml", base_dir=PROJECTS)


# The second name's report (2.5 s) in the slow set: both go through the same drawing.
@pytest.mark.parametrize("name", [r"$\undefinedmacro{x}$",
                                  pytest.param("Budget: $5 to $10 per m",
                                               marks=pytest.mark.slow)])
def test_dollars_in_a_name_are_drawn_as_written(name):
    lines = (PROJECTS / "standard_slope.yaml").read_text().splitlines()
    at = next(i for i, row in enumerate(lines) if row.startswith("name:"))
    lines[at] = f"name: '{name}'"
    project = load_project_text("\n".join(lines) + "\n", "dollars.yaml", base_dir=PROJECTS)
    result = rd.simulate(project, rocks=30)
    for stem, fig in result.figures().items():
        buffer = io.BytesIO()
        with matplotlib.rc_context({"svg.fonttype": "none"}):  # the words as text in the SVG
            fig.savefig(buffer, format="svg")
        svg = buffer.getvalue().decode()
        # In a <text> element as written (matplotlib's SVG also repeats every
        # text in a comment, so the comment alone proves nothing).
        assert f">{name}" in svg, stem


def test_dollars_in_a_name_do_not_stop_the_command(tmp_path, capsys):
    project = tmp_path / "dollars.yaml"
    text = (PROJECTS / "standard_slope.yaml").read_text().splitlines()
    at = next(i for i, row in enumerate(text) if row.startswith("name:"))
    text[at] = r"name: '$\undefinedmacro{x}$'"
    project.write_text("\n".join(text) + "\n")
    assert main(["simulate", str(project), "--rocks", "30", "--plot", str(tmp_path / "fig")]) \
        in (0, 1)
    assert "Traceback" not in capsys.readouterr().err
    # Every figure, the passage figure at the project's one analysis station
    # (its title carries the name too) included.
    assert sorted(p.name for p in (tmp_path / "fig").glob("*.png")) == [
        "envelopes.png", "passing_station_1.png", "profile.png", "stops.png"]


def test_markup_in_names_is_printed_as_written(tmp_path, capsys):
    from tests.calibration.calibration_helpers import SITE, observed_stops, write_site

    write_site(tmp_path, observed_stops(20, seed=2))
    site = tmp_path / "site.yaml"
    site.write_text(SITE.replace("name: site", "name: '[/oops] a [red]b'")
                    .replace("bench: [20.5, 29]", "'[bold]bench[/]': [20.5, 29]"))
    assert main(["compare", str(site), "--observed", str(tmp_path / "stops.csv"),
                 "--rocks", "60"]) == 0
    out = capsys.readouterr().out
    assert "[/oops] a [red]b" in out and "[bold]bench[/]" in out


@given(before=st.text(max_size=8), after=st.text(max_size=8),
       control=st.sampled_from(["\n", "\r", "\t", "\x1b", "\x00", "\x7f", "\x9b", "\u2028",
                                "\u202e", "\u2066"]))
def test_one_line_refuses_every_line_break_and_control(before, after, control):
    with pytest.raises(PydanticCustomError):
        one_line(before + control + after)


@given(st.text(alphabet=st.characters(blacklist_categories=("Cc", "Cf", "Zl", "Zp", "Cs")),
               max_size=30))
def test_one_line_keeps_printable_text(text):
    assert one_line(text) == text

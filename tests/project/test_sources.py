"""Slope sections from survey files (CSV, DXF) and materials from a library file."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rockfall_design.cli.program import main
from rockfall_design.errors import ProjectError
from rockfall_design.project import dump_yaml, load_project, load_project_text

ROOT = Path(__file__).resolve().parents[2]

SECTION_CSV = """\
# surveyed 2026-05-04, chainage from the crest
x,y,material
0,100,rock
30,60,rock
60,30,talus

80,20,talus
120,15,talus
200,12,
"""

PROJECT = """\
name: Survey
slope:
  csv: section.csv
materials:
  rock: {restitution: 0.5, friction: 0.5}
  talus: {restitution: 0.35, friction: 0.58}
rocks:
  radius: 0.5
  release: {x: 1}
"""

LIBRARY = """\
# shared materials
rock:
  restitution: 0.5
  friction: 0.5
talus:
  restitution: 0.35
  friction: 0.58
  rolling_resistance: 0.3
meadow: {restitution: 0.25, friction: 0.6}
"""

LIBRARY_PROJECT = """\
name: Library
slope:
  points: [[0, 100], [30, 60], [60, 30], [200, 12]]
  materials: [rock, talus, meadow]
materials:
  library: lib/materials.yaml
  talus: {restitution: 0.3, friction: 0.7}
  turf: {restitution: 0.2, friction: 0.7}
rocks:
  radius: 0.5
  release: {x: 1}
"""


def write(tmp_path: Path, project: str = PROJECT, csv: str | None = SECTION_CSV,
          library: str | None = None) -> Path:
    if csv is not None:
        (tmp_path / "section.csv").write_text(csv, encoding="utf-8")
    if library is not None:
        (tmp_path / "lib").mkdir(exist_ok=True)
        (tmp_path / "lib" / "materials.yaml").write_text(library, encoding="utf-8")
    path = tmp_path / "project.yaml"
    path.write_text(project, encoding="utf-8")
    return path


def error_of(path: Path) -> ProjectError:
    with pytest.raises(ProjectError) as info:
        load_project(path)
    text = str(info.value)
    assert "\n" not in text and "Traceback" not in text
    return info.value


def line_of(text: str, needle: str) -> int:
    """1-based line of the first line holding ``needle``."""
    return next(i for i, row in enumerate(text.splitlines(), 1) if needle in row)


# ---- CSV -----------------------------------------------------------------------------


def test_csv_section_with_a_material_column(tmp_path):
    project = load_project(write(tmp_path))
    assert project.slope.points == [(0, 100), (30, 60), (60, 30), (80, 20), (120, 15),
                                    (200, 12)]
    # the material of a row is that of the segment starting there; the last row starts none
    assert project.slope.materials == ["rock", "rock", "talus", "talus", "talus"]


def test_csv_is_relative_to_the_project_file_not_the_working_directory(tmp_path,
                                                                       monkeypatch):
    path = write(tmp_path)
    monkeypatch.chdir(ROOT)
    assert load_project(path).slope.n_segments == 5


@pytest.mark.parametrize("materials, expected", [
    ("talus", ["talus"] * 5),
    ("[rock, rock, talus, talus, talus]", ["rock", "rock", "talus", "talus", "talus"]),
])
def test_csv_without_a_material_column_takes_slope_materials(tmp_path, materials, expected):
    csv = "X, Y\n0,100\n30,60\n60,30\n80,20\n120,15\n200,12\n"  # names ignore case and blanks
    text = PROJECT.replace("  csv: section.csv", f"  csv: section.csv\n  materials: {materials}")
    assert load_project(write(tmp_path, text, csv)).slope.materials == expected


def test_csv_with_a_byte_order_mark_and_windows_line_ends(tmp_path):
    csv = "\ufeffx,y,material\r\n0,10,rock\r\n10,0,\r\n"
    path = write(tmp_path, csv=None)
    (tmp_path / "section.csv").write_bytes(csv.encode("utf-8"))
    assert load_project(path).slope.points == [(0, 10), (10, 0)]


def test_csv_section_is_inline_in_the_resolved_project(tmp_path):
    project = load_project(write(tmp_path))
    resolved = project.resolved_dict()
    assert resolved["slope"]["points"][1] == [30.0, 60.0]
    # the run record is self-contained: it loads without the CSV beside it
    again = load_project_text(dump_yaml(resolved), "elsewhere/summary.json (run.project)")
    assert again.resolved_hash() == project.resolved_hash()


@pytest.mark.parametrize("old, new, needle, key, fragment", [
    ("60,30,talus", "60,3O,talus", "60,3O", "y", "expected a number"),
    ("60,30,talus", "60,nan,talus", "60,nan", "y", "must be finite"),
    ("60,30,talus", ",30,talus", ",30,talus", "x", "no value"),
    ("60,30,talus", "20,30,talus", "20,30", "x",
     "x must increase strictly along the slope: x = 20 follows x = 30"),
    ("60,30,talus", "60,3e7,talus", "60,3e7", "y", "farther than 1,000,000 m"),
    ("60,30,talus", "60,30,talas", "talas", "material",
     "undefined material 'talas'; did you mean 'talus'?"),
    ("60,30,talus", "60,30,", "60,30,", "material", "no value"),
    ("60,30,talus", "60,30", "60,30", "", "expected 3 values (x, y, material), got 2"),
    ("x,y,material", "x,z,material", "x,z", "", "column 2 of the header is not a known column"),
    ("x,y,material", "x,y,materials", "x,y,materials", "",
     "column 3 of the header is not a known column; did you mean 'material'?"),
    ("x,y,material", "x;y;material", "x;y", "", "separated by commas"),
    ("x,y,material", "x,material", "x,material", "", "no column 'y'"),
    ("x,y,material", "x,y,x", "x,y,x", "", "column 'x' appears twice"),
    ("x,y,material\n", "", "0,100", "", "expected a header row"),
    ('60,30,talus', '60,"30,talus', '60,"30', "", "invalid CSV"),
])
def test_csv_errors_name_the_csv_file_line_and_column(tmp_path, old, new, needle, key,
                                                      fragment):
    csv = SECTION_CSV.replace(old, new, 1)
    err = error_of(write(tmp_path, csv=csv))
    assert err.file == str(tmp_path / "section.csv")
    assert err.line == line_of(csv, needle)
    assert err.key == key
    assert fragment in err.message


def test_csv_reports_its_earliest_problem(tmp_path):
    csv = SECTION_CSV.replace("30,60,rock", "30,60,rok").replace("80,20", "50,20")
    err = error_of(write(tmp_path, csv=csv))
    assert (err.line, err.key) == (line_of(csv, "rok"), "material")
    csv = SECTION_CSV.replace("30,60,rock", "30,60,rok").replace("30,60", "-1,60")
    err = error_of(write(tmp_path, csv=csv))
    assert (err.line, err.key) == (line_of(csv, "-1,60"), "x")


def test_csv_with_too_few_points_or_no_rows(tmp_path):
    err = error_of(write(tmp_path, csv="x,y,material\n0,10,rock\n"))
    assert str(err) == f"{tmp_path / 'section.csv'}: expected at least 2 points, got 1"
    err = error_of(write(tmp_path, csv="# nothing yet\n"))
    assert "no header row" in str(err)


@pytest.mark.parametrize("old, new, key, fragment", [
    ("  csv: section.csv", "  csv: missing.csv", "slope.csv",
     "cannot read the survey section"),
    ("  csv: section.csv", "  csv: 3", "slope.csv", "expected the file name of a survey"),
    ("  csv: section.csv", "  csv: section.csv\n  materials: rock", "slope.materials",
     "has a material column: give the materials there or here, not both"),
    ("  csv: section.csv", "  csv: section.csv\n  points: [[0, 1], [2, 0]]", "slope.points",
     "not both"),
    ("  csv: section.csv", "  csv: section.csv\n  dxf: section.dxf", "slope.dxf", "not both"),
    ("  csv: section.csv", "  csv: section.csv\n  layer: S", "slope.layer",
     "unknown key 'layer'"),
    ("  csv: section.csv", "  cvs: section.csv\n  csv: section.csv", "slope.cvs",
     "did you mean 'csv'?"),
])
def test_csv_errors_in_the_project_name_the_project_line_and_key(tmp_path, old, new, key,
                                                                  fragment):
    text = PROJECT.replace(old, new)
    err = error_of(write(tmp_path, text))
    assert err.file == str(tmp_path / "project.yaml")
    assert err.line == line_of(text, key.split(".")[1] + ":")
    assert err.key == key and fragment in err.message


def test_csv_without_any_materials(tmp_path):
    err = error_of(write(tmp_path, csv="x,y\n0,10\n10,0\n"))
    assert err.file == str(tmp_path / "project.yaml") and err.key == "slope"
    assert "no materials" in err.message


def test_csv_material_list_of_the_wrong_length_is_the_projects_error(tmp_path):
    text = PROJECT.replace("  csv: section.csv", "  csv: section.csv\n  materials: [rock]")
    err = error_of(write(tmp_path, text, "x,y\n0,10\n5,5\n10,0\n"))
    assert err.file.endswith("project.yaml") and err.key == "slope.materials"
    assert "one material name per segment (2), got 1" in err.message


def test_csv_directory_or_device_is_refused_before_reading(tmp_path):
    text = PROJECT.replace("csv: section.csv", "csv: /dev/zero")
    err = error_of(write(tmp_path, text))
    assert err.key == "slope.csv" and "not a regular file" in err.message


def test_bad_csv_on_the_command_line_is_one_line_and_exit_code_2(tmp_path, capsys):
    path = write(tmp_path, csv=SECTION_CSV.replace("60,30,talus", "60,abc,talus"))
    assert main(["simulate", str(path), "--rocks", "5"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert f"section.csv:{line_of(SECTION_CSV, '60,30')}: y: expected a number" in err


def test_bundled_survey_project_uses_the_csv_and_the_library():
    project = load_project(ROOT / "projects" / "survey_slope.yaml")
    assert project.slope.n_segments == 24
    assert {"bedrock", "talus", "meadow", "gravel", "asphalt"} <= set(project.materials)
    # inline beats the library
    assert project.materials["weathered_rock"].restitution == 0.38


# ---- materials library ---------------------------------------------------------------


def test_library_materials_with_inline_additions_and_overrides(tmp_path):
    project = load_project(write(tmp_path, LIBRARY_PROJECT, csv=None, library=LIBRARY))
    assert set(project.materials) == {"rock", "talus", "meadow", "turf"}
    assert project.materials["rock"].restitution == 0.5  # from the library
    talus = project.materials["talus"]  # inline replaces the library's talus as a whole
    assert (talus.restitution, talus.friction, talus.rolling_resistance) == (0.3, 0.7, 0.0)
    resolved = project.resolved_dict()
    assert "library" not in resolved["materials"]
    assert resolved["materials"]["meadow"]["friction"] == 0.6


def test_a_material_called_library_is_still_a_material(tmp_path):
    text = LIBRARY_PROJECT.replace("library: lib/materials.yaml",
                                   "library: {restitution: 0.4, friction: 0.5}")
    text = text.replace("[rock, talus, meadow]", "[library, talus, turf]")
    project = load_project(write(tmp_path, text, csv=None))
    assert project.materials["library"].restitution == 0.4


@pytest.mark.parametrize("old, new, needle, key, fragment", [
    ("  restitution: 0.35", "  restitution: 1.35", "1.35", "talus.restitution",
     "expected a number <= 1"),
    ("  friction: 0.58", "  fricton: 0.58", "fricton", "talus.fricton",
     "did you mean 'friction'?"),
    ("  friction: 0.58\n", "", "talus:", "talus.friction", "required key is missing"),
    ("meadow: {restitution: 0.25, friction: 0.6}", "meadow: 0.25", "meadow:", "meadow",
     "expected a mapping"),
    ("meadow: {", "7: {", "7: {", "", "material names must be text, got a number"),
])
def test_library_errors_name_the_library_file_line_and_key(tmp_path, old, new, needle, key,
                                                           fragment):
    library = LIBRARY.replace(old, new)
    err = error_of(write(tmp_path, LIBRARY_PROJECT, csv=None, library=library))
    assert err.file == str(tmp_path / "lib" / "materials.yaml")
    assert err.line == line_of(library, needle)
    assert err.key == key and fragment in err.message


@pytest.mark.parametrize("library, fragment", [
    ("", "the materials library is empty"),
    ("{}", "the materials library is empty"),
    ("- rock\n- talus\n", "expected a mapping of material names to materials"),
    ("rock: [1\n", "invalid YAML"),
])
def test_library_that_is_not_a_library(tmp_path, library, fragment):
    err = error_of(write(tmp_path, LIBRARY_PROJECT, csv=None, library=library))
    assert err.file.endswith("materials.yaml") and fragment in err.message


@pytest.mark.parametrize("new, fragment", [
    ("library: lib/nothing.yaml", "cannot read the materials library"),
    ("library: 12", "expected the file name of a materials library, got 12"),
])
def test_library_reference_errors_name_the_project_line(tmp_path, new, fragment):
    text = LIBRARY_PROJECT.replace("library: lib/materials.yaml", new)
    err = error_of(write(tmp_path, text, csv=None, library=LIBRARY))
    assert err.file.endswith("project.yaml") and err.key == "materials.library"
    assert err.line == line_of(text, "library:") and fragment in err.message


def test_undefined_material_suggests_library_names(tmp_path):
    text = LIBRARY_PROJECT.replace("[rock, talus, meadow]", "[rock, talus, medow]")
    err = error_of(write(tmp_path, text, csv=None, library=LIBRARY))
    assert err.key == "slope.materials[2]" and "did you mean 'meadow'?" in err.message


def test_csv_material_names_are_checked_against_the_library(tmp_path):
    text = PROJECT.replace(
        "  rock: {restitution: 0.5, friction: 0.5}\n  talus: {restitution: 0.35, friction: 0.58}",
        "  library: lib/materials.yaml")
    csv = SECTION_CSV.replace("120,15,talus", "120,15,meado")
    err = error_of(write(tmp_path, text, csv=csv, library=LIBRARY))
    assert err.file.endswith("section.csv") and err.line == line_of(csv, "meado")
    assert "did you mean 'meadow'?" in err.message


# ---- DXF -----------------------------------------------------------------------------

DXF_PROJECT = """\
name: Drawing
slope: {dxf: section.dxf, layer: SECTION, materials: talus}
materials:
  talus: {restitution: 0.35, friction: 0.58}
rocks:
  radius: 0.5
  release: {x: 1}
"""

POINTS = [(0, 100), (30, 60), (60, 30), (80, 20), (120, 15), (200, 12)]


def dxf_project(tmp_path: Path, *polylines: tuple, units: int = 6,
                text: str = DXF_PROJECT) -> Path:
    """A drawing with ``(kind, layer, points, options)`` polylines, and a project on it."""
    ezdxf = pytest.importorskip("ezdxf", reason="ezdxf (the [dxf] extra) is not installed")
    doc = ezdxf.new()
    doc.header["$INSUNITS"] = units
    msp = doc.modelspace()
    msp.add_line((0, 0), (5, 5), dxfattribs={"layer": "SECTION"})  # not a polyline: ignored
    for kind, layer, points, options in polylines:
        if kind == "lw":
            msp.add_lwpolyline(points, format=options.get("format", "xy"),
                               close=options.get("close", False), dxfattribs={"layer": layer})
        elif kind == "2d":
            msp.add_polyline2d(points, dxfattribs={"layer": layer})
        else:
            msp.add_polyline3d(points, dxfattribs={"layer": layer})
    doc.saveas(tmp_path / "section.dxf")
    path = tmp_path / "project.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def test_dxf_lwpolyline_on_a_layer(tmp_path):
    path = dxf_project(tmp_path, ("lw", "Section", POINTS, {}), ("lw", "GRID", [(0, 0), (9, 9)],
                                                                 {}))
    project = load_project(path)  # layer names ignore case, as in CAD programs
    assert project.slope.points == POINTS
    assert project.slope.materials == ["talus"] * 5


def test_dxf_polyline_drawn_from_the_toe_up_and_old_style_polylines(tmp_path):
    path = dxf_project(tmp_path, ("2d", "SECTION", POINTS[::-1], {}))
    assert load_project(path).slope.points == POINTS
    flat = [(x, y, 0.0) for x, y in POINTS]
    path = dxf_project(tmp_path, ("3d", "SECTION", flat, {}))
    assert load_project(path).slope.points == POINTS


@pytest.mark.parametrize("polylines, key, fragment", [
    ([("lw", "GROUND_LINE", POINTS, {})], "",
     "no polyline on layer 'SECTION'; layers with polylines: GROUND_LINE"),
    ([("lw", "SECTON", POINTS, {})], "", "did you mean 'SECTON'?"),
    ([("lw", "SECTION", POINTS, {}), ("lw", "SECTION", POINTS, {})], "layer SECTION",
     "2 polylines; expected one"),
    ([("lw", "SECTION", POINTS, {"close": True})], "layer SECTION", "closed"),
    ([("lw", "SECTION", [(0, 100, 0.5), (30, 60, 0), (200, 12, 0)], {"format": "xyb"})],
     "layer SECTION, vertex 1", "arc segment"),
    ([("3d", "SECTION", [(0, 100, 0), (30, 60, 4), (200, 12, 0)], {})], "layer SECTION",
     "not in the x-y plane"),
    ([("lw", "SECTION", [(0, 100), (30, 60), (20, 30), (200, 12)], {})],
     "layer SECTION, vertex 3", "x must increase strictly along the slope: x = 20 follows x = 30"),
])
def test_dxf_errors_name_the_drawing_layer_and_vertex(tmp_path, polylines, key, fragment):
    err = error_of(dxf_project(tmp_path, *polylines))
    assert err.file == str(tmp_path / "section.dxf") and err.line is None
    assert err.key == key and fragment in err.message


def test_dxf_in_millimetres_is_refused(tmp_path):
    err = error_of(dxf_project(tmp_path, ("lw", "SECTION", POINTS, {}), units=4))
    assert err.key == "$INSUNITS" and "millimeters" in err.message.lower()
    assert "metres" in err.message


@pytest.mark.parametrize("old, new, key, fragment", [
    ("layer: SECTION, ", "", "slope.layer", "required key is missing"),
    (", materials: talus", "", "slope", "no materials for the section"),
    ("materials: talus", "materials: [talus, talus]", "slope.materials",
     "one material name per segment (5), got 2"),
    ("dxf: section.dxf", "dxf: nothing.dxf", "slope.dxf", "cannot read the drawing"),
])
def test_dxf_errors_in_the_project(tmp_path, old, new, key, fragment):
    path = dxf_project(tmp_path, ("lw", "SECTION", POINTS, {}),
                       text=DXF_PROJECT.replace(old, new))
    err = error_of(path)
    assert err.file == str(path) and err.line == 2
    assert err.key == key and fragment in err.message


def test_a_file_that_is_not_a_dxf_drawing(tmp_path):
    pytest.importorskip("ezdxf", reason="ezdxf (the [dxf] extra) is not installed")
    (tmp_path / "section.dxf").write_text("x,y\n0,1\n")
    path = tmp_path / "project.yaml"
    path.write_text(DXF_PROJECT)
    err = error_of(path)
    assert err.file.endswith("section.dxf") and "not a readable DXF drawing" in err.message


def test_without_ezdxf_the_message_names_the_extra(tmp_path, monkeypatch):
    # A None entry in sys.modules makes "import ezdxf" raise ImportError.
    monkeypatch.setitem(sys.modules, "ezdxf", None)
    path = tmp_path / "project.yaml"
    path.write_text(DXF_PROJECT)
    err = error_of(path)
    assert err.key == "slope.dxf" and "[dxf]" in err.message and "ezdxf" in err.message


# ---- hostile files: an error line, never a traceback ---------------------------------

_CELL = st.one_of(st.sampled_from(["0", "1e3", "-5", "nan", "inf", "", " ", "x", "y",
                                   "material", "talus", "rock", "#", '"', "1_0", "1,5"]),
                  st.text(max_size=6))
_CSV_TEXT = st.one_of(
    st.text(max_size=200),
    st.lists(st.lists(_CELL, max_size=4).map(",".join), max_size=8).map("\n".join),
)


@settings(max_examples=150, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(text=_CSV_TEXT)
def test_any_csv_text_loads_or_fails_in_one_line(tmp_path, text):
    path = write(tmp_path, csv=None)
    (tmp_path / "section.csv").write_text(text, encoding="utf-8", errors="surrogatepass")
    try:
        load_project(path)
    except ProjectError as exc:
        assert "\n" not in str(exc)


@settings(max_examples=100, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(text=st.one_of(st.text(max_size=120), st.sampled_from([
    "rock: 1", "rock: [1, 2]", "rock: {restitution: .nan, friction: 1}", "? [a]\n: 1",
    "a: &x {b: *x}", "rock: !!python/object:os.system {}", "- 1", "1", "null", "''",
])))
def test_any_library_text_loads_or_fails_in_one_line(tmp_path, text):
    path = write(tmp_path, LIBRARY_PROJECT, csv=None, library="{}")
    (tmp_path / "lib" / "materials.yaml").write_text(text, encoding="utf-8",
                                                     errors="surrogatepass")
    try:
        load_project(path)
    except ProjectError as exc:
        assert "\n" not in str(exc)


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.binary(max_size=300) | st.text(max_size=300).map(str.encode))
def test_any_dxf_bytes_load_or_fail_in_one_line(tmp_path, data):
    pytest.importorskip("ezdxf", reason="ezdxf (the [dxf] extra) is not installed")
    (tmp_path / "section.dxf").write_bytes(data)
    path = tmp_path / "project.yaml"
    path.write_text(DXF_PROJECT)
    try:
        load_project(path)
    except ProjectError as exc:
        assert "\n" not in str(exc)

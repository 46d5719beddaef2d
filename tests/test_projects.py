"""Every bundled example project runs as it is."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rockfall_design.cli.program import main
from rockfall_design.project import Project, load_corridor

from .plugin_helpers import install_embankment_example

# Catalogue files (products, prices) and the materials library live beside the
# projects but are not projects.
PROJECTS = sorted(
    p
    for p in (Path(__file__).resolve().parents[1] / "projects").glob("*.yaml")
    if not p.name.startswith("catalogue_") and p.name != "materials.yaml"
)


@pytest.mark.parametrize("path", PROJECTS, ids=[p.stem for p in PROJECTS])
def test_example_project_runs(path, capsys, tmp_path, monkeypatch):
    if path.name == "design_embankment.yaml":  # its candidate is the example plugin's
        install_embankment_example(tmp_path, monkeypatch)
    loaded = load_corridor(path)
    if isinstance(loaded, Project):
        projects = [loaded]
    else:  # a corridor: every section runs, the totals add them up
        projects = [s.project for s in loaded.sections]
    if any(p.measures for p in projects):
        code = main(["check", str(path), "--rocks", "30", "--json"])
        assert code in (0, 1)
    else:
        assert main(["simulate", str(path), "--rocks", "30", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    if isinstance(loaded, Project):
        assert out["rocks"] == 30
    else:
        assert out["totals"]["rocks"] == 30 * len(projects)
        assert [s["rocks"] for s in out["sections"]] == [30] * len(projects)


# ---- The materials library: every entry loads and says its law and its source ---------

LIBRARY = Path(__file__).resolve().parents[1] / "projects" / "materials.yaml"


def _library_comments() -> dict[str, list[str]]:
    """Each top-level entry of materials.yaml -> the comment lines right above it."""
    out: dict[str, list[str]] = {}
    block: list[str] = []
    for line in LIBRARY.read_text(encoding="utf-8").splitlines():
        if line.startswith("#"):
            block.append(line.lstrip("# ").strip())
        elif line and not line[0].isspace() and line.rstrip().endswith(":"):
            out[line.rstrip()[:-1]] = block
            block = []
        else:
            block = []
    return out


def test_every_library_entry_loads_in_a_project(tmp_path):
    """A project naming every entry of the library loads (the loader checks each)."""
    import yaml

    names = list(yaml.safe_load(LIBRARY.read_text(encoding="utf-8")))
    (tmp_path / "materials.yaml").write_text(LIBRARY.read_text(encoding="utf-8"),
                                             encoding="utf-8")
    n = len(names)
    points = [[10.0 * i, 10.0 * (n - i)] for i in range(n + 1)]
    project = {
        "name": "every library material",
        "slope": {"points": points, "materials": names},
        "materials": {"library": "materials.yaml"},
        "rocks": {"count": 5, "volume": 0.1, "release": {"x": 1}},
    }
    path = tmp_path / "all_materials.yaml"
    path.write_text(yaml.safe_dump(project), encoding="utf-8")
    from rockfall_design.project import load_project

    loaded = load_project(path)
    assert set(loaded.materials) >= set(names)
    # and the engine runs rocks over all of them
    assert main(["simulate", str(path), "--rocks", "5", "--json"]) == 0


def test_every_library_entry_says_its_law_and_its_source():
    """The comment above each entry names its impact law (as impact_model says)
    and a source: a published table, or ILLUSTRATIVE."""
    import yaml

    data = yaml.safe_load(LIBRARY.read_text(encoding="utf-8"))
    comments = _library_comments()
    assert set(comments) == set(data)
    for name, entry in data.items():
        law = [c.removeprefix("law:").strip() for c in comments[name] if c.startswith("law:")]
        source = [c.removeprefix("source:").strip() for c in comments[name]
                  if c.startswith("source:")]
        assert law == [entry.get("impact_model", "spang")], name
        assert len(source) == 1 and source[0], name
        published = not source[0].startswith("ILLUSTRATIVE")
        # A published source names its authors and year.
        assert not published or any(ch.isdigit() for ch in source[0]), name


def test_the_library_keeps_the_names_projects_use():
    """Bundled projects and the docs refer to these entries by name."""
    import yaml

    data = yaml.safe_load(LIBRARY.read_text(encoding="utf-8"))
    for name in ("bedrock", "weathered_rock", "talus", "meadow", "forest_floor", "gravel",
                 "asphalt", "meadow_rn_rt"):
        assert name in data


def test_the_materials_page_lists_every_entry_with_its_values():
    """docs/materials.md's table is the library's: same entries, laws and values."""
    import re

    import yaml

    data = yaml.safe_load(LIBRARY.read_text(encoding="utf-8"))
    page = (LIBRARY.parents[1] / "docs" / "materials.md").read_text(encoding="utf-8")
    rows = {}
    for line in page.splitlines():
        m = re.match(r"\| `(\w+)` \| (\w+) \| ([\d.]+) \| ([\d.]+|-) \| ([\d.]+)\*? \| ([\d.]+) \|",
                     line)
        if m:
            rows[m.group(1)] = m.groups()[1:]
    assert set(rows) == set(data)
    for name, entry in data.items():
        law, e, rt, mu, mur = rows[name]
        assert law == entry.get("impact_model", "spang"), name
        assert float(e) == entry["restitution"], name
        assert (rt == "-") == ("tangential_restitution" not in entry), name
        assert rt == "-" or float(rt) == entry["tangential_restitution"], name
        assert float(mu) == entry["friction"], name
        assert float(mur) == entry.get("rolling_resistance", 0.0), name


#: Examples whose file says they hold: each must hold with confidence at its own seed and
#: rocks, and at two fresh seeds with twice its rocks (issue 25: no example that holds
#: only at its own seed). The seeds were chosen before the design was checked with them.
HOLDING = ("quarry_fence_ditch.yaml",)
FRESH_SEEDS = (1001, 1002)


def test_the_examples_that_say_they_hold_are_the_ones_checked_here():
    said = {p.name for p in PROJECTS
            if "holds with confidence" in " ".join(
                line.lstrip("# ") for line in p.read_text().splitlines()
                if line.startswith("#"))}
    assert said == set(HOLDING)
    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    assert "passes" not in readme.split("Other bundled projects", 1)[1]


@pytest.mark.parametrize("name", HOLDING)
def test_an_example_that_says_it_holds_holds_with_confidence_at_fresh_seeds(name, capsys):
    import rockfall_design as rd

    path = Path(__file__).resolve().parents[1] / "projects" / name
    project = rd.load_project(path)
    n = project.rocks.count
    runs = [(project.rocks.seed, n)] + [(s, 2 * n) for s in FRESH_SEEDS]
    for seed, rocks in runs:
        code = main(["check", str(path), "--seed", str(seed), "--rocks", str(rocks), "--json"])
        out = json.loads(capsys.readouterr().out)
        assert out["verdict"]["state"] == "holds with confidence", (seed, rocks, out["verdict"])
        assert code == 0 and out["ok"] and out["holds_with_confidence"]


def test_the_spang_default_statistic_is_the_percentile_the_readme_advises():
    from rockfall_design_builtins.safety import SpangConcept

    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    assert "statistic: p95" in readme
    assert SpangConcept.Params().statistic == "p95"

"""Hostile but valid geometry and misbehaving plugins (hardening)."""

from __future__ import annotations

import json
import os

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings

from rockfall_design.cli.program import main
from rockfall_design.engine import EngineSettings, Material, columns
from rockfall_design.errors import strip_controls

from ..engine_helpers import one_rock, run_one, section
from ..plugin_helpers import write_distribution
from .test_project import EXAMPLE, EXAMPLE_DATA, mutated_projects

MAT = Material(restitution=0.35, friction=0.55, rolling_resistance=0.3, roughness_deg=5,
               sd_restitution=0.05, sd_friction=0.05)
NAMED = {columns.STOPPED, columns.EXIT_UPSLOPE, columns.EXIT_DOWNSLOPE, columns.UNRESOLVED}


def _ok(res, sec):
    assert set(np.unique(res.status)) <= NAMED
    stopped = res.status == columns.STOPPED
    assert np.all((res.x_end[stopped] >= sec.x[0]) & (res.x_end[stopped] <= sec.x[-1]))


def test_near_vertical_cliff_face():
    sec = section([[0, 60], [5, 58], [5.001, 10], [60, 0]], MAT)
    res = run_one(sec, one_rock(r=0.4, x=1.0, vx=2.0, rolling=True, n=50))
    _ok(res, sec)
    assert np.all(res.max_x > 5.0)  # every rock went over the cliff


def test_millimetre_segments_among_long_ones():
    pts = [[0, 30], [20, 20], [20.001, 19.9995], [20.002, 19.9992], [40, 10], [80, 8]]
    sec = section(pts, MAT)
    _ok(run_one(sec, one_rock(r=0.5, x=1.0, rolling=True, n=50)), sec)


def test_thousands_of_vertices():
    x = np.linspace(0, 200, 4001)
    y = 100 - 0.45 * x + 0.3 * np.sin(x * 3.0)  # a rough surveyed surface
    sec = section(np.column_stack([x, y]), MAT)
    res = run_one(sec, one_rock(r=0.3, x=2.0, rolling=True, n=20),
                  settings=EngineSettings(max_events=20000))
    _ok(res, sec)


def test_counter_slope_and_flat_section():
    sec = section([[0, 20], [30, 0], [60, 0], [80, 6], [100, 6]], MAT)
    _ok(run_one(sec, one_rock(r=0.5, x=1.0, rolling=True, n=50)), sec)


def test_rock_larger_than_the_segments():
    sec = section([[0, 20], [10, 12], [10.5, 11.8], [11, 11.4], [11.5, 11.3], [40, 0]], MAT)
    res = run_one(sec, one_rock(r=3.0, x=1.0, rolling=True, n=20))
    _ok(res, sec)


@pytest.mark.parametrize("x0", [30.0, 60.0, 80.0])
def test_release_exactly_on_a_vertex(x0):
    sec = section([[0, 20], [30, 0], [60, 0], [80, 6], [100, 6]], MAT)
    res = run_one(sec, one_rock(r=0.5, x=x0, n=10))
    _ok(res, sec)
    res = run_one(sec, one_rock(r=0.5, x=x0, vx=3.0, rolling=True, n=10))
    _ok(res, sec)


# capsys is read (and so emptied) once per example, which is what the test needs.
@settings(
    max_examples=int(os.environ.get("RF_EXAMPLES", "40")),
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(mutated_projects())
def test_mutated_project_files_run_or_fail_with_one_line(tmp_path_factory, capsys, data):
    import yaml

    path = tmp_path_factory.mktemp("mut") / "p.yaml"
    path.write_text(yaml.safe_dump(data))
    try:
        code = main(["simulate", str(path), "--rocks", "3", "--json"])
    except SystemExit as exc:  # argparse-level errors are exit 2 as well
        code = exc.code
    out = capsys.readouterr()
    assert code in (0, 2), out.err
    if code == 2:
        assert out.err.count("\n") == 1 and "Traceback" not in out.err
        # The message names the file and a key the mutation touched (or one that
        # depends on it, such as a release on a mutated slope).
        err = _project_error(path)
        assert err is not None and str(err) in out.err, out.err
        assert err.file == str(path) and err.line is not None, out.err
        # As the message shows them: one line, without control characters.
        mutated = [" ".join(strip_controls(k).split()) for k in _mutated_keys(EXAMPLE_DATA, data)]
        assert any(_related(err.key, key) for key in mutated), (err.key, mutated)
    else:
        assert json.loads(out.out)["rocks"] == 3


#: Keys whose errors a mutation elsewhere may cause: the section's extent
#: places the releases, stations and protection; a point's x orders it among
#: its neighbours (a point moved onto the next one's x is reported at the next);
#: the materials name the slope's.
_DEPENDS = {"slope": ("rocks.release", "analysis.stations", "protect.x", "slope.points"),
            "materials": ("slope.materials",), "rocks": ("rocks",)}


def _key(path: tuple) -> str:
    return "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in path).lstrip(".")


def _mutated_keys(base, data, path: tuple = ()) -> list[str]:
    """Key paths where ``data`` differs from ``base`` (deleted, replaced or changed)."""
    if isinstance(base, dict) and isinstance(data, dict):
        keys = [k for k in base if k not in data] + [k for k in data if k not in base]
        out = [_key(path + (k,)) for k in keys]
        for k in base.keys() & data.keys():
            out += _mutated_keys(base[k], data[k], path + (k,))
        return out
    if isinstance(base, list) and isinstance(data, list) and len(base) == len(data):
        return [k for i, (b, d) in enumerate(zip(base, data, strict=True))
                for k in _mutated_keys(b, d, path + (i,))]
    same = type(base) is type(data) and base == data
    return [] if same else [_key(path)]


def _related(error_key: str, mutated: str) -> bool:
    def under(a: str, b: str) -> bool:  # a is b or inside it
        return a == b or a.startswith(b + ".") or a.startswith(b + "[")

    top = mutated.split(".")[0].split("[")[0]
    return (under(error_key, mutated) or under(mutated, error_key)
            or any(under(error_key, dep) for dep in _DEPENDS.get(top, ())))


def test_a_point_moved_onto_its_neighbour_is_reported_at_a_related_key(tmp_path, capsys):
    # Found by the test above: x of point 1 set to point 2's, reported at point 2.
    import copy

    import yaml

    data = copy.deepcopy(EXAMPLE_DATA)
    data["slope"]["points"][1][0] = data["slope"]["points"][2][0]
    path = tmp_path / "p.yaml"
    path.write_text(yaml.safe_dump(data))
    assert main(["simulate", str(path), "--rocks", "3", "--json"]) == 2
    err = _project_error(path)
    assert err is not None and err.key.startswith("slope.points")
    assert str(err) in capsys.readouterr().err
    assert any(_related(err.key, key) for key in _mutated_keys(EXAMPLE_DATA, data))


def _project_error(path):
    """The error the loader and the whole-file validation give for ``path``, if any."""
    from rockfall_design.api import validate_project
    from rockfall_design.errors import ProjectError
    from rockfall_design.plugins import default_registry
    from rockfall_design.project import load_project

    try:
        validate_project(load_project(path), default_registry())
    except ProjectError as err:
        return err
    return None


RAISING = '''
from rockfall_design import (Barrier, BarrierBehaviour, MeasureParams, ProtectiveMeasure,
                             hookimpl)


class BadParams(MeasureParams):
    height: float = 2.0


class Bad(ProtectiveMeasure):
    kind = "bad_net"
    Params = BadParams
    example = {"x": 10.0}

    def footprint(self, section):
        raise ZeroDivisionError("oops in the plugin")

    def design_properties(self):
        return {"height_m": self.params.height}


@hookimpl
def rockfall_design_measures():
    return [Bad]
'''


def test_a_plugin_that_raises_is_named_and_stops_the_run_with_exit_3(tmp_path, monkeypatch,
                                                                      capsys):
    write_distribution(tmp_path, "bad_plugin", RAISING, "bad")
    monkeypatch.syspath_prepend(str(tmp_path))
    p = tmp_path / "p.yaml"
    p.write_text(EXAMPLE + "measures:\n  - {type: bad_net, x: 70}\n")
    assert main(["check", str(p), "--rocks", "5"]) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "bad_net" in err and "oops in the plugin" in err


@pytest.mark.parametrize("streamed", [False, True])
def test_an_unresolved_path_counts_as_reaching_the_protected_zone(streamed, tmp_path, capsys,
                                                                  monkeypatch):
    """A path cut off by the event limit is no evidence that the rock stopped short."""
    from rockfall_design.run import simulation

    from .test_bad_input import STANDARD

    if streamed:
        monkeypatch.setattr(simulation, "EXACT_ROCKS", 20)
    path = tmp_path / "p.yaml"
    # Ten events end most paths high on the slope, far from the road at x = 150 m.
    path.write_text(STANDARD.replace("protect:\n", "engine: {max_events: 10}\nprotect:\n"))
    out = tmp_path / "out"
    assert main(["simulate", str(path), "--rocks", "50", "--json", "--out", str(out)]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["statistics"]["method"] == ("histograms" if streamed else "exact")
    rocks = pd.read_csv(out / "rocks.csv")
    unresolved = rocks.end == "unresolved"
    short = unresolved & (rocks.max_x_m < 150.0)
    assert s["stops"]["unresolved"] == unresolved.sum() and short.sum() > 25
    assert s["protect"]["unresolved"] == short.sum()
    assert s["protect"]["reaching"] == ((rocks.max_x_m >= 150.0) | unresolved).sum()


def test_check_fails_a_design_whose_rocks_are_unresolved(tmp_path, capsys):
    """`check` never passes a design on paths that did not end: they count as reaching."""
    from .test_bad_input import STANDARD, with_measures

    text = STANDARD.replace(*with_measures("{type: fence, x: 100, height: 12, capacity_kj: 1e5}"))
    path = tmp_path / "p.yaml"
    path.write_text(text.replace("protect:\n", "engine: {max_events: 10}\nprotect:\n"))
    assert main(["check", str(path), "--rocks", "40", "--json"]) == 1
    s = json.loads(capsys.readouterr().out)
    assert s["protect"]["unresolved"] > 0 and not s["ok"]
    assert any("unresolved paths, counted as reaching" in f for f in s["failures"])
    # With enough events the same fence holds every rock.
    path.write_text(text)
    assert main(["check", str(path), "--rocks", "40", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["protect"]["unresolved"] == 0


def test_repeat_reads_back_names_that_look_like_numbers(tmp_path, capsys):
    """A material named '1e3' is written back quoted, so --repeat reads the same project."""
    from .test_bad_input import STANDARD

    text = STANDARD.replace("  talus:\n", "  '1e3':\n").replace("materials: talus ",
                                                                 "materials: '1e3' ")
    path = tmp_path / "p.yaml"
    path.write_text(text)
    out = tmp_path / "out"
    assert main(["simulate", str(path), "--rocks", "30", "--out", str(out), "--json"]) == 0
    first = json.loads(capsys.readouterr().out)
    assert main(["simulate", "--repeat", str(out / "summary.json"), "--json"]) == 0
    captured = capsys.readouterr()
    assert "identical" in captured.err, captured.err
    again = json.loads(captured.out)
    assert again["project_hash"] == first["project_hash"]

"""Observation files and the calibrate: section: each problem one line, exit 2."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from rockfall_design.calibration.distances import (
    distance,
    level_shares,
    objective,
    stop_positions,
    wilson_interval,
)
from rockfall_design.calibration.observations import parse_observations, size_distribution
from rockfall_design.cli.program import main
from rockfall_design.errors import ProjectError

from .calibration_helpers import SITE

GOOD = "x,volume_m3\n" + "".join(f"{40 + i},{0.1 + 0.05 * i}\n" for i in range(8))


@pytest.mark.parametrize(("text", "where"), [
    ("", "stops.csv:1: the file of observed stops is empty"),
    ("x\n", "stops.csv:1: x: only 0 observed block(s)"),
    ("x\n50\n", "stops.csv:2: x: only 1 observed block(s): a calibration needs at least 5"),
    ("x\n50\n51\nabc\n52\n53\n", "stops.csv:4: x: expected a number, got 'abc'"),
    ("x\n50\n51\n52\n\n53\n200\n", "stops.csv:7: x: stop x 200 is outside the slope section "
     "[0, 107] m"),
    ("station,mass\n50,1\n", "stops.csv:1: x: no column 'x' (the stop station of each block, m) "
     "in the header row (station, mass)"),
    ("X\n50\n", "did you mean 'X'?"),
    ("x\n50\nnan\n", "stops.csv:3: x: expected a finite number, got nan"),
    ("x,volume_m3\n50,0.2\n51,-1\n", "stops.csv:3: volume_m3: expected a size > 0, got -1"),
    ("x,volume_m3,mass_kg\n50,1,2\n", "stops.csv:1: mass_kg: give only one of volume_m3 and "
     "mass_kg"),
    ("x,volume_m3\n50\n", "stops.csv:2: expected 2 cells as in the header row, got 1"),
])
def test_a_bad_file_is_one_line_at_its_line_and_column(text, where):
    with pytest.raises(ProjectError) as err:
        parse_observations(text, "stops.csv", (0.0, 107.0))
    assert where in str(err.value)
    assert "\n" not in str(err.value)


def test_a_good_file_and_its_sizes():
    obs = parse_observations(GOOD, "stops.csv", (0.0, 107.0))
    assert obs.n == 8 and obs.size_key == "volume"
    assert_allclose(obs.x, 40 + np.arange(8))
    (key, spec), = size_distribution(obs).items()
    assert key == "volume"
    median, sigma = spec["lognormal"]
    assert_allclose(median, np.exp(np.log(obs.size).mean()))
    assert_allclose(sigma, np.log(obs.size).std())


@pytest.mark.parametrize(("text", "message"), [
    ("", "is empty"),
    ("x\n50\n", "only 1 observed block"),
    ("x\n50\n51\nabc\n52\n53\n", "expected a number, got 'abc'"),
    ("x\n50\n51\n52\n53\n200\n", "outside the slope section"),
    ("station\n50\n", "no column 'x'"),
])
def test_the_command_exits_2_with_one_line(tmp_path, capsys, text, message):
    (tmp_path / "site.yaml").write_text(SITE)
    (tmp_path / "stops.csv").write_text(text)
    assert main(["calibrate", str(tmp_path / "site.yaml"), "--bootstrap", "0"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "Traceback" not in err
    assert f"{tmp_path / 'stops.csv'}:" in err and message in err


@pytest.mark.parametrize(("section", "message"), [
    ("  fit: {materials.soil.restitution: [0.7, 0.05]}\n",
     "calibrate.fit.materials.soil.restitution: expected [lo, hi] with lo < hi"),
    ("  fit: {materials.soil.restitution: [0.05, 1.5]}\n",
     "calibrate.fit.materials.soil.restitution: value 1.5: materials.soil.restitution: "),
    ("  fit: {materials.sand.restitution: [0.05, 0.5]}\n",
     "calibrate.fit.materials.sand.restitution: not an input of the project: no key 'sand'"),
    ("  fit: {}\n", "calibrate.fit: "),
    ("  fit: {materials.soil.restitution: [0.05, 0.5]}\n  levels: {a: [20, 40], b: [30, 50]}\n",
     "calibrate.levels.b: level 'b' overlaps level 'a'"),
    ("  fit: {materials.soil.restitution: [0.05, 0.5]}\n  levels: {a: [200, 300]}\n",
     "calibrate.levels.a: level [200, 300] lies outside the slope section"),
    ("  fit: {materials.soil.restitution: [0.05, 0.5]}\n  bootstrp: 3\n",
     "calibrate.bootstrp: unknown key"),
])
def test_a_bad_section_is_one_line_at_its_key(tmp_path, capsys, section, message):
    text = SITE.split("  fit:")[0] + section
    (tmp_path / "site.yaml").write_text(text)
    (tmp_path / "stops.csv").write_text(GOOD)
    assert main(["calibrate", str(tmp_path / "site.yaml"), "--bootstrap", "0"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and message in err, err


def test_no_section_is_one_line(tmp_path, capsys):
    (tmp_path / "site.yaml").write_text(SITE.split("calibrate:")[0])
    assert main(["calibrate", str(tmp_path / "site.yaml")]) == 2
    assert "no calibrate: section" in capsys.readouterr().err


# ---- the statistics, against closed forms -------------------------------------------------


def test_energy_distance_closed_form():
    # Two point masses a apart: F - G = 1 over a length a, so sqrt(2 a).
    assert_allclose(distance(np.zeros(3), np.full(5, 4.0)), np.sqrt(8.0))
    assert distance(np.arange(5.0), np.arange(5.0)) == 0.0
    assert_allclose(distance(np.zeros(3), np.full(5, 4.0), "wasserstein"), 4.0)
    # The objective: d**2 / L with L the IQR (10 m here), plus the shares. Shifted by
    # 1 m, F - G = 0.5 on two stretches of 1 m: d**2 = 2 * (0.25 + 0.25) = 1.
    obs = np.array([0.0, 0.0, 10.0, 10.0])
    assert_allclose(objective(obs, obs + 1.0, {}), 1.0 / 10.0)
    assert_allclose(objective(obs, obs, {"low": (-1.0, 5.0)}), 0.0)


def test_wilson_interval_published_value():
    # Wilson (1927) score interval of 20 of 41 at 95 %: 0.3395..0.6425 (closed form).
    z = 1.959963984540054
    n, p = 41, 20 / 41
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z / (1 + z * z / n) * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    assert_allclose(wilson_interval(20, 41), (centre - half, centre + half), rtol=1e-9)


def test_rocks_that_leave_count_at_the_end_and_levels_are_half_open():
    from rockfall_design.engine.columns import STOPPED

    status = np.array([STOPPED, STOPPED + 1, STOPPED])
    x = stop_positions(np.array([30.0, 120.0, 41.0]), status, (0.0, 107.0))
    assert_allclose(x, [30.0, 107.0, 41.0])
    shares = level_shares(np.array([30.0, 41.0, 50.0, 60.0]), x,
                          {"bench": (20.0, 41.0), "floor": (41.0, 107.0)})
    assert [s.observed_count for s in shares] == [1, 3]
    assert_allclose([s.simulated_share for s in shares], [1 / 3, 1 / 3])


def test_path_of_the_observations_is_relative_to_the_project(tmp_path):
    from rockfall_design.calibration.observations import observed_file
    from rockfall_design.project import load_project

    (tmp_path / "site.yaml").write_text(SITE)
    assert observed_file(load_project(tmp_path / "site.yaml")) == Path(tmp_path / "stops.csv")


def test_deposit_points_become_stations_along_the_trace(tmp_path):
    import importlib.util
    import subprocess
    import sys

    script = Path(__file__).resolve().parents[2] / "examples" / "stops_from_points.py"
    spec = importlib.util.spec_from_file_location("stops_from_points", script)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    # An L-shaped trace: 30 m east, then 40 m north.
    trace = np.array([[0.0, 0.0], [30.0, 0.0], [30.0, 40.0]])
    x, d = module.stations(np.array([[10.0, 2.0], [31.0, 20.0], [50.0, 45.0]]), trace)
    assert_allclose(x, [10.0, 50.0, 70.0])
    assert_allclose(d, [2.0, 1.0, np.hypot(20.0, 5.0)])
    (tmp_path / "dep.csv").write_text("id,E,N,vol\n1,10,2,0.3\n2,31,20,0.5\n3,50,45,0.2\n")
    (tmp_path / "trace.csv").write_text("e,n\n0,0\n30,0\n30,40\n")
    subprocess.run([sys.executable, str(script), str(tmp_path / "dep.csv"),
                    str(tmp_path / "trace.csv"), str(tmp_path / "stops.csv"), "--e", "E",
                    "--n", "N", "--volume", "vol", "--corridor", "5"], check=True)
    assert (tmp_path / "stops.csv").read_text() == "x,volume_m3\n10.00,0.3\n50.00,0.5\n"


def test_expanded_percentile_tail():
    # Hesterberg (2015): quantiles at Phi(-sqrt(n/(n-1)) t(0.975, n-1)); to 0.025 as n grows.
    from scipy import stats

    from rockfall_design.calibration.uncertainty import expanded_tail

    z = np.sqrt(41 / 40) * stats.t.ppf(0.975, 40)
    assert_allclose(expanded_tail(0.95, 41), stats.norm.cdf(-z))
    assert 0.020 < expanded_tail(0.95, 41) < 0.021
    assert expanded_tail(0.95, 20) < expanded_tail(0.95, 41) < expanded_tail(0.95, 10**6)
    assert_allclose(expanded_tail(0.95, 10**6), 0.025, atol=1e-4)

"""The ``simulate`` command end to end: report, JSON, files, figures, errors."""

from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from numpy.testing import assert_allclose

from rockfall_design.cli.program import main

ROOT = Path(__file__).resolve().parents[2]
STANDARD = ROOT / "projects" / "standard_slope.yaml"


def run_json(capsys, *args: str) -> dict:
    code = main(["simulate", *args, "--json"])
    out = capsys.readouterr().out
    assert code == 0
    return json.loads(out)


def test_json_has_the_documented_keys(capsys):
    s = run_json(capsys, str(STANDARD), "--rocks", "200")
    # (runtime_s >= 0 alone could not fail: a duration is never negative.)
    assert s["rocks"] == 200 and s["seed"] == 42
    assert isinstance(s["runtime_s"], float) and math.isfinite(s["runtime_s"])
    assert s["version"] and len(s["project_hash"]) == 64 and s["events"] > 200
    assert set(s["stops"]) >= {"x", "out_of_section", "unresolved"}
    assert set(s["stops"]["x"]) == {"mean", "p50", "p95", "max"}
    (st,) = s["stations"]
    assert st["x"] == 80.0 and st["crossings"] == 200
    for key in ("passing_height_m", "velocity_ms", "energy_kj", "translational_energy_kj",
                "rotational_energy_kj"):
        assert set(st[key]) == {"mean", "p50", "p95", "p99", "max"}
    e = st["energy_kj"]
    assert e["p50"] <= e["p95"] <= e["p99"] <= e["max"]
    assert set(s["protect"]) == {"x", "reaching", "fraction", "unresolved"}
    assert s["protect"]["fraction"] == s["protect"]["reaching"] / 200


def test_same_seed_same_numbers_other_seed_other_numbers(capsys):
    a = run_json(capsys, str(STANDARD), "--rocks", "100", "--seed", "5")
    b = run_json(capsys, str(STANDARD), "--rocks", "100", "--seed", "5")
    c = run_json(capsys, str(STANDARD), "--rocks", "100", "--seed", "6")
    for d in (a, b, c):
        d.pop("runtime_s")
    assert a == b
    assert a["stations"] != c["stations"]


def test_out_files_agree_with_the_summary(tmp_path, capsys):
    out = tmp_path / "out"
    s = run_json(capsys, str(STANDARD), "--rocks", "150", "--out", str(out))
    rocks = pd.read_csv(out / "rocks.csv")
    cross = pd.read_csv(out / "crossings.csv")
    summary = json.loads((out / "summary.json").read_text())
    assert len(rocks) == 150 and len(cross) == 150  # one station
    assert summary["run"]["seed"] == 42 and summary["run"]["rocks"] == 150
    assert summary["run"]["project_hash"] == s["project_hash"]
    assert summary["stations"] == s["stations"]
    c = cross[cross.crossed]
    assert_allclose(c.energy_kj.max(), s["stations"][0]["energy_kj"]["max"], rtol=1e-12)
    assert_allclose(c.energy_kj, c.translational_energy_kj + c.rotational_energy_kj, rtol=1e-12)
    assert_allclose(np.percentile(c.passing_height_m, 95),
                    s["stations"][0]["passing_height_m"]["p95"], rtol=1e-12)
    assert (rocks.end == "exit_downslope").sum() == s["stops"]["out_of_section"] - (
        rocks.end == "exit_upslope").sum()
    reaching = (rocks.max_x_m >= 150).sum()
    assert reaching == s["protect"]["reaching"]


def test_plot_writes_png_figures(tmp_path, capsys):
    code = main(["simulate", str(STANDARD), "--rocks", "50", "--plot", str(tmp_path)])
    assert code == 0
    report = capsys.readouterr().out
    assert "Standard slope" in report and "Analysis stations" in report
    for name in ("profile.png", "envelopes.png", "stops.png"):
        data = (tmp_path / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000


def test_bad_project_is_one_line_exit_2(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text(STANDARD.read_text().replace("radius: 0.5", "radius: -0.5"))
    code = main(["simulate", str(bad)])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and "Traceback" not in err
    assert f"{bad}:" in err and "rocks.radius" in err


def test_missing_file_and_bad_arguments(tmp_path, capsys):
    assert main(["simulate", str(tmp_path / "nope.yaml")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "nope.yaml" in err
    with pytest.raises(SystemExit) as exc:
        main(["simulate", str(STANDARD), "--rocks", "0"])
    assert exc.value.code == 2
    assert capsys.readouterr().err.count("\n") == 1


@pytest.mark.skipif(shutil.which("rockfall-design") is None, reason="console script not installed")
def test_console_script_runs():
    proc = subprocess.run(
        ["rockfall-design", "simulate", str(STANDARD), "--rocks", "20", "--json"],
        capture_output=True, text=True, check=False,
    )
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["rocks"] == 20


def test_module_entry_point():
    proc = subprocess.run(
        [sys.executable, "-m", "rockfall_design", "--version"],
        capture_output=True, text=True, check=False, cwd=ROOT,
    )
    assert proc.returncode == 0 and "rockfall-design" in proc.stdout


def test_repeat_reproduces_a_recorded_run_exactly(tmp_path, capsys):
    out = tmp_path / "first"
    assert main(["simulate", str(ROOT / "projects" / "quarry_road.yaml"), "--rocks", "150",
                 "--seed", "31", "--out", str(out), "--json"]) == 0
    first = json.loads(capsys.readouterr().out)
    recorded = json.loads((out / "summary.json").read_text())
    assert recorded["run"]["seed"] == 31 and recorded["run"]["rocks"] == 150
    assert main(["simulate", "--repeat", str(out / "summary.json"), "--json"]) == 0
    captured = capsys.readouterr()
    again = json.loads(captured.out)
    assert "identical" in captured.err
    for s in (first, again):
        s.pop("runtime_s")
    assert again == first


def test_repeat_exits_1_when_the_results_differ(tmp_path, capsys):
    out = tmp_path / "first"
    assert main(["simulate", str(STANDARD), "--rocks", "40", "--out", str(out), "--json"]) == 0
    capsys.readouterr()
    summary = out / "summary.json"
    recorded = json.loads(summary.read_text())
    recorded["stations"][0]["crossings"] += 1  # as another version or machine might
    summary.write_text(json.dumps(recorded))
    assert main(["simulate", "--repeat", str(summary), "--json"]) == 1
    captured = capsys.readouterr()
    assert "DIFFER" in captured.err and json.loads(captured.out)["rocks"] == 40


def test_ctrl_c_right_at_exit_prints_no_traceback():
    """Once the command is over, the process exits: a Ctrl-C then changes nothing."""
    script = (
        "import os, signal, sys\n"
        "from rockfall_design.cli.program import main\n"
        "sys.argv = ['rockfall-design', 'plugins', '--json']\n"
        "code = main()\n"
        "os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C as the program ends\n"
        "sys.exit(code)\n"
    )
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=120, check=False)
    assert proc.returncode == 0 and "Traceback" not in proc.stderr, proc.stderr
    assert json.loads(proc.stdout)["measures"]


def test_a_signal_after_the_command_is_ignored():
    from rockfall_design.cli import program as cli

    cli._exiting[0] = True
    try:
        assert cli._on_signal(2, None) is None
    finally:
        cli._exiting[0] = False

"""Calibration loses nothing (issue 34 item 5; issue 36 item 7's calibration side).

Each case of the issue: ``--out .`` beside a shared materials library,
``--observed`` recorded, ``--out`` and ``--save-materials`` naming one file,
sizes outside a rock's limits, an Excel BOM, Ctrl-C, rough intervals from
few replicates, compare's verdict and values to their interval's precision.
"""

from __future__ import annotations

import _thread
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
import yaml
from hypothesis import given
from hypothesis import strategies as st

import rockfall_design as rd
import rockfall_design.api
import rockfall_design.calibration.fit as fit
from rockfall_design.calibration.uncertainty import FittedParameter, decimals, rounded
from rockfall_design.cli.program import main
from rockfall_design.report.staging import MANIFEST

from .calibration_helpers import observed_stops, write_site

ROOT = Path(__file__).resolve().parents[2]
PROJECTS = ROOT / "projects"


@pytest.fixture(autouse=True)
def _ctrl_c_raises():
    """Ctrl-C raises KeyboardInterrupt here, as in a user's terminal (see tests/cli)."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    directory = tmp_path_factory.mktemp("site")
    return write_site(directory, observed_stops(30, seed=3))


def _one_line(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "Traceback" not in err, err
    return err


def _no_work(monkeypatch) -> None:
    """Fail the test if the command gets as far as calibrating."""
    def refuse(*args, **kwargs):
        raise AssertionError("the command calibrated before it refused its outputs")
    monkeypatch.setattr(rockfall_design.api, "calibrate", refuse)


def test_out_dot_beside_the_shared_library_keeps_it(tmp_path, capsys, monkeypatch):
    # The bundled layout: projects/ holds the shared materials.yaml that other projects read.
    for name in ("calibrate_quarry.yaml", "quarry_stops_a.csv", "materials.yaml"):
        shutil.copy(PROJECTS / name, tmp_path / name)
    library = (tmp_path / "materials.yaml").read_bytes()
    _no_work(monkeypatch)
    code = main(["calibrate", str(tmp_path / "calibrate_quarry.yaml"), "--out", str(tmp_path)])
    err = _one_line(capsys)
    assert code == 2
    assert f"cannot write {tmp_path / 'materials.yaml'}: a file this program did not write" \
        in err and "nothing was written" in err
    assert (tmp_path / "materials.yaml").read_bytes() == library
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "calibrate_quarry.yaml", "materials.yaml", "quarry_stops_a.csv"]


def test_save_materials_onto_a_users_library_is_refused(site, tmp_path, capsys, monkeypatch):
    own = tmp_path / "lib.yaml"
    own.write_text("# my library\nsoil: {restitution: 0.3, friction: 0.6}\n")
    _no_work(monkeypatch)
    assert main(["calibrate", str(site), "--save-materials", str(own)]) == 2
    assert "did not write" in _one_line(capsys)
    assert own.read_text().startswith("# my library")


def test_observed_is_what_was_fitted_and_a_rerun_replaces_its_own_files(site, tmp_path,
                                                                        capsys):
    other = tmp_path / "other_stops.csv"
    other.write_text("x\n" + "".join(f"{x:.3f}\n" for x in observed_stops(25, seed=8)))
    out = tmp_path / "out"
    argv = ["calibrate", str(site), "--observed", str(other), "--bootstrap", "0",
            "--workers", "1", "--rocks", "60", "--out", str(out),
            "--save-materials", str(out / "materials.yaml")]
    assert main(argv) == 0
    data = yaml.safe_load((out / "calibrated.yaml").read_text())
    assert (out / data["calibrate"]["observed"]).resolve() == other.resolve()
    assert "other_stops.csv (25 blocks)" in (out / "calibrated.yaml").read_text()
    # --save-materials naming --out's own materials.yaml: one file, written once.
    assert sorted(p.name for p in out.iterdir() if p.name != MANIFEST) == [
        "calibrated.yaml", "materials.yaml", "parameters.csv", "replicates.csv", "summary.json"]
    # A second run into the same folder replaces what the first wrote.
    assert main(argv) == 0
    capsys.readouterr()


@pytest.mark.parametrize("name", ["summary.json", "calibrated.yaml"])
def test_save_materials_onto_another_out_file_is_one_line(site, tmp_path, capsys, monkeypatch,
                                                           name):
    _no_work(monkeypatch)
    out = tmp_path / "out"
    assert main(["calibrate", str(site), "--out", str(out), "--save-materials",
                 str(out / name)]) == 2
    err = _one_line(capsys)
    assert f"--save-materials {out / name}: another option of this command writes" in err
    assert not out.exists() or [p.name for p in out.iterdir()] == []


@pytest.mark.parametrize(("cell", "words"), [
    ("1e30", "mass_kg: 1e+30 kg is larger than the largest rock"),
    ("0.001", "mass_kg: 0.001 kg is smaller than the smallest rock"),
])
def test_masses_outside_the_rock_limits_are_refused_at_their_line(site, tmp_path, capsys,
                                                                   cell, words):
    stops = tmp_path / "masses.csv"
    rows = [f"{40 + i},{cell if i == 3 else 500}\n" for i in range(8)]
    stops.write_text("x,mass_kg\n" + "".join(rows))
    assert main(["calibrate", str(site), "--observed", str(stops), "--bootstrap", "0"]) == 2
    err = _one_line(capsys)
    assert f"{stops}:5: {words}" in err and "StopIteration" not in err


def test_a_bom_from_excel_is_read(site, tmp_path):
    stops = tmp_path / "excel.csv"
    text = "x\r\n" + "".join(f"{x:.3f}\r\n" for x in observed_stops(20, seed=4))
    stops.write_bytes(text.encode("utf-8-sig"))
    result = rd.compare(site, stops, rocks=60)
    assert result.observations.n == 20


def test_few_replicates_give_flagged_intervals(site, capsys):
    assert main(["calibrate", str(site), "--bootstrap", "2", "--workers", "1",
                 "--rocks", "60"]) == 0
    out = capsys.readouterr().out
    assert "ROUGH intervals, not 95 %" in " ".join(out.split())
    assert "rough intervals from only 2 bootstrap replicates" in " ".join(out.split())


def test_values_are_written_to_their_intervals_precision(site):
    result = rd.calibrate(site, bootstrap=4, workers=1, rocks=60)
    (p,) = result.parameters
    written = result.calibrated_data()["materials"]["soil"]["restitution"]
    assert written == rounded(p).value == round(p.value, decimals(p))
    assert len(repr(written)) <= 8 and abs(written - p.value) <= 0.5 * 10 ** -decimals(p)


def test_compare_prints_a_verdict_naming_its_test(site, capsys):
    assert main(["compare", str(site), "--observed", str(site.parent / "stops.csv"),
                 "--rocks", "200"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "verdict: consistent with the observations (two-sample Kolmogorov-Smirnov test " \
           "at 5 %: p = " in out
    assert main(["compare", str(site), "--observed", str(site.parent / "stops.csv"),
                 "--rocks", "200", "--json"]) == 0
    summary = yaml.safe_load(capsys.readouterr().out)
    assert summary["consistent"] is True and "Kolmogorov-Smirnov" in summary["verdict"]


def test_a_bad_prediction_is_not_consistent(site):
    project = rd.load_project(site)
    bouncy = project.model_copy(update={"materials": {
        **project.materials,
        "soil": project.materials["soil"].model_copy(update={"restitution": 0.7})}})
    result = rd.compare(bouncy, site.parent / "stops.csv", rocks=200)
    assert result.summary["consistent"] is False
    assert result.verdict_line.startswith("NOT consistent with the observations")


def test_ctrl_c_stops_the_replicates_under_way(site, monkeypatch):
    """An interrupt stops every replicate on the pool's threads at its next engine run.

    Before, the replicates under way ran to their ends (about 70 s on the
    bundled project) after Ctrl-C: counted here as engine runs started
    after the interrupt reached the caller, which no clock decides.
    """
    calls, after = [0], [0]
    raised = threading.Event()
    run_in_memory = fit.run_in_memory  # imported at fit's top: patched where it is called

    def counted(*args, **kwargs):
        calls[0] += 1
        if raised.is_set():
            after[0] += 1
        elif calls[0] == 12:
            # Ctrl-C as Python notes it when the kernel hands SIGINT to another
            # thread: the main thread, waiting for the replicates, must still see it.
            _thread.interrupt_main()
        return run_in_memory(*args, **kwargs)

    monkeypatch.setattr(fit, "run_in_memory", counted)
    with pytest.raises(KeyboardInterrupt):
        rd.calibrate(site, bootstrap=6, workers=2, pool="threads", rocks=60)
    raised.set()  # the calibration has given up; count what still starts
    for thread in threading.enumerate():
        if thread.name.startswith("rockfall-task"):
            thread.join()
    # At most the runs that had passed their check as the interrupt came (one per thread).
    assert after[0] <= 2, after[0]


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals sent to a process")
def test_ctrl_c_ends_a_real_calibration(tmp_path):
    out = tmp_path / "out"
    # Replicates of minutes each: waited for, they would outlast the wait below many times.
    argv = [sys.executable, "-m", "rockfall_design", "calibrate",
            str(PROJECTS / "calibrate_quarry.yaml"), "--rocks", "20000", "--workers", "2",
            "--out", str(out)]
    with open(tmp_path / "stderr", "w+") as stderr:
        proc = subprocess.Popen(argv, cwd=ROOT, stdin=subprocess.DEVNULL,
                                stdout=subprocess.DEVNULL, stderr=stderr,
                                preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        try:
            deadline = time.monotonic() + 180
            while not (out.exists() and any(out.iterdir())):  # outputs reserved: work begins
                assert proc.poll() is None, (tmp_path / "stderr").read_text()
                assert time.monotonic() < deadline
                time.sleep(0.05)
            time.sleep(2)  # into the replicates
            proc.send_signal(signal.SIGINT)
            proc.wait(timeout=120)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
    err = (tmp_path / "stderr").read_text()
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "interrupted; no files were changed" in err
    assert not out.exists() or list(out.iterdir()) == []


@given(lo=st.floats(-1e3, 1e3), width=st.floats(1e-3, 1e3), u=st.floats(0, 1),
       a=st.floats(0, 1), b=st.floats(0, 1))
def test_rounding_keeps_the_value_in_range_and_within_half_a_digit(lo, width, u, a, b):
    hi = lo + width
    value = lo + u * width
    low, high = sorted((lo + a * width, lo + b * width))
    low, high = min(low, value), max(high, value)
    p = FittedParameter("x", value, low=low, high=high, sd=width / 10, range=(lo, hi))
    r, places = rounded(p), decimals(p)
    assert lo <= r.value <= hi
    assert abs(r.value - value) <= 0.5 * 10.0 ** -places + 1e-9 * max(1.0, abs(value))
    # Two significant digits of the half-width at least: the rounding is finer than it.
    if high > low:
        assert 10.0 ** -places <= (high - low) / 2 + 1e-12

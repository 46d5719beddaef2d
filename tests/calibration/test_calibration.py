"""Calibration: known parameters recovered with honest intervals; outputs; Dask = local.

The full coverage check (20 repetitions) is benchmarks/calibration.py; here
a few repetitions with few rocks keep each test to seconds.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml

import rockfall_design as rd
from rockfall_design.calibration.uncertainty import FittedParameter, rounded
from rockfall_design.cli.program import main
from rockfall_design.project import load_project
from rockfall_design.report.staging import MANIFEST

from .calibration_helpers import TRUTH, observed_stops, write_site

PATH = "materials.soil.restitution"


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The site with 40 stops simulated at the true restitution."""
    directory = tmp_path_factory.mktemp("site")
    return write_site(directory, observed_stops(40, seed=1))


@pytest.fixture(scope="module")
def result(site):
    return rd.calibrate(site, workers=1)


def test_a_known_restitution_is_recovered_inside_its_interval(result):
    (p,) = result.parameters
    assert p.path == PATH and p.low <= TRUTH <= p.high
    assert abs(p.value - TRUTH) < 0.1
    assert p.identified is True and p.at_bound is None
    assert p.low <= p.value <= p.high
    fit = result.summary["fit"]
    assert set(fit) >= {"distance", "ks_statistic", "ks_pvalue", "observed", "simulated"}
    assert fit["observed"]["count"] == 40 and fit["simulated"]["count"] == 100


@pytest.mark.slow  # an end-to-end run of a few seconds: CI runs it with -m slow
def test_intervals_cover_the_truth_at_other_seeds(tmp_path):
    # A small coverage check: each repetition its own observations and seed; the full
    # one (20 repetitions, 40 replicates each) is benchmarks/calibration.py.
    inside = []
    for seed in (2, 3, 4):
        site = write_site(tmp_path, observed_stops(40, seed=seed))
        (p,) = rd.calibrate(site, bootstrap=10, rocks=80, seed=seed, workers=2).parameters
        inside.append(p.low <= TRUTH <= p.high)
        assert p.high - p.low < 0.3 and abs(p.value - TRUTH) < 0.1, p
    assert sum(inside) >= 2, inside


def test_an_input_the_stops_do_not_depend_on_is_flagged_not_identified(tmp_path):
    # A material on no segment of the slope: every value fits equally well.
    section = ("calibrate:\n  observed: stops.csv\n  fit: {materials.unused.restitution: "
               "[0.05, 0.7]}\n  rocks: 60\n  bootstrap: 8\n")
    site = write_site(tmp_path, observed_stops(30, seed=5), section)
    result = rd.calibrate(site, workers=1)
    (p,) = result.parameters
    assert p.identified is False and p.width_share > 0.5
    assert any("not identified" in w for w in result.summary["warnings"])


def test_the_same_seed_gives_the_same_numbers_on_any_pool(site, result):
    threads = rd.calibrate(site, workers=2, pool="threads")
    assert json.dumps(threads.summary) == json.dumps(result.summary)


def test_a_dask_cluster_gives_the_same_numbers(site, result):
    distributed = pytest.importorskip("distributed")
    # In-process workers (fast to start); the tasks still go through the Dask path.
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        remote = rd.calibrate(site, scheduler=cluster.scheduler_address)
    assert json.dumps(remote.summary) == json.dumps(result.summary)


def test_json_out_plot_and_calibrated_project(site, tmp_path, capsys):
    out, plots, lib = tmp_path / "out", tmp_path / "fig", tmp_path / "lib.yaml"
    code = main(["calibrate", str(site), "--json", "--workers", "1", "--bootstrap", "3",
                 "--out", str(out), "--plot", str(plots), "--save-materials", str(lib)])
    assert code == 0
    summary = json.loads(capsys.readouterr().out)
    assert [p["path"] for p in summary["parameters"]] == [PATH]
    assert set(summary["parameters"][0]) >= {"path", "value", "low", "high", "identified"}
    assert [lv["name"] for lv in summary["levels"]] == ["bench", "floor"]
    assert set(summary["levels"][0]) >= {"observed_share", "low", "high", "simulated_share"}
    names = sorted(p.name for p in out.iterdir() if p.name != MANIFEST)
    assert names == ["calibrated.yaml", "materials.yaml", "parameters.csv", "replicates.csv",
                     "summary.json"]
    names = sorted(p.name for p in plots.iterdir() if p.name != MANIFEST)
    assert names == ["calibration_cloud.png", "calibration_stops.png"]
    calibrated = load_project(out / "calibrated.yaml")
    soil = calibrated.materials["soil"]
    # Written to the interval's precision, not with 17 digits (issue 36 item 7).
    best = rounded(FittedParameter(**{**summary["parameters"][0],
                                      "range": tuple(summary["parameters"][0]["range"])}))
    assert soil.restitution == best.value
    assert soil.restitution == pytest.approx(summary["parameters"][0]["value"], abs=5e-3)
    # The ground's own (aleatory) scatter is written; the fitted value's
    # uncertainty (epistemic) is recorded beside it, never drawn (issue 35).
    assert soil.scatter.restitution == 0.0
    sd = float(f"{summary['parameters'][0]['sd']:.2g}")
    header = (out / "calibrated.yaml").read_text()
    assert "NOT drawn by a run" in header
    assert f"#   {PATH} = {best.value:g}, sd {sd:g}, interval [{best.low:g}, " in header
    assert yaml.safe_load(lib.read_text())["soil"]["restitution"] == soil.restitution
    # The library says where each entry comes from, as projects/materials.yaml does.
    text = (out / "materials.yaml").read_text()
    assert text == lib.read_text()
    assert (f"# law: spang\n# source: calibrated on {site.parent / 'stops.csv'} (40 blocks), "
            in text and f"seed {summary['method']['seed']} " in text)
    assert (f"fitted: restitution {best.value:g} [{best.low:g}, {best.high:g}]"
            in text)
    # Three replicates: the intervals are flagged as rough, not 95 % ones.
    assert "rough intervals from only 3 bootstrap replicates" in text
    assert summary["method"]["rough_intervals"].startswith("rough intervals from only 3")
    assert "# law: spang\n# source: the project " in text  # rock and unused: not fitted
    assert set(yaml.safe_load(text)) == {"soil", "rock", "unused"}
    assert f"fitted: restitution {best.value:g} [{best.low:g}, {best.high:g}] sd {sd:g}" in text
    again = rd.calibrate(site, workers=1, bootstrap=3)
    assert again.calibrated_project().materials["soil"].scatter.restitution == 0.0
    widened = again.calibrated_project(spread=True).materials["soil"].scatter.restitution
    assert widened == float(f"{again.parameters[0].sd:.2g}") > 0.0
    # compare: the calibrated project against the same observations, nothing fitted
    code = main(["compare", str(out / "calibrated.yaml"), "--observed",
                 str(site.parent / "stops.csv"), "--json", "--rocks", "200"])
    assert code == 0
    compared = json.loads(capsys.readouterr().out)
    assert compared["fit"]["observed"]["count"] == 40 and len(compared["levels"]) == 2


def test_compare_reports_a_bad_prediction_as_bad(site, capsys):
    # Textbook soil far too bouncy: the distance and KS say so, a level is flagged.
    project = load_project(site)
    bouncy = rd.compare(project.model_copy(update={"materials": {
        **project.materials,
        "soil": project.materials["soil"].model_copy(update={"restitution": 0.7})}}),
        site.parent / "stops.csv", rocks=200)
    fair = rd.compare(project, site.parent / "stops.csv", rocks=200)
    assert bouncy.fit.distance > 3 * fair.fit.distance
    assert bouncy.fit.ks_pvalue < 0.01 < fair.fit.ks_pvalue


def test_observed_sizes_set_the_simulated_rocks(tmp_path):
    site = write_site(tmp_path, observed_stops(20, seed=6))
    rng = np.random.default_rng(0)
    xs = (tmp_path / "stops.csv").read_text().split()[1:]
    (tmp_path / "stops.csv").write_text("x,volume_m3\n" + "".join(
        f"{x},{v:.3f}\n" for x, v in zip(xs, rng.lognormal(np.log(0.3), 0.5, len(xs)),
                                         strict=True)))
    result = rd.calibrate(site, bootstrap=0, workers=1)
    assert result.parameters[0].low is None  # no replicates, no interval
    median, sigma = result.sizes["volume"]["lognormal"]
    assert 0.15 < median < 0.6 and 0.2 < sigma < 0.9
    assert result.calibrated_project().rocks.volume.kind == "lognormal"

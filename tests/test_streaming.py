"""Large runs in bounded memory: histograms, chunked runs, the streamed ``simulate``."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from numpy.testing import assert_allclose

from rockfall_design.cli.program import main
from rockfall_design.project import load_project
from rockfall_design.report.staging import MANIFEST
from rockfall_design.run import simulation
from rockfall_design.run.histograms import LinearHistogram, LogHistogram
from rockfall_design.run.releases import ReleaseStream, draw_releases
from rockfall_design.run.simulation import simulate
from rockfall_design.run.streamed import STREAM_REL_ERROR

ROOT = Path(__file__).resolve().parents[1]
QUARRY = ROOT / "projects" / "quarry_road.yaml"


# ---- histograms ------------------------------------------------------------------
def _bounds(values: np.ndarray, q: float, a: float, zero: float) -> tuple[float, float]:
    """Where a percentile read from a relative-error-a histogram must lie."""
    exact = float(np.percentile(values, q))
    slack = 1e-9 * abs(exact)  # rounding of the bucket's logarithm
    return (1 - a) * exact - zero - slack, (1 + a) * exact + zero + slack


@settings(max_examples=150, deadline=None)
@given(
    values=arrays(np.float64, st.integers(1, 400),
                  elements=st.floats(0.0, 1e8, allow_nan=False)),
    q=st.floats(0.0, 100.0),
    parts=st.integers(1, 5),
)
def test_log_histogram_percentiles_are_within_the_stated_relative_error(values, q, parts):
    h = LogHistogram(1, rel_error=0.01, zero=1e-6)
    for chunk in np.array_split(values, parts):
        h.add(chunk)
    lo, hi = _bounds(values, q, 0.01, 1e-6)
    got = h.percentile(q)[0]
    assert lo <= got <= hi
    assert h.n[0] == values.size
    assert h.maximum()[0] == values.max()
    assert_allclose(h.mean()[0], values.mean(), rtol=1e-12, atol=1e-300)


def test_log_histogram_columns_nan_and_extremes():
    rng = np.random.default_rng(3)
    v = rng.lognormal(1.0, 2.0, size=(20_000, 4))
    v[rng.random(v.shape) < 0.3] = np.nan
    v[:, 3] = np.nan  # a station no rock passed
    v[0, 0] = 0.0  # in the zero bucket
    v[1, 1] = 5e9  # above the top of the buckets: stands for the maximum
    h = LogHistogram(4, rel_error=STREAM_REL_ERROR)
    h.add(v)
    for j in range(3):
        col = v[:, j][np.isfinite(v[:, j])]
        for q in (0.0, 1.0, 50.0, 95.0, 99.0, 99.9, 100.0):
            lo, hi = _bounds(col, q, STREAM_REL_ERROR, h.zero)
            assert lo <= h.percentile(q)[j] <= hi, (j, q)
        assert h.percentile(100.0)[j] == col.max()
        assert h.percentile(0.0)[j] == col.min()
    assert h.n[3] == 0 and np.isnan(h.percentile(50)[3]) and np.isnan(h.mean()[3])
    assert np.isnan(h.maximum()[3])


def test_histogram_counts_do_not_depend_on_the_chunking():
    rng = np.random.default_rng(5)
    v = rng.exponential(3.0, size=(5_000, 3))
    a, b = LogHistogram(3), LogHistogram(3)
    a.add(v)
    for chunk in np.array_split(v, 17):
        b.add(chunk)
    assert np.array_equal(a.counts, b.counts)
    for q in (50, 95, 99):
        assert np.array_equal(a.percentile(q), b.percentile(q))


def test_scale_divides_each_value():
    v = np.array([[1000.0, 2500.0], [np.nan, 40_000.0]], dtype=np.float32)
    a, b = LogHistogram(2), LogHistogram(2)
    a.add(v, 1e3)
    b.add(v.astype(float) / 1e3)
    assert np.array_equal(a.counts, b.counts) and np.array_equal(a.total, b.total)


@settings(max_examples=100, deadline=None)
@given(
    values=arrays(np.float64, st.integers(1, 300),
                  elements=st.floats(-50.0, 150.0, allow_nan=False)),
    q=st.floats(0.0, 100.0),
)
def test_linear_histogram_percentiles_are_within_half_a_bucket(values, q):
    h = LinearHistogram(-50.0, 150.0, 4000)
    h.add(values)
    exact = np.percentile(values, q)
    assert abs(h.percentile(q)[0] - exact) <= h.width / 2 + 1e-9


def test_histograms_reject_bad_arguments():
    with pytest.raises(ValueError):
        LogHistogram(1, rel_error=0.0)
    with pytest.raises(ValueError):
        LinearHistogram(1.0, 1.0, 10)
    with pytest.raises(ValueError, match="columns"):
        LogHistogram(2).add(np.zeros((3, 3)))


# ---- chunked runs ------------------------------------------------------------
@pytest.fixture(scope="module")
def quarry():
    return load_project(QUARRY)


def test_releases_drawn_in_chunks_are_the_releases_drawn_at_once(quarry):
    # quarry_road has two release zones and a lognormal size: every generator.
    whole = draw_releases(quarry, 2_000, 9)
    stream = ReleaseStream(quarry, 9)
    parts = [stream.draw(k) for k in (1, 700, 299, 1_000)]
    for name in ("radius", "x", "height", "vx", "vy", "spin", "spin_rolling", "zone"):
        got = np.concatenate([getattr(p, name) for p in parts])
        assert np.array_equal(got, getattr(whole, name)), name
    assert len(set(whole.zone.tolist())) == 2


@pytest.fixture(scope="module")
def exact_and_streamed(quarry):
    """The same 3,000 rocks, exact and streamed in chunks of 700 (with their tables)."""
    tables: list[simulation.SimulationRun] = []
    exact = simulate(quarry, rocks=3_000, seed=4)
    streamed = simulate(quarry, rocks=3_000, seed=4, chunk=700, on_chunk=tables.append)
    return exact, streamed, tables


def test_chunked_rocks_are_the_rocks_of_the_whole_run(exact_and_streamed):
    exact, streamed, tables = exact_and_streamed
    assert [t.first_rock for t in tables] == [0, 700, 1400, 2100, 2800]
    rocks = pd.concat([t.rocks_table() for t in tables], ignore_index=True)
    pd.testing.assert_frame_equal(rocks, exact.rocks_table())
    cross = pd.concat([t.crossings_table() for t in tables], ignore_index=True)
    pd.testing.assert_frame_equal(cross, exact.crossings_table())
    assert streamed.n == exact.n == 3_000


def test_streamed_summary_agrees_with_the_exact_one(exact_and_streamed):
    exact, streamed, _ = exact_and_streamed
    a, b = exact.summary(), streamed.summary()
    assert a["statistics"] == {"method": "exact"}
    assert b["statistics"]["method"] == "histograms"
    assert b["statistics"]["chunk_rocks"] == 700
    # Counts are exact.
    for key in ("rocks", "seed", "events", "project_hash", "protect"):
        assert a[key] == b[key], key
    sa, sb = dict(a["stops"]), dict(b["stops"])
    xa, xb = sa.pop("x"), sb.pop("x")
    assert sa == sb
    assert xa["max"] == xb["max"]
    assert_allclose(xa["mean"], xb["mean"], rtol=1e-12)
    tol = b["statistics"]["stop_x_error_m"]
    for k in ("p50", "p95"):
        assert abs(xa[k] - xb[k]) <= tol + 1e-9
    assert len(a["stations"]) == len(b["stations"]) == 3
    for ea, eb in zip(a["stations"], b["stations"], strict=True):
        assert ea["x"] == eb["x"] and ea["crossings"] == eb["crossings"] > 0
        for key in ("passing_height_m", "velocity_ms", "energy_kj",
                    "translational_energy_kj", "rotational_energy_kj"):
            assert ea[key]["max"] == eb[key]["max"]
            assert_allclose(eb[key]["mean"], ea[key]["mean"], rtol=1e-12)
            for p in ("p50", "p95", "p99"):
                # Linear interpolation between order statistics can move the
                # exact value a little off either neighbour; the bound holds
                # for the interpolated value too.
                assert_allclose(eb[key][p], ea[key][p], rtol=STREAM_REL_ERROR * (1 + 1e-9),
                                atol=1e-6)


def test_streamed_envelopes_agree_with_the_exact_ones(exact_and_streamed):
    exact, streamed, _ = exact_and_streamed
    ea, eb = exact.envelopes(), streamed.envelopes()
    assert list(ea.columns) == list(eb.columns)
    assert np.array_equal(ea["x_m"], eb["x_m"])
    assert np.array_equal(ea["crossings"], eb["crossings"])
    for col in ea.columns[3:]:
        a, b = ea[col].to_numpy(), eb[col].to_numpy()
        assert np.array_equal(np.isnan(a), np.isnan(b)), col
        m = ~np.isnan(a)
        if col.endswith(("max_m", "max_kj")):
            assert np.array_equal(a[m], b[m]), col
        else:
            assert_allclose(b[m], a[m], rtol=STREAM_REL_ERROR * (1 + 1e-9), atol=1e-6)


def test_streamed_figures_data(exact_and_streamed):
    exact, streamed, _ = exact_and_streamed
    assert np.array_equal(exact.status_counts(), streamed.status_counts())
    assert np.array_equal(exact.stop_counts(80), streamed.stop_counts(80))
    xa, ya = exact.rest_positions()
    xb, yb = streamed.rest_positions()
    assert np.array_equal(xa, xb) and np.array_equal(ya, yb)  # fewer than the sample size


def test_chunk_size_changes_nothing_but_the_last_bits_of_the_means(quarry):
    a = simulate(quarry, rocks=1_500, seed=8, chunk=400).summary()
    b = simulate(quarry, rocks=1_500, seed=8, chunk=1_100).summary()

    def split(s):
        means = []

        def walk(d):
            if isinstance(d, dict):
                return {k: (means.append(v) or 0.0) if k == "mean" else walk(v)
                        for k, v in d.items() if k not in ("runtime_s", "statistics")}
            if isinstance(d, list):
                return [walk(v) for v in d]
            return d

        return walk(s), np.array(means, dtype=float)

    (ra, ma), (rb, mb) = split(a), split(b)
    assert ra == rb
    assert_allclose(ma, mb, rtol=1e-12)


# ---- the command line ---------------------------------------------------------
@pytest.fixture
def small_exact_limit(monkeypatch):
    """Stream every run above 400 rocks, in chunks of 400."""
    monkeypatch.setattr(simulation, "EXACT_ROCKS", 400)


def test_simulate_streams_a_large_run_and_writes_every_row(small_exact_limit, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["simulate", str(QUARRY), "--rocks", "1000", "--seed", "3",
                 "--out", str(out), "--plot", str(tmp_path / "fig"), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["statistics"]["method"] == "histograms" and s["statistics"]["chunk_rocks"] == 400
    rocks = pd.read_csv(out / "rocks.csv")
    cross = pd.read_csv(out / "crossings.csv")
    assert list(rocks["rock"]) == list(range(1000))
    assert len(cross) == 1000 * 3 and cross["rock"].max() == 999
    assert int((rocks["end"] == "stopped").sum()) == s["stops"]["stopped"]
    for j, st_ in enumerate(s["stations"]):
        at = cross[cross["station_x_m"] == st_["x"]]
        assert int(at["crossed"].sum()) == st_["crossings"]
        assert at["passing_height_m"].max() == pytest.approx(st_["passing_height_m"]["max"],
                                                             rel=1e-12), j
    assert sorted(p.name for p in (tmp_path / "fig").iterdir() if p.name != MANIFEST) == [
        "envelopes.png", "profile.png", "stops.png"]
    assert not [p for p in out.iterdir()
                if p.name.startswith(".") and p.name != MANIFEST]


def test_repeat_reproduces_a_streamed_run_exactly(small_exact_limit, tmp_path, capsys):
    out = tmp_path / "first"
    assert main(["simulate", str(QUARRY), "--rocks", "900", "--out", str(out), "--json"]) == 0
    first = json.loads(capsys.readouterr().out)
    assert main(["simulate", "--repeat", str(out / "summary.json"), "--json"]) == 0
    captured = capsys.readouterr()
    again = json.loads(captured.out)
    assert "identical" in captured.err
    first.pop("runtime_s")
    again.pop("runtime_s")
    assert again == first


def test_an_interrupted_streamed_run_leaves_the_previous_tables(small_exact_limit, tmp_path,
                                                                capsys, monkeypatch):
    out = tmp_path / "out"
    assert main(["simulate", str(QUARRY), "--rocks", "500", "--out", str(out), "--json"]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    capsys.readouterr()
    calls = []
    real = simulation.run_ensemble

    def interrupted_on_the_second_chunk(*args, **kw):
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(*args, **kw)

    monkeypatch.setattr(simulation, "run_ensemble", interrupted_on_the_second_chunk)
    assert main(["simulate", str(QUARRY), "--rocks", "1200", "--out", str(out)]) == 130
    assert "interrupted" in capsys.readouterr().err
    assert len(calls) == 2
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_a_run_that_would_not_fit_in_memory_is_refused_up_front(tmp_path, capsys, monkeypatch):
    project = tmp_path / "huge.yaml"
    project.write_text(QUARRY.read_text().replace(
        "analysis:", "analysis:\n  envelope_points: 10000", 1))  # the most allowed
    monkeypatch.setattr(simulation, "run_ensemble", None)  # must not be reached
    # 100,000 rocks are kept exactly: with 10,000 envelope points, 30 GiB.
    real = os.sysconf
    monkeypatch.setattr("os.sysconf", lambda name: {"SC_PAGE_SIZE": 4096, "SC_PHYS_PAGES": 2**22}
                        .get(name) or real(name))  # a machine of 16 GiB
    assert main(["simulate", str(project), "--rocks", "100000"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert "would need about" in err and "GiB" in err and "envelope_points" in err
    # check keeps every rock: a million rocks of the example is fine, a
    # billion are not.
    assert main(["check", str(QUARRY), "--rocks", "1000000000"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "would need about" in err

"""Parametric studies: the study command, its executors, and the physics it should show."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import rockfall_design as rd
from rockfall_design.cli.program import main
from rockfall_design.project import load_project, load_project_text
from rockfall_design.studies import with_values

ROOT = Path(__file__).resolve().parents[2]
TALUS = ROOT / "projects" / "study_talus.yaml"

#: The talus study's slope, with the inputs varied set by each test.
RUNOUT = """\
name: runout
slope:
  points: [[0, 100], [30, 60], [60, 30], [80, 20], [120, 15], [200, 12], [260, 12]]
  materials: talus
materials:
  talus: {restitution: 0.35, friction: 0.58, rolling_resistance: 0.6, roughness_deg: 5}
rocks:
  count: 200
  seed: 1
  volume: 1.0
  release: {x: 1, velocity: [0.6, -0.8]}
analysis:
  stations: [160]
protect:
  x: 200
measures:
  - {type: fence, x: 160, height: 4.0, capacity_kj: 3000}
study:
"""


def comparable(summary: dict) -> str:
    """A study's JSON without what differs between runs (the wall time)."""
    return json.dumps({k: v for k, v in summary.items() if k != "runtime_s"}, sort_keys=True)


@pytest.fixture(scope="module")
def talus():
    """The bundled 3 x 3 study, in this process, few rocks."""
    return rd.study(TALUS, rocks=120, seed=5, workers=1)


def test_a_grid_of_two_inputs_of_three_values_is_nine_scenarios(talus):
    s = talus.summary
    assert (s["rocks"], s["seed"], s["sampling"]) == (120, 5, "grid")
    assert s["vary"] == {"materials.talus.restitution": [0.28, 0.35, 0.42],
                         "rocks.volume": [0.5, 1.0, 2.0]}
    assert [b["index"] for b in s["scenarios"]] == list(range(9))
    for block in s["scenarios"]:
        assert list(block["values"]) == ["materials.talus.restitution", "rocks.volume"]
        assert {"seed", "stations", "stops", "protect", "measures"} <= set(block)
    assert len({b["seed"] for b in s["scenarios"]}) == 9
    # ranked unit-free (issue 25): the design values by their largest relative effect,
    # each design value's inputs by the raw effect, which stays beside it
    ranked = s["sensitivity"]
    targets = list(dict.fromkeys(e["target"] for e in ranked))
    assert [e["target"] for e in ranked] == sorted((e["target"] for e in ranked),
                                                   key=targets.index)
    tops = [max(e["relative_effect"] for e in ranked if e["target"] == t) for t in targets]
    assert tops == sorted(tops, reverse=True)
    for t in targets:
        effects = [e["effect"] for e in ranked if e["target"] == t]
        assert effects == sorted(effects, reverse=True)
    from rockfall_design.studies.sensitivity import rank  # the terminal's order

    assert [e.to_json() for e in rank(talus.entries)] == ranked
    assert {e["target"] for e in s["sensitivity"]} >= {
        "x=100 energy_kj p95", "x=100 passing_height_m p99",
        "measures[0] x=160 energy_kj p95", "x=200 residual"}
    json.dumps(s, allow_nan=False)  # --json prints it so


def test_a_scenario_is_the_simulate_run_of_its_project(talus):
    scenario = talus.scenario_list[4]
    project = with_values(load_project(TALUS), scenario.values)
    plain = rd.simulate(project, rocks=120, seed=scenario.seed, trajectories=0).summary
    block = talus.summary["scenarios"][4]
    for key in ("stations", "stops", "protect", "events", "project_hash"):
        assert block[key] == plain[key], key


def test_the_thread_pool_gives_the_same_numbers(talus):
    pooled = rd.study(TALUS, rocks=120, seed=5, workers=2)  # threads: the default
    assert comparable(pooled.summary) == comparable(talus.summary)


def test_the_process_pool_gives_the_same_numbers(talus):
    pooled = rd.study(TALUS, rocks=120, seed=5, workers=2, pool="processes")
    assert comparable(pooled.summary) == comparable(talus.summary)


def test_a_study_without_its_envelopes_gives_the_same_numbers(talus):
    bare = rd.study(TALUS, rocks=120, seed=5, workers=2, envelopes=False)
    assert comparable(bare.summary) == comparable(talus.summary)
    assert all(result.envelope is None for result in bare.results)
    assert all(result.envelope is not None for result in talus.results)
    with pytest.raises(ValueError, match="envelopes=True"):
        bare.plot_envelopes()


def _engine_threads(_task):
    from rockfall_design.engine.batching import default_threads

    return default_threads()


def test_a_task_on_the_thread_pool_runs_the_engine_on_one_thread():
    from rockfall_design.engine.batching import default_threads
    from rockfall_design.studies.executors import run_tasks

    before = default_threads()
    assert run_tasks(_engine_threads, range(5), workers=2, pool="threads") == [1] * 5
    assert default_threads() == before  # this thread's runs keep every core
    with pytest.raises(ValueError, match="pool"):
        run_tasks(_engine_threads, range(2), workers=2, pool="fibres")


# Slow set: two worker processes of Dask's own to start (7.6 s); the Dask path
# (in-process workers) runs in the fast set in tests/calibration/test_calibration.py.
@pytest.mark.slow
def test_a_dask_local_cluster_gives_the_same_numbers(talus):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        remote = rd.study(TALUS, rocks=120, seed=5, scheduler=cluster.scheduler_address)
    assert comparable(remote.summary) == comparable(talus.summary)


def test_tables_and_figures(talus, tmp_path):
    frame = talus.scenarios
    assert list(frame.columns[:4]) == ["index", "seed", "materials.talus.restitution",
                                       "rocks.volume"]
    assert len(frame) == 9 and "x=200 residual" in frame.columns
    assert set(talus.sensitivity.columns) >= {"parameter", "target", "effect"}
    written = talus.save_figures(tmp_path, ("png", "svg"))
    assert sorted(p.name for p in written) == ["study_envelopes.png", "study_envelopes.svg",
                                               "tornado.png", "tornado.svg"]


# ---- physics: the directions an engineer expects, with margin, on several seeds --------------


@pytest.mark.parametrize("seed", [1, 2])
def test_more_restitution_more_energy_and_reach_downslope(seed):
    text = RUNOUT + ("  vary:\n    materials.talus.restitution: [0.2, 0.35, 0.5]\n"
                     "    rocks.volume: [0.5, 1.0, 2.0]\n")
    result = rd.study(load_project_text(text, "runout.yaml"), rocks=200, seed=seed, workers=1)
    blocks = result.summary["scenarios"]
    for v in range(3):  # each rock volume: scenarios v, 3 + v, 6 + v by restitution
        by_e = [blocks[3 * k + v] for k in range(3)]
        energy = [b["stations"][0]["energy_kj"]["mean"] for b in by_e]
        residual = [b["protect"]["fraction"] for b in by_e]
        envelope = []
        for k in range(3):
            env = result.results[3 * k + v].envelope
            x = np.asarray(env["x_m"])
            p95 = np.asarray(env["energy_p95_kj"], dtype=float)
            envelope.append(np.nanmean(p95[(x >= 120) & (x <= 180)]))
        # each step of restitution (0.15) adds more than 5 % (observed: 10 to 25 %)
        assert energy[1] > 1.05 * energy[0] and energy[2] > 1.05 * energy[1], energy
        assert envelope[1] > 1.05 * envelope[0] and envelope[2] > 1.05 * envelope[1]
        assert residual[1] > residual[0] + 0.05 and residual[2] > residual[1] + 0.05


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_wide_rock_volume_range_outranks_a_small_friction_change(seed):
    text = RUNOUT + ("  vary:\n    materials.talus.friction: [0.55, 0.6]\n"
                     "    rocks.volume: [0.3, 3.0]\n")
    result = rd.study(load_project_text(text, "runout.yaml"), rocks=150, seed=seed, workers=1)
    for target in ("measures[0] x=160 energy_kj p95", "x=160 energy_kj p99"):
        rows = [e for e in result.summary["sensitivity"] if e["target"] == target]
        assert rows[0]["parameter"] == "rocks.volume"
        # ten times the mass: several times the energy; the friction barely moves it
        # (the ratio of the effects: 7 to 130 at seeds 1-6 with the hop criterion of
        # the transition to contact, the friction's p99 effect being noisy at 150 rocks)
        assert rows[0]["effect"] > 5 * rows[1]["effect"]


def test_a_sampled_study_adds_variance_based_indices():
    pytest.importorskip("SALib")
    text = RUNOUT + ("  vary:\n    materials.talus.restitution: {range: [0.3, 0.4]}\n"
                     "    rocks.volume: {range: [0.5, 2.0]}\n"
                     "  scenarios: {sample: latin_hypercube, n: 24, seed: 3}\n")
    result = rd.study(load_project_text(text, "runout.yaml"), rocks=40, seed=2, workers=1)
    s = result.summary
    assert s["sampling"] == {"sample": "latin_hypercube", "n": 24, "seed": 3}
    assert len(s["scenarios"]) == 24
    energy = {e["parameter"]: e for e in s["sensitivity"]
              if e["target"] == "measures[0] x=160 energy_kj p95"}
    assert energy["rocks.volume"]["S1"] > 0.5 > energy["materials.talus.restitution"]["S1"]
    assert all(np.isfinite(e["S1_conf"]) for e in energy.values())


# ---- the command ---------------------------------------------------------------------------


def test_study_command_json(capsys):
    assert main(["study", str(TALUS), "--rocks", "40", "--seed", "3", "--workers", "1",
                 "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert {"seed", "rocks", "version", "vary", "scenarios", "sensitivity"} <= set(summary)
    assert summary["seed"] == 3 and summary["rocks"] == 40


def test_study_command_draws_the_envelopes_it_computes_only_for_plot(tmp_path, capsys):
    # Without --plot the scenarios skip their envelopes (only the figure reads them).
    assert main(["study", str(TALUS), "--rocks", "40", "--seed", "3", "--workers", "1",
                 "--plot", str(tmp_path / "fig"), "--json"]) == 0
    with_plot = comparable(json.loads(capsys.readouterr().out))
    assert (tmp_path / "fig" / "study_envelopes.png").stat().st_size > 0
    assert main(["study", str(TALUS), "--rocks", "40", "--seed", "3", "--workers", "1",
                 "--json"]) == 0
    assert comparable(json.loads(capsys.readouterr().out)) == with_plot


def test_a_streamed_run_keeps_the_engine_threads_of_its_scenario(monkeypatch):
    # A streamed run computes its chunks on a helper thread: that thread must
    # run the engine on the scenario's one thread too, not on every core.
    import rockfall_design.run.simulation as simulation
    from rockfall_design.engine.batching import ENGINE_THREADS, default_threads

    seen = []
    real = simulation.run_ensemble

    def spy(*args, **kwargs):
        seen.append(default_threads())
        return real(*args, **kwargs)

    monkeypatch.setattr(simulation, "run_ensemble", spy)
    token = ENGINE_THREADS.set(1)
    try:
        simulation.simulate(load_project(TALUS), rocks=60, seed=1, chunk=20)
    finally:
        ENGINE_THREADS.reset(token)
    assert seen == [1, 1, 1]


def test_study_command_pools_give_the_same_json(capsys):
    runs = []
    for pool in ("threads", "processes"):
        assert main(["study", str(TALUS), "--rocks", "40", "--seed", "3", "--workers", "2",
                     "--pool", pool, "--json"]) == 0
        runs.append(comparable(json.loads(capsys.readouterr().out)))
    assert runs[0] == runs[1]


def test_study_command_report(capsys):
    assert main(["study", str(TALUS), "--rocks", "30", "--workers", "1"]) == 0
    out = capsys.readouterr().out
    assert "Scenarios" in out and "Which input moves each design value" in out


def test_a_bad_varied_value_is_one_line_and_exit_2(tmp_path, capsys):
    path = tmp_path / "bad.yaml"
    path.write_text(TALUS.read_text().replace("[0.28, 0.35, 0.42]", "[0.28, 0.35, 1.42]"))
    assert main(["study", str(path), "--rocks", "20"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "study.vary.materials.talus.restitution: value 1.42" in err
    # every command reads the whole file, study: included
    assert main(["simulate", str(path), "--rocks", "20"]) == 2


def test_a_project_without_a_study_is_exit_2(capsys):
    assert main(["study", str(ROOT / "projects" / "standard_slope.yaml")]) == 2
    assert "no study: section" in capsys.readouterr().err


def test_scheduler_without_dask_names_the_extra(monkeypatch, capsys):
    import sys

    monkeypatch.setitem(sys.modules, "distributed", None)  # as if not installed
    assert main(["study", str(TALUS), "--rocks", "20", "--scheduler",
                 "tcp://127.0.0.1:8786"]) == 2
    err = capsys.readouterr().err
    assert "rockfall-design[study]" in err and len(err.strip().splitlines()) == 1


def test_the_function_keeps_its_name_over_the_package():
    import rockfall_design.studies.sampling  # noqa: F401  (imports a submodule)

    assert callable(rd.study) and rd.study is rd.api.study


def test_the_package_exports_the_function_scenarios_not_a_module():
    # The submodule is sampling.py: a submodule named scenarios.py would be
    # bound to the package's name when imported, over the function.
    import types

    from rockfall_design import studies
    from rockfall_design.studies import sampling

    assert not isinstance(studies.scenarios, types.ModuleType)
    assert studies.scenarios is sampling.scenarios
    assert studies.Scenario is sampling.Scenario
    assert studies.scenario_seed is sampling.scenario_seed


def test_the_scenario_envelope_percentile_is_numpys():
    from rockfall_design.studies.runner import column_percentile

    rng = np.random.default_rng(3)
    table = rng.lognormal(size=(500, 6)).astype(np.float32)
    table[rng.random(table.shape) < 0.4] = np.nan
    table[:, 2] = np.nan  # no rock passes here
    table[1:, 4] = np.nan  # one rock passes here
    for q in (0, 50, 95, 99, 100):
        with np.errstate(all="ignore"), pytest.warns(RuntimeWarning):
            expected = np.nanpercentile(table.astype(float), q, axis=0)
        np.testing.assert_allclose(column_percentile(table, q), expected, rtol=1e-12)


def _sorted_percentile(values, q):
    """The envelope percentile as the study first computed it: one sort down the columns."""
    ordered = np.sort(values, axis=0)
    count = np.isfinite(values).sum(axis=0)
    out = np.full(values.shape[1], np.nan)
    cols = np.nonzero(count > 0)[0]
    pos = (count[cols] - 1) * (q / 100.0)
    lo = np.floor(pos).astype(np.int64)
    hi = np.minimum(lo + 1, count[cols] - 1)
    low = ordered[lo, cols].astype(float)
    out[cols] = low + (ordered[hi, cols].astype(float) - low) * (pos - lo)
    return out


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_envelope_percentile_is_the_column_sorts_to_the_bit(seed):
    # The study's JSON numbers must not move: the same order statistics,
    # interpolated in the same float64 operations (float32 tables, as the engine's).
    from rockfall_design.studies.runner import column_percentile

    rng = np.random.default_rng(seed)
    for shape in [(2000, 13), (40, 5), (3, 4), (1, 3)]:
        table = rng.lognormal(size=shape).astype(np.float32)
        table[rng.random(shape) < 0.4] = np.nan
        table[:, 0] = np.nan
        for q in (0, 12.5, 50, 95, 99, 100):
            got, want = column_percentile(table, q), _sorted_percentile(table, q)
            assert got.tobytes() == want.tobytes()


@pytest.mark.parametrize(("values", "words"), [
    ("[4.0, -1.0]", "value -1: measures[0].height: expected a number > 0"),
    ("[160, 999]", "outside the section"),
])
def test_a_varied_plugin_parameter_is_checked_by_its_plugin(tmp_path, capsys, values, words):
    path = tmp_path / "bad.yaml"
    text = TALUS.read_text().replace("rocks.volume: [0.5, 1.0, 2.0]",
                                     f"measures[0].{'height' if '4.0' in values else 'x'}: "
                                     f"{values}")
    path.write_text(text)
    for command in ("study", "check"):
        assert main([command, str(path), "--rocks", "20"]) == 2
        err = capsys.readouterr().err.strip()
        assert words in err and "study.vary.measures[0]." in err
        assert len(err.splitlines()) == 1


@pytest.mark.parametrize("workers", ["1", "2"])  # in turn; threads, each task as it is made
def test_values_that_do_not_fit_together_stop_the_study_before_it_runs(tmp_path, capsys,
                                                                        workers):
    path = tmp_path / "bad.yaml"
    text = TALUS.read_text().replace("volume: 1.0 ", "volume: {uniform: [0.5, 1.0]}")
    text = text.replace("rocks.volume: [0.5, 1.0, 2.0]",
                        "rocks.volume.uniform.0: [0.5, 0.9]\n"
                        "    rocks.volume.uniform.1: [0.8, 1.2]")
    path.write_text(text)
    assert main(["check", str(path), "--rocks", "20"]) in (0, 1)  # each value fits alone
    capsys.readouterr()
    assert main(["study", str(path), "--rocks", "20", "--workers", workers]) == 2
    err = capsys.readouterr().err.strip()
    assert "do not fit together" in err and len(err.splitlines()) == 1


def test_common_seeds_keep_the_monte_carlo_noise_out_of_the_sensitivity():
    # a varied input that does nothing (the scatter of a material no segment uses)
    text = RUNOUT.replace("materials:\n", "materials:\n  unused: {restitution: 0.3, "
                          "friction: 0.5}\n") + (
        "  vary:\n    materials.unused.restitution: [0.2, 0.4]\n"
        "    rocks.volume: [0.5, 2.0]\n")
    own = rd.study(load_project_text(text, "r.yaml"), rocks=60, seed=4, workers=1)
    common = rd.study(load_project_text(text + "  seeds: common\n", "r.yaml"), rocks=60,
                      seed=4, workers=1)
    assert {b["seed"] for b in common.summary["scenarios"]} == {4}
    noise = [e for e in own.summary["sensitivity"]
             if e["parameter"] == "materials.unused.restitution"]
    none = [e for e in common.summary["sensitivity"]
            if e["parameter"] == "materials.unused.restitution"]
    assert any(e["effect"] > 0 for e in noise)  # independent rocks: noise shows as an effect
    assert all(e["effect"] == 0 for e in none)  # the same rocks: no effect at all

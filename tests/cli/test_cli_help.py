"""Every option's help text says what the option does, command by command.

The help of each subcommand is parsed as a user reads it (``--help``), every
option must appear in the table below, and the files and JSON keys a help
text names are the ones the command really writes and prints.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from rockfall_design.cli.program import build_parser, main
from rockfall_design.report.staging import MANIFEST

ROOT = Path(__file__).resolve().parents[2]
PROJECTS = ROOT / "projects"
#: A design project that optimises in seconds: the tests here are about the files and keys
#: an optimisation writes, not about its design.
SMALL_DESIGN = ROOT / "tests" / "data" / "design_small.yaml"

#: command -> option -> what its help must mention (fragments, in any order)
EXPECTED: dict[str, dict[str, list[str]]] = {
    "section": {
        "dem": ["DEM"],
        "--fall-line": ["steepest descent", "map point"],
        "--line": ["map line", "two or more points"],
        "--stop": ["map line", "fall line ends"],
        "--flat-deg": ["fall line ends", "flatter", "deg"],
        "--spacing": ["sampling step", "DEM's resolution"],
        "--tolerance": ["vertical tolerance"],
        "--out": ["CSV", "x, y"],
        "--plot": ["figure", ".png"],
    },
    "simulate": {
        "project": ["project file"],
        "--repeat": ["summary.json", "instead of reading a project file"],
        "--rocks": ["number of rocks", "rocks.count", "--repeat"],
        "--seed": ["random seed", "rocks.seed", "--repeat"],
        "--out": ["rocks.csv", "crossings.csv", "summary.json", "--repeat", "DIR"],
        "--plot": ["profile.png", "envelopes.png", "stops.png", "DIR"],
        "--json": ["JSON", "stdout"],
        "--block": ["plugin"],
        "--plot-format": ["png", "svg", "pdf", "--plot"],
        "--report": ["report.html", "report.md", "DIR"],
        "--workers": ["corridor", "sections:", "pool", "processes", "one per core"],
        "--scheduler": ["corridor", "Dask", "scheduler"],
    },
    "check": {
        "project": ["project file", "measures:"],
        "--rocks": ["number of rocks", "rocks.count"],
        "--seed": ["random seed", "rocks.seed"],
        "--out": ["rocks.csv", "the measure that caught it", "crossings.csv", "measures.csv",
                  "summary.json", "DIR"],
        "--plot": ["profile.png", "measures", "envelopes.png", "stops.png", "DIR"],
        "--json": ["JSON", "stdout", "measures", "protect", "ok", "failures"],
        "--block": ["plugin"],
        "--plot-format": ["png", "svg", "pdf", "--plot"],
        "--report": ["report.html", "report.md", "DIR"],
        "--scenarios": ["every scenario", "study:", "design.scenarios", "binding scenario"],
        "--workers": ["--scenarios", "corridor", "pool", "processes", "one per core"],
        "--scheduler": ["--scenarios", "corridor", "Dask", "scheduler"],
    },
    "optimise": {
        "project": ["project file", "design:"],
        "--rocks": ["number of rocks", "rocks.count", "fresh"],
        "--seed": ["random seed", "rocks.seed", "fresh"],
        "--out": ["design.yaml", "chosen measures", "no design is admissible",
                  "alternatives.csv", "summary.json", "DIR"],
        "--plot": ["alternatives.png", "profile.png", "envelopes.png", "stops.png",
                   "chosen design", "no design is admissible", "DIR"],
        "--json": ["JSON", "stdout", "alternatives", "best"],
        "--block": ["plugin"],
        "--plot-format": ["png", "svg", "pdf", "--plot"],
        "--report": ["report.html", "report.md", "DIR"],
        "--max-rocks": ["last look", "design.max_rocks", "marginal", "rocks would decide it"],
    },
    "study": {
        "project": ["project file", "study:"],
        "--rocks": ["number of rocks", "each scenario", "rocks.count"],
        "--seed": ["random seed", "rocks.seed", "each scenario's seed"],
        "--out": ["scenarios.csv", "sensitivity.csv", "summary.json", "DIR"],
        "--plot": ["study_envelopes.png", "tornado.png", "DIR"],
        "--json": ["JSON", "stdout", "vary", "scenarios", "stations", "stops", "protect",
                   "sensitivity"],
        "--workers": ["local pool", "processes", "1 runs them in this process"],
        "--pool": ["threads", "processes", "engine thread", "same results"],
        "--scheduler": ["Dask", "tcp://", "study extra"],
        "--block": ["plugin"],
        "--plot-format": ["png", "svg", "pdf", "--plot"],
    },
    "calibrate": {
        "project": ["project file", "calibrate:"],
        "--rocks": ["simulated rocks", "per evaluation", "calibrate.rocks"],
        "--seed": ["random seed", "rocks.seed"],
        "--json": ["JSON", "stdout"],
        "--plot": ["calibration_stops", "calibration_cloud", "DIR"],
        "--plot-format": ["png", "svg", "pdf", "--plot"],
        "--observed": ["observed stops", "calibrate.observed"],
        "--bootstrap": ["bootstrap replicates", "calibrate.bootstrap", "no intervals"],
        "--out": ["calibrated.yaml", "materials.yaml", "parameters.csv", "replicates.csv",
                  "summary.json", "DIR"],
        "--save-materials": ["materials library"],
        "--keep-scatter": ["calibrated.yaml", "scatter as it was", "the default"],
        "--widen-scatter": ["standard deviation", "per-impact scatter", "--save-materials"],
        "--no-prior": ["prior", "fit: auto", "--no-prior", "sampling noise"],
        "--no-screen": ["leave out", "sampling noise", "class's value", "--no-screen"],
        "--report": ["report.html", "report.md", "DIR", "fitted inputs"],
        "--workers": ["local pool", "one per core"],
        "--pool": ["threads", "processes", "same results"],
        "--scheduler": ["Dask", "same results", "study extra"],
        "--block": ["plugin"],
    },
    "compare": {
        "project": ["project file", "calibrated.yaml"],
        "--observed": ["observed stops", "volume_m3"],
        "--rocks": ["simulated rocks", "rocks.count"],
        "--seed": ["random seed", "rocks.seed"],
        "--json": ["JSON", "stdout"],
        "--plot": ["calibration_stops", "DIR"],
        "--plot-format": ["png", "svg", "pdf", "--plot"],
        "--out": ["summary.json", "DIR"],
        "--report": ["report.html", "report.md", "DIR", "fit statistics"],
        "--block": ["plugin"],
    },
    "plugins": {
        "--json": ["JSON", "stdout", "measures", "safety concepts", "cost models", "failed"],
        "--block": ["plugin"],
    },
    "serve": {
        "project": ["project files", "current directory"],
        "--port": ["port", "8765", "any free port"],
        "--host": ["127.0.0.1", "this machine only"],
        "--block": ["plugin"],
    },
}

_FILE = re.compile(r"\b[\w-]+\.(?:csv|json|yaml|png|svg|pdf|html|md)\b")


def _subparsers() -> dict:
    parser = build_parser()
    (action,) = [a for a in parser._actions if a.dest == "command"]
    return action.choices


def help_entries(command: str, capsys, monkeypatch) -> dict[str, str]:
    """Option (its last spelling, or a positional's name) -> its help, from ``--help``."""
    monkeypatch.setenv("COLUMNS", "100")
    with pytest.raises(SystemExit) as exc:
        main([command, "--help"])
    assert exc.value.code == 0
    text = capsys.readouterr().out
    entries: dict[str, str] = {}
    current = None
    for line in text.splitlines():
        if not line.startswith("  "):
            current = None  # a section heading or a blank line
            continue
        head = re.match(r"  (\S.*?)(?:  +(\S.*))?$", line)
        if head and not line.startswith("   "):
            # "  -h, --help    show ...": the spellings, then the help (maybe next line)
            names = [n.split()[0] for n in head.group(1).split(", ")]
            current = names[-1]
            entries[current] = head.group(2) or ""
        elif current is not None:
            entries[current] += " " + line.strip()
    entries.pop("--help", None)
    return {k: " ".join(v.split()) for k, v in entries.items()}


@pytest.mark.parametrize("command", sorted(EXPECTED))
def test_every_option_has_help_that_says_what_it_does(command, capsys, monkeypatch):
    entries = help_entries(command, capsys, monkeypatch)
    assert set(entries) == set(EXPECTED[command]), "an option without an entry in EXPECTED"
    for option, fragments in EXPECTED[command].items():
        for fragment in fragments:
            assert fragment in entries[option], f"{command} {option}: {fragment!r} missing"


def test_the_table_covers_every_option_of_the_parser():
    # independent of the help layout: the parser's own list of options
    subparsers = _subparsers()
    for command, sub in subparsers.items():
        if command not in EXPECTED:  # an alias (optimize)
            assert sub is subparsers["optimise"]
            continue
        names = {a.option_strings[-1] if a.option_strings else a.dest for a in sub._actions}
        assert names - {"--help"} == set(EXPECTED[command])


def named_files(command: str, option: str, capsys, monkeypatch) -> set[str]:
    return set(_FILE.findall(help_entries(command, capsys, monkeypatch)[option]))


@pytest.mark.parametrize("command, project, rocks", [
    ("simulate", "standard_slope.yaml", "40"),
    # check's figures and report take 9 s: the slow set; simulate's run here.
    pytest.param("check", "quarry_fence_ditch.yaml", "40", marks=pytest.mark.slow),
    pytest.param("optimise", SMALL_DESIGN, "200", marks=pytest.mark.slow,
                 id="optimise-design_small.yaml-200"),  # PROJECTS / SMALL_DESIGN: itself
    ("study", "study_talus.yaml", "20"),
])
def test_out_and_plot_write_the_files_their_help_names(command, project, rocks, tmp_path,
                                                       capsys, monkeypatch):
    out, plot = tmp_path / "out", tmp_path / "figures"
    code = main([command, str(PROJECTS / project), "--rocks", rocks, "--seed", "5",
                 "--out", str(out), "--plot", str(plot), "--json"])
    summary = json.loads(capsys.readouterr().out)
    assert code in (0, 1)
    # --rocks and --seed (optimise: the search's rocks; "rocks" are those that decided)
    # (the search takes at least the rocks that can show the residual target)
    if command == "optimise":
        assert summary["search_rocks"] >= int(rocks) and summary["seed"] == 5
    else:
        assert summary["rocks"] == int(rocks) and summary["seed"] == 5
    written = {p.name for p in out.iterdir()} - {MANIFEST}
    # The distributions at every station and barrier: one figure each, named
    # passing_station_N / passing_measure_N as the help says.
    drawn = {re.sub(r"_\d+\.", "_N.", p.name) for p in plot.iterdir()} - {MANIFEST} \
        if plot.exists() else set()
    if command == "optimise" and summary["best"] is None:
        # as the help says: no design.yaml, and only alternatives.png, without an
        # admissible design
        assert "design.yaml" not in written and drawn == {"alternatives.png"}
        written.add("design.yaml")
        drawn = named_files(command, "--plot", capsys, monkeypatch)
    assert written == named_files(command, "--out", capsys, monkeypatch)
    assert drawn == named_files(command, "--plot", capsys, monkeypatch)


@pytest.mark.parametrize("argv, keys", [
    (["check", str(PROJECTS / "quarry_fence_ditch.yaml"), "--rocks", "20"],
     {"measures", "protect", "ok", "failures"}),
    pytest.param(["optimise", str(SMALL_DESIGN), "--rocks", "100"],
                 {"alternatives", "best"}, marks=pytest.mark.slow),
    (["plugins"], {"measures", "safety_concepts", "cost_models", "failures"}),
    (["study", str(PROJECTS / "study_talus.yaml"), "--rocks", "20", "--workers", "1"],
     {"vary", "scenarios", "sensitivity"}),
])
def test_json_prints_the_keys_its_help_names(argv, keys, capsys):
    assert main([*argv, "--json"]) in (0, 1)
    assert keys <= set(json.loads(capsys.readouterr().out))

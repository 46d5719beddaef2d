"""An interrupt is never lost, even when its exception is swallowed (issue 27, item 2).

The command line's handler notes the signal before it raises; numpy swallows
an exception raised while it looks up ``__array_ufunc__`` (``out ==
Outcome.CAUGHT`` on an IntEnum), and any ``except BaseException`` would
too. Here the signal is sent inside such a swallowing block in the middle
of a run: the command must still end with exit code 130 and leave the
previous results as they were.
"""

from __future__ import annotations

import json
import signal
from pathlib import Path

import pytest

from rockfall_design.cli.program import main
from rockfall_design.optimiser.screening import Screening
from rockfall_design.report.staging import MANIFEST

ROOT = Path(__file__).resolve().parents[2]
PROJECTS = ROOT / "projects"
#: A design project that optimises in seconds (tests/data/design_small.yaml): the test is
#: about the interrupt, which the first screening of any design receives.
SMALL_DESIGN = ROOT / "tests" / "data" / "design_small.yaml"


@pytest.fixture(autouse=True)
def _ctrl_c_raises():
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def swallowed(signum: int) -> None:
    """Send ``signum`` to this process inside a block that swallows what it raises."""
    try:
        signal.raise_signal(signum)
    except BaseException:  # noqa: BLE001 - as numpy does in its ufunc lookup
        pass


def files_of(directory: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in directory.iterdir() if p.name != MANIFEST}


@pytest.mark.slow  # two optimisations of a small design: CI runs it with -m slow
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_swallowed_interrupt_during_optimise_still_stops_it(tmp_path, monkeypatch, capsys,
                                                             signum):
    project = SMALL_DESIGN
    out = tmp_path / "out"
    assert main(["optimise", str(project), "--rocks", "300", "--out", str(out), "--json"]) == 0
    before = files_of(out)
    capsys.readouterr()
    real = Screening.screen
    sent = []

    def screen(self, measures):
        if not sent:
            sent.append(signum)
            swallowed(signum)
        return real(self, measures)

    monkeypatch.setattr(Screening, "screen", screen)
    code = main(["optimise", str(project), "--rocks", "300", "--seed", "9", "--out", str(out),
                 "--json"])
    captured = capsys.readouterr()
    assert sent and code == 130, captured.err
    assert "interrupted" in captured.err and "no files were changed" in captured.err
    assert captured.err.count("\n") == 1 and "Traceback" not in captured.err
    assert files_of(out) == before
    assert json.loads(before["summary.json"])["run"]["seed"] != 9


def test_a_swallowed_interrupt_during_simulate_still_stops_it(tmp_path, monkeypatch, capsys):
    from rockfall_design.run import simulation

    out = tmp_path / "out"
    real = simulation.run_ensemble
    sent = []

    def run_ensemble(*args, **kw):
        if not sent:
            sent.append(1)
            swallowed(signal.SIGINT)
        return real(*args, **kw)

    monkeypatch.setattr(simulation, "run_ensemble", run_ensemble)
    code = main(["simulate", str(PROJECTS / "standard_slope.yaml"), "--rocks", "50",
                 "--out", str(out), "--json"])
    captured = capsys.readouterr()
    assert sent and code == 130, captured.err
    assert captured.out == ""
    assert not out.exists() or files_of(out) == {}


def test_a_swallowed_interrupt_without_files_is_still_exit_130(monkeypatch, capsys):
    from rockfall_design.run import simulation

    real = simulation.run_ensemble

    def run_ensemble(*args, **kw):
        result = real(*args, **kw)
        swallowed(signal.SIGTERM)  # after the last safe point of the run
        return result

    monkeypatch.setattr(simulation, "run_ensemble", run_ensemble)
    code = main(["simulate", str(PROJECTS / "standard_slope.yaml"), "--rocks", "20", "--json"])
    assert code == 130
    assert "interrupted" in capsys.readouterr().err


def test_the_next_command_is_not_stopped_by_an_old_interrupt(monkeypatch, capsys):
    from rockfall_design.report import interrupts

    interrupts.note_interrupt(signal.SIGINT)  # left over from an earlier command in this process
    assert main(["simulate", str(PROJECTS / "standard_slope.yaml"), "--rocks", "20",
                 "--json"]) == 0

"""The API validates its numbers as the command line does (issue 27, item 6).

Same bounds, same words, one error type that names the keyword:
``simulate(p, rocks=2.5)`` no longer runs 2 rocks, ``rocks="10"``,
``rocks=True``, ``seed=1.5`` and ``study(workers=-3)`` are refused as
``--rocks 2.5`` and ``--workers -3`` are.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import rockfall_design as rd
from rockfall_design.cli.program import main
from rockfall_design.errors import ExitCode, InputError
from rockfall_design.limits import ArgumentError, ArgumentTypeError

ROOT = Path(__file__).resolve().parents[1]
PROJECTS = ROOT / "projects"


@pytest.fixture(scope="module")
def standard():
    return rd.load_project(PROJECTS / "standard_slope.yaml")


@pytest.mark.parametrize("kw, key, problem", [
    ({"rocks": 2.5}, "rocks", "expected a whole number, got 2.5"),
    ({"rocks": "10"}, "rocks", "expected a whole number, got '10'"),
    ({"rocks": True}, "rocks", "expected a whole number, got True"),
    ({"rocks": 0}, "rocks", "expected a number >= 1, got 0"),
    ({"rocks": 2_000_000_000}, "rocks", "expected a number <= 1,000,000,000"),
    ({"seed": 1.5}, "seed", "expected a whole number, got 1.5"),
    ({"seed": -1}, "seed", "expected a seed >= 0, got -1"),
    ({"seed": "7"}, "seed", "expected a whole number, got '7'"),
])
@pytest.mark.parametrize("function", ["simulate", "check"])
def test_the_api_refuses_what_the_command_line_refuses(standard, kw, key, problem, function):
    with pytest.raises(ArgumentError) as caught:
        getattr(rd, function)(standard, **kw)
    assert caught.value.key == key
    assert problem in str(caught.value) and str(caught.value).startswith(f"{key}: ")
    assert isinstance(caught.value, InputError)
    assert caught.value.exit_code == ExitCode.BAD_INPUT


@pytest.mark.parametrize("option, value, key", [
    ("--rocks", "2.5", "rocks"), ("--rocks", "0", "rocks"), ("--seed", "-1", "seed"),
])
def test_the_same_words_on_the_command_line(standard, capsys, option, value, key):
    with pytest.raises(SystemExit) as exit_:
        main(["simulate", str(PROJECTS / "standard_slope.yaml"), option, value])
    assert exit_.value.code == 2
    cli = capsys.readouterr().err
    number = float(value) if "." in value else int(value)
    with pytest.raises(ArgumentError) as caught:
        rd.simulate(standard, **{key: number})
    # "expected a whole number" / "expected a number >= 1" in both
    assert caught.value.problem.split(", got")[0] in cli


def test_study_workers_are_checked():
    with pytest.raises(ArgumentError, match=r"^workers: expected a number of workers >= 1, "
                                            r"got -3$") as caught:
        rd.study(PROJECTS / "study_talus.yaml", workers=-3, rocks=10)
    assert caught.value.key == "workers"
    with pytest.raises(ArgumentError, match="workers"):
        rd.study(PROJECTS / "study_talus.yaml", workers=2.0, rocks=10)


def test_optimise_seed_and_rocks_are_checked():
    with pytest.raises(ArgumentError, match="^seed: "):
        rd.optimise(PROJECTS / "design_ditch_or_fence.yaml", rocks=100, seed=0.5)
    with pytest.raises(ArgumentError, match="^rocks: "):
        rd.optimise(PROJECTS / "design_ditch_or_fence.yaml", rocks=99.9)


def test_calibrate_bootstrap_is_checked_as_the_option():
    with pytest.raises(ArgumentError, match="^bootstrap: expected a number of replicates "
                                            "<= 2,000"):
        rd.calibrate(PROJECTS / "calibrate_quarry.yaml", bootstrap=10_000)


def test_numpy_integers_are_whole_numbers(standard):
    result = rd.simulate(standard, rocks=np.int64(5), seed=np.uint8(3))
    assert result.summary["rocks"] == 5 and result.summary["seed"] == 3


@pytest.mark.parametrize("kw", [{"rocks": 2.5}, {"seed": 1.5}, {"rocks": 0}, {"seed": -1},
                                {"rocks": 10.0}])
def test_a_wrong_value_is_a_value_error(standard, kw):
    """Issue 34 item 8: ``except ValueError`` in a user's script catches a refused value."""
    with pytest.raises(ValueError) as caught:
        rd.simulate(standard, **kw)
    assert isinstance(caught.value, ArgumentError)
    assert not isinstance(caught.value, TypeError)


@pytest.mark.parametrize("kw", [{"rocks": "10"}, {"seed": "7"}, {"rocks": True},
                                {"seed": [3]}])
def test_a_wrong_type_is_a_type_error(standard, kw):
    """Not a number at all: a TypeError, and still the project's own error (exit code 2)."""
    with pytest.raises(TypeError) as caught:
        rd.simulate(standard, **kw)
    assert isinstance(caught.value, ArgumentTypeError)
    assert isinstance(caught.value, ArgumentError) and isinstance(caught.value, InputError)
    assert caught.value.exit_code == ExitCode.BAD_INPUT

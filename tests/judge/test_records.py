"""The judge's records: one to_json per type, read back by from_json unchanged."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from rockfall_design.api import check, load_project
from rockfall_design.judge.evaluation import protect_record
from rockfall_design.judge.records import (
    CheckSummary,
    DesignVerdict,
    ProtectRecord,
    State,
    run_of,
)
from rockfall_design.judge.verdict import verdict_of
from rockfall_design.run.summary import RunSummary

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def checked():
    project = load_project(ROOT / "projects" / "quarry_fence_ditch.yaml")
    return check(project, rocks=120, seed=7)


def test_a_check_summary_is_its_record_and_reads_back_key_for_key(checked):
    record = checked.record
    assert isinstance(record, CheckSummary) and record.verdict is not None
    d = checked.summary
    assert d == record.to_json()
    again = CheckSummary.from_json(json.loads(json.dumps(d)))
    # Key order too: summary.json and --json print it as it is.
    assert json.dumps(again.to_json()) == json.dumps(d)
    # The run seen through the check carries the judge's residual, as the JSON does.
    assert run_of(record).protect == record.protect
    assert run_of(d).protect.reaching == record.protect.reaching
    run = RunSummary.from_json(checked.run.summary())
    assert json.dumps(run.to_json()) == json.dumps(checked.run.summary())


def test_the_verdict_is_reached_from_the_record_and_carries_its_confidence(checked):
    record = checked.record
    verdict = verdict_of(record)
    assert verdict == record.verdict == checked.verdict
    assert isinstance(verdict.state, State) and verdict.state.value in {s.value for s in State}
    assert verdict.confidence == record.confidence == checked.evaluation.confidence
    assert DesignVerdict.from_json(verdict.to_json()) == verdict
    with pytest.raises(TypeError):
        DesignVerdict(State.FAILS, "Fails: x")  # no confidence: never a default


def test_a_state_is_its_words():
    assert [s.value for s in State] == ["holds with confidence", "holds on point values only",
                                        "fails", "untested"]
    assert State.FAILS == "fails" and json.dumps({"s": State.UNTESTED}) == '{"s": "untested"}'


@given(n=st.integers(1, 5000), share=st.floats(0, 1), allowed=st.floats(0, 0.2),
       confidence=st.sampled_from([0.9, 0.95, 0.99]))
def test_the_residual_reads_back_and_its_bounds_bracket_the_fraction(n, share, allowed,
                                                                     confidence):
    reaching = int(share * n)
    p = protect_record(100.0, reaching, n, allowed, confidence)
    assert ProtectRecord.from_json(p.to_json()) == p
    assert p.lower_fraction <= p.fraction <= p.upper_fraction
    assert p.ok == (p.fraction <= allowed)
    assert not (p.ok_with_confidence and p.fails_with_confidence)

"""What the optimiser says about designs it did not reject with confidence, and about a bare
slope that needs no measure."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from rockfall_design.judge.looks import LookResidual, LookValues
from rockfall_design.judge.sequential import Verdict, plan_looks
from rockfall_design.optimiser import settle
from rockfall_design.optimiser.alternatives import Alternative, Listed
from rockfall_design.optimiser.decide import Decision
from rockfall_design.optimiser.driver import bare_slope
from rockfall_design.optimiser.scenario import set_up
from rockfall_design.optimiser.search import Tally
from rockfall_design.optimiser.settle import FamilyDecision, proof_line
from rockfall_design.plugins.concept import Check
from rockfall_design.project import load_project_text
from rockfall_design.studies.sampling import ScenarioRun

from .test_settle_levels import fake_scenario

PROJECTS = Path(__file__).resolve().parents[2] / "projects"
#: A design project that optimises in seconds, batches of rocks on both threads included.
SMALL_DESIGN = Path(__file__).resolve().parents[1] / "data" / "design_small.yaml"


def _ditch_project(protect_x: float):
    text = (PROJECTS / "design_ditch_or_fence.yaml").read_text(encoding="utf-8")
    assert "\n  x: 120\n" in text
    text = text.replace("\n  x: 120\n", f"\n  x: {protect_x:g}\n")
    return load_project_text(text, "ditch.yaml", base_dir=PROJECTS)


@pytest.mark.parametrize(("protect_x", "holds"), [(150.0, True), (120.0, False)])
def test_a_bare_slope_that_meets_the_residual_target_is_said(registry, protect_x, holds):
    """At x = 150 m no rock of 50,000 arrives on the bare slope (the target is 0.1 %): no
    measure is needed, and the result says so; at 120 m 0.2 to 0.4 % arrive (0.6 to 0.8 %
    before the contact transition's hop criterion), above the target."""
    project = _ditch_project(protect_x)
    sc = set_up(ScenarioRun(0, {}, 11, project), registry, 4603)
    bare = bare_slope(sc)
    assert bare["holds"] is holds
    # The search rocks: at least those asked for, as many as show the target.
    assert bare["rocks"] == sc.screen.n >= 4603 and bare["x"] == protect_x
    assert (bare["upper"] <= bare["allowed"]) is holds
    if not holds:
        # The point value itself misses the target, not only its bound.
        assert bare["reaching"] > bare["rocks"] * bare["allowed"]


@dataclass
class _Design:
    cost: float
    level: int
    result: Any
    measures: list
    scenario: int = 0


def _design(cost: float, level: int, violation: float, value: float = 1.2) -> _Design:
    check = Check(name="height", value=value, target=1.0, ok=value >= 1.0, bound=0.9,
                  optimistic=1.4)
    result = SimpleNamespace(checks=[[check]], labels=[f"fence at {cost}"], residual=3,
                             violation=violation)
    return _Design(cost, level, result, [])


def _screen() -> Any:
    # rejects: the design of cost 30 fails with confidence as the screening counts its rocks.
    return SimpleNamespace(project=SimpleNamespace(protect=object()), n=4603, section=None,
                           allowed_fraction=0.001, confidence=0.99,
                           rejects=lambda checks, residual: checks[0][0].value == 0.5)


def test_cheaper_designs_a_budget_left_undecided_are_counted_and_listed_once_per_cost():
    alt = Alternative(name="fence", family=(0,))
    alt.marginal = [Listed("fence", [], ["m"], 20.0, None, None, "", decided=True)]
    skipped = [(_design(10.0, 1, 0.5), "budget"), (_design(10.0, 2, 0.1), "budget"),
               (_design(20.0, 3, 0.1), "budget"), (_design(30.0, 4, 0.1), "budget"),
               (_design(35.0, 6, 0.1, value=0.5), "budget"), (_design(50.0, 5, 0.1), "budget")]
    sc = fake_scenario(None)
    sc.screen = _screen()
    family = FamilyDecision(alt, [sc], 1, [Tally()], skipped=skipped)
    family.list_undecided(40.0)
    # Five designs are cheaper than the family's design (40); the one at 50 is not.
    assert alt.undecided == 5
    costs = [m.cost for m in alt.marginal]
    # One entry per cost, the decided marginal one at 20 kept, sorted by cost; the one
    # at 35, which fails with confidence as the screening counts it, is not listed.
    assert costs == [10.0, 20.0, 30.0]
    first = alt.marginal[0]
    assert first.decided is False and first.labels == ["fence at 10.0"]
    assert "not decided (budget)" in first.reason and "4,603 search rocks" in first.reason
    assert first.values.residual.reaching == 3
    assert first.to_json()["values"]["residual"]["reaching"] == 3
    assert alt.marginal[1].decided is True


def test_the_proof_line_names_marginal_and_undecided_designs():
    from collections import Counter

    alt = Alternative(name="fence", family=(0,))
    alt.marginal = [Listed("fence", [], [], 1.0, None, None, "", decided=True),
                    Listed("fence", [], [], 2.0, None, None, "", decided=False)]
    alt.undecided = 7
    tally = SimpleNamespace(reasons=Counter({"height": 3}), capped_levels=0, searched=False,
                            designs=12)
    text = proof_line(alt, tally, plan_looks(4603, 50000, 0.95, 0.001))
    assert "or is marginal (1) or was not decided (7) (the cheapest that may hold listed)" in text


@pytest.mark.slow
def test_the_same_seed_gives_the_same_design_on_one_thread_and_on_two(monkeypatch):
    """Bit for bit: the chosen design, its cost, the looks and what is listed as marginal."""
    import rockfall_design as rd
    from rockfall_design.engine.batching import THREADS_ENV

    runs = []
    for threads in ("1", "2"):
        monkeypatch.setenv(THREADS_ENV, threads)
        res = rd.optimise(SMALL_DESIGN, seed=11)
        s = res.summary
        s.pop("runtime_s")
        for a in s["alternatives"]:
            a.pop("wall_s", None)
        runs.append(s)
    assert runs[0] == runs[1]


class _Fixed:
    """A decider whose every decision is ``verdict`` (an evaluation with a margin of 0.1)."""

    margin = None

    def __init__(self, verdict: Verdict) -> None:
        self.verdict = verdict

    def decide(self, measures, first):
        ev = SimpleNamespace(margin=lambda: (0.1, "residual"))
        reason = "" if self.verdict is Verdict.ADMITTED else f"{self.verdict.value} here"
        return Decision(self.verdict, 4603, ev, reason, exact=1, simulated=4603)


def _across(*verdicts: Verdict) -> list[SimpleNamespace]:
    scs = [fake_scenario(_Fixed(v)) for v in verdicts]
    for j, sc in enumerate(scs):
        sc.run.index = j
        sc.screen.screen = lambda measures: SimpleNamespace(feasible=True, near=False,
                                                            violation=0.0)
    return scs


@pytest.mark.parametrize(("verdicts", "required", "verdict", "failed_in"), [
    ((Verdict.ADMITTED, Verdict.MARGINAL, Verdict.ADMITTED), 3, Verdict.MARGINAL, [1]),
    ((Verdict.ADMITTED, Verdict.MARGINAL, Verdict.ADMITTED), 2, Verdict.ADMITTED, [1]),
    ((Verdict.ADMITTED, Verdict.REJECTED, Verdict.MARGINAL), 2, Verdict.MARGINAL, [1, 2]),
    ((Verdict.REJECTED, Verdict.REJECTED, Verdict.ADMITTED), 2, Verdict.REJECTED, [0, 1]),
])
def test_a_design_across_scenarios_is_rejected_only_where_it_fails_with_confidence(
        verdicts, required, verdict, failed_in):
    """Marginal in some scenarios is not "fails in too many scenarios": the design may hold
    (it is listed, and the report says where it is marginal)."""
    d = SimpleNamespace(measures=[], scenario=0,
                        result=SimpleNamespace(feasible=True, near=False, violation=0.0))
    dec = settle.decide_in_scenarios(_across(*verdicts), required, d)
    assert dec.verdict is verdict
    assert sorted(dec.failed_in) == failed_in
    assert dec.exact == sum(p is not None for p in dec.per_scenario)
    if verdict is not Verdict.ADMITTED:
        assert all(f"scenario {j}:" in dec.reason for j in failed_in)
        assert dec.values is None  # one set of values per scenario: none for the design


def test_a_residual_of_nothing_is_said_at_once(registry):
    """An allowed residual of 0 can never be shown with confidence: the optimiser says so
    instead of 'no design of this family fits on the section', and searches nothing."""
    from rockfall_design.optimiser import optimise

    text = (PROJECTS / "design_ditch_or_fence.yaml").read_text(encoding="utf-8")
    assert "residual: {fraction: 0.001}" in text
    project = load_project_text(text.replace("residual: {fraction: 0.001}",
                                             "residual: {fraction: 0}"), "zero.yaml",
                                base_dir=PROJECTS)
    res = optimise(project, registry, rocks=200, seed=11)
    assert res.best is None and res.evaluations == 0
    assert "allows no rock to reach the protected zone" in res.reason
    assert all("allows no rock" in a.reason for a in res.alternatives)


def test_a_marginal_designs_values_are_json_whatever_its_bounds():
    """An unbounded favourable factor (demand's lower bound 0) is null, never Infinity."""
    import json
    import math

    from rockfall_design.judge.looks import look_values, rocks_to_decide

    c = Check(name="energy_factor", value=0.9, target=1.0, ok=False, bound=0.5,
              optimistic=math.inf)
    v = look_values([[c]], ["fence"], 3, 4603, 0.001, 0.99)
    json.dumps(v.to_json(), allow_nan=False)
    assert v.checks[0].optimistic is None and v.checks[0].bound == 0.5
    rocks_to_decide(v)


def _settling(monkeypatch, verdict):
    """A family that decides one design admitted on 4,603 search rocks, with the fresh check's
    verdict forced to ``verdict``."""
    values = LookValues(9206, 0.9875, [], LookResidual(12, 12 / 9206, 6e-4, 2.2e-3, 1e-3))
    fresh = SimpleNamespace(results=[], checks=[], residual=SimpleNamespace(reaching=12),
                            failures=lambda: [], statements=lambda: [],
                            margin=lambda: (0.1, "residual"))
    calls = []

    def verify_fresh(project, registry, measures, concept, *, rocks, seed, max_rocks,
                     margin=None, bare=None):
        calls.append((rocks, seed, max_rocks))
        return Decision(verdict, rocks * 2, fresh, "" if verdict is Verdict.ADMITTED else
                        "marginal: neither holds nor fails", looks=2, exact=2,
                        simulated=rocks * 2, values=values)

    class _Admits:
        margin = None

        def decide(self, measures, first):
            return Decision(Verdict.ADMITTED, 4603, fresh, looks=1, exact=1, simulated=4603)

    monkeypatch.setattr(settle, "verify_fresh", verify_fresh)
    alt = Alternative(name="fence", family=(0,))
    family = FamilyDecision(alt, [fake_scenario(_Admits(), fresh_seed=1_000_010)], 1, [Tally()])
    design = _design(90_000.0, 0, 0.0)
    design.result.feasible, design.result.near = True, False
    return family, design, calls


def test_a_design_neither_held_nor_failed_on_fresh_rocks_is_listed_not_dropped(monkeypatch):
    """design_quarry at its own seed chose a fence at 118,500 while the 90,000 one of seeds 11
    to 15 held on the point values of its fresh rocks but not with its bound: it was dropped as
    failing, and the report did not name it. The fresh check is sequential now (up to
    design.max_rocks); a design still undecided there is listed as marginal."""

    family, design, calls = _settling(monkeypatch, Verdict.MARGINAL)
    assert family.decide(design) is False
    assert calls == [(9206, 1_000_010, 50_000)]  # twice the deciding rocks, up to the cap
    (entry,) = family.alt.marginal
    assert entry.cost == 90_000.0 and entry.decided is True
    assert "admitted on 4,603 search rocks; on fresh rocks" in entry.reason
    assert family.tallies[0].reasons["marginal on fresh rocks"] == 1
    assert not family.alt.holds_on_fresh_rocks and family.alt.rejected == 0
    assert family.simulated == 4603 + 18_412


def test_a_design_that_fails_on_fresh_rocks_with_confidence_is_rejected(monkeypatch):

    family, design, _ = _settling(monkeypatch, Verdict.REJECTED)
    assert family.decide(design) is False
    assert family.alt.marginal == [] and family.alt.rejected == 1
    assert family.tallies[0].reasons["fails with confidence on fresh rocks"] == 1


def test_a_design_that_holds_on_fresh_rocks_records_the_fresh_look_that_decided(monkeypatch):

    family, design, _ = _settling(monkeypatch, Verdict.ADMITTED)
    assert family.decide(design) is True
    alt = family.alt
    assert alt.holds_on_fresh_rocks and alt.cost == 90_000.0
    assert alt.fresh_rocks == 18_412 and alt.fresh_seed == 1_000_010
    assert alt.decision_rocks == 4603


class _Rejects:
    """Every design it decides fails with confidence (on 4,603 rocks)."""

    margin = None

    def __init__(self) -> None:
        self.decided: list[float] = []

    def decide(self, measures, first):
        self.decided.append(float(first.labels[0].split()[-1]))
        return Decision(Verdict.REJECTED, 4603, None, reason="fails", exact=1,
                        simulated=4603, values={})


def _contender(cost: float) -> _Design:
    """A design that meets its targets on the point values of the search rocks."""
    d = _design(cost, int(cost), 0.0)
    d.result.feasible, d.result.point_ok, d.result.near = False, True, True
    return d


@pytest.mark.parametrize("as_generator", [False, True])
def test_designs_left_once_the_decisions_are_used_up_are_listed_not_dropped(
        monkeypatch, as_generator):
    """design_ditch_or_fence at seed 11: the ditch family spent its 40 decisions on ditches of
    23,418 to 28,099, and the stream was cut there; the 29,551 ditch that seeds 12 to 15
    choose or name was never decided and never listed, and the run chose a 67,500 fence.
    The rest of the stream is now counted and listed (one per cost), and a stream of
    barriers, which screens as it is read, is read only as far as a listing can reach."""
    monkeypatch.setattr(settle, "MAX_EXACT_PER_FAMILY", 2)
    monkeypatch.setattr(settle, "MAX_UNDECIDED_LISTED", 3)
    decider = _Rejects()
    sc = fake_scenario(decider)
    sc.screen, sc.looks = _screen(), plan_looks(4603, 50000, 0.95, 0.001)
    alt = Alternative(name="ditch", family=(1,))
    family = FamilyDecision(alt, [sc], 1, [Tally()])
    costs = [10.0, 11.0, 12.0, 12.0, 13.0, 14.0, 15.0, 16.0]
    read: list[float] = []

    def stream():
        for c in costs:
            read.append(c)
            yield _contender(c)

    family.settle(stream() if as_generator else [_contender(c) for c in costs])
    assert decider.decided == [10.0, 11.0]
    # Not one of them dropped unsaid: the cheapest three costs are listed as not decided.
    listed = [m.cost for m in alt.marginal if not m.decided]
    assert listed == [12.0, 13.0, 14.0]
    assert all("decisions were used up" in m.reason for m in alt.marginal)
    # Read up to the first design past three listable costs; the rest left unread.
    assert alt.undecided == 4 and family.unread
    if as_generator:
        assert read == costs[:7]
    assert "was not decided (4 or more)" in family.proof()


def test_a_stream_read_to_its_end_says_how_many_were_not_decided(monkeypatch):
    monkeypatch.setattr(settle, "MAX_EXACT_PER_FAMILY", 1)
    sc = fake_scenario(_Rejects())
    sc.screen = _screen()
    alt = Alternative(name="ditch", family=(1,))
    family = FamilyDecision(alt, [sc], 1, [Tally()])
    family.settle([_contender(c) for c in (10.0, 20.0, 20.0)])
    assert alt.undecided == 2 and not family.unread
    assert [m.cost for m in alt.marginal] == [20.0]

"""How the decisions of a family's screened designs are spent (optimiser.settle.FamilyDecision)."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

from rockfall_design.judge.looks import LookValues
from rockfall_design.judge.sequential import Verdict
from rockfall_design.optimiser.alternatives import Alternative
from rockfall_design.optimiser.decide import Decision
from rockfall_design.optimiser.search import Tally
from rockfall_design.optimiser.settle import FamilyDecision


def fake_scenario(decider: Any, *, sizes: tuple[int, ...] = (4603, 9206, 50_000),
                  fresh_seed: int = 1) -> SimpleNamespace:
    """A scenario that decides with ``decider`` and has no rocks of its own (the section as
    written: index 0, no values)."""
    run = SimpleNamespace(index=0, values={}, seed=0,
                          head=lambda: {"index": 0, "values": {}, "seed": 0})
    return SimpleNamespace(run=run,
                           project=None, concept=None,
                           # its screening rejects every design it is asked about
                           screen=SimpleNamespace(registry=None, section=None,
                                                  rejects=lambda c, r: True),
                           spec=SimpleNamespace(fresh_rocks=None),
                           looks=SimpleNamespace(sizes=sizes), decider=decider,
                           fresh_seed=fresh_seed)


class _Marginal:
    """Every design it decides runs to max_rocks undecided."""

    margin = None

    def __init__(self) -> None:
        self.decided: list[str] = []

    def decide(self, measures, first):
        self.decided.append(first.labels[0])
        values = LookValues(50_000, 0.95, [], None)
        return Decision(Verdict.MARGINAL, 50_000, None, reason="marginal", exact=1,
                        simulated=50_000, values=values)


def _design(label: str, level: tuple, cost: float = 339_000.0):
    result = SimpleNamespace(labels=[label], feasible=False, near=True, point_ok=True,
                             checks=[[]], residual=0, violation=0.0)
    return SimpleNamespace(measures=[], result=result, cost=cost, level=level, scenario=0)


def test_a_level_with_a_marginal_placement_spends_no_more_rocks_on_its_neighbours():
    # design_two_zones at seed 11 decided three fences of one catalogue
    # combination at 136.5, 137 and 137.5 m, 50,000 rocks each, all marginal.
    decider = _Marginal()
    family = FamilyDecision(Alternative(name="fence", family=(0,)), [fake_scenario(decider)], 1,
                            [Tally()])
    designs = [_design("fence at 136.5 m", (0, 3)), _design("fence at 137 m", (0, 3)),
               _design("fence at 120 m", (0, 4), cost=352_000.0)]
    assert family.settle(designs) == 100_000
    assert decider.decided == ["fence at 136.5 m", "fence at 120 m"]
    (skipped, why), = family.skipped
    assert skipped.result.labels == ["fence at 137 m"]
    assert "marginal at max_rocks" in why
    assert [m.cost for m in family.alt.marginal if m.decided] == [339_000.0, 352_000.0]

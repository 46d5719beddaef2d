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



def _fence(registry, x: float, height: float):
    fence = registry.measures["fence"]
    return fence(fence.Params(**{**fence.example, "x": x, "height": height}))


def _placed(measure, label: str, level: tuple, scenario: int, cost: float = 339_000.0):
    d = _design(label, level, cost)
    d.measures, d.scenario = [measure], scenario
    return d


def test_across_scenarios_a_combination_is_one_level_whichever_search_found_it(registry):
    # Each scenario's search numbers its levels itself: the same fence found by
    # two searches (level ids 3 and 7) is one combination, and once a placement
    # of it runs to max_rocks marginal, the other search's placement is not
    # decided (design_ditch_or_fence across three scenarios at seed 14 spent
    # the family's 40 decisions on cheap ditches so, and chose a fence).
    decider = _Marginal()
    scenarios = [fake_scenario(decider), fake_scenario(decider)]
    for sc in scenarios:  # in the other scenario the design passes the screening too
        sc.screen.screen = lambda measures: SimpleNamespace(
            labels=["(the other scenario)"], feasible=False, near=True, violation=0.0,
            point_ok=True, checks=[[]], residual=0)
    family = FamilyDecision(Alternative(name="fence", family=(0,)), scenarios, 2,
                            [Tally(), Tally()])
    designs = [_placed(_fence(registry, 136.5, 3.0), "3 m at 136.5 m", (3,), 0),
               _placed(_fence(registry, 137.0, 3.0), "3 m at 137 m", (7,), 1),
               _placed(_fence(registry, 120.0, 4.0), "4 m at 120 m", (3,), 1, cost=352_000.0)]
    family.settle(designs)
    assert family.decisions == 2  # the 3 m fence at 136.5 m and the 4 m one
    (skipped, why), = family.skipped
    assert skipped.result.labels == ["3 m at 137 m"]
    assert "marginal at max_rocks" in why


def test_without_station_tells_placements_from_designs(registry):
    a, b = _fence(registry, 100.0, 3.0), _fence(registry, 112.5, 3.0)
    assert a.without_station() == b.without_station()
    assert _fence(registry, 100.0, 4.0).without_station() != a.without_station()

"""How the decisions of a family's screened designs are spent (optimiser.section._settle)."""

from __future__ import annotations

from types import SimpleNamespace

from rockfall_design.judge.sequential import Verdict
from rockfall_design.optimiser.alternatives import Alternative
from rockfall_design.optimiser.decide import Decision
from rockfall_design.optimiser.search import _Tally
from rockfall_design.optimiser.section import _SettleState


class _Marginal:
    """Every design it decides runs to max_rocks undecided."""

    def __init__(self) -> None:
        self.decided: list[str] = []

    def decide(self, measures, first):
        self.decided.append(first.labels[0])
        values = {"rocks": 50_000, "confidence": 0.95, "checks": [], "residual": None}
        return Decision(Verdict.MARGINAL, 50_000, None, reason="marginal", exact=1,
                        simulated=50_000, values=values)


def _design(label: str, level: tuple, cost: float = 339_000.0):
    result = SimpleNamespace(labels=[label], feasible=False, point_ok=True, checks=[[]],
                             residual=0, violation=0.0)
    return SimpleNamespace(measures=[], result=result, cost=cost, level=level)


def test_a_level_with_a_marginal_placement_spends_no_more_rocks_on_its_neighbours():
    # design_two_zones at seed 11 decided three fences of one catalogue
    # combination at 136.5, 137 and 137.5 m, 50,000 rocks each, all marginal.
    decider = _Marginal()
    state = _SettleState(Alternative(name="fence", family=(0,)), _Tally(), decider, None, None,
                         fresh_seed=1)
    assert not state.decide(_design("fence at 136.5 m", (0, 3)))
    assert not state.decide(_design("fence at 137 m", (0, 3)))
    assert not state.decide(_design("fence at 120 m", (0, 4), cost=352_000.0))
    assert decider.decided == ["fence at 136.5 m", "fence at 120 m"]
    (skipped, why), = state.skipped
    assert skipped.result.labels == ["fence at 137 m"]
    assert "marginal at max_rocks" in why
    assert state.simulated == 100_000
    assert [m["cost"] for m in state.alt.marginal] == [339_000.0, 352_000.0]

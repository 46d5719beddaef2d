"""The plan of a run (measures placed, safety concept, design) is resolved once per command."""

from __future__ import annotations

from typing import ClassVar

from pydantic import Field

import rockfall_design as rd
from rockfall_design import Barrier, BarrierBehaviour, MeasureParams, ProtectiveMeasure
from rockfall_design.judge.plan import plan_for
from rockfall_design.testing import make_registry, tiny_slope


class _CountingParams(MeasureParams):
    height: float = Field(2.0, gt=0, description="net height (m)")


class CountingNet(ProtectiveMeasure):
    """A net that counts how often the program asks for its footprint."""

    kind = "counting_net"
    Params = _CountingParams
    example: ClassVar[dict] = {"x": 40.0, "height": 2.0}
    asked: ClassVar[int] = 0

    def footprint(self, section):
        CountingNet.asked += 1
        return Barrier(x=self.params.x, height_m=self.params.height, capacity_kj=500.0,
                       behaviour=BarrierBehaviour.NET)

    def design_properties(self):
        return {"height_m": self.params.height, "capacity_kj": 500.0}


def test_check_asks_a_measure_for_its_footprint_once():
    registry = make_registry(CountingNet)
    project = tiny_slope({"type": "counting_net", "x": 40.0}, registry=registry)
    CountingNet.asked = 0
    result = rd.check(project, rocks=5, registry=registry)
    assert result.evaluation.placed[0].footprint.x == 40.0
    # tiny_slope validated the project: check reuses that plan.
    assert CountingNet.asked == 0


def test_a_plan_belongs_to_one_project_and_one_registry():
    registry = make_registry(CountingNet)
    project = tiny_slope({"type": "counting_net", "x": 40.0}, registry=registry)
    plan = plan_for(project, registry)
    assert plan_for(project, registry) is plan
    assert plan.measures[0].params.x == 40.0 and plan.protect_x is None
    # A copy with other measures (as the optimiser's design_project makes) is planned anew.
    moved = project.model_copy(update={"measures": [{"type": "counting_net", "x": 45.0}]})
    assert plan_for(moved, registry).measures[0].params.x == 45.0
    # So is the same project with other plugins.
    other = make_registry(CountingNet)
    assert plan_for(project, other) is not plan

"""Designs checked across the scenarios of a study: the run behind ``check --scenarios``.

Every scenario of the project's ``study:`` section is checked with its own
rocks (its values set, its own seed, as ``rockfall-design study`` runs it),
on this process or on the study's executors; the command's printing, files
and report are in :mod:`rockfall_design.cli.scenario_commands`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ..judge.evaluation import evaluate
from ..judge.plan import validate_plugin_sections
from ..judge.verdict import UNTESTED, DesignVerdict, verdict_of_scenarios, with_verdict
from ..plugins import default_registry
from ..project.study import values_text
from ..run.summary import ReachSummary
from .executors import run_tasks
from .sampling import required_scenarios, scenario_runs

if TYPE_CHECKING:  # pragma: no cover
    from ..plugins import Registry
    from ..project import Project

__all__ = ["Binding", "ScenarioCheck", "ScenariosCheck", "check_across"]


@dataclass(frozen=True)
class Binding:
    """The scenario that binds a design across scenarios.

    Attributes
    ----------
    index : int
        The scenario's index.
    values : dict
        Its values, keyed as under ``vary:``.
    seed : int
        Its rock seed.
    margin : float or None
        Its margin: the least relative slack of a check or of the residual
        with the confidence bounds in place (-), negative where it fails;
        None with nothing to check.
    binds_at : str or None
        The check or zone the margin is at.
    """

    index: int
    values: dict[str, Any]
    seed: int
    margin: float | None
    binds_at: str | None

    def to_json(self) -> dict[str, Any]:
        """``index``, ``values``, ``seed``, ``margin``, ``binds_at``."""
        return {"index": self.index, "values": self.values, "seed": self.seed,
                "margin": self.margin, "binds_at": self.binds_at}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Binding:
        """The binding scenario from its JSON (or from a scenario's block)."""
        return cls(int(data["index"]), data["values"], int(data["seed"]), data["margin"],
                   data["binds_at"])


@dataclass(frozen=True)
class ScenarioCheck:
    """One scenario's check in ``check --scenarios``.

    Attributes
    ----------
    binding : Binding
        The scenario's index, values, seed, margin and where it binds.
    ok : bool
        Every check holds on its point value.
    holds_with_confidence : bool
        Every check holds with its confidence bound.
    rocks : int
        Rocks of the scenario's run.
    failures : tuple of str
        One line per failed check.
    check : dict
        ``check --json`` in that scenario (its verdict first), as printed.
    """

    binding: Binding
    ok: bool
    holds_with_confidence: bool
    rocks: int
    failures: tuple[str, ...]
    check: dict[str, Any]

    @classmethod
    def of(cls, head: Mapping[str, Any], slack: float, what: str | None,
           check: dict[str, Any]) -> ScenarioCheck:
        """A scenario's check from its head (index, values, seed), margin and check JSON."""
        margin = round(slack, 4) if math.isfinite(slack) else None
        return cls.from_json({**head, "margin": margin, "binds_at": what, **check})

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> ScenarioCheck:
        """The check from its entry of ``scenarios`` in ``check --scenarios --json``."""
        head = ("index", "values", "seed", "margin", "binds_at")
        return cls(Binding.from_json(data), bool(data["ok"]),
                   bool(data["holds_with_confidence"]), int(data["rocks"]),
                   tuple(data.get("failures", ())),
                   {k: v for k, v in data.items() if k not in head})

    @property
    def reaching(self) -> int | None:
        """Rocks of the scenario's run reaching the protected zone; None without one."""
        protect = self.check.get("protect")
        return None if not protect else ReachSummary.from_json(protect).reaching

    def to_json(self) -> dict[str, Any]:
        """The entry of ``scenarios``: the scenario's keys, then its ``check --json``."""
        return {**self.binding.to_json(), **self.check}


@dataclass(frozen=True)
class ScenariosCheck:
    """What ``check --scenarios`` found (:func:`check_across`).

    Attributes
    ----------
    verdict : DesignVerdict
        Over the scenarios (:func:`~rockfall_design.judge.verdict.verdict_of_scenarios`).
    rocks : int
        Rocks of every scenario.
    seed : int
        The run seed the scenarios' seeds derive from.
    share : float
        ``design.scenarios``' share (1: every scenario).
    required : int
        Scenarios the design must hold in.
    of : int
        Scenarios checked.
    holds_in, holds_with_confidence_in : int
        Scenarios it holds in, on point values and with confidence.
    ok : bool
        It holds in the required scenarios (and was tested).
    binding : Binding
        The scenario of the ``required``-th largest margin.
    failures : list of str
        One line per failed check, naming the scenario.
    scenarios : list of ScenarioCheck
    """

    verdict: DesignVerdict
    rocks: int
    seed: int
    share: float
    required: int
    of: int
    holds_in: int
    holds_with_confidence_in: int
    ok: bool
    binding: Binding
    failures: list[str]
    scenarios: list[ScenarioCheck]

    def to_json(self) -> dict[str, Any]:
        """The JSON object of ``check --scenarios --json``."""
        return {
            "verdict": self.verdict.as_dict(), "rocks": self.rocks, "seed": self.seed,
            "share": self.share, "required": self.required, "of": self.of,
            "holds_in": self.holds_in, "holds_with_confidence_in": self.holds_with_confidence_in,
            "ok": self.ok, "binding": self.binding.to_json(), "failures": self.failures,
            "scenarios": [p.to_json() for p in self.scenarios]}


def _check_task(task: tuple[Any, int | None, tuple[str, ...]]) -> ScenarioCheck:
    """One scenario's check (a task for a pool or a cluster): its JSON block and margin.

    ``task`` is (scenario run, rocks, blocked plugins); the plugins are
    loaded where the task runs, as the command loads them.
    """
    run, rocks, block = task
    ev = evaluate(run.project, default_registry(block), rocks=rocks)
    return ScenarioCheck.of(run.head(), *ev.margin(), with_verdict(ev.summary()))


def check_across(project: Project, registry: Registry, *, rocks: int | None = None,
                 seed: int | None = None, block: tuple[str, ...] = (),
                 workers: int | None = 1, scheduler: Any = None) -> ScenariosCheck:
    """Check the project's measures in every scenario of its study (see the module's text).

    Parameters
    ----------
    project
        With a ``study:`` section (and ``measures:`` to check).
    registry
        The plugins.
    rocks
        Rocks of every scenario (default ``rocks.count``).
    seed
        The run seed the scenarios' seeds derive from (default ``rocks.seed``).
    block
        Plugins not loaded (``--block``), where the scenarios run.
    workers, scheduler
        Where the scenarios run (see
        :func:`rockfall_design.studies.executors.run_tasks`): 1 (the default
        here) in this process with ``registry``, N on a local pool of N
        processes (None: one per core), or on the Dask cluster of
        ``scheduler``; the numbers are the same wherever they run.

    Returns
    -------
    ScenariosCheck
        Its ``to_json()`` is the JSON object of ``check --scenarios --json``.
    """
    runs = scenario_runs(project, seed)
    for run in runs:  # every scenario's plugin sections, before anything runs
        validate_plugin_sections(run.project, registry)
    share = project.design.scenario_share if project.design is not None else None
    share = 1.0 if share is None else share
    required = required_scenarios(share, len(runs))
    if scheduler is None and workers == 1:
        def one(run: Any) -> ScenarioCheck:
            ev = evaluate(run.project, registry, rocks=rocks)
            return ScenarioCheck.of(run.head(), *ev.margin(), with_verdict(ev.summary()))

        per = [one(run) for run in runs]
    else:
        per = run_tasks(_check_task, [(run, rocks, tuple(block)) for run in runs],
                        workers=workers, scheduler=scheduler)
    holds = sum(p.ok for p in per)
    # The binding scenario decides the required count: the one of the required-th
    # largest margin (with every scenario required, the least margin). Below it are
    # the scenarios a share allows the design to fail in.
    ranked = sorted((p.binding for p in per),
                    key=lambda b: (-(math.inf if b.margin is None else b.margin),
                                   -b.index))  # ties: the first scenario binds
    failures = [f"scenario {p.binding.index} ({values_text(p.binding.values)}): {f}"
                for p in per for f in p.failures]
    verdict = verdict_of_scenarios([p.to_json() for p in per], required)
    return ScenariosCheck(
        verdict=verdict, rocks=per[0].rocks,
        seed=int(project.rocks.seed if seed is None else seed), share=share,
        required=required, of=len(per), holds_in=holds,
        holds_with_confidence_in=sum(p.holds_with_confidence for p in per),
        ok=holds >= required and verdict.state != UNTESTED,
        binding=ranked[min(required, len(ranked)) - 1], failures=failures, scenarios=per)

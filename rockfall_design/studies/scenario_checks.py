"""Designs checked across the scenarios of a study: the run behind ``check --scenarios``.

Every scenario of the project's ``study:`` section is checked with its own
rocks (its values set, its own seed, as ``rockfall-design study`` runs it),
on this process or on the study's executors; the command's printing, files
and report are in :mod:`rockfall_design.cli.scenario_commands`.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from ..judge.evaluation import evaluate
from ..judge.plan import validate_plugin_sections
from ..judge.verdict import UNTESTED, verdict_of_scenarios, with_verdict
from ..plugins import default_registry
from ..report.sections import values_text
from .executors import run_tasks
from .scenarios import required_scenarios, scenario_runs

if TYPE_CHECKING:  # pragma: no cover
    from ..plugins import Registry
    from ..project import Project


def _check_task(task: tuple[Any, int | None, tuple[str, ...]]) -> dict[str, Any]:
    """One scenario's check (a task for a pool or a cluster): its JSON block and margin.

    ``task`` is (scenario run, rocks, blocked plugins); the plugins are
    loaded where the task runs, as the command loads them.
    """
    run, rocks, block = task
    ev = evaluate(run.project, default_registry(block), rocks=rocks)
    slack, what = ev.margin()
    return {**run.head(), "margin": round(slack, 4) if math.isfinite(slack) else None,
            "binds_at": what, **with_verdict(ev.summary())}


def check_across(project: Project, registry: Registry, *, rocks: int | None = None,
                 seed: int | None = None, block: tuple[str, ...] = (),
                 workers: int | None = 1, scheduler: Any = None) -> dict[str, Any]:
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
    dict
        The JSON object of ``check --scenarios --json``.
    """
    runs = scenario_runs(project, seed)
    for run in runs:  # every scenario's plugin sections, before anything runs
        validate_plugin_sections(run.project, registry)
    share = project.design.scenario_share if project.design is not None else None
    share = 1.0 if share is None else share
    required = required_scenarios(share, len(runs))
    if scheduler is None and workers == 1:
        def one(run: Any) -> dict[str, Any]:
            ev = evaluate(run.project, registry, rocks=rocks)
            slack, what = ev.margin()
            return {**run.head(), "margin": round(slack, 4) if math.isfinite(slack) else None,
                    "binds_at": what, **with_verdict(ev.summary())}

        per = [one(run) for run in runs]
    else:
        per = run_tasks(_check_task, [(run, rocks, tuple(block)) for run in runs],
                        workers=workers, scheduler=scheduler)
    holds = sum(bool(p["ok"]) for p in per)
    # The binding scenario decides the required count: the one of the required-th
    # largest margin (with every scenario required, the least margin). Below it are
    # the scenarios a share allows the design to fail in.
    ranked = sorted(per, key=lambda p: (-(math.inf if p["margin"] is None else p["margin"]),
                                        -p["index"]))  # ties: the first scenario binds
    bind = ranked[min(required, len(ranked)) - 1]
    failures = [f"scenario {p['index']} ({values_text(p['values'])}): {f}"
                for p in per for f in p.get("failures", [])]
    verdict = verdict_of_scenarios(per, required)
    return {
        "verdict": verdict.as_dict(),
        "rocks": int(per[0]["rocks"]),
        "seed": int(project.rocks.seed if seed is None else seed),
        "share": share,
        "required": required,
        "of": len(per),
        "holds_in": holds,
        "holds_with_confidence_in": sum(bool(p["holds_with_confidence"]) for p in per),
        "ok": holds >= required and verdict.state != UNTESTED,
        "binding": {k: bind[k] for k in ("index", "values", "seed", "margin", "binds_at")},
        "failures": failures,
        "scenarios": per,
    }

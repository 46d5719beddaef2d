"""Designs across the scenarios of a study: ``check --scenarios`` and the optimiser's report.

``check --scenarios`` checks the project's measures in every scenario of its
``study:`` section, each scenario with its own rocks (its values set, its own
seed, as ``rockfall-design study`` runs it), and says in how many the design
holds against how many it must (``design.scenarios``: ``all``, the default,
or ``{share: S}``, at least ``ceil(S k)`` of ``k``) and which scenario binds.
A scenario's margin is the smallest relative slack of a check or of the
residual with the confidence bounds in place, negative where it fails; the
binding scenario is the one that decides the required count, the one of the
``required``-th largest margin: with every scenario required, the least
margin; with a share, the scenarios of smaller margins are those the share
lets the design fail in.

``--json`` prints ``rocks``, ``seed`` (the run seed), ``share``,
``required``, ``of``, ``holds_in``, ``holds_with_confidence_in``, ``ok``,
``binding`` (``index``, ``values``, ``seed``, ``margin``, ``binds_at``),
``failures`` (one line per failed check, naming the scenario) and
``scenarios``: per scenario ``index``, ``values``, ``seed``, ``margin``,
``binds_at`` and the JSON of ``check`` in that scenario. ``--plot`` draws the
binding scenario's figures (as ``check --plot`` draws them) and the margin of
every scenario (:func:`~rockfall_design.report.design_figures.margins_figure`);
``--report`` writes the report of every scenario and the binding one in full
(:class:`ScenariosCheckResult`, rendered by :mod:`rockfall_design.report.documents`).

For ``optimise`` with ``design.scenarios`` (see
:mod:`rockfall_design.optimiser.driver`) this module prints the scenario
lines of the report and writes ``design.yaml``.
"""

from __future__ import annotations

import argparse
import json
import sys
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..api import check, check_across, scenario_runs
from ..errors import ExitCode
from ..project import dump_yaml
from ..project.study import values_text
from ..report.outputs import OutputSet
from ..report.terminal import fitted_console
from ..results import DEFAULT_TRAJECTORIES, Binding, ScenariosCheck
from .common import REPORT_FILES, figure_files, figures_and_report, reserve

if TYPE_CHECKING:  # pragma: no cover
    from ..optimiser.alternatives import AcrossOutcome
    from ..plugins import Registry
    from ..project import Project
    from ..report.outputs import OutputSet

__all__ = ["check_across", "cli_check_scenarios", "across_design_yaml", "print_across",
           "ScenariosCheckResult", "SCENARIO_FIGURES", "check_scenarios_with_files",
           "print_check_across"]


def _binding_text(b: Binding) -> str:
    """Where a binding scenario binds: its margin and check, or that nothing binds."""
    return ("no check to bind" if b.margin is None else
            f"margin {100 * b.margin:+.1f} % at {b.binds_at}")


def print_check_across(check: ScenariosCheck) -> None:
    """The terminal report of ``check --scenarios``: a row per scenario, the verdict."""
    from rich.table import Table


    table = Table(show_edge=False)
    for col, just in (("#", "right"), ("values", "left"), ("seed", "right"),
                      ("holds", "left"), ("with conf.", "left"), ("margin", "right"),
                      ("binds at", "left")):
        table.add_column(col, justify=just)
    for p in check.scenarios:
        b = p.binding
        table.add_row(str(b.index), values_text(b.values), str(b.seed),
                      "yes" if p.ok else "NO", "yes" if p.holds_with_confidence else "no",
                      "-" if b.margin is None else f"{100 * b.margin:+.1f} %",
                      b.binds_at or "-",
                      style="" if p.ok else "red")
    console = fitted_console(table)
    v = check.verdict  # the verdict first, in the words of every report
    console.print(v.headline, style="bold green" if v.state == "holds with confidence"
                  else "bold red" if v.state == "fails" else "bold yellow",
                  markup=False, highlight=False)
    console.print(f"check over {check.of} scenarios, {check.rocks:,} rocks each, "
                  f"run seed {check.seed}", style="bold", markup=False, highlight=False)
    console.print(table)
    b = check.binding
    console.print(f"Binding scenario {b.index} ({values_text(b.values)}): " + _binding_text(b),
                  markup=False, highlight=False)
    verdict = (f"Design holds in {check.holds_in} of {check.of} scenarios; "
               f"required: {check.required}")
    console.print(verdict, style="bold green" if check.ok else "bold red", markup=False,
                  highlight=False)
    for line in check.failures:
        console.print("  " + line, style="dim", markup=False, highlight=False)


#: The figures of ``check --scenarios --plot``: the binding scenario's three and the margins.
SCENARIO_FIGURES = ("profile", "envelopes", "stops", "margins")


class ScenariosCheckResult:
    """What ``check --scenarios`` found, for its figures and report.

    Attributes
    ----------
    project : Project
        The project as written (with its ``study:``).
    check : ScenariosCheck
        What :func:`check_across` found.
    """

    command = "check"
    #: The report shows every scenario, then the binding one in full.
    across = True

    def __init__(self, project: Project, check: ScenariosCheck, registry: Registry) -> None:
        self.project = project
        self.check = check
        self._registry = registry

    @cached_property
    def summary(self) -> dict[str, Any]:
        """The JSON of ``check --scenarios --json``, which the report is rendered from."""
        return self.check.to_json()

    @cached_property
    def binding_check(self) -> Any:
        """The binding scenario checked again in this process, keeping paths for the figures.

        Its own project (the study's values set) and its own seed and rocks:
        the same rocks as in :func:`check_across`, so the same numbers.
        """

        found = self.check
        run = next(r for r in scenario_runs(self.project, found.seed)
                   if r.index == found.binding.index)
        return check(run.project, rocks=int(found.rocks), seed=run.seed,
                     trajectories=DEFAULT_TRAJECTORIES, registry=self._registry)

    def plot_margins(self) -> Any:
        """A bar per scenario: the margin, the binding scenario, the count required."""
        # Drawn only for --plot and --report: the drawing module imports matplotlib
        # (a fifth of a second) at its top, as it subclasses its Figure.
        from ..report.design_figures import margins_figure


        c = self.check
        return margins_figure([p.to_json() for p in c.scenarios], c.required, c.binding.index,
                              self.project.name)

    def figures(self) -> dict[str, Any]:
        """The binding scenario's profile, envelopes and stops, and the margins, by name."""
        return {**self.binding_check.figures(), "margins": self.plot_margins()}


def reserve_scenarios_files(files: OutputSet, args: argparse.Namespace) -> None:
    """Reserve the files of ``check --scenarios`` (``--out``, ``--plot``, ``--report``)."""

    reserve(files, args.out, ("summary.json",))
    reserve(files, args.report, REPORT_FILES)
    reserve(files, args.plot, figure_files(SCENARIO_FIGURES, args))


def check_scenarios_with_files(project: Project, args: argparse.Namespace, registry: Registry,
                               files: OutputSet) -> ScenariosCheck:
    """Check ``project`` in every scenario and put its files in the output set.

    ``args`` gives ``rocks``, ``seed``, ``block``, ``workers``,
    ``scheduler`` and the directories ``out`` (``summary.json``), ``plot``
    (:data:`SCENARIO_FIGURES` in every ``--plot-format``) and ``report``.
    Returns what :func:`check_across` found.
    """

    found = check_across(project, registry, rocks=args.rocks, seed=args.seed,
                         block=tuple(args.block), workers=args.workers,
                         scheduler=args.scheduler)
    result = ScenariosCheckResult(project, found, registry)
    if args.out:
        files.write_json(args.out / "summary.json", result.summary)
    figures_and_report(result, args, files)
    return found


def cli_check_scenarios(args: argparse.Namespace, project: Project, registry: Registry) -> int:
    """``check --scenarios``: exit 0 when the design holds in the required scenarios, else 1."""

    if project.study is None:
        raise project.error_at((), "check --scenarios needs a study: section (its scenarios)")
    with OutputSet() as files:
        reserve_scenarios_files(files, args)
        found = check_scenarios_with_files(project, args, registry, files)
    if args.json:
        sys.stdout.write(json.dumps(found.to_json(), allow_nan=False) + "\n")
    else:
        print_check_across(found)
    return int(ExitCode.OK if found.ok else ExitCode.CHECK_FAILED)


def print_across(result: AcrossOutcome) -> None:
    """The scenario lines of the optimiser's report: where the chosen design binds."""
    from rich.text import Text


    block = result.scenarios_block()
    lines = [f"Scenarios: a design must hold in {result.required} of {len(result.runs)} "
             f"(design.scenarios share {result.share:g}), each with its own rocks."]
    if result.best is not None and block["binding"] is not None:
        b = Binding.from_json(block["binding"])
        lines.append(f"Binding scenario {b.index} ({values_text(b.values)}, seed "
                     f"{b.seed}): " + _binding_text(b))
        nxt = block["next_cheaper"]
        if nxt is not None:
            lines.append(f"The next cheaper design ({nxt['cost']:,.0f}) fails in scenario(s) "
                         f"{', '.join(map(str, nxt['failed_in'])) or '-'}: {nxt['reason']}")
    text = Text("\n".join(lines))
    fitted_console(text).print(text)


def across_design_yaml(result: AcrossOutcome, project_file: Path | str,
                       project: Project) -> str:
    """design.yaml of a design across scenarios: ``check --scenarios`` checks it as decided.

    The project as written (its ``study:`` and ``design:`` sections, the
    catalogues inline) with the chosen measures; ``rocks.seed`` is the run
    seed the scenarios' seeds derive from and ``rocks.count`` the most rocks
    that decided the design in a scenario.
    """

    best = result.best
    assert best is not None and best.evaluation is not None
    ev = best.evaluation
    data = project.resolved_dict()
    data["rocks"]["count"] = int(best.decision_rocks or result.rocks)
    data["rocks"]["seed"] = int(result.seed)
    # the residual target as the protected zone's allowance, as the optimiser judged it
    data["protect"] = ev.run.project.resolved_dict()["protect"]
    data["measures"] = [{"type": m.kind, **m.params.model_dump(mode="json")}
                        for m in best.measures]
    data["safety"] = {"concept": ev.concept.name, **ev.concept.params.model_dump(mode="json")}
    # The project's confidence, not the look's (as design_yaml: a check is one look).
    data["safety"]["confidence"] = float(result.confidence)
    block = result.scenarios_block()
    b = Binding.from_json(block["binding"])
    head = (
        f"# Chosen by rockfall-design optimise from {project_file}: {best.name}, "
        f"cost {best.cost:,.0f}, holding in {result.required} of {len(result.runs)} scenarios "
        "of the study.\n"
        f"# Each scenario has its own rocks: seeds derived from rocks.seed ({result.seed}); "
        f"rocks.count is the most rocks that decided it in a scenario.\n"
        f"# binding scenario {b.index} ({values_text(b.values)}): " + _binding_text(b) + "\n"
        "# verification: each scenario's fresh rocks (its seed + 1000003, twice its rocks) "
        "held.\n"
        "# check it in every scenario with: rockfall-design check design.yaml --scenarios\n"
    )
    return head + dump_yaml(data)

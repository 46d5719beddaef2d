"""The result of a study: its JSON summary, tables, figures and terminal report.

:class:`StudyResult` is what :func:`rockfall_design.study` returns and what
``rockfall-design study`` prints (``--json``: :attr:`StudyResult.summary`),
writes (``--out``: scenarios.csv and summary.json) and draws (``--plot``:
the envelopes of every scenario on one figure, and a tornado chart).
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..project import Project
from ..project.messages import fmt
from ..report.figures import DEFAULT_MIN_ROCKS_ENVELOPE, RockfallFigure, save_figures
from ..report.terminal import fitted_console
from ..version import __version__
from .sampling import Scenario
from .scenario_result import ScenarioResult
from .sensitivity import SensitivityEntry, joint_bounds, rank, relative_effect, targets

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd
    from matplotlib.figure import Figure
    from rich.console import Console

__all__ = ["StudyResult", "FIGURES"]

#: The figures of a study (``--plot``), by file stem.
FIGURES = ("study_envelopes", "tornado")
#: Scenarios drawn with their values in the legend of the envelopes; more get a colour scale.
_LEGEND_SCENARIOS = 12
#: Targets drawn in the tornado chart (the ones whose inputs move them most).
_TORNADO_TARGETS = 4


def _text(value: Any) -> str:
    """A varied value for a table cell or a legend: numbers as written, the rest as JSON."""
    if isinstance(value, bool | int | float | str):
        return fmt(value)
    return json.dumps(value, sort_keys=True)



def envelope_percentile(project: Project) -> float:
    """The percentile of the study's envelope figure: p95 if configured, else the highest."""
    pcts = [float(q) for q in project.analysis.percentiles]
    return 95.0 if 95.0 in pcts or not pcts else max(pcts)

class StudyResult:
    """The scenarios of a parametric study, their results and the sensitivity.

    Attributes
    ----------
    project : Project
        The study's project (with its ``study:`` section).
    scenario_list : list of Scenario
        Index, values and seed of each scenario.
    results : list of ScenarioResult
        Each scenario's result (:func:`~rockfall_design.studies.runner.run_scenario`).
    seed : int
        The run's seed, from which each scenario's seed was derived.
    runtime_s : float
        Wall time of the whole study (s).
    """

    def __init__(self, project: Project, scenario_list: Sequence[Scenario],
                 results: Sequence[ScenarioResult], seed: int, runtime_s: float,
                 sensitivity: list[SensitivityEntry]) -> None:
        self.project = project
        self.scenario_list = list(scenario_list)
        self.results = list(results)
        self.seed = int(seed)
        self.runtime_s = float(runtime_s)
        #: The sensitivity's entries, in the one order of ``--json`` (:func:`~.sensitivity.rank`).
        self.entries = list(sensitivity)

    def __repr__(self) -> str:
        return (f"<StudyResult {self.project.name!r}: {len(self.results)} scenarios of "
                f"{self.n_rocks:,} rocks, seed {self.seed}>")

    @property
    def n_rocks(self) -> int:
        """Rocks per scenario."""
        return int(self.results[0].rocks) if self.results else 0

    @cached_property
    def summary(self) -> dict[str, Any]:
        """The dict that ``study --json`` prints.

        ``project``, ``version``, ``seed`` (the run's), ``rocks`` (per
        scenario), ``project_hash``, ``vary``, ``sampling`` and ``seeds`` (the
        study section, resolved), ``runtime_s``, ``scenarios`` (each with
        ``index``, ``seed``, ``values`` keyed exactly as under ``vary:``,
        ``rocks``, ``events``, ``project_hash`` of the scenario's project,
        and ``stations``, ``stops``, ``protect`` as ``simulate --json``, and
        ``measures`` for the barriers, and ``bounds``: ``confidence`` c,
        ``upper`` and ``lower``, the one-sided upper and lower confidence
        bound at c of each design value by name, and ``joint``: its
        ``confidence`` and the ``lower`` and ``upper`` bounds of the
        intervals that hold for all scenarios together at c, from which the
        sensitivity's intervals come), ``sensitivity`` (see
        :func:`~rockfall_design.studies.sensitivity.sensitivity`) and
        ``sensitivity_confidence``, the c at which its ``effect_low`` ..
        ``effect_high`` hold (None if no scenario has bounds).
        """
        study = self.project.resolved_dict()["study"]
        joint = joint_bounds(self.results)
        scenarios = []
        for k, (scenario, result) in enumerate(zip(self.scenario_list, self.results,
                                                   strict=True)):
            block = {"index": scenario.index, "seed": scenario.seed,
                     "values": dict(scenario.values)}
            mine = None if joint is None else {"confidence": joint.scenario_confidence,
                                               "lower": joint.lower[k], "upper": joint.upper[k]}
            # the ladder is the run's working: the bounds used show
            block.update(result.to_json(ladder=False, envelope=False, head=False, joint=mine))
            scenarios.append(block)
        return {
            "project": self.project.name,
            "version": __version__,
            "seed": self.seed,
            "rocks": self.n_rocks,
            "project_hash": self.project.resolved_hash(),
            "runtime_s": round(self.runtime_s, 6),
            "vary": study["vary"],
            "sampling": study["scenarios"],
            "seeds": study["seeds"],
            "scenarios": scenarios,
            "sensitivity": [e.to_json() for e in self.entries],
            "sensitivity_confidence": None if joint is None else joint.confidence,
        }

    @property
    def sensitivity_confidence(self) -> float | None:
        """The confidence c of the sensitivity's ``effect_low`` .. ``effect_high``."""
        joint = joint_bounds(self.results)
        return None if joint is None else float(joint.confidence)

    @property
    def sensitivity(self) -> pd.DataFrame:
        """One row per (parameter, target), as the JSON's entries, and the ``confidence``.

        Columns: parameter, target, effect, unit, low, high, effect_low,
        effect_high (empty where there is no interval), resolved (True: the
        effect is more than Monte Carlo noise at the confidence), confidence
        (:attr:`sensitivity_confidence`), and S1, S1_conf for a sampled study.
        """
        import pandas as pd

        cols = ["parameter", "target", "effect", "unit", "low", "high", "effect_low",
                "effect_high", "resolved", "confidence"]
        frame = pd.DataFrame([e.to_json() for e in self.entries])
        if frame.empty:
            return pd.DataFrame(columns=cols)
        if "resolved" in frame.columns:
            frame.insert(int(frame.columns.get_loc("resolved")) + 1, "confidence",
                         self.sensitivity_confidence)
        return frame

    @property
    def scenarios(self) -> pd.DataFrame:
        """One row per scenario: index, seed, the varied values, then every design value.

        Each design value ``x=100 energy_kj p95`` is followed (after all of
        them) by ``x=100 energy_kj p95 upper``, its one-sided upper confidence
        bound, then (after all of those) by ``x=100 energy_kj p95 lower``,
        its one-sided lower one (NaN where too few rocks passed to bound it;
        see ``bounds`` in the summary).
        """
        import pandas as pd


        table = targets(self.results)
        rows = []
        for k, scenario in enumerate(self.scenario_list):
            row: dict[str, Any] = {"index": scenario.index, "seed": scenario.seed}
            for path, value in scenario.values.items():
                row[path] = value if isinstance(value, bool | int | float | str) else \
                    json.dumps(value, sort_keys=True)
            for name, (_, values) in table.items():
                row[name] = values[k]
            for side in ("upper", "lower"):
                bounds = self.results[k].bounds
                given = bounds.upper if side == "upper" else bounds.lower
                for name in table:
                    if name in given:
                        bound = given[name]
                        row[f"{name} {side}"] = math.nan if bound is None else bound
            rows.append(row)
        return pd.DataFrame(rows)

    # ---- figures -------------------------------------------------------------------
    def plot_envelopes(self) -> Figure:
        """Envelopes of passing height and energy along x, every scenario on one figure."""
        from matplotlib import colormaps


        if any(result.envelope is None for result in self.results):
            raise ValueError("this study ran without its envelopes (envelopes=False); run it "
                             "again with envelopes=True to draw them")
        analysis = self.project.analysis
        min_rocks = int(getattr(analysis, "min_rocks_envelope", DEFAULT_MIN_ROCKS_ENVELOPE))
        q = envelope_percentile(self.project)
        label = f"p{q:g}"
        col = f"p{q:g}".replace(".", "_")
        fig = RockfallFigure(figsize=(11, 7.5), layout="constrained")
        a1, a2 = fig.subplots(2, 1, sharex=True)
        n = len(self.results)
        colors = colormaps["viridis"](np.linspace(0.05, 0.95, max(n, 1)))
        for scenario, result, color in zip(self.scenario_list, self.results, colors,
                                           strict=False):
            env = result.envelope
            assert env is not None  # checked above
            x = np.asarray(env["x_m"], dtype=float)
            enough = np.asarray(env["crossings"]) >= min_rocks
            name = ", ".join(f"{_short(p)}={_text(v)}" for p, v in scenario.values.items())
            for ax, key in ((a1, f"height_{col}_m"), (a2, f"energy_{col}_kj")):
                y = np.where(enough, np.asarray(env.get(key, [np.nan] * x.size), dtype=float),
                             np.nan)
                ax.plot(x, y, color=color, lw=1.0,
                        label=f"{scenario.index}: {name}" if n <= _LEGEND_SCENARIOS else None)
        for ax in (a1, a2):
            ax.grid(alpha=0.3)
        if n <= _LEGEND_SCENARIOS:
            a1.legend(loc="upper right", fontsize=7)
        if n > _LEGEND_SCENARIOS:
            from matplotlib.cm import ScalarMappable
            from matplotlib.colors import Normalize

            fig.colorbar(ScalarMappable(Normalize(0, n - 1), colormaps["viridis"]),
                         ax=[a1, a2], label="scenario index")
        a1.set_ylabel(f"passing height {label} (m)")
        a2.set_ylabel(f"kinetic energy {label} (kJ)")
        a2.set_xlabel("x (m)")
        a1.set_title(f"{self.project.name}: {label} envelopes of {n} scenarios, "
                     f"{self.n_rocks:,} rocks each (drawn where at least {min_rocks} pass)")
        return fig

    def plot_tornado(self) -> Figure:
        """Tornado chart: for the targets moved most, each input's range of level means."""
        entries = self.entries
        chosen: list[str] = []
        for e in entries:  # the targets, most moved first (relative to their own size)
            if e.target not in chosen and (e.target.endswith(" p95") or _is_residual(e.target)):
                chosen.append(e.target)
        chosen.sort(key=lambda t: -max(relative_effect(e) for e in entries if e.target == t))
        chosen = chosen[:_TORNADO_TARGETS]
        fig = RockfallFigure(figsize=(10, 2.2 + 1.9 * max(len(chosen), 1)),
                             layout="constrained")
        if not chosen:
            ax = fig.subplots()
            ax.text(0.5, 0.5, "no design value changed between the scenarios",
                    ha="center", va="center", transform=ax.transAxes)
            ax.set_axis_off()
            return fig
        axes = np.atleast_1d(fig.subplots(len(chosen), 1))
        for ax, target in zip(axes, chosen, strict=True):
            rows = sorted((e for e in entries if e.target == target), key=lambda e: e.effect)
            names = [e.parameter + ("" if e.resolved else " *") for e in rows]
            lows = np.array([e.low for e in rows])
            highs = np.array([e.high for e in rows])
            resolved = [e.resolved for e in rows]
            ax.barh(names, highs - lows, left=lows, color=["#2980b9" if r else "#95a5a6"
                                                          for r in resolved], alpha=0.8)
            # The interval of each bar's length (the effect), drawn from its left end:
            # the bar's right end could lie anywhere on the error bar.
            ends = [(k, e) for k, e in enumerate(rows)
                    if e.effect_low is not None and e.effect_high is not None]
            if ends:
                at = np.array([lows[k] + e.effect for k, e in ends])
                spread = np.array([[e.effect - (e.effect_low or 0.0) for _, e in ends],
                                   [(e.effect_high or 0.0) - e.effect for _, e in ends]])
                ax.errorbar(at, [k for k, _ in ends], xerr=np.clip(spread, 0.0, None), fmt="none",
                            ecolor="black", elinewidth=1.0, capsize=3)
            for k, e in enumerate(rows):
                right = e.high if e.effect_high is None else max(e.high, e.low + e.effect_high)
                ax.text(right, k, f"  {_number(e.effect, e.unit)}", va="center", fontsize=8)
            ax.margins(x=0.15)
            unit = rows[0].unit if rows else ""
            ax.set_title(f"{target} ({unit})", fontsize=9, loc="left")
            ax.grid(axis="x", alpha=0.3)
        c = self.sensitivity_confidence
        axes[-1].set_xlabel("range of the level means of each input; error bar: where its "
                            f"end may lie at {_percent(c)} (Monte Carlo noise); * grey: not "
                            "resolved from the noise")
        fig.suptitle(f"{self.project.name}: which input moves each design value")
        return fig

    def figures(self) -> dict[str, Figure]:
        """The study's figures by name (:data:`FIGURES`)."""
        return {"study_envelopes": self.plot_envelopes(), "tornado": self.plot_tornado()}

    def save_figures(self, directory: str | os.PathLike[str],
                     formats: Sequence[str] = ("png",)) -> list[Path]:
        """Write :meth:`figures` into ``directory``, one file per figure and format."""
        return save_figures(self.figures(), directory, formats)

    # ---- terminal --------------------------------------------------------------------
    def print(self, console: Console | None = None, top: int = 20) -> None:
        """The study as rich tables: the scenarios, and the sensitivity ranking."""
        from rich.table import Table
        from rich.text import Text


        rate = len(self.results) * self.n_rocks / self.runtime_s if self.runtime_s else 0.0
        head = Text.assemble(
            (self.project.name, "bold"),
            f"   {len(self.results)} scenarios x {self.n_rocks:,} rocks, seed {self.seed}, "
            f"{self.runtime_s:.1f} s ({rate:,.0f} rocks/s)",
        )
        frame = self.scenarios
        paths = list(self.scenario_list[0].values) if self.scenario_list else []
        shown = [c for c in frame.columns if c.endswith(" p95") or _is_residual(c)][:6]
        table = Table(title="Scenarios", show_edge=False, title_justify="left")
        for col in ["#", *paths, *shown]:
            table.add_column(col, justify="right")
        for k, scenario in enumerate(self.scenario_list):
            cells = [str(scenario.index), *(_text(scenario.values[p]) for p in paths)]
            cells += [_number(float(frame[c].iloc[k]), _unit(c)) for c in shown]
            table.add_row(*cells)
        ranked = Table(title="Which input moves each design value (per design value, the "
                       "largest effect first; the design values moved most, relative to "
                       "their size, first)", show_edge=False, title_justify="left")
        indices = any(e.s1 is not None for e in self.entries)
        c = self.sensitivity_confidence
        sure = "effect, sure" if c is None else f"effect at {_percent(c)}"
        for col in ("target", "input", "effect", sure, "level means",
                    *(("S1",) if indices else ())):
            ranked.add_column(col, justify="left" if col in ("target", "input") else "right")
        shown_entries = rank(self.entries)[:top]
        for e in shown_entries:
            unit = e.unit
            mark = "" if e.resolved else " *"
            cells = [e.target, e.parameter, f"{_number(e.effect, unit)} {unit}{mark}",
                     _interval(e), f"{_number(e.low, unit)} .. {_number(e.high, unit)}"]
            if indices:
                cells.append("-" if e.s1 is None else f"{e.s1:.2f} ± {e.s1_conf or 0.0:.2f}")
            ranked.add_row(*cells)
        from rich.console import Group

        parts: list[Any] = [head, table, ranked]
        if any(not e.resolved for e in shown_entries):
            parts.append(Text(
                f"* not resolved from Monte Carlo noise: at {_percent(c)} the effect may "
                "be 0 (its interval reaches 0), or '-': too few rocks passed to bound "
                "the design value in some scenario; more rocks, or seeds: common, may "
                "resolve it. The intervals hold for all inputs of a design value together.",
                style="dim"))
        group = Group(*parts)
        (console or fitted_console(group)).print(group)


def _short(path: str) -> str:
    """A varied input's name for a legend: its last key (with the one before an index)."""
    keys = path.replace("[", ".").replace("]", "").split(".")
    return ".".join(keys[-2:]) if keys[-1].isdigit() and len(keys) > 1 else keys[-1]


def _unit(target: str) -> str:
    """The unit of a design value by its name (see :func:`~.sensitivity.targets`)."""
    if "passing_height_m" in target:
        return "m"
    if "energy_kj" in target:
        return "kJ"
    return "fraction" if _is_residual(target) else ""


def _is_residual(target: str) -> bool:
    """A residual target: ``x=200 residual`` or ``x=200 residual, bare slope``."""
    return target.endswith(" residual") or target.endswith(" residual, bare slope")


def _number(v: Any, unit: str = "") -> str:
    """A design value as a report shows it: m to cm, kJ to 1 kJ, fractions to 4 digits."""
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    if unit == "m":
        return f"{v:,.2f}"
    if unit == "kJ":
        return f"{v:,.0f}"
    if unit == "fraction":
        return f"{v:.4f}"
    return f"{v:,.4g}"


def _percent(c: float | None) -> str:
    """A confidence as the report says it: 0.95 as 95 %, 0.975 as 97.5 %."""
    return "-" if c is None else f"{100 * c:g} %"


def _interval(entry: SensitivityEntry) -> str:
    """The interval of an effect, ``effect_low .. effect_high``, or '-' if it has none."""
    low, high, unit = entry.effect_low, entry.effect_high, entry.unit
    if low is None or high is None:
        return "-"
    return f"{_number(low, unit)} .. {_number(high, unit)}"


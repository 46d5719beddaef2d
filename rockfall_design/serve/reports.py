"""The report and figures of a check or optimise started from the page.

The command line writes ``--report DIR/report.html`` through
:func:`rockfall_design.report.documents.report_context` and
:func:`~rockfall_design.report.documents.render_html` from a result of
:mod:`rockfall_design.api`. The app may not import that module (it imports
the command line, which imports the app: an import cycle), so the two small
classes here give the report code what it reads of those results: the
project, the command, the ``--json`` summary, the evaluation, the plugins and
the figures. The HTML is then made by the same code as ``--report``.
"""

from __future__ import annotations

import io
import threading
from collections.abc import Callable
from dataclasses import replace
from functools import cached_property
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from ..judge.evaluation import Evaluation
    from ..plugins import Registry
    from ..project import Project

#: Paths drawn on the profile figure (as the command line's ``--report``).
REPORT_TRAJECTORIES = 60

#: Figure formats the page offers for download.
DOWNLOAD_FORMATS = ("png", "svg")

_MEDIA = {".html": "text/html; charset=utf-8", ".png": "image/png",
          ".svg": "image/svg+xml", ".yaml": "application/yaml", ".csv": "text/csv"}


def media_type(name: str) -> str:
    """The media type of a downloadable file, by its suffix."""
    for suffix, media in _MEDIA.items():
        if name.endswith(suffix):
            return media
    return "application/octet-stream"


class CheckReport:
    """A check's result as the report code reads it (``rockfall_design.api.CheckResult``)."""

    command = "check"

    def __init__(self, project: Project, evaluation: Evaluation, registry: Registry) -> None:
        self.project = project
        self.evaluation = evaluation
        self.study = evaluation.study
        self.registry = registry

    @cached_property
    def summary(self) -> dict[str, Any]:
        """``check --json``: the evaluation's summary, beginning with its verdict."""
        from ..judge.verdict import with_verdict

        return with_verdict(self.evaluation.summary())

    def figures(self) -> dict[str, Figure]:
        """profile, envelopes and stops, as ``check --plot`` draws them."""
        from ..report.figures import envelopes_figure, profile_figure, stops_figure

        ev = self.evaluation
        return {"profile": profile_figure(ev.study, ev),
                "envelopes": envelopes_figure(ev.study, ev, None),
                "stops": stops_figure(ev.study, ev)}


class OptimiseReport:
    """An optimisation's result as the report code reads it
    (``rockfall_design.api.OptimiseResult``): the alternatives and the chosen
    design, checked again on the search rocks with paths for the figures."""

    command = "optimise"

    def __init__(self, project: Project, result: Any, registry: Registry) -> None:
        self.project = project
        self.result = result
        self._registry = registry

    @cached_property
    def best(self) -> dict[str, Any] | None:
        return None if self.result.best is None else self.result.best.as_dict()

    @cached_property
    def design(self) -> CheckReport | None:
        """The chosen design checked on the search rocks (None without one)."""
        if self.best is None:
            return None
        from ..judge.evaluation import evaluate

        p = self.project
        d = p.design
        allowed = d.residual_fraction
        if allowed is None:
            allowed = (d.residual_count or 0) / max(int(self.result.rocks), 1)
        project = p.model_copy(update={
            "measures": [dict(m) for m in self.best["measures"]],
            "protect": p.protect.model_copy(update={"allowed_fraction": allowed})})
        ev = evaluate(project, self._registry, rocks=int(self.result.rocks),
                      seed=int(self.result.seed), n_trajectories=REPORT_TRAJECTORIES)
        return CheckReport(project, ev, self._registry)

    @cached_property
    def summary(self) -> dict[str, Any]:
        """``optimise --json``: the verdict on the chosen design, then the optimiser's summary
        and the chosen design's bill."""
        from ..judge.verdict import FAILS, HOLDS_ON_POINT_VALUES, DesignVerdict, verdict_of

        res = self.result
        best = res.best
        if best is None:
            verdict = DesignVerdict(FAILS, "Fails: no admissible design: "
                                    f"{res.reason or 'no family meets the targets'}",
                                    confidence=float(res.confidence))
            bill = None
        else:
            assert self.design is not None
            verdict = verdict_of(self.design.summary)
            if best.holds_on_fresh_rocks is False and verdict.holds:
                verdict = replace(
                    verdict, state=HOLDS_ON_POINT_VALUES,
                    headline="Holds on point values only: admitted on its deciding rocks, but "
                    f"it does not hold on {best.fresh_rocks:,} fresh rocks (seed "
                    f"{best.fresh_seed}).", details=(*best.fresh_failures, *verdict.details))
            bill = self._bill()
        return {"verdict": verdict.as_dict(), **res.summary(), "bill": bill}

    def _bill(self) -> dict[str, Any]:
        from ..optimiser.design_spec import design_bill, resolve_design
        from ..run.releases import section_from_project

        d = self.project.design
        source = f"catalogue {d.costs.file}" if d.costs.file else "design.costs.params"
        bill = design_bill(self._registry, resolve_design(self.project, self._registry),
                           self.result.best.measures, section_from_project(self.project),
                           source)
        return {**bill, "currency": self.result.currency or ""}

    def figures(self) -> dict[str, Figure]:
        """The alternatives, and the chosen design's profile, envelopes and stops."""
        from ..report.figures import alternatives_figure

        s = self.summary
        out = {"alternatives": alternatives_figure(s["alternatives"], s["best_name"],
                                                   s.get("currency", ""), self.project.name)}
        if self.design is not None:
            out.update(self.design.figures())
        return out


def report_files(result: CheckReport | OptimiseReport) -> dict[str, bytes]:
    """``report.html`` (as ``--report`` writes it) and every figure as PNG and SVG."""
    from ..report.documents import render_html, report_context

    figures = result.figures()  # drawn once, for the report and the downloads
    files = {"report.html": render_html(report_context(result, figures)).encode("utf-8")}
    for name, fig in figures.items():
        for fmt in DOWNLOAD_FORMATS:
            buf = io.BytesIO()
            # The settings of --plot: the same figure as the command line's file.
            meta = {"svg": {"Date": None}}.get(fmt, {})
            fig.savefig(buf, format=fmt, dpi=150, bbox_inches="tight", metadata=meta)
            files[f"{name}.{fmt}"] = buf.getvalue()
    return files


def report_names(result: CheckReport | OptimiseReport) -> list[str]:
    """The names :func:`report_files` will give, without drawing anything."""
    names = ["profile", "envelopes", "stops"]
    if isinstance(result, OptimiseReport):
        names = ["alternatives"] + (names if result.result.best is not None else [])
    return ["report.html"] + [f"{n}.{f}" for n in names for f in DOWNLOAD_FORMATS]


def lazy_files(result: CheckReport | OptimiseReport) -> dict[str, Callable[[], bytes]]:
    """A loader per file of :func:`report_names`: drawn together on the first request."""
    cache: dict[str, bytes] = {}
    lock = threading.Lock()

    def loader(name: str) -> Callable[[], bytes]:
        def load() -> bytes:
            with lock:
                if not cache:
                    cache.update(report_files(result))
            return cache[name]
        return load

    return {name: loader(name) for name in report_names(result)}

"""Figures of a design search: the alternatives, and the margins across scenarios.

matplotlib Figures, no pyplot, as :mod:`.figures` draws them.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, MaxNLocator

from .figures import RockfallFigure

if TYPE_CHECKING:  # pragma: no cover

    pass


def _slack(value: float, target: float, relation: str, unit: str) -> float:
    """How far a check's value stands from its target on the safe side, relative (-).

    ``relation`` ``">="`` (a safety factor) or ``"<="`` (a design value
    against a limit, a braking distance, a probability); a check that names
    none is taken as a factor when it is one (unit ``"-"``), else as a limit.
    """
    at_least = relation == ">=" or (not relation and unit == "-")
    return value / target - 1.0 if at_least else 1.0 - value / target


def _binding(checks: Sequence[Mapping[str, Any]]) -> str:
    """The check closest to its target (a failing one first): 'height 2.05/2.00'."""
    best: tuple[float, str] | None = None
    for c in checks:
        v, t = c.get("value"), c.get("target")
        if v is None or t is None or not t:
            continue
        name = str(c.get("name", "")).removesuffix("_factor")
        margin = (_slack(float(v), float(t), str(c.get("relation") or ""),
                         str(c.get("unit") or "-")) if c.get("ok", True) else -math.inf)
        text = f"{name} {float(v):.2f}/{float(t):.2f}" + ("" if c.get("ok", True) else " fails")
        if best is None or margin < best[0]:
            best = (margin, text)
    return "" if best is None else best[1]


def alternatives_figure(
    alternatives: Sequence[Mapping[str, Any]],
    best: str | None = None,
    currency: str = "",
    title: str = "",
) -> Figure:
    """A bar per family: its cost, residual rocks and the check that binds or fails.

    Parameters
    ----------
    alternatives : sequence of dict
        The optimiser's alternatives as in its summary (``name``, ``cost``,
        ``feasible``, ``residual``, ``checks``, ``reason``; other keys ignored).
    best : str, optional
        The name of the chosen family (marked).
    currency : str
        The cost model's currency, for the axis label.
    title : str
        A title (e.g. the project's name).

    Returns
    -------
    matplotlib.figure.Figure
    """
    rows = sorted(alternatives, key=lambda a: (not a.get("feasible"),
                                               math.inf if a.get("cost") is None
                                               else a["cost"]))
    texts = [_wrapped(_bar_note(a, currency)) for a in rows]
    # Each family takes as many lines as its note: every label in full, nothing cut.
    heights = [max(1, t.count("\n") + 1) for t in texts]
    ys, y = [], 0.0
    for h in heights:
        ys.append(y + 0.5 * (h - 1) * _LINE)
        y += 1.0 + (h - 1) * _LINE
    fig = RockfallFigure(figsize=(11, 1.4 + 0.5 * max(y, 1.0)), layout="constrained")
    ax, notes = fig.subplots(1, 2, sharey=True, width_ratios=[1, 1.25])
    notes.axis("off")
    finite = [a["cost"] for a in rows if a.get("cost") is not None]
    top = max(finite) if finite else 1.0
    for a, yi, text in zip(rows, ys, texts, strict=True):
        cost = a.get("cost")
        chosen = best is not None and a.get("name") == best
        color, hatch = (("#1e8449" if chosen else "#7dcea0"), None) if a.get("feasible") \
            else ("#d5d8dc", "//")
        width = cost if cost is not None else 0.0
        ax.barh(yi, width, color=color, hatch=hatch, edgecolor="#566573", height=0.6)
        # The note in a panel of its own right of the bars: no bar runs under it, and
        # the layout gives it its width.
        notes.text(0.0, yi, text, va="center", ha="left", fontsize=8, linespacing=1.25,
                   transform=notes.get_yaxis_transform())
    ax.set_yticks(ys, [("* " if best is not None and a.get("name") == best else "") +
                       str(a.get("name", "?")) for a in rows], fontsize=9)
    ax.set_ylim(y - 0.4, -0.6)
    ax.set_xlim(0, top * 1.05)
    ax.spines[["right", "top"]].set_visible(False)
    # Three ticks in thousands where costs run to six digits: four full numbers
    # ran into each other under a narrow panel.
    ax.xaxis.set_major_locator(MaxNLocator(3))
    thousands = top >= 1e4
    ax.xaxis.set_major_formatter(FuncFormatter(
        lambda v, _: f"{v / 1e3:,.0f}" if thousands else f"{v:,.0f}"))
    unit = ("thousand " if thousands else "") + currency
    ax.set_xlabel(f"cost ({unit.strip()})" if unit.strip() else "cost")
    ax.grid(axis="x", alpha=0.3)
    head = "cheapest design of each family; * chosen, hatched: not admissible"
    ax.set_title(f"{title}: {head}" if title else head, loc="left")
    if not rows:
        ax.text(0.5, 0.5, "no alternatives", transform=ax.transAxes, ha="center")
    return fig


#: Height of a note's further line, in rows (the bars are 1 apart).
_LINE = 0.42

#: Characters per line of a family's note on the alternatives figure.
_NOTE_WIDTH = 95


def _bar_note(a: Mapping[str, Any], currency: str) -> str:
    """A family's note: its cost, the rocks reaching the zone, what binds, or why not."""
    cost = a.get("cost")
    note = [] if cost is None else [f"{cost:,.0f} {currency}".strip()]
    if a.get("residual") is not None:
        k = int(a["residual"])
        note.append(f"{k} {'rock' if k == 1 else 'rocks'} reach the protected zone")
    if a.get("feasible"):
        bind = _binding(a.get("checks") or [])
        if bind:
            note.append(f"binding: {bind}")
        if a.get("holds_on_fresh_rocks") is False:
            note.append("fails on fresh rocks")
    else:
        note.append(str(a.get("reason") or "not admissible"))
    return "; ".join(note)


def _wrapped(text: str) -> str:
    """The note over lines of :data:`_NOTE_WIDTH` characters (all of it: nothing cut)."""
    return "\n".join(textwrap.wrap(text, _NOTE_WIDTH, break_long_words=False)) or text


def _short_paths(paths: Sequence[str]) -> dict[str, str]:
    """Each varied path by its shortest ending of at least two parts that no other shares.

    'materials.talus.restitution' -> 'talus.restitution', 'rocks.volume.lognormal.0'
    -> 'lognormal.0': the scenario labels stay short and still say which input.
    """
    out = {}
    for path in paths:
        parts = path.split(".")
        for n in range(min(2, len(parts)), len(parts) + 1):
            tail = ".".join(parts[-n:])
            if not any(o != path and (o == tail or o.endswith("." + tail)) for o in paths):
                break
        out[path] = tail
    return out


def _scenario_label(index: int, values: Mapping[str, Any], short: Mapping[str, str],
                    width: int = 60) -> str:
    """'#2 talus.restitution = 0.3, ...' shortened to ``width`` characters."""
    text = ", ".join(f"{short.get(k, k)} = {v}" for k, v in values.items()) or "as written"
    if len(text) > width:
        text = text[:width - 3] + "..."
    return f"#{index} {text}"


def margins_figure(
    scenarios: Sequence[Mapping[str, Any]],
    required: int,
    binding: int | None = None,
    title: str = "",
) -> Figure:
    """A bar per scenario: the design's margin, the binding scenario, the count required.

    Parameters
    ----------
    scenarios : sequence of dict
        The scenarios of ``check --scenarios --json`` (``index``, ``values``,
        ``margin`` (a fraction, None without a check), ``binds_at``, ``ok``,
        ``holds_with_confidence``; other keys ignored).
    required : int
        Scenarios the design must hold in.
    binding : int, optional
        The index of the binding scenario (marked).
    title : str
        A title (e.g. the project's name).

    Returns
    -------
    matplotlib.figure.Figure
        Top: a horizontal bar per scenario, its margin in % (green where the
        design holds on the point values, hatched where not with the
        confidence bounds, red where it fails). Bottom: one cell per
        scenario, those it holds in first, and a line at the count required.
    """
    k = len(scenarios)
    fig = RockfallFigure(figsize=(10, 2.2 + 0.42 * max(k, 1)), layout="constrained")
    ax, strip = fig.subplots(2, 1, height_ratios=[max(k, 1) * 0.42, 0.7])
    margins = [None if p.get("margin") is None else 100.0 * float(p["margin"])
               for p in scenarios]
    finite = [abs(m) for m in margins if m is not None]
    span = max(finite) if finite else 1.0
    span = span if span > 0 else 1.0
    for i, (p, m) in enumerate(zip(scenarios, margins, strict=True)):
        bind = binding is not None and p.get("index") == binding
        if not p.get("ok"):
            color, hatch = "#e6b0aa", None
        else:
            color = "#1e8449" if bind else "#7dcea0"
            hatch = None if p.get("holds_with_confidence") else "//"
        width = 0.0 if m is None else m
        ax.barh(i, width, color=color, hatch=hatch, height=0.6,
                edgecolor="#1b2631" if bind else "#566573", linewidth=2.0 if bind else 0.8)
        note = "no check to bind" if m is None else f"{m:+.1f} %  {p.get('binds_at') or ''}"
        if bind:
            note += "   (binding)"
        ax.text(max(width, 0.0) + 0.02 * span, i, note.rstrip(), va="center", fontsize=8)
    ax.axvline(0.0, color="#1b2631", lw=1.0)
    short = _short_paths(list(dict.fromkeys(k for p in scenarios for k in p.get("values") or {})))
    ax.set_yticks(range(k), [("* " if binding is not None and p.get("index") == binding
                              else "") + _scenario_label(int(p.get("index", i)),
                                                         p.get("values") or {}, short)
                             for i, p in enumerate(scenarios)], fontsize=8)
    ax.invert_yaxis()
    low = min([m for m in margins if m is not None] + [0.0])
    ax.set_xlim(low - 0.1 * span, span * 2.2)
    ax.set_xlabel("margin (%): least relative slack with the confidence bounds in place")
    ax.grid(axis="x", alpha=0.3)
    head = "design margin per scenario; * binding (decides the count required)"
    ax.set_title(f"{title}: {head}" if title else head)
    # The count: one cell per scenario, those the design holds in first.
    holds = sum(bool(p.get("ok")) for p in scenarios)
    for j in range(k):
        strip.barh(0, 1, left=j, height=0.8, color="#7dcea0" if j < holds else "#e6b0aa",
                   edgecolor="white")
    strip.axvline(required, color="#1b2631", lw=2.0)
    strip.text(required, 0.55, f" required: {required} of {k}", va="bottom", fontsize=8)
    strip.set_xlim(0, max(k, 1) * 1.0001)
    strip.set_ylim(-0.5, 1.2)
    strip.set_yticks([])
    strip.set_xticks(range(k + 1))
    ok = holds >= required
    strip.set_xlabel(f"holds in {holds} of {k} scenarios (point values): "
                     + ("enough" if ok else "too few"))
    return fig

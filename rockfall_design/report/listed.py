"""The cheaper designs an optimisation left marginal or undecided, in words.

The terminal panel, the report's "How sure" and the head of ``design.yaml``
name them alike: each one's point values and confidence bounds, and what
would decide it, the rocks the 1/sqrt(n) trend of its look's bounds needs
(:func:`rockfall_design.judge.looks.rocks_to_decide`), to be given as
``--max-rocks``.

See Also
--------
rockfall_design.optimiser.alternatives.listed_entry : the entries themselves.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

from ..judge.records import CheckSummary, run_of
from ..run.summary import RunSummary, Share

if TYPE_CHECKING:  # pragma: no cover
    from ..optimiser.alternatives import Listed

__all__ = ["forest_text", "listed_lines", "what_decides", "values_phrase"]


#: Marginal or undecided cheaper designs the panel, the report and design.yaml show.
SHOWN = 6


def what_decides(m: Listed) -> str:
    """What would decide a listed design: the rocks it needs, or why no number says so."""
    if m.short_of_margin:
        return ("it holds with these bounds, but a checker's check would confirm it less "
                "often than design.checker_power asks, with confidence")
    if m.margin_undecided:
        return ("it holds with these bounds, but whether a checker's check would confirm "
                "it often enough (design.checker_power) is open; more rocks (--max-rocks) "
                "may decide it")
    need = m.rocks_to_decide
    if need:
        return f"about {need:,} rocks would decide it (--max-rocks {_round_up(need)})"
    if m.values is not None:
        return m.beyond_rocks or ("its point value sits on the target: no number of rocks "
                                  "is likely to decide it")
    return "more rocks (--max-rocks) may decide it"


def _round_up(n: int) -> int:
    """``n`` rounded up to two significant figures (a budget to type, not a figure)."""
    step = 10 ** max(len(str(int(n))) - 2, 0)
    return -(-int(n) // step) * step


def values_phrase(m: Listed) -> str:
    """A listed design's point values and bounds, one phrase each (see judge.looks)."""
    v = m.values
    if v is None:  # a design across scenarios: why it is undecided
        return str(m.reason)
    parts = []
    for c in v.checks:
        if c.value is None:
            continue
        rng = check_range(c.bound, c.optimistic)
        parts.append(f"{c.name} {c.value:.2f}{rng}, target {c.target:.2f}")
    r = v.residual
    if r is not None:
        parts.append(f"residual {100 * r.fraction:.3f} % ({100 * r.lower:.3f} to "
                     f"{100 * r.upper:.3f} %), allowed {100 * r.allowed:.3f} %")
    return f"on {v.rocks:,} rocks at {100 * v.confidence:.4g} %: " + ", ".join(parts)


def check_range(bound: float | None, optimistic: float | None) -> str:
    """A check's two confidence ends as " (a to b)", or the one it has, said as what it is.

    ``bound`` is the value that holds with confidence, ``optimistic`` the one
    a check would have at the other end (``plugins.concept.Check``). With too
    few rocks at a measure a percentile has a lower order-statistic bound but
    no upper one: only ``optimistic`` is known, and a range of that one value
    ("1.12 to 1.12" beside a point value of 0.66) would read as a bound.
    """
    if bound is not None and optimistic is not None:
        return f" ({min(bound, optimistic):.2f} to {max(bound, optimistic):.2f})"
    if optimistic is not None:
        return f" (at best {optimistic:.2f}; too few rocks to bound it the other way)"
    if bound is not None:
        return f" (with confidence {bound:.2f})"
    return ""


def listed_lines(marginal: Sequence[Listed] | None, currency: str = "",
                 shown: int = SHOWN) -> list[str]:
    """The cheaper designs that are marginal or not decided, one sentence each ("- ...").

    Parameters
    ----------
    marginal : sequence of Listed
        ``SearchOutcome.marginal``, cheapest first.
    currency : str
        Written after each cost.
    shown : int
        The cheapest this many are written; one line counts the rest.
    """
    marginal = list(marginal or [])
    out = []
    for m in marginal[:shown]:
        head = ("Short of the checker's margin, cheaper" if m.short_of_margin else
                "Marginal, cheaper" if m.decided else "Not decided, cheaper")
        cost = f"{m.cost:,.0f}" + (f" {currency}" if currency else "")
        out.append(f"- {head}: {m.family} {cost}: {'; '.join(m.labels)}: "
                   f"{values_phrase(m)}; {what_decides(m)}")
    if len(marginal) > shown:
        out.append(f"- ... and {len(marginal) - shown} more cheaper designs marginal or not "
                   "decided (listed under 'marginal' in --json and summary.json)")
    return out


def forest_text(summary: RunSummary | CheckSummary | Mapping[str, Any]) -> str:
    """What the forest did, with the shares' Clopper-Pearson intervals; '' without one."""
    f = run_of(summary).forest
    if f is None:
        return ""

    def share(count: int, s: Share) -> str:
        return (f"{count:,} rocks ({100 * s.fraction:.1f} %, "
                f"{100 * f.confidence:g} % interval {100 * s.lower:.1f} to "
                f"{100 * s.upper:.1f} %)")

    return (f"Forest: {share(f.met_stems, f.met_stems_share)} met at least one stem; "
            f"{share(f.stopped, f.stopped_share)} were stopped by a stem (counted among "
            "the stopped).")

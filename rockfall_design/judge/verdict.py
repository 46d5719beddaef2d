"""The verdict on a design: one of four states, in the same words everywhere.

Every report (terminal, report.html, report.md) and every ``--json`` of
``check``, ``optimise``, ``check --scenarios`` and corridors is headed by the
verdict this module gives, so that the first line a reader sees is the one
the tool stands behind:

``holds with confidence``
    Every check and the residual hold with their one-sided confidence
    bounds (``safety.confidence``) in place of their point values: the
    design the tool stands behind.
``holds on point values only``
    Every check and the residual hold on their point values, but not all
    with their bounds; the verdict says what would settle it (about how many
    rocks), or that no number of rocks can (an allowed fraction of 0).
``fails``
    A check or the residual misses its target on its point value; the
    verdict says which and by how much.
``untested``
    Nothing was tested: no measure and no protected zone, or no rock met any
    measure and there is no protected zone. A measure that no rock meets is
    listed as untested under any verdict: its checks say nothing.

The verdict is computed from a check's record
(:class:`~rockfall_design.judge.records.CheckSummary`, what
:meth:`rockfall_design.judge.evaluation.Evaluation.record` returns and whose
``to_json()`` ``check --json`` prints), so it reads the same numbers as the
report; it imports nothing from the optimiser or the study rooms.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ..plugins.concept import DEFAULT_CONFIDENCE, Check
from .bounds import fraction_upper_bound, rocks_to_show_fraction
from .records import (
    CheckSummary,
    DesignVerdict,
    MeasureRecord,
    ProtectRecord,
    State,
    check_from_json,
    check_of,
)
from .records import check_state as state_of_check

if TYPE_CHECKING:  # pragma: no cover
    from ..project import Project

__all__ = [
    "HOLDS_WITH_CONFIDENCE",
    "HOLDS_ON_POINT_VALUES",
    "FAILS",
    "UNTESTED",
    "STATES",
    "State",
    "DesignVerdict",
    "verdict_of",
    "judged",
    "with_verdict",
    "check_state",
    "verdict_of_scenarios",
    "verdict_of_sections",
    "requirement_warnings",
]

HOLDS_WITH_CONFIDENCE = State.HOLDS_WITH_CONFIDENCE
HOLDS_ON_POINT_VALUES = State.HOLDS_ON_POINT_VALUES
FAILS = State.FAILS
UNTESTED = State.UNTESTED
#: The four states, from the one the tool stands behind to the one that says nothing.
STATES = tuple(State)

#: Beyond this many rocks the verdict says "more than" instead of a count.
_MAX_ROCKS_NEEDED = 10**10


def _head(state: State, text: str) -> str:
    return f"{state[0].upper()}{state[1:]}: {text}"


def _pct(fraction: float) -> str:
    return f"{100 * fraction:.3g} %"


def _num(v: float | None, unit: str) -> str:
    if v is None:
        return "no value"
    return f"{v:,.2f}" if unit == "-" else f"{v:,.2f} {unit}"


def _miss(c: Check) -> str:
    """How far a failed check's value is from its target: 'by 0.35 (18 % of the target)'."""
    v, t = c.value, c.target
    if v is None or t is None or not math.isfinite(v) or not math.isfinite(t):
        return str(c.detail or "it has no value")
    gap = abs(v - t)
    rel = f" ({100 * gap / abs(t):.3g} % of the target)" if t else ""
    return f"by {_num(gap, c.unit)}{rel}"


def _check_rocks(c: Check, met: int, n: int) -> int | None:
    """About how many rocks in all would settle a check that holds on its point value only.

    A sample too small to bound the statistic says how many rocks must meet
    the measure (``rocks_needed``): scaled by the share of the rocks that
    meet it. Otherwise the bound's distance from the point value shrinks as
    1/sqrt(n): a value ``d`` from the target with a bound ``w`` from the
    value is settled at about ``n (w / d)**2`` rocks. None: never (the value
    sits on the target).
    """
    if c.rocks_needed and met > 0:
        return int(math.ceil(int(c.rocks_needed) * n / met))
    v, b, t = c.value, c.bound, c.target
    if v is None or b is None or t is None or not all(map(math.isfinite, (v, b, t))):
        return None
    d, w = abs(v - t), abs(b - v)
    if d <= 0.0:
        return None
    return max(n + 1, int(math.ceil(n * (w / d) ** 2)))


def residual_rocks(reaching: int, n: int, allowed: float, confidence: float) -> int | None:
    """Fewest rocks whose Clopper-Pearson bound, at the observed rate, is within ``allowed``.

    None when no number of rocks can show it: an allowed fraction of 0, or an
    observed rate at the allowance.
    """
    if allowed <= 0.0 or n <= 0:
        return None
    if reaching == 0:
        return rocks_to_show_fraction(allowed, confidence, 0)
    rate = reaching / n
    if rate >= allowed:
        return None

    def holds(m: int) -> bool:
        return fraction_upper_bound(int(math.ceil(rate * m)), m, confidence) <= allowed

    hi = max(n, 1)
    while not holds(hi):
        hi *= 2
        if hi > _MAX_ROCKS_NEEDED:
            return None
    lo = max(1, hi // 2)
    while lo < hi:
        mid = (lo + hi) // 2
        if holds(mid):
            hi = mid
        else:
            lo = mid + 1
    return hi


@dataclass
class _Findings:
    """What the verdict has found so far: failures, open items and the rocks to settle them."""

    n: int
    confidence: float
    failed: list[str] = field(default_factory=list)
    open_items: list[str] = field(default_factory=list)
    needs: list[int | None] = field(default_factory=list)

    @property
    def at(self) -> str:
        return f"{100 * self.confidence:g} %"


def _untested_verdict(summary: CheckSummary, untested: tuple[str, ...],
                      untested_lines: tuple[str, ...]) -> DesignVerdict:
    """The verdict when nothing was checked: no protected zone and no measure met."""
    if not summary.measures:
        text = ("no measure and no protected zone: nothing was checked. Add measures: "
                "to check, or protect: {x: ...} to count the rocks reaching the zone.")
    else:
        text = (f"no rock of {summary.rocks:,} reached any measure and there is no protected "
                "zone: nothing was checked. Place the measures where the rocks pass, or add "
                "protect: {x: ...}.")
    return DesignVerdict(UNTESTED, _head(UNTESTED, text), untested_lines, untested,
                         confidence=summary.confidence)


def _judge_checks(found: _Findings, m: MeasureRecord) -> None:
    """Each check of a measure: failed (and by how much) or open (and what would settle it)."""
    for c in m.checks:
        if not c.ok:
            found.failed.append(f"{m.label}: {c.name} {_num(c.value, c.unit)} misses its "
                                f"target {_num(c.target, c.unit)} {_miss(c)}")
        elif not c.holds_with_confidence:
            need = _check_rocks(c, m.met, found.n)
            found.needs.append(need)
            bound = ("cannot be bounded yet" if c.bound is None
                     else f"its {found.at} bound {_num(c.bound, c.unit)}")
            found.open_items.append(
                f"{m.label}: {c.name} {_num(c.value, c.unit)} meets its target "
                f"{_num(c.target, c.unit)}, {bound} does not"
                + (f"; about {need:,} rocks would settle it" if need else
                   "; its value sits on the target"))


def _judge_residual(found: _Findings, prot: ProtectRecord) -> None:
    """The residual: failed (rocks too many) or open (what would settle its bound)."""
    n, conf = found.n, found.confidence
    reaching, allowed = prot.reaching, prot.allowed_fraction
    where = f"the protected zone at x >= {prot.x:g} m"
    if not prot.ok:
        excess = reaching - int(math.floor(allowed * n + 1e-9))
        many = f"{excess:,} rock{'s' if excess != 1 else ''} too many"
        found.failed.append(f"{reaching:,} of {n:,} rocks ({_pct(prot.fraction)}) reach "
                            f"{where}; allowed {_pct(allowed)}: {many}")
        return
    if prot.ok_with_confidence:
        return
    need = residual_rocks(reaching, n, allowed, conf)
    found.needs.append(need)
    if allowed <= 0.0:
        settle = ("no number of rocks shows a fraction of 0: allow a fraction "
                  "(protect.allowed_fraction, design.residual), e.g. 0.001, which "
                  f"{rocks_to_show_fraction(0.001, conf, 0):,} rocks with none "
                  "reaching show")
    elif need is None:
        settle = "its rate sits on the allowance; no number of rocks settles it"
    else:
        settle = f"about {need:,} rocks at this rate would settle it"
    found.open_items.append(
        f"{reaching:,} of {n:,} rocks ({_pct(prot.fraction)}) reach {where}, "
        f"within the allowed {_pct(allowed)}, but the {found.at} upper bound "
        f"{_pct(prot.upper_fraction)} is not; {settle}")


def _summed_up(found: _Findings, untested: tuple[str, ...],
               untested_lines: tuple[str, ...]) -> DesignVerdict:
    """The verdict from what was found: fails, holds on point values only, or with confidence."""
    n, conf = found.n, found.confidence
    if found.failed:
        miss = "s miss their targets" if len(found.failed) > 1 else " misses its target"
        text = f"{len(found.failed)} requirement{miss} on {n:,} rocks."
        return DesignVerdict(FAILS, _head(FAILS, text), tuple(found.failed) + untested_lines,
                             untested, confidence=conf)
    if found.open_items:
        needs = found.needs
        need = None if any(x is None for x in needs) else max(needs, default=None)
        settle = (f" about {need:,} rocks would settle it (--rocks)." if need else
                  " no number of rocks settles it as the requirement is written.")
        text = (f"every check and the residual pass on their point values ({n:,} rocks), but "
                f"not all with their {found.at} confidence bounds;" + settle)
        return DesignVerdict(HOLDS_ON_POINT_VALUES, _head(HOLDS_ON_POINT_VALUES, text),
                             tuple(found.open_items) + untested_lines, untested, need,
                             confidence=conf)
    text = (f"every check and the residual hold with their {found.at} upper confidence "
            f"bounds on {n:,} rocks.")
    return DesignVerdict(HOLDS_WITH_CONFIDENCE, _head(HOLDS_WITH_CONFIDENCE, text),
                         untested_lines, untested, confidence=conf)


def verdict_of(summary: CheckSummary | Mapping[str, Any]) -> DesignVerdict:
    """The verdict on a design from its check summary.

    Parameters
    ----------
    summary : CheckSummary or mapping
        The check's record (:meth:`rockfall_design.judge.evaluation.Evaluation.record`);
        a dict of ``check --json`` is read back with
        :meth:`~rockfall_design.judge.records.CheckSummary.from_json`. The
        confidence is the one the summary carries (the plan's).

    Returns
    -------
    DesignVerdict
    """
    summary = check_of(summary)
    untested = tuple(m.label for m in summary.measures if m.met == 0)
    untested_lines = tuple(f"{u}: untested, no rock reached it (its checks say nothing)"
                           for u in untested)
    if summary.protect is None and len(untested) == len(summary.measures):
        return _untested_verdict(summary, untested, untested_lines)
    found = _Findings(summary.rocks, summary.confidence)
    for m in summary.measures:
        _judge_checks(found, m)
    if summary.protect is not None:
        _judge_residual(found, summary.protect)
    return _summed_up(found, untested, untested_lines)


def judged(summary: CheckSummary) -> CheckSummary:
    """The check summary headed by its verdict (:func:`verdict_of`).

    Its JSON is what ``check --json`` prints: the verdict first, then the
    summary's own keys, with ``ok`` and ``holds_with_confidence`` false when
    nothing was tested (no vacuous "holds"), and every measure and each of
    its checks with its ``state`` in the verdict's words: a measure no rock
    met is ``untested``, never "ok".
    """
    return summary.with_verdict(verdict_of(summary))


def check_state(check: Check | Mapping[str, Any], met: int) -> State:
    """The state of one check of a measure, in the verdict's words (:class:`State`).

    See :func:`rockfall_design.judge.records.check_state`; a check given as
    its ``as_dict()`` is read back first.

    Parameters
    ----------
    check : Check or mapping
    met : int
        Rocks that met the measure.

    Returns
    -------
    State
    """
    return state_of_check(check if isinstance(check, Check) else check_from_json(check), met)


def with_verdict(summary: Mapping[str, Any]) -> dict[str, Any]:
    """:func:`judged` of a summary dict (``Evaluation.summary()``), as ``check --json``."""
    return judged(CheckSummary.from_json(summary)).to_json()


def verdict_of_scenarios(scenarios: Sequence[CheckSummary | Mapping[str, Any]],
                         required: int) -> DesignVerdict:
    """The verdict over the scenarios of ``check --scenarios``: it must hold in ``required``.

    Parameters
    ----------
    scenarios : sequence of CheckSummary or mapping
        Each scenario's check summary (a dict with its ``index``).
    required : int
        Scenarios the design must hold in.
    """
    per = [(s.get("index", i) if isinstance(s, Mapping) else i, verdict_of(s))
           for i, s in enumerate(scenarios)]
    if not per:
        raise ValueError("a verdict over scenarios needs at least one scenario")
    conf = per[0][1].confidence
    of = len(per)
    parts = tuple((f"scenario {k}", v.state) for k, v in per)
    if all(v.state == UNTESTED for _, v in per):
        return DesignVerdict(UNTESTED, _head(UNTESTED, f"nothing was checked in any of the {of} "
                             "scenarios (no rock met a measure and no protected zone)."),
                             per[0][1].details, confidence=conf, parts=parts)
    sure = sum(v.with_confidence for _, v in per)
    holds = sum(v.holds for _, v in per)
    details = tuple(f"scenario {k}: {v.headline}" for k, v in per if not v.with_confidence)
    counts = (f"it holds with confidence in {sure} of {of} scenarios, on point values in "
              f"{holds}; required: {required}.")
    if sure >= required:
        return DesignVerdict(HOLDS_WITH_CONFIDENCE, _head(HOLDS_WITH_CONFIDENCE, counts),
                             details, confidence=conf, parts=parts)
    if holds >= required:
        needs = [v.rocks_needed for _, v in per if v.state == HOLDS_ON_POINT_VALUES]
        need = None if any(x is None for x in needs) else max(needs, default=None)
        return DesignVerdict(HOLDS_ON_POINT_VALUES, _head(HOLDS_ON_POINT_VALUES, counts),
                             details, (), need, confidence=conf, parts=parts)
    return DesignVerdict(FAILS, _head(FAILS, counts), details, confidence=conf, parts=parts)


def verdict_of_sections(sections: Iterable[tuple[str, DesignVerdict]]) -> DesignVerdict:
    """The verdict on a corridor: its weakest section's state, every section named.

    A corridor fails if a section fails; else it is untested if a section
    is; else it holds on point values only if a section does.
    """
    items = list(sections)
    if not items:
        raise ValueError("a verdict over sections needs at least one section")
    parts = tuple((name, v.state) for name, v in items)
    conf = items[0][1].confidence
    for state in (FAILS, UNTESTED, HOLDS_ON_POINT_VALUES):
        bad = [name for name, v in items if v.state == state]
        if bad:
            needs = [v.rocks_needed for _, v in items if v.state == HOLDS_ON_POINT_VALUES]
            need = (None if state != HOLDS_ON_POINT_VALUES or any(x is None for x in needs)
                    else max(needs, default=None))
            return DesignVerdict(
                state, _head(state, f"section{'s' if len(bad) > 1 else ''} "
                             f"{', '.join(bad)} of {len(items)}."),
                tuple(f"{name}: {v.headline}" for name, v in items if not v.with_confidence),
                (), need, confidence=conf, parts=parts)
    return DesignVerdict(HOLDS_WITH_CONFIDENCE, _head(
        HOLDS_WITH_CONFIDENCE, f"every one of the {len(items)} sections."),
        confidence=conf, parts=parts)


def requirement_warnings(project: Project, command: str) -> list[str]:
    """Requirements that can never hold with confidence, one line each, located in the file.

    An allowed fraction of 0 (``protect.allowed_fraction`` when ``check``
    judges the residual, ``design.residual`` for ``optimise``) is shown by no
    finite number of rocks: its upper confidence bound is always above 0.

    Parameters
    ----------
    project : Project
    command : {"check", "optimise"}

    Returns
    -------
    list of str
        ``file:line: key: message`` lines (empty when there is nothing to say).
    """
    # Before the plan: the file's confidence, or the default the contract's
    # SafetyParams gives it (the same value the plan resolves to).
    conf = float((project.safety or {}).get("confidence", DEFAULT_CONFIDENCE))
    example = rocks_to_show_fraction(0.001, conf, 0)

    def advice(written: str) -> str:
        return (f"write the fraction you can accept instead, e.g. {written} (at least "
                f"{example:,} rocks with none reaching the zone show it at {100 * conf:g} %)")

    out: list[str] = []
    if command == "check" and project.protect is not None and project.measures:
        if float(project.protect.allowed_fraction) <= 0.0:
            key = ("protect", "allowed_fraction")
            written = "allowed_fraction" in project.protect.model_fields_set
            said = "is 0" if written else "is 0 (the default when it is not written)"
            out.append(str(project.error_at(
                key, f"{said}: no number of rocks shows that no rock reaches the zone, so the "
                "design can never hold with confidence; "
                + advice("allowed_fraction: 0.001"))))
    design = getattr(project, "design", None)
    if command == "optimise" and design is not None:
        if design.residual_count == 0 or design.residual_fraction == 0.0:
            out.append(str(project.error_at(
                ("design", "residual"), "allows no rock: no number of rocks shows that, so no "
                "design can be admitted with confidence; "
                + advice("residual: {fraction: 0.001}"))))
    return out

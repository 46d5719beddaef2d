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

The verdict is computed from the JSON-ready summary of a check (what
:meth:`rockfall_design.judge.evaluation.Evaluation.summary` returns and ``check
--json`` prints), so it reads the same numbers as the report; it imports
nothing from the optimiser or the study rooms.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from .bounds import fraction_upper_bound, rocks_to_show_fraction

if TYPE_CHECKING:  # pragma: no cover
    from ..project import Project

__all__ = [
    "HOLDS_WITH_CONFIDENCE",
    "HOLDS_ON_POINT_VALUES",
    "FAILS",
    "UNTESTED",
    "STATES",
    "DesignVerdict",
    "verdict_of",
    "with_verdict",
    "check_state",
    "verdict_of_scenarios",
    "verdict_of_sections",
    "requirement_warnings",
]

HOLDS_WITH_CONFIDENCE = "holds with confidence"
HOLDS_ON_POINT_VALUES = "holds on point values only"
FAILS = "fails"
UNTESTED = "untested"
#: The four states, from the one the tool stands behind to the one that says nothing.
STATES = (HOLDS_WITH_CONFIDENCE, HOLDS_ON_POINT_VALUES, FAILS, UNTESTED)

#: Beyond this many rocks the verdict says "more than" instead of a count.
_MAX_ROCKS_NEEDED = 10**10


@dataclass(frozen=True)
class DesignVerdict:
    """The verdict on one design (or a set of scenarios or sections).

    Attributes
    ----------
    state : str
        One of :data:`STATES`.
    headline : str
        One sentence that begins with the state's words, capitalised
        ("Holds with confidence: ..."): the first line of every report.
    details : tuple of str
        What fails and by how much, or what is not settled and what would
        settle it, or why nothing was tested; one line each.
    untested : tuple of str
        The labels of the measures that no rock met.
    rocks_needed : int or None
        For ``holds on point values only``: about how many rocks (in all,
        at the observed rates) would settle every open item; None when no
        number of rocks can (or for the other states).
    confidence : float
        The one-sided confidence of the bounds (-).
    """

    state: str
    headline: str
    details: tuple[str, ...] = ()
    untested: tuple[str, ...] = ()
    rocks_needed: int | None = None
    confidence: float = 0.95
    parts: tuple[tuple[str, str], ...] = field(default=(), repr=False)

    @property
    def holds(self) -> bool:
        """True for both "holds" states (the checks pass on their point values)."""
        return self.state in (HOLDS_WITH_CONFIDENCE, HOLDS_ON_POINT_VALUES)

    @property
    def with_confidence(self) -> bool:
        """True only for ``holds with confidence``."""
        return self.state == HOLDS_WITH_CONFIDENCE

    def lines(self) -> list[str]:
        """The headline and then each detail, as a report prints them."""
        return [self.headline, *self.details]

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> DesignVerdict:
        """The verdict from its :meth:`as_dict` (a section's JSON block, say)."""
        return cls(str(d["state"]), str(d["headline"]), tuple(d.get("details") or ()),
                   tuple(d.get("untested_measures") or ()), d.get("rocks_needed"),
                   float(d.get("confidence") or 0.95),
                   tuple((p["name"], p["state"]) for p in d.get("parts") or ()))

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: ``state``, ``headline``, ``details``, ``untested_measures``, ..."""
        out: dict[str, Any] = {
            "state": self.state,
            "headline": self.headline,
            "details": list(self.details),
            "untested_measures": list(self.untested),
            "rocks_needed": self.rocks_needed,
            "confidence": self.confidence,
        }
        if self.parts:
            out["parts"] = [{"name": n, "state": s} for n, s in self.parts]
        return out


def _head(state: str, text: str) -> str:
    return f"{state[0].upper()}{state[1:]}: {text}"


def _pct(fraction: float) -> str:
    return f"{100 * fraction:.3g} %"


def _num(v: float | None, unit: str) -> str:
    if v is None:
        return "no value"
    return f"{v:,.2f}" if unit == "-" else f"{v:,.2f} {unit}"


def _miss(c: Mapping[str, Any]) -> str:
    """How far a failed check's value is from its target: 'by 0.35 (18 % of the target)'."""
    v, t, unit = c.get("value"), c.get("target"), str(c.get("unit", "-"))
    if v is None or t is None or not math.isfinite(v) or not math.isfinite(t):
        return str(c.get("detail") or "it has no value")
    gap = abs(v - t)
    rel = f" ({100 * gap / abs(t):.3g} % of the target)" if t else ""
    return f"by {_num(gap, unit)}{rel}"


def _holds_with_bound(c: Mapping[str, Any]) -> bool:
    owc = c.get("ok_with_confidence")
    return bool(c.get("ok")) if owc is None else bool(owc)


def _check_rocks(c: Mapping[str, Any], met: int, n: int) -> int | None:
    """About how many rocks in all would settle a check that holds on its point value only.

    A sample too small to bound the statistic says how many rocks must meet
    the measure (``rocks_needed``): scaled by the share of the rocks that
    meet it. Otherwise the bound's distance from the point value shrinks as
    1/sqrt(n): a value ``d`` from the target with a bound ``w`` from the
    value is settled at about ``n (w / d)**2`` rocks. None: never (the value
    sits on the target).
    """
    if c.get("rocks_needed") and met > 0:
        return int(math.ceil(int(c["rocks_needed"]) * n / met))
    v, b, t = c.get("value"), c.get("bound"), c.get("target")
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


def verdict_of(summary: Mapping[str, Any]) -> DesignVerdict:
    """The verdict on a design from its check summary (``check --json``).

    Parameters
    ----------
    summary : mapping
        ``rocks``, ``measures`` (each with ``label``, ``met`` and ``checks``),
        ``protect`` (if the project has a protected zone) and ``confidence``.

    Returns
    -------
    DesignVerdict
    """
    n = int(summary.get("rocks") or 0)
    conf = float(summary.get("confidence") or 0.95)
    at = f"{100 * conf:g} %"
    measures = list(summary.get("measures") or [])
    prot = summary.get("protect")
    untested = tuple(str(m.get("label") or m.get("type")) for m in measures
                     if int(m.get("met") or 0) == 0)
    untested_lines = tuple(f"{u}: untested, no rock reached it (its checks say nothing)"
                           for u in untested)
    if prot is None and len(untested) == len(measures):
        if not measures:
            text = ("no measure and no protected zone: nothing was checked. Add measures: "
                    "to check, or protect: {x: ...} to count the rocks reaching the zone.")
        else:
            text = (f"no rock of {n:,} reached any measure and there is no protected zone: "
                    "nothing was checked. Place the measures where the rocks pass, or add "
                    "protect: {x: ...}.")
        return DesignVerdict(UNTESTED, _head(UNTESTED, text), untested_lines, untested,
                             None, conf)
    failed: list[str] = []
    open_items: list[str] = []
    needs: list[int | None] = []
    for m in measures:
        label, met = str(m.get("label") or m.get("type")), int(m.get("met") or 0)
        for c in m.get("checks") or []:
            unit = str(c.get("unit", "-"))
            if not c.get("ok"):
                failed.append(f"{label}: {c['name']} {_num(c.get('value'), unit)} misses its "
                              f"target {_num(c.get('target'), unit)} {_miss(c)}")
            elif not _holds_with_bound(c):
                need = _check_rocks(c, met, n)
                needs.append(need)
                bound = ("cannot be bounded yet" if c.get("bound") is None
                         else f"its {at} bound {_num(c.get('bound'), unit)}")
                open_items.append(
                    f"{label}: {c['name']} {_num(c.get('value'), unit)} meets its target "
                    f"{_num(c.get('target'), unit)}, {bound} does not"
                    + (f"; about {need:,} rocks would settle it" if need else
                       "; its value sits on the target"))
    if prot is not None:
        reaching, allowed = int(prot["reaching"]), float(prot["allowed_fraction"])
        where = f"the protected zone at x >= {prot['x']:g} m"
        if not prot.get("ok"):
            excess = reaching - int(math.floor(allowed * n + 1e-9))
            many = f"{excess:,} rock{'s' if excess != 1 else ''} too many"
            failed.append(f"{reaching:,} of {n:,} rocks ({_pct(prot['fraction'])}) reach "
                          f"{where}; allowed {_pct(allowed)}: {many}")
        elif not prot.get("ok_with_confidence"):
            need = residual_rocks(reaching, n, allowed, conf)
            needs.append(need)
            if allowed <= 0.0:
                settle = ("no number of rocks shows a fraction of 0: allow a fraction "
                          "(protect.allowed_fraction, design.residual), e.g. 0.001, which "
                          f"{rocks_to_show_fraction(0.001, conf, 0):,} rocks with none "
                          "reaching show")
            elif need is None:
                settle = "its rate sits on the allowance; no number of rocks settles it"
            else:
                settle = f"about {need:,} rocks at this rate would settle it"
            open_items.append(
                f"{reaching:,} of {n:,} rocks ({_pct(prot['fraction'])}) reach {where}, "
                f"within the allowed {_pct(allowed)}, but the {at} upper bound "
                f"{_pct(prot['upper_fraction'])} is not; {settle}")
    if failed:
        miss = "s miss their targets" if len(failed) > 1 else " misses its target"
        text = f"{len(failed)} requirement{miss} on {n:,} rocks."
        return DesignVerdict(FAILS, _head(FAILS, text), tuple(failed) + untested_lines,
                             untested, None, conf)
    if open_items:
        need = None if any(x is None for x in needs) else max(needs, default=None)
        settle = (f" about {need:,} rocks would settle it (--rocks)." if need else
                  " no number of rocks settles it as the requirement is written.")
        text = (f"every check and the residual pass on their point values ({n:,} rocks), but "
                f"not all with their {at} confidence bounds;" + settle)
        return DesignVerdict(HOLDS_ON_POINT_VALUES, _head(HOLDS_ON_POINT_VALUES, text),
                             tuple(open_items) + untested_lines, untested, need, conf)
    text = (f"every check and the residual hold with their {at} upper confidence bounds "
            f"on {n:,} rocks.")
    return DesignVerdict(HOLDS_WITH_CONFIDENCE, _head(HOLDS_WITH_CONFIDENCE, text),
                         untested_lines, untested, None, conf)


def check_state(check: Mapping[str, Any], met: int) -> str:
    """The state of one check of a measure, in the verdict's words (:data:`STATES`).

    ``untested`` when no rock met the measure and the check has no value (a
    statistic of no rock says nothing; a check of geometry, such as a braking
    distance against the protected zone, has its value without rocks and is
    judged on it); ``fails`` when it misses its target on its point value;
    ``holds with confidence`` when it holds with its bound in place (or the
    concept reports no bound); else ``holds on point values only``.

    Parameters
    ----------
    check : mapping
        A check as :meth:`rockfall_design.plugins.concept.Check.as_dict` gives it.
    met : int
        Rocks that met the measure.

    Returns
    -------
    str
    """
    if met <= 0 and check.get("value") is None:
        return UNTESTED
    if not check.get("ok"):
        return FAILS
    return HOLDS_WITH_CONFIDENCE if _holds_with_bound(check) else HOLDS_ON_POINT_VALUES


def _with_check_states(measures: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """The measures with each check's ``state`` (:func:`check_state`) and the measure's."""
    out = []
    for m in measures:
        met = int(m.get("met") or 0)
        checks = [{**c, "state": check_state(c, met)} for c in m.get("checks") or []]
        states = {c["state"] for c in checks}
        # The measure's own word: a failing check's, else untested without a rock,
        # else its least sure check's. A measure with no check has none.
        state = (FAILS if FAILS in states else UNTESTED if met <= 0 else
                 HOLDS_ON_POINT_VALUES if HOLDS_ON_POINT_VALUES in states else
                 HOLDS_WITH_CONFIDENCE if checks else None)
        out.append({**m, "checks": checks, "state": state})
    return out


def with_verdict(summary: Mapping[str, Any]) -> dict[str, Any]:
    """A check summary headed by its ``verdict``; a check of nothing is not ``ok``.

    What ``check --json`` prints: the verdict first, then the summary's own
    keys, with ``ok`` and ``holds_with_confidence`` false when nothing was
    tested (no vacuous "holds"). Every measure and each of its checks carries
    its ``state`` in the verdict's words (:func:`check_state`): a measure no
    rock met is ``untested``, never "ok".
    """
    verdict = verdict_of(summary)
    out = {"verdict": verdict.as_dict(), **summary}
    if "measures" in out:
        out["measures"] = _with_check_states(out["measures"])
    if verdict.state == UNTESTED:
        out["ok"] = out["holds_with_confidence"] = False
    return out


def verdict_of_scenarios(scenarios: Sequence[Mapping[str, Any]], required: int
                         ) -> DesignVerdict:
    """The verdict over the scenarios of ``check --scenarios``: it must hold in ``required``.

    Parameters
    ----------
    scenarios : sequence of mapping
        Each scenario's check summary (with its ``index``).
    required : int
        Scenarios the design must hold in.
    """
    per = [(s, verdict_of(s)) for s in scenarios]
    conf = per[0][1].confidence if per else 0.95
    of = len(per)
    parts = tuple((f"scenario {s.get('index', i)}", v.state) for i, (s, v) in enumerate(per))
    if all(v.state == UNTESTED for _, v in per):
        return DesignVerdict(UNTESTED, _head(UNTESTED, f"nothing was checked in any of the {of} "
                             "scenarios (no rock met a measure and no protected zone)."),
                             per[0][1].details if per else (), (), None, conf, parts)
    sure = sum(v.with_confidence for _, v in per)
    holds = sum(v.holds for _, v in per)
    details = tuple(f"scenario {s.get('index', i)}: {v.headline}"
                    for i, (s, v) in enumerate(per) if not v.with_confidence)
    counts = (f"it holds with confidence in {sure} of {of} scenarios, on point values in "
              f"{holds}; required: {required}.")
    if sure >= required:
        return DesignVerdict(HOLDS_WITH_CONFIDENCE, _head(HOLDS_WITH_CONFIDENCE, counts),
                             details, (), None, conf, parts)
    if holds >= required:
        needs = [v.rocks_needed for _, v in per if v.state == HOLDS_ON_POINT_VALUES]
        need = None if any(x is None for x in needs) else max(needs, default=None)
        return DesignVerdict(HOLDS_ON_POINT_VALUES, _head(HOLDS_ON_POINT_VALUES, counts),
                             details, (), need, conf, parts)
    return DesignVerdict(FAILS, _head(FAILS, counts), details, (), None, conf, parts)


def verdict_of_sections(sections: Iterable[tuple[str, DesignVerdict]]) -> DesignVerdict:
    """The verdict on a corridor: its weakest section's state, every section named.

    A corridor fails if a section fails; else it is untested if a section
    is; else it holds on point values only if a section does.
    """
    items = list(sections)
    parts = tuple((name, v.state) for name, v in items)
    conf = items[0][1].confidence if items else 0.95
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
                (), need, conf, parts)
    return DesignVerdict(HOLDS_WITH_CONFIDENCE, _head(
        HOLDS_WITH_CONFIDENCE, f"every one of the {len(items)} sections."), (), (), None, conf,
        parts)


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
    conf = float((project.safety or {}).get("confidence", 0.95))
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

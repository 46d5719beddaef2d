"""A corridor's result: every section's JSON object and the totals over them.

A corridor runs each of its sections as an ordinary project (``simulate``,
``check``, ``check --scenarios``, ``optimise``, ``study``) and adds them up.
:class:`SectionBlock` is one section's JSON object with what the totals
need read from it once; :func:`corridor_summary` adds the blocks up into a
:class:`CorridorSummary`, whose ``to_json`` is the corridor's ``--json``
object (and its ``summary.json``).

The totals (``totals`` of the JSON): ``sections``, ``rocks`` (the sum; for
``study`` and ``check --scenarios`` every scenario's rocks), ``scenarios``
(``study``, ``check --scenarios``), ``reaching`` (``simulate``, ``check``:
rocks reaching the protected zones, None if no section has one), ``ok``
(``check``: every section holds; ``optimise``: a design for every section;
``check --scenarios``: every section holds in its required scenarios),
``binding`` (``check --scenarios``: of the sections' binding scenarios the
least margin, with its ``section``), ``cost`` and ``currency``
(``optimise``: the corridor design's cost, None unless every section has a
design), ``failures`` (one line each, naming the section) and ``bill``
(``optimise``, when every section has one).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

from ..judge.verdict import UNTESTED, DesignVerdict, verdict_of, verdict_of_sections
from .scenario_checks import Binding

if TYPE_CHECKING:  # pragma: no cover
    from ..project import Corridor, CorridorSection

__all__ = ["COMMANDS", "CorridorSummary", "CorridorTotals", "SectionBlock", "SectionOutcome",
           "corridor_summary", "road_share", "run_sections", "section_block", "section_seeds"]

#: The commands a corridor runs section by section.
COMMANDS = ("simulate", "check", "optimise", "study")


def section_block(section: CorridorSection, summary: Mapping[str, Any]) -> dict[str, Any]:
    """A section's item of ``sections``: its name and index, then its usual JSON object."""
    return {"name": section.name, "index": section.index, **summary}


def road_share(corridor: Corridor, index: int) -> dict[str, Any]:
    """``{"road": {station_m, length_m}}`` of a section of a corridor along a road, else ``{}``.

    The station (m along the road) of the section's fall line and the length
    of road it stands for (its ``design.site.length_m``), in its JSON block.
    """
    if corridor.map is None:
        return {}
    where = corridor.map.sections[index]
    return {"road": {"station_m": round(float(where.station), 3),
                     "length_m": round(float(where.length_m), 3)}}


def section_seeds(corridor: Corridor, seed: int | None = None) -> tuple[int, list[int]]:
    """The run seed (``seed``, default the corridor's) and each section's seed derived from it."""
    run = corridor.seed if seed is None else int(seed)
    return run, corridor.section_seeds(run)


@dataclass(frozen=True)
class SectionOutcome:
    """What one section's run gives the corridor (see :func:`run_sections`).

    Attributes
    ----------
    summary : dict
        The section's JSON object, as the command gives it for one project.
    cost : float or None
        ``optimise``: the chosen design's cost (None: no design).
    result : object
        The section's own result (a ``CheckResult``, ``StudyResult``, ...), for
        whoever wants more than its JSON.
    """

    summary: dict[str, Any]
    cost: float | None = None
    result: Any = None


def run_sections(corridor: Corridor, command: str,
                 run_one: Callable[[int, CorridorSection, int], SectionOutcome], *,
                 seed: int | None = None, scenarios: bool = False
                 ) -> tuple[CorridorSummary, list[SectionOutcome]]:
    """Run a command over every section of a corridor, in order, and add them up.

    Parameters
    ----------
    corridor
        The corridor.
    command
        ``simulate``, ``check``, ``optimise`` or ``study`` (:data:`COMMANDS`).
    run_one
        Called as ``run_one(i, section, section_seed)`` for each section in
        order: its run (its own rocks, with its own seed) and its JSON.
    seed
        The run seed the sections' seeds derive from (default the corridor's).
    scenarios
        ``check --scenarios`` (:func:`corridor_summary`).

    Returns
    -------
    (CorridorSummary, list of SectionOutcome)
        The corridor's result and each section's outcome.
    """
    if command not in COMMANDS:
        raise ValueError(f"a corridor runs {', '.join(COMMANDS)}, not {command!r}")
    run_seed, seeds = section_seeds(corridor, seed)
    done = [run_one(i, section, section_seed) for i, (section, section_seed)
            in enumerate(zip(corridor.sections, seeds, strict=True))]
    blocks = [{**section_block(s, d.summary), **road_share(corridor, i)}
              for i, (s, d) in enumerate(zip(corridor.sections, done, strict=True))]
    costs = [d.cost for d in done] if command == "optimise" else ()
    return corridor_summary(corridor, command, run_seed, blocks, costs, scenarios), done


@dataclass(frozen=True)
class SectionBlock:
    """One section's JSON object (its item of ``sections``) and what the totals read of it.

    Attributes
    ----------
    data : dict
        The JSON object: ``name``, ``index``, then the section's usual JSON.
    name : str
        The section's name.
    index : int
        Its index in the corridor.
    seed : int
        The seed it ran with.
    rocks : int
        Its rocks (per scenario for ``study`` and ``check --scenarios``).
    scenarios : int
        Its scenarios (``study``: the study's; ``check --scenarios``: ``of``); 0 otherwise.
    ok : bool
        Whether it holds (``check``, ``check --scenarios``); False where not said.
    failures : tuple of str
        Its failure lines.
    reaching : int or None
        Rocks reaching its protected zone (``simulate``, ``check``), None without one.
    binding : Binding or None
        ``check --scenarios``: its binding scenario.
    currency : str
        ``optimise``: the currency of its costs ("" if none).
    reason : str
        ``optimise``: why no admissible design was found ("" if one was).
    bill : dict or None
        ``optimise``: its chosen design's bill (``total``, ``items``).
    verdict : DesignVerdict or None
        Its verdict, where its JSON has one.
    """

    data: dict[str, Any]
    name: str
    index: int
    seed: int
    rocks: int
    scenarios: int = 0
    ok: bool = False
    failures: tuple[str, ...] = ()
    reaching: int | None = None
    binding: Binding | None = None
    currency: str = ""
    reason: str = ""
    bill: dict[str, Any] | None = None
    verdict: DesignVerdict | None = field(default=None, repr=False)

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> SectionBlock:
        """The block from its JSON object (:func:`section_block`, read back once)."""
        d = dict(data)
        protect = d.get("protect")
        of = d.get("of")
        scenarios = int(of) if of is not None else len(d.get("scenarios") or ())
        binding = d.get("binding")
        verdict = d.get("verdict")
        return cls(d, str(d["name"]), int(d["index"]), int(d.get("seed", 0)),
                   int(d.get("rocks", 0)), scenarios=scenarios, ok=bool(d.get("ok")),
                   failures=tuple(d.get("failures") or ()),
                   reaching=None if not protect else int(protect.get("reaching", 0)),
                   binding=None if binding is None else Binding.from_json(binding),
                   currency=str(d.get("currency") or ""), reason=str(d.get("reason", "")),
                   bill=d.get("bill"),
                   verdict=None if verdict is None else DesignVerdict.from_dict(verdict))

    def with_verdict(self) -> SectionBlock:
        """The block with a verdict: its own, else the one of its check JSON (``check``).

        The verdict is added to the JSON object's end, as ``check --json`` of
        an older record would lack it.
        """
        if self.verdict is not None:
            return self
        verdict = verdict_of(self.data)
        return SectionBlock.from_json({**self.data, "verdict": verdict.as_dict()})

    def to_json(self) -> dict[str, Any]:
        """The JSON object, as the section's command gave it."""
        return self.data


@dataclass(frozen=True)
class CorridorTotals:
    """The corridor's totals over its sections (see the module's text for each key).

    Attributes
    ----------
    command : str
        The command run (:data:`COMMANDS`).
    across : bool
        ``check --scenarios``.
    sections, rocks : int
    scenarios : int or None
    reaching : int or None
    ok : bool or None
    binding : Binding or None
        With ``binding_section``, the section it is in.
    cost : float or None
        In ``currency``.
    currency : str
    failures : list of str
    bill : dict or None
    """

    command: str
    across: bool
    sections: int
    rocks: int
    scenarios: int | None = None
    reaching: int | None = None
    ok: bool | None = None
    binding: Binding | None = None
    binding_section: str = ""
    cost: float | None = None
    currency: str = ""
    failures: list[str] = field(default_factory=list)
    bill: dict[str, Any] | None = None

    def to_json(self) -> dict[str, Any]:
        """``totals`` of the corridor's JSON: the keys of its command, in their order."""
        out: dict[str, Any] = {"sections": self.sections, "rocks": self.rocks}
        if self.command == "study" or self.across:
            out["scenarios"] = self.scenarios
        if self.command in ("simulate", "check") and not self.across:
            out["reaching"] = self.reaching
        if self.command in ("check", "optimise"):
            out["ok"] = self.ok
        if self.across and self.binding is not None:
            out["binding"] = {"section": self.binding_section, **self.binding.to_json()}
        if self.command == "optimise":
            out.update(cost=self.cost, currency=self.currency)
        if self.command in ("check", "optimise"):
            out["failures"] = self.failures
        if self.bill is not None:
            out["bill"] = self.bill
        return out


@dataclass(frozen=True)
class CorridorSummary:
    """What a command found over a corridor's sections (:func:`corridor_summary`).

    Attributes
    ----------
    name : str
        The corridor's name.
    command : str
        The command run (:data:`COMMANDS`).
    seed : int
        The run seed the sections' seeds derive from.
    sections : list of SectionBlock
        One per section, in order.
    totals : CorridorTotals
    verdict : DesignVerdict or None
        ``check`` and ``optimise``: its weakest section's
        (:func:`~rockfall_design.judge.verdict.verdict_of_sections`).
    across : bool
        ``check --scenarios`` (the JSON says ``"scenarios": true``).
    """

    name: str
    command: str
    seed: int
    sections: list[SectionBlock]
    totals: CorridorTotals
    verdict: DesignVerdict | None = None
    across: bool = False

    @property
    def ok(self) -> bool:
        """Whether the corridor holds (``check``) or has a design (``optimise``)."""
        return bool(self.totals.ok)

    def to_json(self) -> dict[str, Any]:
        """The corridor's ``--json`` object (and ``summary.json``)."""
        out: dict[str, Any] = {} if self.verdict is None else {"verdict": self.verdict.as_dict()}
        out.update(name=self.name, command=self.command)
        if self.across:
            out["scenarios"] = True
        out.update(seed=self.seed, sections=[b.to_json() for b in self.sections],
                   totals=self.totals.to_json())
        return out


def _verdict(blocks: Sequence[SectionBlock], command: str
             ) -> tuple[list[SectionBlock], DesignVerdict | None]:
    """The blocks (each ``check`` block given its own verdict) and the corridor's verdict."""
    if command not in ("check", "optimise"):
        return list(blocks), None
    if command == "check":
        blocks = [b.with_verdict() for b in blocks]
    if any(b.verdict is None for b in blocks):
        return list(blocks), None
    return list(blocks), verdict_of_sections((b.name, b.verdict) for b in blocks
                                             if b.verdict is not None)


def _across_totals(blocks: Sequence[SectionBlock]) -> CorridorTotals:
    """The totals of ``check --scenarios``: every scenario's rocks, the binding scenario."""
    def margin(b: SectionBlock) -> tuple[float, int]:
        m = None if b.binding is None else b.binding.margin
        return (math.inf if m is None else m, b.index)

    bind = min(blocks, key=margin)
    return CorridorTotals(
        "check", True, len(blocks), int(sum(b.rocks * b.scenarios for b in blocks)),
        scenarios=int(sum(b.scenarios for b in blocks)), ok=all(b.ok for b in blocks),
        binding=bind.binding, binding_section=bind.name,
        failures=[f"{b.name}: {f}" for b in blocks for f in b.failures])


def _optimise_totals(blocks: Sequence[SectionBlock], costs: Sequence[float | None]
                     ) -> CorridorTotals:
    """The totals of ``optimise``: the cost of a design for every section, and its bill."""
    found = [c for c in costs if c is not None]
    ok = len(found) == len(blocks)
    currencies = sorted({b.currency for b in blocks} - {""})
    currency = currencies[0] if len(currencies) == 1 else ""
    bill = None
    if all(b.bill is not None for b in blocks):  # the corridor's bill: each section's, the total
        bills = [(b.name, b.bill) for b in blocks if b.bill is not None]
        bill = {"sections": [{"section": name, "total": one["total"], "items": one["items"]}
                             for name, one in bills],
                "total": float(sum(one["total"] for _, one in bills)), "currency": currency}
    return CorridorTotals(
        "optimise", False, len(blocks), int(sum(b.rocks for b in blocks)), ok=ok,
        cost=float(sum(found)) if ok else None, currency=currency,
        failures=[f"{b.name}: no admissible design: {b.reason}"
                  for b, c in zip(blocks, costs, strict=True) if c is None], bill=bill)


def corridor_summary(corridor: Corridor, command: str, seed: int,
                     blocks: Sequence[Mapping[str, Any]],
                     costs: Sequence[float | None] = (),
                     scenarios: bool = False) -> CorridorSummary:
    """The corridor's result: the run, every section's block, and the totals.

    Parameters
    ----------
    corridor
        The corridor run.
    command
        ``simulate``, ``check``, ``optimise`` or ``study``.
    seed
        The run seed the sections' seeds derive from.
    blocks
        One :func:`section_block` per section, in order.
    costs
        ``optimise``: each section's chosen design's cost (None: no design).
    scenarios
        ``check --scenarios``: each block is the section's ``check
        --scenarios`` JSON; the totals count every scenario's rocks and name
        the binding scenario of the corridor, and the JSON says
        ``"scenarios": true``.
    """
    typed = [SectionBlock.from_json(b) for b in blocks]
    typed, verdict = _verdict(typed, command)
    if scenarios:
        totals = _across_totals(typed)
    elif command == "optimise":
        totals = _optimise_totals(typed, costs)
    else:
        reaching = [b.reaching for b in typed if b.reaching is not None]
        rocks = sum(b.rocks * (b.scenarios if command == "study" else 1) for b in typed)
        totals = CorridorTotals(
            command, False, len(typed), int(rocks),
            scenarios=int(sum(b.scenarios for b in typed)) if command == "study" else None,
            reaching=int(sum(reaching)) if reaching else None,
            ok=all(b.ok for b in typed) if command == "check" else None,
            failures=[f"{b.name}: {f}" for b in typed for f in b.failures])
    if command == "check" and verdict is not None and verdict.state == UNTESTED:
        totals = replace(totals, ok=False)
    return CorridorSummary(corridor.name, command, int(seed), typed, totals, verdict, scenarios)

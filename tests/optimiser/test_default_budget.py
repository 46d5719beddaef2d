"""The default rock budget of a decision (``design.max_rocks``): one value, said alike.

Issue 37, item 3: the default is set where the bundled design projects decide
their margins (docs/speed.md, "The default rock budget"); the schema, the
optimiser's spec, the CLI's help and the docs must all say the same value.
"""

from __future__ import annotations

from pathlib import Path

from rockfall_design.cli.program import build_parser
from rockfall_design.judge.design_spec import DesignSpec
from rockfall_design.judge.sequential import plan_looks
from rockfall_design.project.design import Design
from rockfall_design.project.schema import DEFAULT_MAX_ROCKS

ROOT = Path(__file__).resolve().parents[2]


def test_one_default_everywhere():
    assert Design.model_fields["max_rocks"].default == DEFAULT_MAX_ROCKS
    assert DesignSpec.__dataclass_fields__["max_rocks"].default == DEFAULT_MAX_ROCKS
    parser = build_parser()
    (sub,) = [a for a in parser._actions if a.dest == "command"]
    (opt,) = [a for a in sub.choices["optimise"]._actions if a.dest == "max_rocks"]
    assert f"{DEFAULT_MAX_ROCKS:,}" in opt.help
    for doc in ("optimise.md", "sequential-decisions.md"):
        text = " ".join((ROOT / "docs" / doc).read_text(encoding="utf-8").split())
        assert f"default {DEFAULT_MAX_ROCKS:,}" in text, doc


def test_the_default_schedule_is_what_the_docs_say():
    # 0.1 % at 95 %: the first look shows the target with none reaching, and the
    # error is spent over every look up to the default budget.
    looks = plan_looks(3000, DEFAULT_MAX_ROCKS, 0.95, 0.001)
    assert looks.sizes[-1] == DEFAULT_MAX_ROCKS and len(looks) <= looks.spent_over
    assert all(b <= 2 * a for a, b in zip(looks.sizes, looks.sizes[1:], strict=False))


def test_the_default_budget_fits_a_16_gib_machine(monkeypatch):
    """optimise's guard of its last look: the default budget on a project of 201 envelope
    points passes on a machine of 16 GiB (the guard of a check's rocks, which keeps float64
    copies of every point, would refuse it); the largest budget passes there too, the
    looks holding no envelope grid, and one that does not fit says what to give."""
    import os

    import pytest

    from rockfall_design.cli import common
    from rockfall_design.errors import InputError

    pages = {"SC_PAGE_SIZE": 4096, "SC_PHYS_PAGES": 16 * 2**30 // 4096}
    monkeypatch.setattr(common.os, "sysconf", lambda name: pages[name])
    assert os.sysconf is common.os.sysconf
    common.decision_memory_guard(DEFAULT_MAX_ROCKS, 4)
    common.decision_memory_guard(2_000_000, 4)
    with pytest.raises(InputError):
        common.in_memory_guard(DEFAULT_MAX_ROCKS, 201 + 400, 0)
    pages["SC_PHYS_PAGES"] = 4 * 2**30 // 4096
    with pytest.raises(InputError, match="--max-rocks"):
        common.decision_memory_guard(2_000_000, 4)

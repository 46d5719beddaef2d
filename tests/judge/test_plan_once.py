"""A command builds the slope's section and resolves its design section once (issue 38).

The plan (:mod:`rockfall_design.judge.plan`) holds both; every later step
of the command takes them from it (or from the optimiser's screening, which
the plan's section is handed to). Counted here by replacing the two
functions wherever the package holds them, and running the commands as a
user does, in-process.
"""

from __future__ import annotations

import contextlib
import functools
import inspect
import io
import sys
from collections import Counter
from pathlib import Path

import pytest

import rockfall_design.judge.design_spec as design_spec
import rockfall_design.run.releases as releases
from rockfall_design.cli.program import main

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def counted(monkeypatch) -> Counter:
    """Calls of ``section_from_project`` and ``resolve_design``, wherever they are named."""
    calls: Counter = Counter()
    for name, original in (("section_from_project", releases.section_from_project),
                           ("resolve_design", design_spec.resolve_design)):

        @functools.wraps(original)
        def counting(*args, _name=name, _original=original, **kwargs):
            calls[_name] += 1
            return _original(*args, **kwargs)

        for module in list(sys.modules.values()):
            # unwrap: a module first imported during an earlier test holds that
            # test's counting function (taken from the patched module), not the
            # original; it must count for this test too.
            held = getattr(module, name, None)
            if (getattr(module, "__name__", "").startswith("rockfall_design")
                    and held is not None and inspect.unwrap(held) is original):
                monkeypatch.setattr(module, name, counting)
    return calls


@pytest.mark.parametrize("args", [
    ["simulate", "projects/standard_slope.yaml", "--rocks", "200"],
    ["simulate", "projects/design_two_zones.yaml", "--rocks", "200"],
    ["check", "projects/quarry_fence_ditch.yaml", "--rocks", "200"],
    ["optimise", "tests/data/design_small.yaml"],
], ids=lambda a: f"{a[0]}-{Path(a[1]).stem}")
def test_one_section_and_one_design_per_command(args, counted, tmp_path):
    argv = [args[0], str(ROOT / args[1]), *args[2:], "--out", str(tmp_path / "out")]
    if args[0] == "optimise":  # the report of the chosen design: its bill and its check
        argv += ["--report", str(tmp_path / "report")]
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        assert main(argv) == 0
    assert counted["section_from_project"] == 1
    has_design = args[1].endswith(("design_two_zones.yaml", "design_small.yaml"))
    assert counted["resolve_design"] == (1 if has_design else 0)

"""The README's quick start is what CI runs; the physics reference holds the model.

The links, paths and command lines of the README and of docs/, and the
examples of docs/, are checked in ``test_docs.py``.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")


def _quick_start_blocks() -> list[str]:
    """The bash blocks of the "Quick start" section, as .ci/run reads them."""
    section = README[README.index("## Quick start"):]
    section = section[:section.index("\n## ", 1)]
    return re.findall(r"```bash\n(.*?)```", section, re.S)


def test_quick_start_is_two_one_line_commands_in_a_virtual_environment():
    blocks = _quick_start_blocks()
    assert len(blocks) == 2, "CI runs exactly two quick-start commands"
    lines = [b.strip() for b in blocks]
    assert all("\n" not in line for line in lines), "each block is one command line"
    install, test = (line.split(" && ") for line in lines)
    # The first creates the environment and works in it: a plain `pip install`
    # is refused by an externally managed (PEP 668) system Python.
    assert install[:3] == ["python3 -m venv .venv", ". .venv/bin/activate",
                           "python -m pip install ."]
    run = install[3].split()
    assert run[:2] == ["rockfall-design", "optimise"] and "--plot" in run
    assert (ROOT / run[2]).is_file(), f"{run[2]} is not in the repository"
    # The second reuses it (CI runs each block in its own shell).
    assert test == [". .venv/bin/activate", 'python -m pip install ".[test]"',
                    "python -m pytest"]


def test_quick_start_names_the_debian_venv_package():
    section = README[README.index("## Quick start"):README.index("## Designing protection")]
    assert "python3-venv" in section


def test_ci_lints_with_the_ruff_of_the_quick_start_environment():
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert "\n.venv/bin/ruff check .\n" in ci


def test_the_virtual_environment_is_neither_collected_nor_linted():
    import tomllib

    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    pytest_options = config["tool"]["pytest"]["ini_options"]
    assert pytest_options["testpaths"] == ["tests"]
    assert ".*" in pytest_options["norecursedirs"]  # .venv, .git, ...
    assert ".venv" in config["tool"]["ruff"]["extend-exclude"]
    assert ".venv/" in (ROOT / ".gitignore").read_text(encoding="utf-8").split()


def test_physics_reference_covers_the_model_and_the_design_values():
    text = (ROOT / "docs" / "PHYSICS.md").read_text(encoding="utf-8")
    for needle in ("5/7 g (sin β − μ_r cos β)",          # rolling with resistance
                   "−(7 μ + 5 μ_r) / 2  ≤  tan β  ≤  (7 μ − 5 μ_r) / 2",  # both limits
                   "r ds/dt   = 5/2 g cos β (μ sgn σ − μ_r sgn s)",   # resistance while slipping
                   "|u| ≤ 7/2 μ p_n", "Clopper", "Binomial(n, q)"):
        assert needle in text, needle

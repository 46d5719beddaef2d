"""The README's worked plugin example is real: installed through an entry point, it works."""

from __future__ import annotations

import json
import re
from pathlib import Path

from rockfall_design.cli import main

from .plugin_helpers import write_distribution

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")


def _block_after(marker: str, lang: str) -> str:
    tail = README[README.index(marker):]
    m = re.search(rf"```{lang}\n(.*?)```", tail, re.S)
    assert m, f"no {lang} block after {marker!r}"
    return m.group(1)


def test_readme_plugin_example_installs_and_checks(tmp_path, monkeypatch, capsys):
    source = _block_after("`rockfall_catchnet/__init__.py`", "python")
    toml = _block_after("`pyproject.toml` of the plugin", "toml")
    assert 'catchnet = "rockfall_catchnet"' in toml
    write_distribution(tmp_path, "rockfall_catchnet", source, "catchnet",
                       dist_name="rockfall-catchnet")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert main(["plugins", "--json"]) == 0
    listing = json.loads(capsys.readouterr().out)
    (net,) = [m for m in listing["measures"] if m["kind"] == "catch_net"]
    assert net["provider"] == "rockfall-catchnet"
    project = (ROOT / "projects" / "quarry_road.yaml").read_text()
    project += _block_after("a project can use it:", "yaml")
    p = tmp_path / "p.yaml"
    p.write_text(project)
    code = main(["check", str(p), "--rocks", "100", "--json"])
    s = json.loads(capsys.readouterr().out)
    assert code in (0, 1)
    (m,) = s["measures"]
    assert m["type"] == "catch_net" and m["met"] > 0
    assert m["caught"] + m["passed_over"] + m["broken_through"] == m["met"]


def test_readme_plugin_test_example_passes(tmp_path, monkeypatch):
    """The README's "Testing a plugin" example, run against the README's catch net."""
    import rockfall_design.api as api
    from rockfall_design.testing import tiny_slope

    source = _block_after("`rockfall_catchnet/__init__.py`", "python")
    write_distribution(tmp_path, "rockfall_catchnet", source, "catchnet",
                       dist_name="rockfall-catchnet")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(api, "_REGISTRIES", {})  # the installed plugins, with the net
    namespace: dict = {}
    exec(_block_after("### Testing a plugin", "python"), namespace)
    namespace["test_catch_net_holds_slow_rocks_only"](tiny_slope)


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


# Top-level directories of the repository: a backticked path starting with one
# of them names a file or directory the README promises is there.
_REPO_DIRS = ("benchmarks", "docs", "examples", "plugins", "projects", "rockfall_design",
              "tests")


def _readme_prose() -> str:
    """README.md without its fenced code blocks (whose paths are examples)."""
    return re.sub(r"^```.*?^```", "", README, flags=re.S | re.M)


def test_every_relative_link_in_the_readme_resolves_to_a_file():
    links = re.findall(r"\[[^\]]*\]\(([^)\s]+)\)", _readme_prose())
    links += re.findall(r"^\[[^\]]+\]:\s*(\S+)", README, flags=re.M)  # reference links
    assert any(link.startswith("docs/PHYSICS.md") for link in links)
    for link in links:
        if re.match(r"[a-z][a-z0-9+.-]*:", link) or link.startswith("#"):
            continue  # a URL or a heading in the README itself
        target = ROOT / link.split("#", 1)[0]
        assert target.exists(), f"README links to {link}, which is not in the repository"


def test_every_repository_path_the_readme_names_exists():
    pattern = r"`((?:" + "|".join(_REPO_DIRS) + r")/[^`\s]*)`"
    paths = re.findall(pattern, _readme_prose())
    assert "projects/design_two_zones.yaml" in paths
    missing = [p for p in paths if not (ROOT / p).exists()]
    assert not missing, f"the README names {missing}, which are not in the repository"


def test_physics_reference_covers_the_model_and_the_design_values():
    text = (ROOT / "docs" / "PHYSICS.md").read_text(encoding="utf-8")
    for needle in ("5/7 g (sin β − μ_r cos β)",          # rolling with resistance
                   "−(7 μ + 5 μ_r) / 2  ≤  tan β  ≤  (7 μ − 5 μ_r) / 2",  # both limits
                   "r ds/dt   = 5/2 g cos β (μ sgn σ − μ_r sgn s)",   # resistance while slipping
                   "|u| ≤ 7/2 μ p_n", "Clopper", "Binomial(n, q)"):
        assert needle in text, needle

def test_readme_from_python_block_runs(tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    source = _block_after("## From Python", "python")
    (tmp_path / "projects").symlink_to(ROOT / "projects")
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    exec(compile(source, "README.md", "exec"), namespace)  # noqa: S102
    assert isinstance(namespace["r"].plot(), Figure)
    assert (tmp_path / "report" / "report.html").is_file()

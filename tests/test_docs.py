"""The user documentation holds together: README.md and the pages of docs/.

What is checked is what exists: a page added to docs/ later is checked as
soon as it is there (its links, its command lines, and that the README leads
to it). The examples the pages show run here too: the plugin guide's catch
net is installed through an entry point and used, and its test passes; the
Python page's block runs as written (the ``slow`` set, as it optimises).
"""

from __future__ import annotations

import argparse
import json
import re
import shlex
from pathlib import Path

import pytest

from rockfall_design.cli.program import build_parser, main

from .plugin_helpers import write_distribution

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
DOCS = ROOT / "docs"
MAX_README_LINES = 300

#: Options the pages name that belong to other programs than rockfall-design.
OTHER_PROGRAMS_OPTIONS = {
    "--write": "benchmarks/golden.py",
    "--dist": "pytest (pytest-xdist)",
    "--kernel-only": "benchmarks/engine.py",
    "--no-first-compile": "benchmarks/engine.py",
    "--seeds": "benchmarks/optimise.py",
    "--no-reference": "benchmarks/optimise.py",
    "--check-seeds": "benchmarks/optimise.py",
    "--projects": "benchmarks/optimise.py",
    "--points": "benchmarks/survey.py",
    "--varying-rocks": "benchmarks/survey.py",
    "--nthreads": "dask worker",
    "--nworkers": "dask worker",
    "--host": "dask scheduler and dask worker",
    "--e": "examples/stops_from_points.py",
    "--n": "examples/stops_from_points.py",
    "--volume": "examples/stops_from_points.py",
    "--corridor": "examples/stops_from_points.py",
    "--against": "benchmarks/optimise.py",
    "--repeats": "benchmarks/optimise_speed.py and benchmarks/engine.py",
    "--across-only": "benchmarks/across.py",
    "--no-check": "benchmarks/across.py",
    "--project": "benchmarks/across.py",
    "--law": "examples/authume_quarry.py",
    "--replicates": "examples/authume_refits.py",
    "--trace": "examples/authume_quarry.py",
    "--stations": "examples/authume_sensitivity.py",
}


def _pages() -> list[Path]:
    """README.md and every Markdown page of docs/ (what exists now)."""
    return [README, *sorted(DOCS.glob("*.md"))]


def _text(path: Path) -> str:
    return path.read_text(encoding="utf-8")


def _prose(text: str) -> str:
    """A page without its fenced code blocks (whose paths and links are examples)."""
    return re.sub(r"^```.*?^```", "", text, flags=re.S | re.M)


def _blocks(text: str, lang: str) -> list[str]:
    return re.findall(rf"^```{lang}\n(.*?)^```", text, flags=re.S | re.M)


def _links(text: str) -> list[str]:
    prose = _prose(text)
    links = re.findall(r"\[[^\]]*\]\(([^)\s]+)\)", prose)
    links += re.findall(r"^\[[^\]]+\]:\s*(\S+)", prose, flags=re.M)  # reference links
    return [link for link in links if not re.match(r"[a-z][a-z0-9+.-]*:", link)]  # no URLs


def _slug(heading: str) -> str:
    """The anchor GitHub gives a heading: lower case, punctuation dropped, spaces as hyphens."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def _anchors(path: Path) -> set[str]:
    headings = re.findall(r"^#{1,6} +(.+?)\s*$", _prose(_text(path)), flags=re.M)
    return {_slug(h) for h in headings}


def _target(page: Path, link: str) -> tuple[Path, str]:
    where, _, anchor = link.partition("#")
    return ((page.parent / where).resolve() if where else page), anchor


def test_the_readme_is_short():
    n = len(_text(README).splitlines())
    assert n <= MAX_README_LINES, f"README.md has {n} lines, at most {MAX_README_LINES}"


@pytest.mark.parametrize("page", _pages(), ids=lambda p: p.name)
def test_every_relative_link_resolves(page):
    for link in _links(_text(page)):
        target, anchor = _target(page, link)
        assert target.exists(), f"{page.name} links to {link}, which is not in the repository"
        if anchor and target.suffix == ".md":
            assert anchor in _anchors(target), f"{page.name} links to {link}: no such heading"


def test_every_docs_page_is_reachable_from_the_readme():
    seen, todo = {README.resolve()}, [README.resolve()]
    while todo:
        page = todo.pop()
        for link in _links(_text(page)):
            target, _ = _target(page, link)
            if target.suffix == ".md" and target.is_file() and target not in seen:
                seen.add(target)
                todo.append(target)
    unreached = [p.name for p in DOCS.glob("*.md") if p.resolve() not in seen]
    assert not unreached, f"no link from README.md leads to docs/{unreached}"


# Top-level directories of the repository: a backticked path starting with one
# of them names a file or directory the pages promise is there.
_REPO_DIRS = ("benchmarks", "docs", "examples", "plugins", "projects", "rockfall_design",
              "tests")


@pytest.mark.parametrize("page", _pages(), ids=lambda p: p.name)
def test_every_repository_path_a_page_names_exists(page):
    pattern = r"`((?:" + "|".join(_REPO_DIRS) + r")/[^`\s]*)`"
    paths = re.findall(pattern, _prose(_text(page)))
    missing = [p for p in paths if not (ROOT / p).exists()]
    assert not missing, f"{page.name} names {missing}, which are not in the repository"


def _command_lines() -> list[tuple[str, str]]:
    """Every ``rockfall-design`` command line of the pages' console and bash blocks."""
    out = []
    for page in _pages():
        text = _text(page)
        for block in _blocks(text, "console") + _blocks(text, "bash"):
            for line in block.splitlines():
                line = line.removeprefix("$ ")
                if line.startswith("rockfall-design "):
                    out.append((page.name, " ".join(shlex.split(line, comments=True))))
    return out


def _options() -> set[str]:
    """Every option of every subcommand of the command line."""
    parser = build_parser()
    found = {o for a in parser._actions for o in a.option_strings}
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                found |= {o for a in sub._actions for o in a.option_strings}
    return found


def test_the_pages_show_command_lines():
    assert len(_command_lines()) >= 10


@pytest.mark.parametrize(("page", "line"), _command_lines())
def test_every_command_line_shown_parses(page, line):
    try:
        build_parser().parse_args(shlex.split(line)[1:])
    except SystemExit as exc:  # argparse's way of refusing
        pytest.fail(f"{page}: `{line}` is not a valid command line ({exc})")


@pytest.mark.parametrize("page", _pages(), ids=lambda p: p.name)
def test_every_option_a_page_names_exists(page):
    known = _options() | set(OTHER_PROGRAMS_OPTIONS)
    named = set(re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*)", _text(page)))
    assert not named - known, f"{page.name} names options no command has: {named - known}"


@pytest.mark.parametrize("page", _pages(), ids=lambda p: p.name)
def test_every_subcommand_a_page_names_exists(page):
    parser = build_parser()
    (subs,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    named = set(re.findall(r"`rockfall-design ([a-z]+)", _text(page)))
    named |= {line.split()[1] for p, line in _command_lines() if p == page.name}
    assert named <= set(subs.choices), f"{page.name}: no subcommand {named - set(subs.choices)}"


# --- The plugin guide's catch net (docs/plugins.md) ---------------------------------

PLUGINS = DOCS / "plugins.md"


def _block_after(path: Path, marker: str, lang: str) -> str:
    text = _text(path)
    tail = text[text.index(marker):]
    m = re.search(rf"```{lang}\n(.*?)```", tail, re.S)
    assert m, f"no {lang} block after {marker!r} in {path.name}"
    return m.group(1)


def catch_net_source() -> str:
    """The catch net's ``__init__.py`` as the plugin guide prints it."""
    return _block_after(PLUGINS, "`rockfall_catchnet/__init__.py`", "python")


def test_the_guide_plugin_example_installs_and_checks(tmp_path, monkeypatch, capsys):
    toml = _block_after(PLUGINS, "`pyproject.toml` of the plugin", "toml")
    assert 'catchnet = "rockfall_catchnet"' in toml
    write_distribution(tmp_path, "rockfall_catchnet", catch_net_source(), "catchnet",
                       dist_name="rockfall-catchnet")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert main(["plugins", "--json"]) == 0
    listing = json.loads(capsys.readouterr().out)
    (net,) = [m for m in listing["measures"] if m["kind"] == "catch_net"]
    assert net["provider"] == "rockfall-catchnet"
    project = (ROOT / "projects" / "quarry_road.yaml").read_text()
    project += _block_after(PLUGINS, "a project can use it:", "yaml")
    p = tmp_path / "p.yaml"
    p.write_text(project)
    code = main(["check", str(p), "--rocks", "100", "--json"])
    s = json.loads(capsys.readouterr().out)
    assert code in (0, 1)
    (m,) = s["measures"]
    assert m["type"] == "catch_net" and m["met"] > 0
    assert m["caught"] + m["passed_over"] + m["broken_through"] == m["met"]


def test_the_guide_plugin_test_example_passes(tmp_path, monkeypatch):
    """The guide's "Testing a plugin" example, run against the guide's catch net."""
    import rockfall_design.api as api
    from rockfall_design.testing import tiny_slope

    write_distribution(tmp_path, "rockfall_catchnet", catch_net_source(), "catchnet",
                       dist_name="rockfall-catchnet")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(api, "_REGISTRIES", {})  # the installed plugins, with the net
    namespace: dict = {}
    exec(_block_after(PLUGINS, "## Testing a plugin", "python"), namespace)  # noqa: S102
    namespace["test_catch_net_holds_slow_rocks_only"](tiny_slope)


def _routes(text: str) -> str:
    """The list of current and older routes under its heading, as plain words."""
    start = text.index("Current routes and older routes")
    items = re.search(r"^- .*?(?=^[^\s-]|\Z)", text[start:], flags=re.S | re.M)
    assert items, "no list of routes"
    return " ".join(items.group(0).replace("``", "`").split())


def test_the_guide_marks_current_and_older_routes_as_the_manual_does():
    """The plugin guide and hookspecs.py give the same routes, with their version markers."""
    from rockfall_design.plugins import hookspecs

    guide = _routes(_text(PLUGINS))
    assert guide == _routes(hookspecs.__doc__)
    for route in ("bill(section)", "quantities(section)", "price(", "cost(", "design_variables"):
        assert route in guide
    assert guide.count("Current (since 0.1.0)") == guide.count("Kept for") == 4

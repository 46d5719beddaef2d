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


def test_readme_from_python_block_runs(tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    source = _block_after("## From Python", "python")
    (tmp_path / "projects").symlink_to(ROOT / "projects")
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    exec(compile(source, "README.md", "exec"), namespace)  # noqa: S102
    assert isinstance(namespace["r"].plot(), Figure)
    assert (tmp_path / "report" / "report.html").is_file()

"""docs/api.md is what docs/make_api_reference.py writes from the sources now.

A docstring or a signature of a public name changed without the page
regenerated fails here; the message says the command that brings it up
to date.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "docs" / "make_api_reference.py"


def _script():
    spec = importlib.util.spec_from_file_location("make_api_reference", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_committed_api_page_is_current():
    script = _script()
    committed = script.PAGE.read_text(encoding="utf-8")
    assert committed == script.render(), (
        "docs/api.md is not current: run python docs/make_api_reference.py")


def test_the_page_covers_every_public_name():
    import rockfall_design

    text = _script().render()
    missing = [n for n in rockfall_design.__all__
               if n != "__version__" and f"### `{n}" not in text]
    assert not missing, f"docs/api.md has no entry for {missing}"


def test_check_mode_reports_a_stale_page(tmp_path, monkeypatch, capsys):
    script = _script()
    monkeypatch.setattr(script, "PAGE", tmp_path / "api.md")
    (tmp_path / "api.md").write_text("# stale\n", encoding="utf-8")
    assert script.main(["--check"]) == 1
    assert "not current" in capsys.readouterr().err
    assert script.main([]) == 0
    assert script.main(["--check"]) == 0

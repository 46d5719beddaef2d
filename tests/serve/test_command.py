"""``rockfall-design serve`` as a user starts it: the address, the token, this machine only."""

from __future__ import annotations

import json
import urllib.error
import urllib.request
from urllib.parse import urlsplit

import pytest

from rockfall_design.cli.program import main

from .conftest import start_server, stop_server


def _status(url: str) -> int:
    try:
        with urllib.request.urlopen(url, timeout=30) as r:
            return r.status
    except urllib.error.HTTPError as exc:
        return exc.code


def test_serve_prints_an_address_on_this_machine_with_a_token(project_copy):
    proc, url = start_server(str(project_copy))
    try:
        parts = urlsplit(url)
        assert parts.hostname == "127.0.0.1"
        assert parts.query.startswith("token=") and len(parts.query) > 30
        base = f"{parts.scheme}://{parts.netloc}"
        assert _status(url) == 200
        assert _status(base + "/") == 403
        assert _status(base + "/api/projects") == 403
        assert _status(f"{base}/api/projects?{parts.query}") == 200
    finally:
        code, err = stop_server(proc)
    assert "Traceback" not in err
    assert code == 0


def test_two_runs_have_different_tokens(project_copy):
    urls = []
    for _ in range(2):
        proc, url = start_server(str(project_copy))
        stop_server(proc)
        urls.append(url)
    assert urlsplit(urls[0]).query != urlsplit(urls[1]).query


def test_serve_a_missing_project_is_one_line_and_exit_2(tmp_path, capsys):
    assert main(["serve", str(tmp_path / "nope.yaml")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "nope.yaml" in err


def test_serve_without_projects_where_there_are_none(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["serve"]) == 2
    assert "no project file" in capsys.readouterr().err


@pytest.mark.parametrize("port", ["-1", "70000", "http"])
def test_serve_bad_port(port, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["serve", "--port", port])
    assert exc.value.code == 2


def test_serve_without_projects_serves_those_of_the_directory(project_copy, monkeypatch):
    broken = project_copy.parent / "broken.yaml"
    broken.write_text("slope:\n  points: [[0, 10]]\n")
    try:
        proc, url = start_server(cwd=project_copy.parent)
        try:
            with urllib.request.urlopen(url.replace("/?", "/api/projects?"), timeout=30) as r:
                ids = [p["id"] for p in json.loads(r.read())["projects"]]
        finally:
            code, err = stop_server(proc)
    finally:
        broken.unlink()
    assert ids == ["design_two_zones"]
    assert "left out" in err and "broken.yaml" in err
    assert code == 0

"""Hostile files: special and oversized files, alias bombs, files that echo (hardening, round 2).

Each case runs through the command line and asserts the contract: a
documented exit code, one line on stderr naming the file, no traceback.
Cases that could hang run in a subprocess with a generous timeout as a guard
(never a timed assertion).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from rockfall_design.cli.program import main
from rockfall_design.errors import ProjectError
from rockfall_design.project import load_project_text

ROOT = Path(__file__).resolve().parents[2]
PROJECTS = ROOT / "projects"
STANDARD = (PROJECTS / "standard_slope.yaml").read_text(encoding="utf-8")
GUARD_S = 60  # a guard against a hang, not a measure of speed


def one_line_error(capsys, *argv: str) -> str:
    try:
        code = main(list(argv))
    except SystemExit as exc:
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


def design_project(tmp_path: Path, old: str, new: str) -> Path:
    """design_two_zones.yaml with ``old`` replaced, beside copies of its catalogues."""
    text = (PROJECTS / "design_two_zones.yaml").read_text(encoding="utf-8")
    assert text.count(old) == 1
    for name in ("catalogue_products.yaml", "catalogue_costs.yaml"):
        (tmp_path / name).write_text((PROJECTS / name).read_text(encoding="utf-8"))
    path = tmp_path / "d.yaml"
    path.write_text(text.replace(old, new), encoding="utf-8")
    return path


def run_cli(*argv: str, env: dict | None = None, **kw) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "rockfall_design", *argv], capture_output=True, text=True,
        timeout=GUARD_S, env={**os.environ, **(env or {})}, **kw)


# --------------------------------------------------------------------------------------
# special and oversized files
# --------------------------------------------------------------------------------------


def test_dev_zero_is_refused_before_reading(capsys):
    err = one_line_error(capsys, "simulate", "/dev/zero")
    assert "/dev/zero: cannot read file: a device, not a regular file" in err


def test_a_fifo_is_refused_without_waiting_for_a_writer(tmp_path):
    fifo = tmp_path / "p.yaml"
    os.mkfifo(fifo)
    proc = run_cli("simulate", str(fifo))  # would block forever on open() without O_NONBLOCK
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1, proc.stderr
    assert f"{fifo}: cannot read file: a FIFO (named pipe), not a regular file" in proc.stderr


def test_a_directory_is_refused(tmp_path, capsys):
    err = one_line_error(capsys, "check", str(tmp_path))
    assert "a directory, not a regular file" in err


def test_a_file_over_the_limit_is_refused_and_the_limit_is_configurable(tmp_path, capsys,
                                                                      monkeypatch):
    path = tmp_path / "p.yaml"
    path.write_text(STANDARD + "# " + "x" * 3000 + "\n", encoding="utf-8")
    monkeypatch.setenv("RF_MAX_FILE_MB", "0.002")  # 2,000 bytes
    err = one_line_error(capsys, "simulate", str(path))
    assert f"{path}: cannot read file: larger than 0.002 MB" in err and "RF_MAX_FILE_MB" in err
    monkeypatch.setenv("RF_MAX_FILE_MB", "1")
    assert main(["simulate", str(path), "--rocks", "3", "--json"]) == 0
    capsys.readouterr()
    monkeypatch.setenv("RF_MAX_FILE_MB", "lots")
    err = one_line_error(capsys, "simulate", str(path))
    assert "RF_MAX_FILE_MB='lots'" in err


def test_a_file_that_grows_while_it_is_read_is_refused(tmp_path, monkeypatch):
    """No more than limit + 1 bytes are read, whatever the size was when it was checked."""
    from rockfall_design.project import inputs

    path = tmp_path / "p.yaml"
    path.write_text("a: 1\n" * 100)  # 500 bytes
    monkeypatch.setenv("RF_MAX_FILE_MB", "0.00001")  # 10 bytes
    real_fstat, real_read = os.fstat, os.read
    # The size as it was when checked, before the file grew.
    monkeypatch.setattr(inputs.os, "fstat", lambda fd: os.stat_result(
        (*real_fstat(fd)[:6], 5, *real_fstat(fd)[7:])))
    read: list[int] = []
    monkeypatch.setattr(inputs.os, "read",
                        lambda fd, n: read.append(n) or real_read(fd, n))
    with pytest.raises(inputs.UnreadableFile, match="larger than 1e-05 MB"):
        inputs.read_text(path)
    assert sum(read) <= 11


@pytest.mark.parametrize("what", ["products", "costs"])
def test_a_catalogue_that_is_a_special_or_huge_file_is_refused(what, tmp_path, capsys,
                                                              monkeypatch):
    old = {"products": "products: catalogue_products.yaml",
           "costs": "file: catalogue_costs.yaml"}[what]
    key = {"products": "design.products", "costs": "design.costs.file"}[what]
    path = design_project(tmp_path, old, old.split(":")[0] + ": /dev/zero")
    err = one_line_error(capsys, "optimise", str(path))
    assert f"{path}:" in err and key in err and "a device, not a regular file" in err
    big = tmp_path / "big.yaml"
    big.write_text("# padding\n" * 1000)  # 10 kB, the project 2 kB
    path = design_project(tmp_path, old, old.split(":")[0] + f": {big}")
    monkeypatch.setenv("RF_MAX_FILE_MB", "0.005")
    err = one_line_error(capsys, "optimise", str(path))
    assert key in err and "larger than 0.005 MB" in err


def test_repeat_refuses_a_special_file(capsys):
    err = one_line_error(capsys, "simulate", "--repeat", "/dev/zero")
    assert "/dev/zero" in err and "a device, not a regular file" in err


# --------------------------------------------------------------------------------------
# alias and merge-key bombs
# --------------------------------------------------------------------------------------


def merge_bomb(levels: int = 11) -> str:
    """Ten levels of mappings, each merging ten aliases of the level above (~1 KB)."""
    lines = ["name: bomb", "l0: &l0 {a: 1, b: 2, c: 3, d: 4, e: 5, f: 6, g: 7, h: 8, i: 9, j: 0}"]
    for k in range(1, levels + 1):
        lines.append(f"l{k}: &l{k} {{<<: [{', '.join([f'*l{k - 1}'] * 10)}], k{k}: 0}}")
    return "\n".join(lines) + "\n"


def test_a_merge_key_bomb_is_refused_at_once(tmp_path):
    path = tmp_path / "bomb.yaml"
    path.write_text(merge_bomb())
    assert path.stat().st_size < 1800
    proc = run_cli("simulate", str(path))  # hung before: 10**11 entries to copy
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1, proc.stderr
    assert "merge keys (<<) would copy more than 10,000 entries" in proc.stderr
    assert f"{path}:5:" in proc.stderr  # the first merge beyond the budget


def test_a_merge_key_bomb_in_a_catalogue_is_refused(tmp_path, capsys):
    bomb = tmp_path / "catalogue.yaml"
    bomb.write_text(merge_bomb(6))
    path = design_project(tmp_path, "products: catalogue_products.yaml", f"products: {bomb}")
    err = one_line_error(capsys, "optimise", str(path))
    assert f"{bomb}:" in err and "merge keys (<<)" in err


def test_ordinary_merge_keys_still_work():
    text = STANDARD.replace("  talus:\n", "  base: &base {restitution: 0.3, friction: 0.5}\n"
                            "  talus:\n    <<: *base\n")
    text = text.replace("    restitution: 0.35         # e (spang) or Rn (rn_rt)\n", "")
    assert load_project_text(text).materials["talus"].restitution == 0.3


def test_a_billion_laughs_of_aliases_is_refused():
    lines = ["name: b", "l0: &l0 [1, 2, 3, 4, 5, 6, 7, 8, 9, 10]"]
    lines += [f"l{k}: &l{k} [{', '.join([f'*l{k - 1}'] * 10)}]" for k in range(1, 12)]
    with pytest.raises(ProjectError, match="more than 200000 values"):
        load_project_text("\n".join(lines) + "\n", "laughs.yaml")


def test_a_merge_that_contains_itself_is_refused():
    with pytest.raises(ProjectError, match="recursive alias"):
        load_project_text("name: x\na: &a {b: 1, <<: *a}\n")


# --------------------------------------------------------------------------------------
# a referenced file's content is never repeated in a message
# --------------------------------------------------------------------------------------

SECRET = "hunter2-do-not-print"


@pytest.mark.parametrize("content", [
    f"{SECRET}\n",                                   # a text file: one string
    f"password: {SECRET}\n",                         # a mapping of strings
    f"fence: {{a: {{capacity_kj: {SECRET}, heights: [1]}}}}\n",  # almost a catalogue
    f"currency: {SECRET}\nbarrier_per_m: {{1: {SECRET}}}\n",     # almost a price file
])
@pytest.mark.parametrize("what", ["products", "costs"])
def test_a_referenced_file_is_never_quoted(what, content, tmp_path, capsys):
    other = tmp_path / "unrelated.txt"
    other.write_text(content)
    old = {"products": "products: catalogue_products.yaml",
           "costs": "file: catalogue_costs.yaml"}[what]
    path = design_project(tmp_path, old, old.split(":")[0] + f": {other}")
    err = one_line_error(capsys, "optimise", str(path), "--rocks", "10")
    assert SECRET not in err and str(other) in err


def test_a_project_path_at_an_unrelated_file_is_not_quoted(tmp_path, capsys):
    path = tmp_path / "notes.txt"
    path.write_text(f"{SECRET}\n")
    err = one_line_error(capsys, "simulate", str(path))
    assert SECRET not in err and "expected a mapping of top-level keys" in err


# --------------------------------------------------------------------------------------
# large files under the limit: bounded work whatever they hold
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("values", [pytest.param(300_000, marks=pytest.mark.slow), 3_000_000],
                         ids=["pure-python", "libyaml"])
def test_a_file_of_many_values_is_refused_as_it_is_read(values):
    """Counted while parsed: before, a 48 MB list took minutes and gigabytes."""
    text = "name: x\nl: [" + "1, " * values + "1]\n"
    with pytest.raises(ProjectError, match="more than 200000 values"):
        load_project_text(text, "many.yaml")


def test_a_large_file_reads_as_the_small_one():
    """Over 1 MB, libyaml parses: the same project, the same line numbers."""
    from rockfall_design.project.yaml_file import LIBYAML_FROM

    text = (PROJECTS / "quarry_road.yaml").read_text(encoding="utf-8")
    padded = text + "# padding\n" * 120_000
    assert len(padded) > LIBYAML_FROM
    assert (load_project_text(padded).resolved_dict()
            == load_project_text(text).resolved_dict())
    bad = text.replace("  seed: 7\n", "  seed: 7\n  seed: 8\n")
    assert bad != text
    for source in (bad, bad + "# padding\n" * 120_000):
        with pytest.raises(ProjectError) as info:
            load_project_text(source, "q.yaml")
        assert str(info.value).startswith(
            f"q.yaml:{bad.splitlines().index('  seed: 8') + 1}: rocks.seed: duplicate key")


def test_a_file_of_one_long_comment_near_the_limit_is_read_quickly(tmp_path):
    """Pure-Python scanning would take half a minute here; the guard is a timeout."""
    path = tmp_path / "c.yaml"
    path.write_text("name: x\n" + ("#" + "c" * 98 + "\n") * 400_000)  # 40 MB
    proc = run_cli("simulate", str(path))
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1, proc.stderr
    assert "slope: required key is missing" in proc.stderr


def test_a_price_that_would_make_an_infinite_cost_is_bad_input(tmp_path, capsys):
    """1e308 per metre made a cost of inf, reported as a bug of the built-in cost model."""
    prices = (PROJECTS / "catalogue_costs.yaml").read_text(encoding="utf-8")
    assert prices.count("RX-100: {3: 520,") == 1
    path = design_project(tmp_path, "file: catalogue_costs.yaml", "file: prices.yaml")
    (tmp_path / "prices.yaml").write_text(prices.replace("RX-100: {3: 520,", "RX-100: {3: 1e308,"))
    err = one_line_error(capsys, "optimise", str(path), "--rocks", "10")
    assert f"{tmp_path / 'prices.yaml'}:" in err and "barrier_per_m.fence.RX-100.3" in err
    assert err.rstrip().endswith("expected a number <= 1000000000")  # the value not repeated

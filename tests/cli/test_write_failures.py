"""Write failures: a full disk, a file-size limit, a directory where a file goes.

Each gives exit code 2 and one line naming the file and the operating
system's reason, no traceback, and leaves the previous results exactly as
they were: a command's files are committed all together or not at all. The
full disk is simulated (``os.write`` raising ENOSPC), the size limit is a
real one (RLIMIT_FSIZE in a child process).
"""

from __future__ import annotations

import errno
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from rockfall_design.cli.program import main
from rockfall_design.report import outputs
from rockfall_design.report.outputs import OutputSet
from rockfall_design.report.staging import MANIFEST, OutputError
from rockfall_design.run import simulation

ROOT = Path(__file__).resolve().parents[2]
PROJECTS = ROOT / "projects"
STANDARD = PROJECTS / "standard_slope.yaml"
TABLES = ["crossings.csv", "rocks.csv", "summary.json"]


def previous_set(directory: Path, names: list[str]) -> dict[str, bytes]:
    directory.mkdir(parents=True, exist_ok=True)
    for name in names:
        (directory / name).write_bytes(f"previous {name}\n".encode())
    return contents(directory)


def contents(directory: Path) -> dict[str, bytes]:
    """Every file in ``directory``, hidden temporaries and backups included (not the manifest)."""
    return {p.name: p.read_bytes() for p in sorted(directory.iterdir())
            if p.is_file() and p.name != MANIFEST}


def written_earlier(directory: Path, names: list[str]) -> None:
    """Files ``names`` in ``directory`` as an earlier run wrote them (listed in its manifest)."""
    with OutputSet() as earlier:
        for name in names:
            earlier.write_text(directory / name, f"previous {name}\n")


def one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


def disk_full_under(monkeypatch, directory: Path, after: int = 0) -> None:
    """Make writes to files under ``directory`` fail with ENOSPC after ``after`` bytes."""
    real_write = os.write
    written = [0]

    def write(fd: int, data) -> int:
        try:
            name = os.readlink(f"/proc/self/fd/{fd}")
        except OSError:
            name = ""
        if name.startswith(str(directory)):
            if written[0] + len(data) > after:
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
            written[0] += len(data)
        return real_write(fd, data)

    monkeypatch.setattr(os, "write", write)


@pytest.mark.skipif(not Path("/proc/self/fd").is_dir(), reason="needs /proc")
@pytest.mark.parametrize("after", [0, 5000], ids=["at-once", "half-way"])
def test_a_full_disk_is_one_line_and_leaves_the_previous_results(tmp_path, monkeypatch, capsys,
                                                                 after):
    out = tmp_path / "out"
    previous = previous_set(out, TABLES)
    disk_full_under(monkeypatch, out, after)
    code = main(["simulate", str(STANDARD), "--rocks", "200", "--out", str(out)])
    err = one_line(capsys)
    assert code == 2, err
    assert f"cannot write {out}/" in err and "No space left on device" in err, err
    assert "no file was changed" in err
    assert contents(out) == previous


@pytest.mark.skipif(not Path("/proc/self/fd").is_dir(), reason="needs /proc")
def test_a_full_disk_while_writing_the_figures(tmp_path, monkeypatch, capsys):
    out, plot = tmp_path / "out", tmp_path / "figures"
    previous = previous_set(out, TABLES)
    old_figures = previous_set(plot, ["envelopes.png", "profile.png", "stops.png"])
    disk_full_under(monkeypatch, plot)
    code = main(["check", str(PROJECTS / "quarry_fence_ditch.yaml"), "--rocks", "30",
                 "--out", str(out), "--plot", str(plot)])
    err = one_line(capsys)
    assert code == 2 and f"cannot write {plot}/" in err and "No space left" in err, err
    assert contents(out) == {**previous} and contents(plot) == old_figures


@pytest.mark.skipif(sys.platform != "linux", reason="RLIMIT_FSIZE and EFBIG as on Linux")
def test_a_file_size_limit_is_one_line_and_leaves_the_previous_results(tmp_path):
    """EFBIG for real: the child may write files of at most 20 kB."""
    import resource

    out = tmp_path / "out"
    previous = previous_set(out, TABLES)

    def limit() -> None:  # runs in the child
        resource.setrlimit(resource.RLIMIT_FSIZE, (20_000, resource.RLIM_INFINITY))

    proc = subprocess.run(
        [sys.executable, "-m", "rockfall_design", "simulate", str(STANDARD), "--rocks", "400",
         "--out", str(out)],
        capture_output=True, text=True, timeout=300, preexec_fn=limit)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert f"cannot write {out}/" in proc.stderr and "File too large" in proc.stderr
    assert contents(out) == previous


def test_an_output_name_that_is_a_directory_is_reported_before_the_run(tmp_path, monkeypatch,
                                                                       capsys):
    out = tmp_path / "out"
    previous = previous_set(out, ["crossings.csv", "rocks.csv"])
    (out / "summary.json").mkdir()
    monkeypatch.setattr(simulation, "run_ensemble", None)  # must not be reached
    code = main(["simulate", str(STANDARD), "--rocks", "100000", "--out", str(out)])
    err = one_line(capsys)
    assert code == 2 and f"cannot write {out / 'summary.json'}: it is a directory" in err, err
    assert contents(out) == previous and (out / "summary.json").is_dir()


def test_a_plot_directory_that_cannot_be_made_is_reported_before_the_run(tmp_path,
                                                                         monkeypatch, capsys):
    (tmp_path / "a-file").write_text("not a directory\n")
    plot = tmp_path / "a-file" / "figures"
    monkeypatch.setattr(simulation, "run_ensemble", None)  # must not be reached
    code = main(["simulate", str(STANDARD), "--rocks", "100000", "--plot", str(plot)])
    err = one_line(capsys)
    assert code == 2 and "cannot write" in err and str(plot) in err, err


def test_a_rename_refused_half_way_puts_back_the_ones_done(tmp_path, monkeypatch):
    previous = previous_set(tmp_path, ["a.csv", "b.json", "c.png"])
    real_replace = os.replace
    new_files = []

    def replace(src, dst) -> None:
        if Path(src).name.endswith(".tmp"):  # a new file going into place
            new_files.append(Path(dst).name)
            if len(new_files) == 2:
                raise OSError(errno.EIO, os.strerror(errno.EIO))
        real_replace(src, dst)

    monkeypatch.setattr(outputs.os, "replace", replace)
    with pytest.raises(OutputError, match=r"cannot write .*b\.json: Input/output error; "
                                          "no file was changed"):
        with OutputSet() as files:
            files.write_text(tmp_path / "a.csv", "new a\n")
            files.write_json(tmp_path / "b.json", {"new": True})
            files.write_with(tmp_path / "c.png", lambda fh: fh.write(b"new c"))
    assert new_files == ["a.csv", "b.json"]
    assert contents(tmp_path) == previous  # a.csv put back, no temporaries, no backups


def test_a_target_that_became_a_directory_before_the_commit(tmp_path):
    previous = previous_set(tmp_path, ["a.csv"])
    with pytest.raises(OutputError, match="it is a directory; no file was changed"):
        with OutputSet() as files:
            files.write_text(tmp_path / "a.csv", "new a\n")
            files.write_text(tmp_path / "b.json", "new b\n")
            (tmp_path / "b.json").mkdir()  # after the check when it was opened
    assert contents(tmp_path) == previous


def test_a_commit_leaves_no_backups(tmp_path):
    previous_set(tmp_path, ["a.csv"])
    with OutputSet() as files:
        files.write_text(tmp_path / "a.csv", "new a\n")
        files.write_text(tmp_path / "b.json", "new b\n")
    assert contents(tmp_path) == {"a.csv": b"new a\n", "b.json": b"new b\n"}


def test_optimise_without_a_design_removes_earlier_figures(tmp_path, capsys):
    """Figures of an earlier design must not stay beside a result that has none."""
    text = (PROJECTS / "design_ditch_or_fence.yaml").read_text()
    text = text[: text.index("    - type: ditch")]
    # (by pattern: the project's stations change with its design; the road moved to 120 m)
    text = re.sub(r"\n      x: \[[0-9., ]+\]", "\n      x: [2, 10]", text, count=1)
    text = re.sub(r"protect:\n  x: [0-9.]+", "protect:\n  x: 50", text, count=1)
    text = text.replace("catalogue_", f"{PROJECTS}/catalogue_")
    assert "x: [2, 10]" in text and "protect:\n  x: 50" in text
    project = tmp_path / "hopeless.yaml"
    project.write_text(text)
    plot = tmp_path / "figures"
    written_earlier(plot, ["envelopes.png", "profile.png", "stops.png"])
    previous_set(plot, ["mine.txt"])
    code = main(["optimise", str(project), "--rocks", "200", "--plot", str(plot), "--json"])
    s = json.loads(capsys.readouterr().out)
    assert code == 1 and s["best"] is None
    # Only the figure that compares the families (they all failed) is drawn.
    assert sorted(contents(plot)) == ["alternatives.png", "mine.txt"]


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
@pytest.mark.parametrize("argv", [["simulate", str(STANDARD), "--rocks", "5", "--json"],
                                  ["simulate", str(STANDARD), "--rocks", "5"],
                                  ["plugins"]], ids=["json", "report", "plugins"])
def test_a_full_disk_on_standard_output_is_one_line(argv):
    with open("/dev/full", "w") as full:
        proc = subprocess.run([sys.executable, "-m", "rockfall_design", *argv], stdout=full,
                              stderr=subprocess.PIPE, text=True, timeout=300)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr == ("rockfall-design: error: cannot write to standard output: "
                           "No space left on device\n")

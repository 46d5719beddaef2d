"""Round four of the browser app's hardening (issue 34 items 1-4), through the test client.

Only the app's own page changes anything; Save writes the project file it
opened and nothing else; errors are JSON, never tracebacks; finished jobs
keep their summaries and only the latest few full results; the page judges
as ``check`` does. The real-browser cases (a cross-origin form, two servers)
are in ``test_browser.py``.
"""

from __future__ import annotations

import errno
import gc
import os
import shutil
import weakref
from pathlib import Path

import pytest

pytest.importorskip("httpx", reason="Starlette's test client needs httpx")

from starlette.testclient import TestClient  # noqa: E402

from rockfall_design.judge.verdict import UNTESTED, verdict_of  # noqa: E402
from rockfall_design.plugins import load_registry  # noqa: E402
from rockfall_design.serve import find_projects, guards  # noqa: E402
from rockfall_design.serve.app import TOKEN_HEADER, create_app  # noqa: E402
from rockfall_design.serve.jobs import Job, JobStore  # noqa: E402
from rockfall_design.serve.workbench import load_entries  # noqa: E402

from ..plugin_helpers import install_embankment_example  # noqa: E402
from .conftest import start_server, stop_server  # noqa: E402
from .conftest import wait_job as _wait  # noqa: E402

TOKEN = "test-token-hardening-0123"
OWN = "http://127.0.0.1"
HEADERS = {TOKEN_HEADER: TOKEN, "Origin": OWN}
FENCE = {"type": "fence", "height": 5.0, "capacity_kj": 2000.0}
QUARRY_FILES = ("calibrate_quarry.yaml", "quarry_stops_a.csv", "quarry_stops_b.csv")


def _snapshot(directory: Path) -> dict[Path, tuple[bytes, int]]:
    """Every file under ``directory`` with its bytes and mode: to show nothing changed."""
    return {p: (p.read_bytes(), p.stat().st_mode) for p in sorted(directory.rglob("*"))
            if p.is_file()}


def _serve(registry, directory: Path, name: str, **kw) -> tuple[TestClient, object]:
    (entry,) = load_entries([directory / name], registry)
    app = create_app([entry], TOKEN)
    return TestClient(app, base_url=OWN, headers=HEADERS, **kw), entry


@pytest.fixture()
def quarry(tmp_path, registry, projects_dir):
    """calibrate_quarry.yaml with its observed stops, in a directory of their own, served."""
    for name in QUARRY_FILES:
        shutil.copy(projects_dir / name, tmp_path / name)
    c, entry = _serve(registry, tmp_path, "calibrate_quarry.yaml")
    with c:
        yield c, entry, tmp_path


@pytest.fixture()
def two_zones(tmp_path, registry, projects_dir):
    """design_two_zones.yaml, its catalogues and a survey CSV beside it, served, no run."""
    for name in ("design_two_zones.yaml", "catalogue_products.yaml", "catalogue_costs.yaml",
                 "survey_section.csv"):
        shutil.copy(projects_dir / name, tmp_path / name)
    c, entry = _serve(registry, tmp_path, "design_two_zones.yaml")
    with c:
        yield c, entry, tmp_path


# ---- item 1: only the app's own page changes anything --------------------------------------


@pytest.mark.parametrize("headers, why", [
    ({"Origin": "http://127.0.0.1:38999"}, "Origin"),
    ({"Origin": "null"}, "Origin"),
    ({"Origin": None}, "no Origin"),
    ({"Origin": None, "Referer": "http://127.0.0.1:38999/attack.html"}, "no Origin"),
    ({"Content-Type": "text/plain"}, "Content-Type"),
    ({"Content-Type": "application/x-www-form-urlencoded"}, "Content-Type"),
    ({"Content-Type": "multipart/form-data; boundary=x"}, "Content-Type"),
])
def test_a_change_from_another_page_or_not_json_is_refused(quarry, headers, why):
    c, entry, d = quarry
    before = _snapshot(d)
    sent = {k: v for k, v in {"Content-Type": "application/json", **headers}.items()
            if v is not None}
    for k, v in headers.items():
        if v is None:
            del c.headers[k]  # not sent at all
    body = ('{"path": "quarry_stops_a.csv", "replace": true, '
            '"text": "x\\n1\\n2\\n3\\n4\\n5\\n"}')
    r = c.post("/api/projects/calibrate_quarry/upload", content=body, headers=sent)
    assert r.status_code == 403, r.text
    assert why in r.json()["error"]
    r = c.post("/api/projects/calibrate_quarry/simulate", content="{}", headers=sent)
    assert r.status_code == 403 and entry.job is None
    assert _snapshot(d) == before


def test_a_same_origin_referer_stands_in_for_a_missing_origin(quarry):
    c, _, _ = quarry
    r = c.post("/api/projects/calibrate_quarry/validate", json={"text": "slope: 1"},
               headers={"Origin": "", "Referer": f"{OWN}/?token=x"})
    # An empty Origin is not this app's: refused; without one, the Referer decides.
    assert r.status_code == 403
    del c.headers["Origin"]
    r = c.post("/api/projects/calibrate_quarry/validate", json={"text": "slope: 1"},
               headers={"Referer": f"{OWN}/?token=x"})
    assert r.status_code == 400 and r.json()["error"].startswith("calibrate_quarry.yaml")


def test_the_token_comes_in_a_header_not_a_cookie(quarry):
    c, _, _ = quarry
    c.cookies.set("rockfall_design_token", TOKEN)  # the cookie of rounds one to three
    r = c.get("/api/projects", headers={TOKEN_HEADER: ""})
    assert r.status_code == 403 and r.headers["content-type"] == "application/json"
    assert "token" in r.json()["error"]


# ---- item 2: Save writes the project file it opened, Upload its own kind -------------------


def test_save_never_writes_another_file(two_zones):
    c, _, d = two_zones
    before = _snapshot(d)
    version = c.get("/api/projects/design_two_zones/file").json()["version"]
    text = (d / "design_two_zones.yaml").read_text()
    for path in ("survey_section.csv", "notes.txt", "other.yaml", "../design_two_zones.yaml"):
        r = c.post("/api/projects/design_two_zones/save",
                   json={"text": text, "path": path, "version": version})
        assert r.status_code == 400 and "nothing else" in r.json()["error"], r.text
    assert _snapshot(d) == before


def test_save_refuses_a_file_changed_since_the_page_read_it(two_zones):
    c, entry, d = two_zones
    path = d / "design_two_zones.yaml"
    read = c.get("/api/projects/design_two_zones/file").json()
    assert read["version"] and read["text"] == path.read_text()
    # Someone edits the file in another editor after the page read it.
    theirs = path.read_text().replace("count: 3000", "count: 2500")
    path.write_text(theirs)
    ours = read["text"].replace("count: 3000", "count: 2000")
    r = c.post("/api/projects/design_two_zones/save", json={"text": ours,
                                                          "version": read["version"]})
    assert r.status_code == 409 and "changed since the page read it" in r.json()["error"]
    assert path.read_text() == theirs
    r = c.post("/api/projects/design_two_zones/save", json={"text": ours})
    assert r.status_code == 400 and r.json()["error"].startswith("version:")
    assert path.read_text() == theirs
    # Read again: saved.
    fresh = c.get("/api/projects/design_two_zones/file").json()["version"]
    r = c.post("/api/projects/design_two_zones/save", json={"text": ours, "version": fresh})
    assert r.status_code == 200 and path.read_text() == ours


def test_save_is_refused_while_a_job_of_the_project_runs(two_zones):
    c, entry, d = two_zones
    before = _snapshot(d)
    read = c.get("/api/projects/design_two_zones/file").json()
    entry.job = Job("simulate", 1000)  # running
    try:
        r = c.post("/api/projects/design_two_zones/save",
                   json={"text": read["text"].replace("count: 3000", "count: 2000"),
                         "version": read["version"]})
        assert r.status_code == 409 and "under way" in r.json()["error"], r.text
        # As Apply Material does in the same case.
    finally:
        entry.job.state = "cancelled"
    assert _snapshot(d) == before and entry.project.rocks.count == 3000


STOPS = "x\n" + "".join(f"{30 + i}.5\n" for i in range(12))
SECTION = "x,y,material\n0,50,rock\n100,0,\n"
LIBRARY = "rockish:\n  restitution: 0.4\n  friction: 0.5\n"


@pytest.mark.parametrize("path, text, status, words", [
    # an upload replaces only a file of its own kind
    ("quarry_stops_a.csv", SECTION, 409, "observed stops"),
    ("calibrate_quarry.yaml", LIBRARY, 400, "project file"),
    ("other_project.yaml", LIBRARY, 409, "project file"),
    # what is none of the kinds an upload writes
    ("quarry_stops_a.csv", '{"ok":true}', 400, "not one of"),
    ("notes.yaml", "script:\n  - rm -rf /\n", 400, "not one of"),
    # never a dotfile or anything under a dot-folder
    (".gitlab-ci.yml", LIBRARY, 403, "dotfile"),
    (".github/workflows/ci.yml", LIBRARY, 403, "dot"),
    ("sub/.hidden.csv", STOPS, 403, "dot"),
])
def test_upload_never_replaces_another_kind_of_file(quarry, projects_dir, path, text, status,
                                                    words):
    c, _, d = quarry
    shutil.copy(projects_dir / "standard_slope.yaml", d / "other_project.yaml")
    (d / ".github" / "workflows").mkdir(parents=True)
    (d / ".github" / "workflows" / "ci.yml").write_text("on: push\n")
    (d / ".gitlab-ci.yml").write_text("script: [make]\n")
    (d / "sub").mkdir()
    before = _snapshot(d)
    r = c.post("/api/projects/calibrate_quarry/upload",
               json={"path": path, "text": text, "replace": True})
    assert r.status_code == status and words in r.json()["error"], r.text
    assert _snapshot(d) == before


def test_upload_replaces_a_file_of_its_own_kind_and_keeps_its_mode(quarry):
    c, _, d = quarry
    target = d / "quarry_stops_b.csv"
    target.chmod(0o664)
    r = c.post("/api/projects/calibrate_quarry/upload",
               json={"path": "quarry_stops_b.csv", "text": STOPS, "replace": True})
    assert r.status_code == 200, r.text
    assert target.read_text() == STOPS and target.stat().st_mode & 0o777 == 0o664
    r = c.post("/api/projects/calibrate_quarry/upload",
               json={"path": "lib.yaml", "text": LIBRARY})
    assert r.status_code == 200 and (d / "lib.yaml").read_text() == LIBRARY


def test_a_write_leaves_no_temporary_of_a_killed_server_behind(quarry, monkeypatch):
    """Save and Upload name their temporaries by owner, as the commands do (item 7).

    A server killed during a write leaves ``.NAME.PID-HOST.RANDOM.tmp``; the
    next write into that folder removes it once its process is gone.
    """
    from rockfall_design.report import temporaries

    c, _, d = quarry
    fd, made = temporaries.make(d, "quarry_stops_b.csv")
    os.write(fd, b"half a file")
    os.close(fd)
    # As if another process, long gone, had made it.
    dead = Path(made.replace(f".{os.getpid()}-", ".999999999-"))
    os.rename(made, dead)
    seen: list[str] = []
    real = guards.write_bytes

    def spy(fd: int, data: bytes) -> None:
        seen.extend(p.name for p in d.iterdir() if p.name.endswith(".tmp"))
        real(fd, data)

    monkeypatch.setattr(guards, "write_bytes", spy)
    r = c.post("/api/projects/calibrate_quarry/upload",
               json={"path": "quarry_stops_b.csv", "text": STOPS, "replace": True})
    assert r.status_code == 200, r.text
    assert not dead.exists()
    assert [n for n in seen if n.startswith(f".quarry_stops_b.csv.{os.getpid()}-")], seen
    assert not [p for p in d.iterdir() if p.name.endswith(".tmp")]


# ---- item 3: serve fails cleanly --------------------------------------------------------------


@pytest.mark.parametrize("endpoint, raw, key", [
    ("/api/projects/calibrate_quarry/simulate", '{"rocks": NaN}', "rocks"),
    ("/api/projects/calibrate_quarry/simulate", '{"rocks": Infinity}', "rocks"),
    ("/api/projects/calibrate_quarry/simulate", '{"seed": -Infinity}', "seed"),
    ("/api/projects/calibrate_quarry/simulate", '{"seed": 1e400}', "seed"),
    ("/api/projects/calibrate_quarry/simulate", '{"seed": 1e300}', "seed"),
    ("/api/projects/calibrate_quarry/simulate", '{"rocks": 1e300}', "rocks"),
    ("/api/projects/calibrate_quarry/check", '{"measures": [{"type": "fence", "x": NaN}]}',
     "measures[0].x"),
    ("/api/place", '{"project": "calibrate_quarry", "measure": {"type": "fence", '
     '"height": Infinity}, "x": 20}', "measure.height"),
    ("/api/projects/calibrate_quarry/calibrate", '{"bootstrap": NaN}', "bootstrap"),
])
def test_non_finite_and_huge_numbers_are_refused_at_their_key(quarry, endpoint, raw, key):
    c, entry, _ = quarry
    r = c.post(endpoint, content=raw, headers={"Content-Type": "application/json"})
    assert r.status_code == 400, r.text
    assert r.json()["error"].startswith(f"{key}:"), r.text
    assert entry.job is None


def test_every_refusal_is_json_with_a_message(quarry):
    c, _, _ = quarry
    for r in (c.get("/api/nosuch"), c.get("/api/projects/calibrate_quarry/simulate"),
              c.post("/api/projects", json={}), c.get("/api/projects", headers={
                  TOKEN_HEADER: "wrong"})):
        assert r.status_code in (403, 404, 405)
        assert r.headers["content-type"] == "application/json" and r.json()["error"]


@pytest.mark.parametrize("code", [errno.ENOSPC, errno.EFBIG])
def test_a_full_disk_is_507_with_nothing_half_written(two_zones, quarry, monkeypatch, code):
    c, _, d = two_zones
    qc, _, qd = quarry
    before, qbefore = _snapshot(d), _snapshot(qd)
    written: list[int] = []

    def full(fd: int, data: bytes) -> None:
        # Half the bytes go, then the disk is full: what a real ENOSPC leaves.
        written.append(os.write(fd, data[: len(data) // 2]))
        raise OSError(code, os.strerror(code))

    monkeypatch.setattr(guards, "write_bytes", full)
    read = c.get("/api/projects/design_two_zones/file").json()
    r = c.post("/api/projects/design_two_zones/save",
               json={"text": read["text"] + "# more\n", "version": read["version"]})
    assert r.status_code == 507 and "not written" in r.json()["error"], r.text
    r = qc.post("/api/projects/calibrate_quarry/upload",
                json={"path": "quarry_stops_b.csv", "text": STOPS, "replace": True})
    assert r.status_code == 507 and "as it was" in r.json()["error"], r.text
    assert written and _snapshot(d) == before and _snapshot(qd) == qbefore  # no temporaries


def test_the_server_prints_no_traceback_for_bad_numbers(tmp_path, projects_dir):
    import httpx

    for name in QUARRY_FILES:
        shutil.copy(projects_dir / name, tmp_path / name)
    proc, url = start_server(str(tmp_path / "calibrate_quarry.yaml"))
    try:
        origin, token = url.split("/?token=")
        h = {TOKEN_HEADER: token, "Origin": origin, "Content-Type": "application/json"}
        for raw in ('{"rocks": NaN}', '{"rocks": Infinity}', '{"seed": -Infinity}'):
            r = httpx.post(f"{origin}/api/projects/calibrate_quarry/simulate", content=raw,
                           headers=h)
            assert r.status_code == 400 and r.json()["error"], r.text
    finally:
        code, err = stop_server(proc)
    assert "Traceback" not in err and "Exception" not in err, err


class _Heavy:
    """Stands in for a check's full evaluation (tens of MB in a real one)."""


def _finished_job(heavy: _Heavy) -> Job:
    job = Job("check", 1)
    job.result = {"verdict": {"state": "fails"}, "rocks": 1}
    job.files = {"report.html": lambda: repr(heavy).encode(), "design.yaml": "measures: []\n"}
    job.state = "done"
    return job


def test_finished_jobs_keep_their_summaries_and_a_bounded_number_of_full_results():
    store = JobStore(keep_full=4)
    refs = []
    jobs = []
    for _ in range(50):
        heavy = _Heavy()
        refs.append(weakref.ref(heavy))
        job = _finished_job(heavy)
        del heavy
        store.add(job)
        jobs.append(job)
        assert len(store.full()) <= 4
    gc.collect()
    alive = [r() is not None for r in refs]
    assert sum(alive) == 4 and alive[-4:] == [True] * 4  # the latest four, all others freed
    for job in jobs:
        assert store.get(job.id) is job and job.result["rocks"] == 1  # every summary kept
        assert job.files.get("design.yaml") == "measures: []\n"  # small files too
    assert jobs[0].released == {"report.html"}
    # A download counts as a use: the job used last keeps its full result longest.
    store.touch(jobs[-4])
    store.add(_finished_job(_Heavy()))
    assert jobs[-4] in store.full() and jobs[-3] not in store.full()


def test_a_running_job_keeps_everything_and_old_jobs_are_forgotten():
    store = JobStore(keep_full=1, keep_jobs=10)
    running = Job("check", 1)
    running.files = {"report.html": lambda: b""}
    store.add(running)
    for _ in range(30):
        store.add(_finished_job(_Heavy()))
    assert store.get(running.id) is running and "report.html" in running.files
    assert len(store) == 10


def test_old_checks_release_their_downloads_with_a_clear_410(quarry):
    c, _, _ = quarry
    ids = []
    for i in range(6):
        r = c.post("/api/projects/calibrate_quarry/check",
                   json={"rocks": 20, "seed": i, "measures": [{**FENCE, "x": 40}]})
        assert r.status_code == 202, r.text
        job = _wait(c, r.json()["id"])
        assert job["state"] == "done", job
        ids.append(job["id"])
    first = c.get(f"/api/jobs/{ids[0]}")
    assert first.json()["result"]["rocks"] == 20  # the summary stays
    r = c.get(f"/api/jobs/{ids[0]}/files/report.html")
    assert r.status_code == 410 and "no longer kept" in r.json()["error"]
    assert "report.html" in c.get(f"/api/jobs/{ids[-1]}").json()["files"]


# ---- item 4: the page judges as check does ---------------------------------------------------


def _with_allowed(tmp_path, projects_dir, allowed: float) -> Path:
    text = (projects_dir / "quarry_fence_ditch.yaml").read_text()
    assert "allowed_fraction: 0.001" in text
    path = tmp_path / "quarry_fence_ditch.yaml"
    path.write_text(text.replace("allowed_fraction: 0.001", f"allowed_fraction: {allowed}"))
    return path


@pytest.mark.parametrize("allowed", [0.05, 0.2])
def test_without_a_design_section_the_residual_is_judged_against_allowed_fraction(
        tmp_path, registry, projects_dir, allowed):
    """The residual's allowance is protect.allowed_fraction (not 0), and the page's verdict
    is check's on the same rocks (a fence no rock breaks through: exact)."""
    from rockfall_design.judge.evaluation import evaluate
    from rockfall_design.results import CheckResult

    path = _with_allowed(tmp_path, projects_dir, allowed)
    c, entry = _serve(registry, tmp_path, path.name)
    fence = {"type": "fence", "x": 60.0, "height": 12.0, "capacity_kj": 20000.0}
    with c:
        r = c.post("/api/projects/quarry_fence_ditch/simulate", json={"rocks": 400, "seed": 3})
        assert _wait(c, r.json()["id"])["state"] == "done"
        out = c.post("/api/place", json={"project": "quarry_fence_ditch",
                                         "measures": [fence]}).json()
    assert out["residual"]["allowed_fraction"] == pytest.approx(allowed)
    assert out["measures"][0]["broken_through"] == 0 and out["measures"][0]["rebounded"] == 0
    project = entry.project.model_copy(update={"measures": [fence]})
    ev = evaluate(project, registry, rocks=400, seed=3)
    summary = CheckResult(project, ev, registry).summary
    assert out["residual"]["reaching"] == summary["protect"]["reaching"]
    assert out["verdict"]["state"] == summary["verdict"]["state"]
    assert out["verdict"]["state"] == verdict_of(summary).state


def test_a_measure_no_rock_reaches_is_untested_not_holds(quarry):
    c, _, _ = quarry
    r = c.post("/api/projects/calibrate_quarry/simulate", json={"rocks": 300, "seed": 2})
    assert _wait(c, r.json()["id"])["state"] == "done"
    section = c.get("/api/projects/calibrate_quarry").json()["ground"]
    crest = section[0][0] + 0.5  # upslope of every release: no rock goes there
    out = c.post("/api/place", json={"project": "calibrate_quarry", "measure": FENCE,
                                     "x": crest}).json()
    (m,) = out["measures"]
    assert m["met"] == 0
    assert out["verdict"]["state"] == UNTESTED
    assert out["verdict"]["untested_measures"] == [m["label"]]


@pytest.mark.parametrize("name", [p.name for p in find_projects(
    Path(__file__).resolve().parents[2] / "projects")])
def test_place_and_check_with_the_projects_own_measures_on_every_bundled_project(
        name, registry, projects_dir, tmp_path, monkeypatch):
    """As the page sends them: the project's own measures as describe() gives them (with
    their labels) and a fence placed where it fits."""
    if name == "design_embankment.yaml":  # its candidate is the example plugin's
        install_embankment_example(tmp_path, monkeypatch)
        registry = load_registry()
    (entry,) = load_entries([projects_dir / name], registry)
    app = create_app([entry], TOKEN)
    with TestClient(app, base_url=OWN, headers=HEADERS) as c:
        d = c.get(f"/api/projects/{entry.id}").json()
        own = d["measures"]
        x = _free_place(d)
        placed = {**FENCE, "x": x}
        r = c.post(f"/api/projects/{entry.id}/simulate", json={"rocks": 60, "seed": 1})
        assert r.status_code == 202, r.text
        job = _wait(c, r.json()["id"])
        assert job["state"] == "done", job
        r = c.post("/api/place", json={"project": entry.id, "measures": [*own, placed]})
        assert r.status_code == 200, r.text
        assert len(r.json()["measures"]) == len(own) + 1 and r.json()["verdict"]["state"]
        r = c.post(f"/api/projects/{entry.id}/check",
                   json={"rocks": 30, "seed": 1, "measures": [*own, placed]})
        assert r.status_code == 202, r.text
        job = _wait(c, r.json()["id"])
        assert job["state"] == "done", job
        assert len(job["result"]["measures"]) == len(own) + 1


def _free_place(d: dict) -> float:
    """A station for a fence clear of the project's own measures (10 m either side)."""
    x0, x1 = d["ground"][0][0], d["ground"][-1][0]
    taken = [float(m["x"]) for m in d["measures"]]
    for frac in (0.4, 0.3, 0.5, 0.2, 0.6, 0.7, 0.15):
        x = round(x0 + frac * (x1 - x0), 1)
        if all(abs(x - t) > 10.0 for t in taken):
            return x
    raise AssertionError(f"no free place on {d['name']}")

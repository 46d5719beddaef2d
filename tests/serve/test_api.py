"""The API of rockfall-design serve, through Starlette's test client (no server, no browser)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("httpx", reason="Starlette's test client needs httpx")

from starlette.testclient import TestClient  # noqa: E402

import rockfall_design as rd  # noqa: E402
from rockfall_design.cli.program import main  # noqa: E402
from rockfall_design.judge.placing import place_measures
from rockfall_design.serve.app import TOKEN_HEADER, create_app  # noqa: E402
from rockfall_design.serve.guards import MAX_BODY_BYTES
from rockfall_design.serve.page_run import TABLE_STEP_M
from rockfall_design.serve.workbench import load_entries
from rockfall_design.trial.placements import trial_spec

from .conftest import TWO_ZONES_FILES
from .conftest import wait_job as _wait

TOKEN = "test-token-0123456789"
ROCKS = 1500
SEED = 5
FENCE = {"type": "fence", "height": 5.0, "capacity_kj": 2000.0}
#: A design project that optimises in seconds, and the catalogues it reads beside it.
SMALL_DESIGN_DIR = Path(__file__).resolve().parents[1] / "data"
SMALL_DESIGN_FILES = ("design_small.yaml", "catalogue_products.yaml", "catalogue_costs.yaml")


#: What the page sends with every request: its token, and its own origin.
HEADERS = {TOKEN_HEADER: TOKEN, "Origin": "http://127.0.0.1"}


def _client(app) -> TestClient:
    """A client that is the app's own page: the token in the header, the app's origin."""
    return TestClient(app, base_url="http://127.0.0.1", headers=HEADERS)


@pytest.fixture(scope="module")
def entries(project_copy, registry):
    return load_entries([project_copy], registry)


@pytest.fixture(scope="module")
def client(entries):
    """A client holding the token's cookie, with one finished run of the project."""
    app = create_app(entries, TOKEN)
    with _client(app) as c:
        assert c.get(f"/?token={TOKEN}").status_code == 200
        r = c.post("/api/projects/design_two_zones/simulate", json={"rocks": ROCKS, "seed": SEED})
        assert r.status_code == 202, r.text
        job = _wait(c, r.json()["id"])
        assert job["state"] == "done", job
        yield c


def _snapshot(directory):
    """Every file under ``directory`` with its bytes: to show that nothing changed."""
    return {p: p.read_bytes() for p in sorted(directory.rglob("*")) if p.is_file()}


# ---- the token --------------------------------------------------------------------


@pytest.mark.parametrize("path", ["/", "/static/app.js", "/api/projects",
                                  "/api/projects/design_two_zones", "/api/plugins"])
def test_every_request_without_the_token_is_refused(entries, path):
    app = create_app(entries, TOKEN)
    with TestClient(app, base_url="http://127.0.0.1") as c:
        assert c.get(path).status_code == 403
        assert c.get(path, params={"token": "wrong"}).status_code == 403
        assert c.get(path, headers={TOKEN_HEADER: "wrong"}).status_code == 403
        r = c.post("/api/place", json={"project": "design_two_zones", "measure": FENCE, "x": 50},
                   headers={"Origin": "http://127.0.0.1"})
        assert r.status_code == 403 and "token" in r.json()["error"]


def test_the_token_in_the_address_gives_the_page_that_holds_it(entries):
    """The page carries its token (for its header and its asset links); no cookie is set:
    a cookie of 127.0.0.1 would go to every port of it."""
    app = create_app(entries, TOKEN)
    with TestClient(app, base_url="http://127.0.0.1") as c:
        r = c.get("/", params={"token": TOKEN})
        assert r.status_code == 200 and "<svg" in r.text
        assert "set-cookie" not in r.headers
        assert f'<meta name="rockfall-token" content="{TOKEN}">' in r.text
        assert f"/static/app.js?token={TOKEN}" in r.text
        assert c.get(f"/static/app.js?token={TOKEN}").status_code == 200
        # The header alone is enough from then on.
        r = c.get("/api/projects", headers={TOKEN_HEADER: TOKEN})
        assert r.json()["projects"][0]["id"] == "design_two_zones"
        assert c.get("/api/projects").status_code == 403


def test_the_page_loads_only_its_own_files_and_leaks_no_token(client):
    r = client.get("/")
    csp = r.headers["content-security-policy"]
    assert "default-src 'self'" in csp and "frame-ancestors 'none'" in csp
    assert r.headers["referrer-policy"] == "no-referrer"
    # No address of another site in the page (the SVG namespace is a name, not a request).
    assert "http" not in r.text.replace("http://www.w3.org/2000/svg", "")
    assert client.get("/static/app.js").headers["content-type"].startswith("text/javascript")
    assert client.get("/static/../app.py").status_code == 404


def test_each_app_has_its_own_random_token(entries):
    a, b = create_app(entries), create_app(entries)
    assert a.state.token != b.state.token and len(a.state.token) >= 24


# ---- the section and the run ------------------------------------------------------------


def test_the_project_describes_its_section(client, entries):
    d = client.get("/api/projects/design_two_zones").json()
    assert d["ground"][0] == [0.0, 200.0] and d["ground"][-1] == [310.0, 6.0]
    assert d["materials"][:3] == ["rock", "rock", "talus"]
    assert [r["x"] for r in d["releases"]] == [[1.0, 7.0], [96.0, 101.0]]
    assert d["stations"] == [30.0, 90.0, 120.0, 240.0]
    assert d["protect"] == {"x": 290.0}
    assert d["run"]["rocks"] == ROCKS


def test_the_run_gives_envelopes_stops_and_paths(client):
    r = client.get("/api/projects/design_two_zones/run").json()
    env = r["envelopes"]
    assert env["x"][0] == 0.0 and env["x"][1] == TABLE_STEP_M
    assert len(env["height"]["p95"]) == len(env["x"]) == len(env["energy"]["max"])
    # Below both release zones every rock has passed.
    j = env["x"].index(150.0)
    assert env["crossings"][j] == ROCKS
    assert env["height"]["p50"][j] <= env["height"]["p95"][j] <= env["height"]["max"][j]
    assert sum(r["stops"]["counts"]) == r["stops"]["stopped"]
    assert len(r["paths"]) == 40 and len(r["paths"][0][0]) == 2


def test_a_run_reports_progress_and_can_be_cancelled(entries, registry, project_copy):
    (entry,) = load_entries([project_copy], registry)
    app = create_app([entry], TOKEN)
    with _client(app) as c:
        job = c.post("/api/projects/design_two_zones/simulate", json={"rocks": 30000}).json()
        assert job["total"] == 30000 and job["state"] == "running"
        # A second run of the same project while one is under way is refused.
        assert c.post("/api/projects/design_two_zones/simulate", json={}).status_code == 409
        c.post(f"/api/jobs/{job['id']}/cancel", json={})
        job = _wait(c, job["id"])
        assert job["state"] == "cancelled" and job["done"] < 30000
        assert entry.run is None
        assert c.get("/api/projects/design_two_zones/run").status_code == 409


# ---- placing a measure ----------------------------------------------------------------------


def test_place_judges_a_fence_from_the_table_as_the_optimisers_screening(client, entries):
    r = client.post("/api/place", json={"project": "design_two_zones", "measure": FENCE,
                                        "x": 60.2})
    assert r.status_code == 200, r.text
    out = r.json()
    (m,) = out["measures"]
    assert m["x"] == 60.2 and m["x_table"] == 60.0
    # The project's concept (uni11211) checks a fence's design height and energy.
    assert {c["name"] for c in m["checks"]} == {"design_height", "design_energy"}
    for c in m["checks"]:
        assert c["bound"] is not None and c["target"] > 0
    res = out["residual"]
    assert res["rocks"] == ROCKS and res["lower_bound"] <= res["fraction"] <= res["upper_bound"]
    # The same numbers as the optimiser's screening of that fence on the same table.
    entry = entries[0]
    sc = entry.run.screening
    placed = place_measures(entry.project, entry.registry,
                            [entry.build_measure({**FENCE, "x": 60.2}, 0)], sc.section)
    ref = sc.screen_placed(placed, sc.bare, 0.0)
    assert res["reaching"] == ref.residual
    assert [c["value"] for c in m["checks"]] == pytest.approx(
        [c.value for c in ref.checks[0]])
    assert out["admitted"] == ref.feasible
    assert sc.n == ROCKS and trial_spec(entry.project, entry.registry).residual_fraction


def test_a_fence_no_rock_gets_through_gives_what_check_gives(client, project_copy):
    """Where the table is exact (no rock breaks through or comes back), it is check's answer."""
    strong = {"type": "fence", "height": 8.0, "capacity_kj": 50000.0}
    out = client.post("/api/place", json={"project": "design_two_zones", "measure": strong,
                                          "x": 200}).json()
    assert not out["approximate"] and out["measures"][0]["broken_through"] == 0
    text = project_copy.read_text() + (
        "measures:\n  - {type: fence, x: 200, height: 8.0, capacity_kj: 50000}\n")
    path = project_copy.parent / "check_me.yaml"
    path.write_text(text)
    try:
        exact = rd.check(path, rocks=ROCKS, seed=SEED, progress=False)
    finally:
        path.unlink()
    assert out["residual"]["reaching"] == exact.summary["protect"]["reaching"]
    (m,) = exact.summary["measures"]
    assert out["measures"][0]["caught"] == m["caught"]
    assert out["measures"][0]["met"] == m["met"]


def test_a_ditch_reruns_only_the_rocks_below_and_gives_what_check_gives(client,
                                                                       project_copy):
    ditch = {"type": "ditch", "width": 8.0, "depth": 1.5}
    out = client.post("/api/place", json={"project": "design_two_zones", "measure": ditch,
                                          "x": 200}).json()
    assert out["reshapes_ground"] and 0 < out["rerun_rocks"] <= ROCKS
    text = project_copy.read_text() + (
        "measures:\n  - {type: ditch, x: 200, width: 8.0, depth: 1.5}\n")
    path = project_copy.parent / "check_ditch.yaml"
    path.write_text(text)
    try:
        exact = rd.check(path, rocks=ROCKS, seed=SEED, progress=False)
    finally:
        path.unlink()
    assert out["residual"]["reaching"] == exact.summary["protect"]["reaching"]
    (m,) = exact.summary["measures"]
    assert (out["measures"][0]["met"], out["measures"][0]["caught"]) == (m["met"], m["caught"])


def test_moving_the_fence_changes_the_residual(client):
    def reaching(x: float) -> int:
        r = client.post("/api/place", json={"project": "design_two_zones",
                                            "measures": [{**FENCE, "x": x}]})
        return r.json()["residual"]["reaching"]

    # Above the lower release zone the fence cannot hold that zone's rocks.
    assert reaching(60) > reaching(280)


@pytest.mark.parametrize("body,status,words", [
    ({"project": "nowhere", "measure": FENCE, "x": 50}, 404, "unknown project 'nowhere'"),
    ({"measure": FENCE, "x": 50}, 400, "project:"),
    ({"project": "design_two_zones", "x": 50}, 400, "measure:"),
    ({"project": "design_two_zones", "measure": FENCE, "x": "fifty"}, 400, "x: expected"),
    ({"project": "design_two_zones", "measure": FENCE, "x": True}, 400, "x: expected"),
    ({"project": "design_two_zones", "measure": {"type": "fense"}, "x": 50}, 400,
     "unknown measure 'fense'"),
    ({"project": "design_two_zones", "measure": {**FENCE, "height": -1}, "x": 50}, 400,
     "height"),
    ({"project": "design_two_zones", "measure": {**FENCE, "colour": "red"}, "x": 50}, 400,
     "colour"),
    ({"project": "design_two_zones", "measure": FENCE, "x": 5000}, 400, "outside the section"),
    ({"project": "design_two_zones", "measures": []}, 400, "measures:"),
    ({"project": "design_two_zones",
      "measure": {"type": "ditch", "width": 3, "depth": 1.5}, "x": 200}, 400,
     "ditch too narrow"),
])
def test_bad_place_requests_get_one_clear_line(client, body, status, words):
    r = client.post("/api/place", json=body)
    assert r.status_code == status, r.text
    assert words in r.json()["error"] and "\n" not in r.json()["error"]


@pytest.mark.parametrize("raw", [b"{not json", b"[1, 2]", b"\xff\xfe"])
def test_a_malformed_body_is_refused(client, raw):
    r = client.post("/api/place", content=raw, headers={"content-type": "application/json"})
    assert r.status_code == 400
    assert "JSON" in r.json()["error"]


def test_place_before_any_run_says_to_simulate_first(entries, registry, project_copy):
    app = create_app(load_entries([project_copy], registry), TOKEN)
    with _client(app) as c:
        r = c.post("/api/place", json={"project": "design_two_zones", "measure": FENCE, "x": 50})
        assert r.status_code == 409 and "simulated" in r.json()["error"]


@pytest.mark.parametrize("body,words", [({"rocks": 0}, "rocks"), ({"rocks": 10**7}, "rocks"),
                                        ({"seed": -1}, "seed"), ({"rocks": 1.5}, "rocks")])
def test_a_run_with_bad_rocks_or_seed_is_refused(client, body, words):
    r = client.post("/api/projects/design_two_zones/simulate", json=body)
    assert r.status_code == 400 and r.json()["error"].startswith(words)


def test_unknown_project_and_job(client):
    for path in ("/api/projects/nowhere", "/api/projects/nowhere/run", "/api/jobs/nope"):
        r = client.get(path)
        assert r.status_code == 404 and "unknown" in r.json()["error"]


# ---- files: only inside the project's directory ---------------------------------------------


def test_the_project_file_is_read_and_nothing_outside(client, project_copy):
    r = client.get("/api/projects/design_two_zones/file")
    assert r.status_code == 200 and r.json()["text"] == project_copy.read_text()
    ok = client.get("/api/projects/design_two_zones/file",
                    params={"path": "catalogue_products.yaml"})
    assert ok.status_code == 200
    for bad in ("../outside.txt", "/etc/passwd", "sub/../../outside.txt"):
        r = client.get("/api/projects/design_two_zones/file", params={"path": bad})
        assert r.status_code == 403 and "outside the project's directory" in r.json()["error"]


def test_a_link_out_of_the_directory_is_refused(client, project_copy):
    link = project_copy.parent / "link.txt"
    link.symlink_to(project_copy.parent.parent / "outside.txt")
    try:
        r = client.get("/api/projects/design_two_zones/file", params={"path": "link.txt"})
        assert r.status_code == 403
        before = _snapshot(project_copy.parent.parent)
        r = client.post("/api/projects/design_two_zones/save",
                        json={"text": project_copy.read_text(), "path": "link.txt"})
        assert r.status_code in (400, 403)
        assert _snapshot(project_copy.parent.parent) == before
    finally:
        link.unlink()


@pytest.mark.parametrize("path", ["../outside.txt", "../new.yaml", "/tmp/x.yaml", ""])
def test_save_outside_the_directory_changes_nothing(client, project_copy, path):
    root = project_copy.parent.parent
    before = _snapshot(root)
    r = client.post("/api/projects/design_two_zones/save",
                    json={"text": project_copy.read_text(), "path": path})
    assert r.status_code in (400, 403)
    assert _snapshot(root) == before


def test_a_project_that_names_a_file_outside_is_not_saved(client, project_copy):
    root = project_copy.parent.parent
    before = _snapshot(root)
    text = project_copy.read_text().replace("products: catalogue_products.yaml",
                                            "products: ../outside.txt")
    for endpoint in ("validate", "save"):
        r = client.post(f"/api/projects/design_two_zones/{endpoint}", json={"text": text})
        assert r.status_code == 403 and "../outside.txt" in r.json()["error"]
    assert _snapshot(root) == before


def test_an_invalid_project_gets_the_command_lines_one_line_error(client, project_copy):
    root = project_copy.parent.parent
    before = _snapshot(root)
    text = project_copy.read_text().replace("  count: 3000", "  count: -3")
    r = client.post("/api/projects/design_two_zones/save", json={"text": text})
    assert r.status_code == 400
    msg = r.json()["error"]
    assert msg.startswith("design_two_zones.yaml:") and "rocks.count" in msg
    assert _snapshot(root) == before


def test_an_oversized_upload_is_refused_and_changes_nothing(client, project_copy):
    root = project_copy.parent.parent
    before = _snapshot(root)
    text = project_copy.read_text() + "#" * MAX_BODY_BYTES
    r = client.post("/api/projects/design_two_zones/save", json={"text": text})
    assert r.status_code == 413 and "bytes" in r.json()["error"]
    assert _snapshot(root) == before


@pytest.fixture()
def fresh(tmp_path, registry, projects_dir):
    """design_two_zones.yaml and its catalogues in a directory of their own, served, no run."""
    for name in TWO_ZONES_FILES:
        shutil.copy(projects_dir / name, tmp_path / name)
    (entry,) = load_entries([tmp_path / "design_two_zones.yaml"], registry)
    with _client(create_app([entry], TOKEN)) as c:
        yield c, entry, tmp_path


def test_save_writes_the_project_file_it_opened(fresh):
    c, entry, d = fresh
    path = d / "design_two_zones.yaml"
    path.chmod(0o664)
    read = c.get("/api/projects/design_two_zones/file").json()
    text = path.read_text().replace("count: 3000", "count: 2000")
    assert c.post("/api/projects/design_two_zones/validate", json={"text": text}).json() == {
        "ok": True}
    r = c.post("/api/projects/design_two_zones/save",
               json={"text": text, "version": read["version"]})
    assert r.status_code == 200 and r.json()["path"] == "design_two_zones.yaml", r.text
    assert path.read_text() == text and entry.project.rocks.count == 2000
    assert r.json()["version"] != read["version"]
    # Its mode is kept (a temporary file's 0600 would lock the group out).
    assert path.stat().st_mode & 0o777 == 0o664
    assert sorted(p.name for p in d.iterdir()) == sorted(TWO_ZONES_FILES)  # no temporary left


def test_plugins_lists_the_measures_parameters(client):
    d = client.get("/api/plugins").json()
    fence = next(m for m in d["measures"] if m["kind"] == "fence")
    assert {"x", "height", "capacity_kj"} <= {p["name"] for p in fence["parameters"]}
    json.dumps(d, allow_nan=False)


def test_place_answers_the_envelope_of_the_table(client):
    """The envelope the page draws is the table the fence is judged on."""
    env = client.get("/api/projects/design_two_zones/run").json()["envelopes"]
    j = env["x"].index(60.0)
    out = client.post("/api/place", json={"project": "design_two_zones", "measure": FENCE,
                                          "x": 60}).json()
    assert out["measures"][0]["met"] == env["crossings"][j]
    assert np.isfinite(env["height"]["p95"][j])


# ---- check and optimise from the page ---------------------------------------------------------


def test_check_from_the_page_is_rockfall_design_check(client, project_copy, capsys):
    fence = {**FENCE, "x": 150.0}
    r = client.post("/api/projects/design_two_zones/check",
                    json={"measures": [fence], "rocks": 800, "seed": 2})
    assert r.status_code == 202, r.text
    job = _wait(client, r.json()["id"])
    assert job["state"] == "done", job
    path = project_copy.parent / "with_fence.yaml"
    path.write_text(project_copy.read_text()
                    + "measures:\n  - {type: fence, x: 150, height: 5.0, capacity_kj: 2000}\n")
    try:
        assert main(["check", str(path), "--rocks", "800", "--seed", "2", "--json"]) in (0, 1)
    finally:
        path.unlink()
    cli = json.loads(capsys.readouterr().out)
    page = job["result"]
    assert page["protect"] == cli["protect"] and page["ok"] == cli["ok"]
    assert page["measures"] == cli["measures"]


@pytest.mark.slow  # an end-to-end run of a few seconds: CI runs it with -m slow
def test_the_report_and_figures_of_a_check_download_as_the_command_line_writes_them(
        client, project_copy, tmp_path):
    fence = {**FENCE, "x": 150.0}
    r = client.post("/api/projects/design_two_zones/check",
                    json={"measures": [fence], "rocks": 400, "seed": 3})
    job = _wait(client, r.json()["id"])
    assert job["state"] == "done", job
    assert job["result"]["verdict"]["state"]  # check --json begins with the verdict
    for name in ("report.html", "profile.png", "profile.svg", "envelopes.png", "stops.svg"):
        assert name in job["files"]
    page = client.get(f"/api/jobs/{job['id']}/files/report.html")
    assert page.status_code == 200 and page.headers["content-type"].startswith("text/html")
    assert "attachment" in page.headers["content-disposition"]
    png = client.get(f"/api/jobs/{job['id']}/files/profile.png")
    assert png.headers["content-type"] == "image/png" and png.content[:8] == b"\x89PNG\r\n\x1a\n"
    svg = client.get(f"/api/jobs/{job['id']}/files/envelopes.svg")
    assert svg.headers["content-type"].startswith("image/svg+xml") and b"<svg" in svg.content
    assert client.get(f"/api/jobs/{job['id']}/files/../../outside.txt").status_code == 404
    # The command line's report of the same check: the same document but for when it
    # was made, the project file's name and the run time.
    path = project_copy.parent / "with_fence.yaml"
    path.write_text(project_copy.read_text()
                    + "measures:\n  - {type: fence, x: 150, height: 5.0, capacity_kj: 2000}\n")
    try:
        main(["check", str(path), "--rocks", "400", "--seed", "3", "--report", str(tmp_path)])
    finally:
        path.unlink()
    theirs = (tmp_path / "report.html").read_text()
    ours = page.text

    def headings(html):
        import re

        return re.findall(r"<h[1-3][^>]*>(.*?)</h[1-3]>", html)

    assert headings(ours) == headings(theirs)
    # profile, envelopes, stops, and a distribution figure per station and measure
    passing = theirs.count("passing_measure_") + theirs.count("passing_station_")
    assert passing and ours.count("<svg") == theirs.count("<svg") >= 3 + 1
    assert "Design" in ours and job["result"]["verdict"]["headline"].split(":")[0] in ours


def test_check_with_a_measure_that_does_not_fit_starts_nothing(client):
    r = client.post("/api/projects/design_two_zones/check",
                    json={"measures": [{**FENCE, "x": -50.0}]})
    assert r.status_code == 400 and "outside the section" in r.json()["error"]
    r = client.post("/api/projects/design_two_zones/check", json={"measures": {"x": 1}})
    assert r.status_code == 400


def test_optimise_can_be_cancelled(entries, registry, project_copy):
    (entry,) = load_entries([project_copy], registry)
    app = create_app([entry], TOKEN)
    with _client(app) as c:
        job = c.post("/api/projects/design_two_zones/optimise", json={"rocks": 3000}).json()
        assert job["kind"] == "optimise"
        c.post(f"/api/jobs/{job['id']}/cancel", json={})
        job = _wait(c, job["id"])
        assert job["state"] == "cancelled" and job["result"] is None
        assert c.get(f"/api/jobs/{job['id']}/files/design.yaml").status_code == 404


def test_optimise_without_a_design_section(tmp_path, registry, projects_dir):
    shutil.copy(projects_dir / "standard_slope.yaml", tmp_path / "standard_slope.yaml")
    app = create_app(load_entries([tmp_path / "standard_slope.yaml"], registry), TOKEN)
    with _client(app) as c:
        r = c.post("/api/projects/standard_slope/optimise", json={})
        assert r.status_code == 400 and "no design: section" in r.json()["error"]


@pytest.mark.slow  # two optimisations of a small design: CI runs it with -m slow
def test_optimise_from_the_page_gives_the_command_lines_design(tmp_path, registry, capsys):
    for name in SMALL_DESIGN_FILES:
        shutil.copy(SMALL_DESIGN_DIR / name, tmp_path / name)
    app = create_app(load_entries([tmp_path / "design_small.yaml"], registry), TOKEN)
    with _client(app) as c:
        job = c.post("/api/projects/design_small/optimise",
                     json={"rocks": 500, "seed": 3}).json()
        job = _wait(c, job["id"])
        assert job["state"] == "done", job
        page = job["result"]
        design = c.get(f"/api/jobs/{job['id']}/files/design.yaml")
        assert {"report.html", "alternatives.png", "profile.svg"} <= set(job["files"])
        report = c.get(f"/api/jobs/{job['id']}/files/report.html")
        assert report.status_code == 200 and page["best"]["name"] in report.text
        assert c.get(f"/api/jobs/{job['id']}/files/alternatives.png").content[:4] == b"\x89PNG"
    out = tmp_path / "out"
    main(["optimise", str(tmp_path / "design_small.yaml"), "--rocks", "500", "--seed", "3",
          "--json", "--out", str(out)])
    cli = json.loads(capsys.readouterr().out)
    assert page["best"] == cli["best"] and page["best"] is not None
    assert page["alternatives"] == cli["alternatives"]
    assert design.status_code == 200
    # The same design.yaml but for the first line's "chosen from" (the file name as given).
    ours, theirs = design.text.splitlines(), (out / "design.yaml").read_text().splitlines()
    assert ours[0].startswith("# Chosen by rockfall-design optimise from design_small.yaml")
    assert ours[1:] == theirs[1:]


def test_a_yaml_bomb_is_refused_without_expanding_it(client, project_copy):
    root = project_copy.parent.parent
    before = _snapshot(root)
    lines = ['a0: &a0 ["../outside.txt", "x"]']
    for i in range(1, 40):
        lines.append(f"a{i}: &a{i} [*a{i - 1}, *a{i - 1}]")
    text = "\n".join(lines) + "\n"
    r = client.post("/api/projects/design_two_zones/save", json={"text": text})
    assert r.status_code == 403 and "../outside.txt" in r.json()["error"]
    safe = text.replace("../outside.txt", "fine")
    r = client.post("/api/projects/design_two_zones/save", json={"text": safe})
    assert r.status_code == 400
    assert _snapshot(root) == before


def test_save_into_a_missing_directory_or_onto_a_directory(client, project_copy):
    before = _snapshot(project_copy.parent.parent)
    for path in ("nosuch/x.yaml", "."):
        r = client.post("/api/projects/design_two_zones/save",
                        json={"text": project_copy.read_text(), "path": path})
        assert r.status_code == 400, r.text
    assert _snapshot(project_copy.parent.parent) == before


def test_a_binary_file_is_not_read_as_text(client, project_copy):
    (project_copy.parent / "blob.bin").write_bytes(b"\xff\xfe\x00\x81")
    try:
        r = client.get("/api/projects/design_two_zones/file", params={"path": "blob.bin"})
        assert r.status_code == 400 and "UTF-8" in r.json()["error"]
        r = client.get("/api/projects/design_two_zones/file", params={"path": "none.yaml"})
        assert r.status_code == 404
    finally:
        (project_copy.parent / "blob.bin").unlink()


def test_the_projects_own_measures_come_with_their_labels(registry, projects_dir):
    (entry,) = load_entries([projects_dir / "quarry_fence_ditch.yaml"], registry)
    d = entry.describe()
    assert [m["label"] for m in d["measures"]] == [
        "fence (6 m, 2000 kJ) at x = 117 m", "ditch (8 m wide, 1.5 m deep) at x = 124 m"]
    assert d["has_design"] is False and d["protect"] == {"x": 135.0}


def test_import_a_section_beside_the_project_and_use_it(client, project_copy, projects_dir):
    csv = (projects_dir / "survey_section.csv").read_text()
    r = client.post("/api/projects/design_two_zones/upload",
                    json={"path": "survey.csv", "text": csv})
    assert r.status_code == 200 and r.json()["path"] == "survey.csv"
    assert (project_copy.parent / "survey.csv").read_text() == csv
    # Not over an existing file unless asked, never the project file, never outside.
    again = client.post("/api/projects/design_two_zones/upload",
                        json={"path": "survey.csv", "text": "x,y\n"})
    assert again.status_code == 409
    before = _snapshot(project_copy.parent.parent)
    for body, status in (({"path": "../survey.csv", "text": csv}, 403),
                         ({"path": "design_two_zones.yaml", "text": "x", "replace": True}, 400),
                         ({"path": "run.sh", "text": "echo"}, 400),
                         ({"path": "s.csv", "text": 5}, 400),
                         ({"text": csv}, 400)):
        r = client.post("/api/projects/design_two_zones/upload", json=body)
        assert r.status_code == status, (body, r.text)
    assert _snapshot(project_copy.parent.parent) == before
    # The edited project may name it: it is inside the directory.
    text = (projects_dir / "survey_slope.yaml").read_text().replace("survey_section.csv",
                                                                   "survey.csv")
    text = text.replace("library: materials.yaml", "library: lib.yaml")
    shutil.copy(projects_dir / "materials.yaml", project_copy.parent / "lib.yaml")
    r = client.post("/api/projects/design_two_zones/validate", json={"text": text})
    assert r.json() == {"ok": True}, r.text
    (project_copy.parent / "survey.csv").unlink()
    (project_copy.parent / "lib.yaml").unlink()


def test_the_envelopes_come_with_bounds_of_the_95th_percentile(client):
    env = client.get("/api/projects/design_two_zones/run").json()["envelopes"]
    j = env["x"].index(150.0)
    for q in ("height", "energy"):
        lo, hi = env[f"{q}_p95_bounds"][j]
        assert lo <= env[q]["p95"][j] <= hi
    assert env["height_p95_bounds"][0] == [None, None]  # no rock passes the crest's x = 0


def test_a_project_without_a_protected_zone_runs_and_says_so(registry, projects_dir):
    (entry,) = load_entries([projects_dir / "calibrate_quarry.yaml"], registry)
    assert entry.project.protect is None
    app = create_app([entry], TOKEN)
    with _client(app) as c:
        job = c.post("/api/projects/calibrate_quarry/simulate", json={"rocks": 300}).json()
        assert _wait(c, job["id"])["state"] == "done"
        out = c.post("/api/place", json={"project": "calibrate_quarry", "measure": FENCE,
                                         "x": 20}).json()
    assert out["residual"]["protected_zone"] is False
    assert out["residual"]["x"] == entry.describe()["ground"][-1][0]


# ---- materials from the library ---------------------------------------------------------


@pytest.fixture()
def survey(tmp_path, registry, projects_dir):
    """survey_slope.yaml, its section and its materials library, in a directory of their own."""
    for name in ("survey_slope.yaml", "survey_section.csv", "materials.yaml"):
        shutil.copy(projects_dir / name, tmp_path / name)
    (entry,) = load_entries([tmp_path / "survey_slope.yaml"], registry)
    app = create_app([entry], TOKEN)
    with _client(app) as c:
        yield c, entry, tmp_path


def test_the_library_the_project_names_lists_its_entries_with_law_and_values(survey):
    c, entry, _ = survey
    r = c.get("/api/projects/survey_slope/materials")
    assert r.status_code == 200, r.text
    lib = r.json()
    assert lib["path"] == "materials.yaml"
    by_name = {m["name"]: m for m in lib["materials"]}
    assert by_name["talus"]["law"] == "spang"
    assert by_name["talus"]["values"]["restitution"] == 0.33
    assert by_name["meadow_rn_rt"]["law"] == "rn_rt"
    assert "tangential_restitution" in by_name["meadow_rn_rt"]["values"]
    assert by_name["bedrock"]["source"].startswith("ILLUSTRATIVE")
    assert c.get("/api/projects/survey_slope").json()["library"] == "materials.yaml"


def test_a_material_from_the_library_goes_onto_a_segment_in_memory_only(survey):
    c, entry, d = survey
    before = _snapshot(d)
    c.post("/api/projects/survey_slope/simulate", json={"rocks": 50, "seed": 1})
    assert _wait(c, entry.job.id)["state"] == "done"
    seg = entry.project.slope.materials.index("talus")
    r = c.post("/api/projects/survey_slope/materials",
               json={"segment": seg, "material": "asphalt"})
    assert r.status_code == 200, r.text
    out = r.json()
    assert out["materials"][seg] == "asphalt" and out["run"] is None  # the old run is dropped
    assert entry.project.slope.materials[seg] == "asphalt"
    assert entry.project.materials["asphalt"].restitution == 0.4
    assert out["edits"] and "asphalt" in out["edits"][0]
    assert _snapshot(d) == before  # nothing written: saving stays on request
    # The YAML it offers for the editor is a valid project that has the change.
    from rockfall_design.project.loading import load_project_text

    changed = load_project_text(out["yaml"], "survey_slope.yaml", base_dir=d)
    assert changed.slope.materials[seg] == "asphalt"
    # A run of the changed project starts.
    r = c.post("/api/projects/survey_slope/simulate", json={"rocks": 50, "seed": 1})
    assert _wait(c, r.json()["id"])["state"] == "done"


@pytest.mark.parametrize("body, status, words", [
    ({"segment": 999, "material": "talus"}, 400, "segment: expected 0 to"),
    ({"segment": 0, "material": "granite"}, 400, "'granite' is not in materials.yaml"),
    ({"segment": 0}, 400, "material: expected"),
    ({"segment": 0, "material": "talus", "library": "../outside.yaml"}, 403, "outside"),
    ({"segment": 0, "material": "talus", "library": "nothere.yaml"}, 404, "no materials library"),
])
def test_bad_material_requests_get_one_clear_line_and_change_nothing(survey, body, status,
                                                                    words):
    c, entry, _ = survey
    project = entry.project
    r = c.post("/api/projects/survey_slope/materials", json=body)
    assert r.status_code == status and words in r.json()["error"], r.text
    assert entry.project is project


def test_a_project_without_a_library_says_so(client):
    r = client.get("/api/projects/design_two_zones/materials")
    assert r.status_code == 404 and "names no materials library" in r.json()["error"]


# ---- study and calibrate from the page ---------------------------------------------------


def _served(tmp_path, registry, projects_dir, *names):
    for name in names:
        shutil.copy(projects_dir / name, tmp_path / name)
    return create_app(load_entries([tmp_path / names[0]], registry), TOKEN)


def test_a_study_from_the_page_is_rockfall_design_study(tmp_path, registry, projects_dir,
                                                        capsys):
    app = _served(tmp_path, registry, projects_dir, "study_talus.yaml")
    with _client(app) as c:
        r = c.post("/api/projects/study_talus/study", json={"rocks": 60, "seed": 4})
        assert r.status_code == 202, r.text
        job = _wait(c, r.json()["id"])
    assert job["state"] == "done", job
    assert job["kind"] == "study" and job["done"] == job["total"] == 9
    assert main(["study", str(tmp_path / "study_talus.yaml"), "--rocks", "60", "--seed", "4",
                 "--json"]) == 0
    cli = json.loads(capsys.readouterr().out)
    page = job["result"]
    assert page["scenarios"] == cli["scenarios"] and page["sensitivity"] == cli["sensitivity"]
    scenarios, sensitivity = job["tables"]
    assert scenarios["title"] == "Scenarios" and len(scenarios["rows"]) == 9
    assert "materials.talus.restitution" in scenarios["columns"]
    assert not any(c.endswith(" upper") for c in scenarios["columns"])
    assert sensitivity["rows"] and sensitivity["columns"][0] == "parameter"


@pytest.mark.slow  # an end-to-end run of a few seconds: CI runs it with -m slow
def test_a_calibration_from_the_page_is_rockfall_design_calibrate(tmp_path, registry,
                                                                  projects_dir, capsys):
    app = _served(tmp_path, registry, projects_dir, "calibrate_quarry.yaml",
                  "quarry_stops_a.csv", "quarry_stops_b.csv")
    with _client(app) as c:
        r = c.post("/api/projects/calibrate_quarry/calibrate",
                   json={"rocks": 80, "seed": 2, "bootstrap": 2})
        assert r.status_code == 202, r.text
        job = _wait(c, r.json()["id"])
    assert job["state"] == "done", job
    assert job["kind"] == "calibrate" and job["done"] == job["total"] == 3
    main(["calibrate", str(tmp_path / "calibrate_quarry.yaml"), "--rocks", "80", "--seed", "2",
          "--bootstrap", "2", "--json"])
    cli = json.loads(capsys.readouterr().out)
    assert job["result"]["parameters"] == cli["parameters"]
    fitted, fit = job["tables"]
    assert [row[0] for row in fitted["rows"]] == [p["path"] for p in cli["parameters"]]
    assert fitted["rows"][0][1] == cli["parameters"][0]["value"]
    assert fit["rows"][0][0] == "distance_kind"


def test_study_and_calibration_can_be_cancelled(tmp_path, registry, projects_dir):
    app = _served(tmp_path, registry, projects_dir, "study_talus.yaml")
    with _client(app) as c:
        job = c.post("/api/projects/study_talus/study", json={"rocks": 3000}).json()
        c.post(f"/api/jobs/{job['id']}/cancel", json={})
        job = _wait(c, job["id"])
        assert job["state"] == "cancelled" and job["result"] is None and job["tables"] == []


def test_study_or_calibrate_without_their_section_or_with_bad_numbers(client):
    r = client.post("/api/projects/design_two_zones/study", json={})
    assert r.status_code == 400 and "no study: section" in r.json()["error"]
    r = client.post("/api/projects/design_two_zones/calibrate", json={})
    assert r.status_code == 400 and "no calibrate: section" in r.json()["error"]
    r = client.post("/api/projects/design_two_zones/study", json={"rocks": "many"})
    assert r.status_code == 400 and "rocks" in r.json()["error"]

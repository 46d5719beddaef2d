"""The page in a real headless Chromium: load a bundled project, simulate, drag a fence.

Driven by Playwright (the Python package) on Debian's ``chromium``
(``/usr/bin/chromium``, or ``ROCKFALL_DESIGN_CHROMIUM``); Playwright's own
browser download is never used. Without a local Chromium the test is
skipped and says why; CI (``.ci/run``) installs Chromium and sets
``ROCKFALL_DESIGN_BROWSER_TESTS=1``, which turns that skip into a failure.
"""

from __future__ import annotations

import contextlib
import html
import http.server
import io
import os
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from .conftest import start_server, stop_server

ROOT = Path(__file__).resolve().parents[2]
CHROMIUM = Path(os.environ.get("ROCKFALL_DESIGN_CHROMIUM", "/usr/bin/chromium"))
REQUIRED = os.environ.get("ROCKFALL_DESIGN_BROWSER_TESTS") == "1"


def _browser_or_skip():
    """Playwright's sync API and the Chromium to drive, or skip (fail when CI requires them)."""
    why = None
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        why = "the playwright package is not installed (pip install '.[test]')"
    if why is None and not CHROMIUM.exists():
        why = (f"no Chromium at {CHROMIUM} (apt-get install chromium, or set "
               "ROCKFALL_DESIGN_CHROMIUM)")
    if why is not None:
        if REQUIRED:
            pytest.fail(f"ROCKFALL_DESIGN_BROWSER_TESTS=1 but {why}")
        pytest.skip(why)
    return sync_playwright


@pytest.fixture(scope="module")
def chromium() -> Iterator[Any]:
    """One headless Chromium (the local one, never Playwright's download) for the module.

    Each test opens a context of its own in it (its own cookies, storage and
    pages) and closes it: a launch of Playwright's driver and Chromium is
    1.8 s of CPU, once here rather than once per test.
    """
    sync_playwright = _browser_or_skip()
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=str(CHROMIUM),
                                     args=["--no-sandbox", "--disable-gpu"])
        try:
            yield browser
        finally:
            browser.close()


@contextlib.contextmanager
def _context(browser: Any, **options: Any) -> Iterator[Any]:
    """A fresh browser context (as a browser of its own to the pages), closed after use."""
    context = browser.new_context(**options)
    try:
        yield context
    finally:
        context.close()


def _distinct_colours(png: bytes) -> int:
    from matplotlib.image import imread

    img = imread(io.BytesIO(png), format="png")
    rgb = (np.asarray(img)[..., :3] * 255).round().astype(np.uint32).reshape(-1, 3)
    # One integer per colour: np.unique over rows (axis=0) sorts a structured
    # view and took 5 s for a full-page shot; over integers it takes a tenth.
    packed = (rgb[:, 0] << 16) | (rgb[:, 1] << 8) | rgb[:, 2]
    return int(np.unique(packed).size)


def test_drag_a_fence_and_the_residual_follows(tmp_path, chromium):
    proc, url = start_server("projects/design_two_zones.yaml", cwd=ROOT)
    errors: list[str] = []
    try:
        with _context(chromium, viewport={"width": 1400, "height": 1000}) as context:
            page = context.new_page()
            page.on("pageerror", lambda e: errors.append(str(e)))
            requested: list[str] = []
            page.on("request", lambda r: requested.append(r.url))
            page.goto(url)
            page.wait_for_selector("body[data-ready='1']", timeout=60_000)
            # The section is drawn: ground segments in their materials' colours.
            assert page.locator("#section line[data-material]").count() == 8
            assert page.locator("#protect-zone").count() == 1
            # 1,000 rocks rather than the project's 3,000: the page's own field, as a
            # user trying a layout would; the residual box still moves with the drag.
            page.fill("#rocks", "1000")
            page.click("#simulate")
            page.wait_for_selector("#status[data-state='done']", timeout=300_000)
            assert page.locator("#env-height path").count() >= 3
            page.click("#place")
            # Predicates as functions, not expressions: the page's CSP forbids
            # eval, which Playwright uses for an expression it polls.
            page.wait_for_function(
                "() => document.getElementById('residual').dataset.reaching !== undefined",
                timeout=30_000)
            before = page.inner_text("#residual")
            reaching_before = page.get_attribute("#residual", "data-reaching")
            box = page.locator("#placed-handle").bounding_box()
            x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
            page.mouse.move(x, y)
            page.mouse.down()
            for i in range(1, 16):
                page.mouse.move(x + 15 * i, y)
            page.mouse.up()
            page.wait_for_function(
                "(before) => document.getElementById('residual').dataset.reaching "
                "!== before", arg=reaching_before, timeout=30_000)
            after = page.inner_text("#residual")
            assert after != before and "At the protected zone" in after
            assert page.locator("#checks td").count() > 4
            # Check that design with a few rocks; its files download from the page.
            page.fill("#rocks", "300")
            page.click("#check")
            link = page.locator("#results .downloads a", has_text="report.html")
            link.wait_for(timeout=300_000)
            # A figure, drawn on this first request. The whole report.html (every
            # figure as SVG, 6 s) is downloaded and read in the slow set
            # (tests/serve/test_api.py), and how its files are drawn in test_reports.py.
            figure = page.locator("#results .downloads a", has_text="profile.png")
            drawn = page.request.get(url.split("/?", 1)[0] + figure.get_attribute("href"),
                                     timeout=300_000)
            assert drawn.status == 200 and drawn.body()[:8] == b"\x89PNG\r\n\x1a\n"
            shot = page.screenshot(path=str(tmp_path / "serve.png"), full_page=True)
            # Everything came from the app itself: it works with no network.
            origin = url.split("/?", 1)[0]
            assert requested and all(u.startswith(origin + "/") or u.startswith("data:")
                                     for u in requested), requested
    finally:
        code, err = stop_server(proc)
    assert not errors, errors
    assert "Traceback" not in err, err
    # Not blank: the ground, the materials, the envelopes, the residual box.
    assert _distinct_colours(shot) > 50


# Slow set (7 s each, a server and a run of their own): the page's load, run and
# charts are driven in the fast set by test_drag_a_fence_and_the_residual_follows.
@pytest.mark.slow
def test_study_and_library_materials_from_the_page(chromium):
    """A study's scenarios table, and a library material put on a segment, in the page."""
    proc, url = start_server("projects/study_talus.yaml", "projects/survey_slope.yaml",
                             cwd=ROOT)
    errors: list[str] = []
    try:
        with _context(chromium, viewport={"width": 1400, "height": 1000}) as context:
            page = context.new_page()
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(url)
            page.wait_for_selector("body[data-ready='1']", timeout=60_000)
            page.fill("#rocks", "40")
            page.click("#study")
            page.wait_for_selector("#status[data-state='done']", timeout=300_000)
            rows = page.locator(".job-table[data-title='Scenarios'] tr")
            assert rows.count() == 10  # the header and nine scenarios
            # The surveyed slope names a library: its entries are listed.
            page.select_option("#project", "survey_slope")
            page.locator("#library-material option[value='asphalt']").wait_for(
                state="attached", timeout=30_000)
            page.click("#materials-box summary")
            page.select_option("#segment", "0")
            page.select_option("#library-material", "asphalt")
            assert "law spang" in page.inner_text("#material-values")
            page.click("#apply-material")
            page.wait_for_function(
                "() => document.getElementById('material-status').textContent"
                ".includes('asphalt from')", timeout=30_000)
            assert "asphalt" in page.input_value("#yaml")
    finally:
        code, err = stop_server(proc)
    assert not errors, errors
    assert "Traceback" not in err, err


# ---- round four: only the app's own page, two servers, the verdict and keyed charts -----------


def _attacker(html: str) -> tuple[Any, str]:
    """A page on another port of 127.0.0.1 (another origin, the same site): its server
    and its address."""
    body = html.encode()

    class Page(http.server.BaseHTTPRequestHandler):
        def do_GET(self) -> None:  # noqa: N802 -- the handler's own name
            self.send_response(200)
            self.send_header("Content-Type", "text/html")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, *args: Any) -> None:
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Page)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server, f"http://127.0.0.1:{server.server_address[1]}/attack.html"


def _form(action: str, target: str) -> str:
    """A text/plain form whose body is JSON: the classic cross-site request of a JSON API."""
    body = '{"path": "' + target + '", "replace": true, "text": "{\\"ok\\":true}", "pad": "'
    name = html.escape(body, quote=True)
    return (f'<form method="POST" enctype="text/plain" action="{html.escape(action)}">'
            f'<input type="hidden" name="{name}" value="&quot;}}">'
            '<button id="go">go</button></form>')


def test_a_form_of_another_page_on_127_0_0_1_changes_nothing(tmp_path, projects_dir,
                                                              chromium):
    """A page on another port posts a text/plain form to the app (with the token too, as
    if it had leaked): 403, and the observed stops are unchanged."""
    import shutil

    for name in ("calibrate_quarry.yaml", "quarry_stops_a.csv", "quarry_stops_b.csv"):
        shutil.copy(projects_dir / name, tmp_path / name)
    target = tmp_path / "quarry_stops_a.csv"
    before = target.read_bytes()
    proc, url = start_server(str(tmp_path / "calibrate_quarry.yaml"))
    origin, token = url.split("/?token=")
    upload = f"{origin}/api/projects/calibrate_quarry/upload"
    attacker, attack_url = _attacker(
        "<!DOCTYPE html><html><body>" + _form(f"{upload}?token={token}", target.name)
        + "</body></html>")
    bare, bare_url = _attacker("<!DOCTYPE html><html><body>" + _form(upload, target.name)
                               + "</body></html>")
    statuses = []
    try:
        with _context(chromium) as context:
            page = context.new_page()
            page.goto(url)  # the user has the app open in the same browser
            page.wait_for_selector("body[data-ready='1']", timeout=60_000)
            for address in (attack_url, bare_url):
                evil = context.new_page()
                evil.goto(address)
                with evil.expect_response(lambda r: "/upload" in r.url) as info:
                    evil.click("#go")
                statuses.append((info.value.status, info.value.text()))
                evil.close()
    finally:
        attacker.shutdown()
        bare.shutdown()
        code, err = stop_server(proc)
    assert [s for s, _ in statuses] == [403, 403], statuses
    assert "Origin" in statuses[0][1] and "token" in statuses[1][1], statuses
    assert target.read_bytes() == before
    assert "Traceback" not in err, err


def test_two_servers_in_one_browser_both_keep_working(chromium):
    """Two servers (two ports of 127.0.0.1) open in one browser: neither locks the other out
    (a token cookie of 127.0.0.1 was one for every port)."""
    first, url_a = start_server("projects/design_two_zones.yaml", cwd=ROOT)
    second, url_b = start_server("projects/quarry_fence_ditch.yaml", cwd=ROOT)
    errors: list[str] = []
    try:
        with _context(chromium) as context:
            pages = []
            for url in (url_a, url_b):
                page = context.new_page()
                page.on("pageerror", lambda e: errors.append(str(e)))
                page.goto(url)
                page.wait_for_selector("body[data-ready='1']", timeout=60_000)
                pages.append(page)
            # Each page brought to the front before its clicks, as a user switches
            # tabs: a page left behind gets no animation frames, which Playwright's
            # click waits on for a stable element (2 s here at the second turn).
            for page in pages:
                page.bring_to_front()
                page.locator("summary", has_text="Project file").click()
            for page in pages + pages[::-1]:  # the first after the second, and back
                page.bring_to_front()
                page.evaluate("() => { document.getElementById('yaml-status')"
                              ".textContent = ''; }")
                page.click("#validate")
                page.wait_for_function(
                    "() => document.getElementById('yaml-status').textContent !== ''",
                    timeout=30_000)
                assert page.inner_text("#yaml-status") == "valid"
    finally:
        for proc in (first, second):
            stop_server(proc)
    assert not errors, errors


@pytest.mark.slow  # as test_study_and_library_materials_from_the_page
def test_the_page_shows_the_verdict_untested_measures_and_keyed_charts(chromium):
    """quarry_fence_ditch.yaml with its own measures: Place and Check work; a fence where no
    rock goes is "untested"; the charts have both axes with ticks and a keyed legend."""
    proc, url = start_server("projects/quarry_fence_ditch.yaml", cwd=ROOT)
    errors: list[str] = []
    try:
        with _context(chromium, viewport={"width": 1400, "height": 1000}) as context:
            page = context.new_page()
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(url)
            page.wait_for_selector("body[data-ready='1']", timeout=60_000)
            assert page.is_checked("#with-own")
            page.fill("#rocks", "400")
            page.click("#simulate")
            page.wait_for_selector("#status[data-state='done']", timeout=300_000)
            for chart, series in (("#env-height", 4), ("#env-energy", 4), ("#stops", 1)):
                assert page.locator(f"{chart} .x-tick").count() >= 4, chart
                assert page.locator(f"{chart} .y-tick").count() >= 3, chart
                assert page.locator(f"{chart} .axis-title").count() == 2, chart
                assert page.locator(f"{chart} .legend-swatch").count() == series, chart
            names = page.locator("#env-height .legend-item").evaluate_all(
                "(items) => items.map((i) => i.dataset.series)")
            assert names == ["p50", "p95", "p99", "max"]
            page.click("#place")
            page.wait_for_function(
                "() => document.getElementById('residual').dataset.verdict !== undefined",
                timeout=30_000)
            assert page.inner_text("#error") == ""
            # The project's fence and ditch and the placed fence: three measures.
            assert page.locator("#checks b").count() == 3
            # Drag the placed fence to the crest, above every release: no rock meets it.
            box = page.locator("#placed-handle").bounding_box()
            left = page.locator("#section").bounding_box()["x"]
            x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
            page.mouse.move(x, y)
            page.mouse.down()
            for i in range(1, 11):
                page.mouse.move(x + (left - 5 - x) * i / 10, y)
            page.mouse.up()
            page.wait_for_function(
                "() => [...document.querySelectorAll('#checks tr[data-untested] b')]"
                ".some((b) => b.textContent.startsWith('fence')"
                " && b.textContent.endsWith('at x = 0.5 m'))",
                timeout=30_000)
            assert page.inner_text("#error") == ""
            # Its checks say "untested", not "holds" (as the verdict says).
            words = page.locator("#checks td.untested").all_inner_texts()
            assert words and set(words) == {"untested"}
            page.fill("#rocks", "200")
            page.click("#check")
            page.wait_for_selector("#check-verdict[data-verdict]", timeout=300_000)
            assert page.locator("#check-table td", has_text="untested").count() >= 1
            assert page.inner_text("#error") == ""
    finally:
        code, err = stop_server(proc)
    assert not errors, errors
    assert "Traceback" not in err, err

"""The page in a real headless Chromium: load a bundled project, simulate, drag a fence.

Driven by Playwright (the Python package) on Debian's ``chromium``
(``/usr/bin/chromium``, or ``ROCKFALL_DESIGN_CHROMIUM``); Playwright's own
browser download is never used. Without a local Chromium the test is
skipped and says why; CI (``.ci/run``) installs Chromium and sets
``ROCKFALL_DESIGN_BROWSER_TESTS=1``, which turns that skip into a failure.
"""

from __future__ import annotations

import io
import os
from pathlib import Path

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


def _distinct_colours(png: bytes) -> int:
    from matplotlib.image import imread

    img = imread(io.BytesIO(png), format="png")
    rgb = (np.asarray(img)[..., :3] * 255).round().astype(np.uint8).reshape(-1, 3)
    return int(np.unique(rgb, axis=0).shape[0])


def test_drag_a_fence_and_the_residual_follows(tmp_path):
    sync_playwright = _browser_or_skip()
    proc, url = start_server("projects/design_two_zones.yaml", cwd=ROOT)
    errors: list[str] = []
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=str(CHROMIUM),
                                         args=["--no-sandbox", "--disable-gpu"])
            try:
                page = browser.new_page(viewport={"width": 1400, "height": 1000})
                page.on("pageerror", lambda e: errors.append(str(e)))
                requested: list[str] = []
                page.on("request", lambda r: requested.append(r.url))
                page.goto(url)
                page.wait_for_selector("body[data-ready='1']", timeout=60_000)
                # The section is drawn: ground segments in their materials' colours.
                assert page.locator("#section line[data-material]").count() == 8
                assert page.locator("#protect-zone").count() == 1
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
                # Check that design with a few rocks; its report downloads from the page.
                page.fill("#rocks", "300")
                page.click("#check")
                link = page.locator("#results .downloads a", has_text="report.html")
                link.wait_for(timeout=300_000)
                report = page.request.get(url.split("/?", 1)[0]
                                          + link.get_attribute("href"))
                assert report.status == 200 and "<svg" in report.text()
                shot = page.screenshot(path=str(tmp_path / "serve.png"), full_page=True)
                # Everything came from the app itself: it works with no network.
                origin = url.split("/?", 1)[0]
                assert requested and all(u.startswith(origin + "/") or u.startswith("data:")
                                         for u in requested), requested
            finally:
                browser.close()
    finally:
        code, err = stop_server(proc)
    assert not errors, errors
    assert "Traceback" not in err, err
    # Not blank: the ground, the materials, the envelopes, the residual box.
    assert _distinct_colours(shot) > 50


def test_study_and_library_materials_from_the_page():
    """A study's scenarios table, and a library material put on a segment, in the page."""
    sync_playwright = _browser_or_skip()
    proc, url = start_server("projects/study_talus.yaml", "projects/survey_slope.yaml",
                             cwd=ROOT)
    errors: list[str] = []
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=str(CHROMIUM),
                                         args=["--no-sandbox", "--disable-gpu"])
            try:
                page = browser.new_page(viewport={"width": 1400, "height": 1000})
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
                browser.close()
    finally:
        code, err = stop_server(proc)
    assert not errors, errors
    assert "Traceback" not in err, err

"""The report page in headless Chromium: it loads cleanly, shows its figures and fits 1280 px.

Needs Debian's ``chromium`` and Python playwright. Without Chromium the test is skipped, unless
``RIGTOOLS_REQUIRE_CHROMIUM`` is set (CI sets it): then it fails.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import report_cases

from rigtools.report import ReportPaths, build_report

WIDTH = 1280
#: Least pixel variance (8-bit grey levels squared) of a screenshot that shows something.
MIN_VARIANCE = 50.0
_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--disable-sync"]


def _chromium() -> str:
    exe = shutil.which("chromium")
    if exe is None:
        if os.environ.get("RIGTOOLS_REQUIRE_CHROMIUM"):
            pytest.fail("RIGTOOLS_REQUIRE_CHROMIUM is set but no `chromium` is on PATH")
        pytest.skip("no `chromium` on PATH (Debian's package; .ci/run installs it)")
    return exe


def _render(html: Path, screenshot: Path) -> dict[str, Any]:
    from playwright.sync_api import sync_playwright

    exe = _chromium()
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=exe, args=_ARGS)
        try:
            page = browser.new_page(viewport={"width": WIDTH, "height": 900})
            problems: list[str] = []
            page.on("console", lambda m: problems.append(f"console {m.type}: {m.text}")
                    if m.type in ("error", "warning") else None)
            page.on("pageerror", lambda e: problems.append(f"page error: {e}"))
            page.on("requestfailed", lambda r: problems.append(f"request failed: {r.url}"))
            requests: list[str] = []
            page.on("request", lambda r: requests.append(r.url))
            page.goto(html.resolve().as_uri(), wait_until="load")
            facts = page.evaluate("""(WIDTH) => {
                const imgs = [...document.images].map(i => ({alt: i.alt, complete: i.complete,
                    w: i.naturalWidth, h: i.naturalHeight}));
                const svgs = [...document.querySelectorAll('svg')].map(s => {
                    const r = s.getBoundingClientRect(); return {w: r.width, h: r.height}; });
                let over = [];
                for (const el of document.querySelectorAll('body *')) {
                    const r = el.getBoundingClientRect();
                    if (r.width > 0 && r.right > WIDTH + 0.5)
                        over.push(el.tagName + '.' + el.className + ' right=' + r.right);
                }
                return {imgs, svgs, over: over.slice(0, 20),
                        scrollWidth: document.documentElement.scrollWidth,
                        scripts: document.scripts.length};
            }""", WIDTH)
            page.screenshot(path=str(screenshot), full_page=True)
        finally:
            browser.close()
    facts["problems"] = problems
    facts["requests"] = requests
    return facts


def _pixel_variance(png: Path) -> float:
    import matplotlib.image as mpimg

    img = np.asarray(mpimg.imread(str(png)), dtype=float)[..., :3] * 255.0
    return float(img.mean(axis=-1).var())


def _check(paths: ReportPaths, tmp_path: Path, n_images: int) -> None:
    shot = tmp_path / "page.png"
    facts = _render(paths.html, shot)
    assert facts["problems"] == []
    assert all(u.startswith(("file:", "data:")) for u in facts["requests"]), facts["requests"]
    assert facts["scripts"] == 0
    assert len(facts["imgs"]) == n_images
    for img in facts["imgs"]:
        assert img["complete"] and img["w"] > 0 and img["h"] > 0, img
    for svg in facts["svgs"]:
        assert svg["w"] > 0 and svg["h"] > 0, svg
    assert facts["scrollWidth"] <= WIDTH
    assert facts["over"] == []
    assert _pixel_variance(shot) > MIN_VARIANCE


def test_full_report_in_chromium(demo_report: ReportPaths, tmp_path: Path) -> None:
    _check(demo_report, tmp_path, n_images=1 + len(report_cases.KEEP) + 4)


def test_hostile_partial_report_in_chromium(outdir_copy: Path, tmp_path: Path) -> None:
    report_cases.fail_run(report_cases.drop_calibration(report_cases.plant_hostile(outdir_copy)),
                          "LS7-55C", "x" * 300 + " a very long error without spaces " + "y" * 200)
    _check(build_report(outdir_copy), tmp_path, n_images=2)

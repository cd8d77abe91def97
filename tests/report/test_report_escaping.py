"""Strings from recordings and campaigns are text: no live markup in the page."""

from __future__ import annotations

from pathlib import Path

import report_cases
from page_checks import scan

from rigtools.report import build_report
from rigtools.schemas import iter_errors


def test_planted_markup_is_shown_as_text(outdir_copy: Path) -> None:
    report_cases.plant_hostile(outdir_copy)
    paths = build_report(outdir_copy)
    assert iter_errors(paths.content, "report.schema.json") == []
    ids = [r["run_id"] for r in paths.content["runs"]]
    assert report_cases.HOSTILE_RUN in ids
    run = paths.content["runs"][ids.index(report_cases.HOSTILE_RUN)]
    assert run["notes"] == report_cases.HOSTILE_NOTES
    assert report_cases.HOSTILE_CHANNEL in run["spectrum"]["channels"]
    assert paths.content["notes"] == []  # every file still reads
    html = paths.html.read_text(encoding="utf-8")
    page = scan(html)
    assert "script" not in page.tags
    assert page.event_handlers == []
    assert page.external_urls == []
    assert [t for t in page.tags if t == "img"] == ["img"] * (1 + 3 + 4)
    text = "".join(page.text)
    # shown, as text, where the page names them
    for s in (report_cases.HOSTILE_RUN, report_cases.HOSTILE_CHANNEL,
              report_cases.HOSTILE_NOTES):
        assert s in text
    assert "<script>" not in html

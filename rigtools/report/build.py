"""Build the report of an OUTDIR: read the stage files, write ``report.json`` and ``report.html``.

:func:`build_report` reads only the files the stages wrote (:mod:`rigtools.report.inputs`),
with the run-up calibration's (:mod:`rigtools.report.runup_section`), computes the content
(:mod:`rigtools.report.content`), draws the figures
(:mod:`rigtools.report.figures`), renders the page (:mod:`rigtools.report.html`) and writes
both files atomically (:mod:`rigtools.report.atomic`). Both documents are complete in memory
before anything is written; the old ``report.html`` is removed first, so a report interrupted
while writing leaves no page that looks complete (``report.html`` is written last).
"""

from __future__ import annotations

import base64
import contextlib
import json
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import Any, Final

from rigtools.report.atomic import remove_stale_temporaries, write_atomic
from rigtools.report.content import report_content
from rigtools.report.figures import png_base64, spectrum_figure, verdict_figure
from rigtools.report.html import render_html
from rigtools.report.inputs import CALIBRATION_FIGURES, ReportInputs, read_inputs
from rigtools.report.runup_section import FIGURE_PREFIX, RunUpInputs, read_runup_inputs

__all__ = ["REPORT_HTML", "REPORT_JSON", "ReportPaths", "build_report", "report_figures"]

REPORT_JSON: Final = "report.json"
REPORT_HTML: Final = "report.html"


@dataclass(frozen=True)
class ReportPaths:
    """Where the report was written.

    Attributes
    ----------
    json, html : pathlib.Path
        ``OUTDIR/report.json`` and ``OUTDIR/report.html``.
    content : dict
        The report.json document.
    """

    json: Path
    html: Path
    content: dict[str, Any]


def report_figures(inputs: ReportInputs, content: dict[str, Any],
                   runup: RunUpInputs | None = None) -> dict[str, str]:
    """Every figure of the page as a base64 PNG, keyed as :func:`.html.render_html` expects.

    The run-up figures (``runup:<run id>``) are those the ``runup_calibration`` section lists.
    """
    figs: dict[str, str] = {}
    fig = verdict_figure(content["verdict"])
    if fig is not None:
        figs["verdict"] = png_base64(fig)
    for run in content["runs"]:
        sp = inputs.spectra.get(run["run_id"])
        if sp is not None and sp.channels:
            figs[f"spectrum:{run['run_id']}"] = png_base64(spectrum_figure(run, sp))
    for name in CALIBRATION_FIGURES:
        if name in content["status"]["calibration_figures"]:
            figs[name] = base64.b64encode(inputs.figures[name]).decode("ascii")
    section = content.get("runup_calibration")
    if runup is not None and section is not None:
        for entry in section["figures"]:
            png = runup.figures.get(entry["run_id"])
            if png is not None and entry["key"].startswith(FIGURE_PREFIX):
                figs[entry["key"]] = base64.b64encode(png).decode("ascii")
    return figs


def build_report(outdir: str | Path, *, generated_at: datetime | None = None) -> ReportPaths:
    """Write ``report.json`` and ``report.html`` of an OUTDIR from its files alone.

    Parameters
    ----------
    outdir : str or pathlib.Path
        A pipeline's output folder (``rigtools run -o OUTDIR``). Missing stage files are
        reported on the page, not errors.
    generated_at : datetime, optional
        Time stamp written into the report (volatile); default now (UTC).

    Returns
    -------
    ReportPaths

    Raises
    ------
    ReportInputError
        ``outdir`` is not a folder, or one of its JSON files is malformed (file named).
    OSError
        A report file cannot be written (nothing that looks complete is left).
    """
    base = Path(outdir)
    inputs = read_inputs(base)
    runup = read_runup_inputs(base, inputs.pipeline)
    content = report_content(inputs, runup=runup, generated_at=generated_at)
    text_json = json.dumps(content, indent=2, ensure_ascii=False, allow_nan=False) + "\n"
    text_html = render_html(content, report_figures(inputs, content, runup))
    paths = ReportPaths(json=base / REPORT_JSON, html=base / REPORT_HTML, content=content)
    remove_stale_temporaries(base, (REPORT_JSON, REPORT_HTML))
    with contextlib.suppress(FileNotFoundError):
        paths.html.unlink()
    write_atomic(paths.json, text_json)
    write_atomic(paths.html, text_html)
    return paths

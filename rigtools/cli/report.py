"""``rigtools report OUTDIR``: rebuild the validation report from the files of an OUTDIR alone.

Reads what ``rigtools run`` wrote (``pipeline.json``, ``ingest/``, ``spectra/``,
``observations.parquet``, ``calibration/``) and writes ``report.json`` and ``report.html``
atomically (:func:`rigtools.report.build_report`). Exit code 3 with one line when OUTDIR holds
no ``pipeline.json`` or one of its JSON files is malformed.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from rigtools.cli.common import EXIT_OK, fail

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> None:
    """Register the subcommand."""
    p = subparsers.add_parser(
        "report",
        help="rebuild report.html and report.json of a pipeline OUTDIR",
        description="Rebuild the validation report (report.html, report.json) from the files "
        "`rigtools run` wrote into OUTDIR; nothing is recomputed.",
    )
    p.add_argument("outdir", metavar="OUTDIR", help="output folder of `rigtools run`")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the subcommand."""
    # Imported here, not at the top: the report loads matplotlib, pyarrow and jinja2, which
    # every other subcommand's start-up should not pay for.
    from rigtools.report import build_report

    outdir = Path(args.outdir)
    if not outdir.is_dir():
        what = "a file" if outdir.exists() else "no such folder"
        return fail(f"{outdir}: expected the output folder of `rigtools run`, found {what}")
    if not (outdir / "pipeline.json").is_file():
        return fail(f"{outdir}: expected pipeline.json (the output folder of `rigtools run`), "
                    "found none")
    paths = build_report(outdir)
    status = paths.content["status"]
    print(f"report: {paths.html}")
    print(f"data:   {paths.json}")
    if status["calibration"] != "ok":
        print(f"calibration {status['calibration']}: the report shows the data without a "
              "verdict")
    return EXIT_OK

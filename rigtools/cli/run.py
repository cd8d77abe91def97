"""``rigtools run CAMPAIGN.toml -o OUTDIR``: recordings to a validation report in one command.

Runs the pipeline (:func:`rigtools.pipeline.run_campaign`): ingest -> observe -> calibrate ->
report, each stage writing its files into OUTDIR and reusing what an earlier run there
computed from the same inputs. Ends with a few plain lines: the backlash, c* at each test
temperature, the regime of every run and the report's path.

Progress goes to stderr: tqdm bars when stderr is a terminal, log lines otherwise;
``--quiet`` prints only the verdict and errors, ``--verbose`` adds debug lines (cache keys).

Exit codes: 0 done (a ``rigtools: warning:`` line for each run that failed and each
calibration warning); 3 when OUTDIR is a file or cannot be written (before any work), when
every run failed, when the calibration cannot be done (the report is written all the same),
or when a file cannot be written (a full disk: the file is named).
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path
from typing import Any

import rigtools.pipeline as pipeline
from rigtools.cli.calibrate import format_verdict
from rigtools.cli.common import fail, one_line, output_problem

__all__ = ["add_parser", "add_pipeline_options", "run", "run_pipeline"]

_LOGGER = "rigtools.pipeline"


def _positive(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}") from None
    if n < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}")
    return n


def add_parser(subparsers: Any) -> None:
    """Register the subcommand."""
    p = subparsers.add_parser(
        "run",
        help="recordings to a validation report: ingest, observe, calibrate, report",
        description="Run a campaign from its recordings to the validation report: ingest every "
        "run, observe its spectra and natural frequencies, calibrate backlash and thermal "
        "closure, and write report.html and report.json into OUTDIR. Stages are cached in "
        "OUTDIR: a re-run reuses what did not change, and a killed run resumes.",
    )
    p.add_argument("campaign", help="campaign manifest (TOML)")
    p.add_argument("-o", "--output", required=True, metavar="OUTDIR",
                   help="output folder (created; holds the cache of earlier runs)")
    add_pipeline_options(p)
    p.set_defaults(func=run)


def add_pipeline_options(p: argparse.ArgumentParser, *, seed: bool = True,
                         jobs: int = 1) -> None:
    """The pipeline's options: ``--jobs``, ``--dask``, ``--seed``, ``--quiet``, ``--verbose``.

    ``--jobs`` defaults to ``jobs``; ``seed=False`` leaves ``--seed`` out (``rigtools demo``,
    which runs the same pipeline on the demo campaign, uses ``--seed`` for the generator).
    """
    p.add_argument("--jobs", type=_positive, default=jobs, metavar="N",
                   help=f"processes for ingest and observe (default {jobs})")
    p.add_argument("--dask", metavar="ADDRESS",
                   help="send ingest and observe of each run to a dask.distributed scheduler "
                   "at ADDRESS, or 'local' for a cluster in this process")
    if seed:
        p.add_argument("--seed", type=int, default=None,
                       help="random seed of the calibration (default: the [calibration] "
                       "block's)")
    loud = p.add_mutually_exclusive_group()
    loud.add_argument("--quiet", action="store_true",
                      help="print only the verdict and errors")
    loud.add_argument("--verbose", action="store_true", help="print debug lines too")


def _log_handler(level: int) -> logging.Handler:
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("rigtools: %(message)s"))
    log = logging.getLogger(_LOGGER)
    log.addHandler(handler)
    log.setLevel(level)
    log.propagate = False
    return handler


def run(args: argparse.Namespace) -> int:
    """Run the subcommand."""
    outdir = Path(args.output)
    problem = output_problem(outdir, folder=True)
    if problem:
        return fail(problem)
    return run_pipeline(args, args.campaign, outdir, seed=args.seed)


def run_pipeline(args: argparse.Namespace, campaign: str | Path, outdir: Path, *,
                 truth: Path | None = None, seed: int | None = None) -> int:
    """Run the pipeline with the options of :func:`add_pipeline_options`; print the verdict.

    Returns the exit code (module notes). ``truth``: a demo campaign's ``truth.json``;
    ``seed``: the calibration's (None: the campaign's ``[calibration]`` block's).
    """
    level = logging.WARNING if args.quiet else logging.DEBUG if args.verbose else logging.INFO
    handler = _log_handler(level)
    try:
        result = pipeline.run_campaign(campaign, outdir, jobs=args.jobs, dask=args.dask,
                                       progress=False if args.quiet else None, seed=seed,
                                       truth=truth)
    finally:
        logging.getLogger(_LOGGER).removeHandler(handler)
    report = f"report: {result.report}" if result.report is not None else ""
    if result.all_failed:
        why = "; ".join(f"{r.run_id}: {r.error}" for r in result.runs)
        return fail(f"every run of the campaign failed ({len(result.runs)}): {why}"
                    + (f" ({report})" if report else ""))
    for r in result.failed_runs:
        print(f"rigtools: warning: run {r.run_id!r} failed at {r.stage}: {one_line(r.error or '')}",
              file=sys.stderr)
    if result.calibration_status == "failed":
        return fail(f"calibration failed: {result.calibration_error}"
                    + (f" ({report})" if report else ""))
    if not args.quiet:
        for w in result.warnings:
            print(f"rigtools: warning: {one_line(w)}", file=sys.stderr)
    if result.summary is not None:
        print(format_verdict(result.summary))
    if report:
        print(report)
    return 0

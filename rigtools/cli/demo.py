"""``rigtools demo``: the main job on the built-in demo campaign.

Generates an FZG-C backlash study from the physics with a known truth
(:func:`rigtools.demo.campaign.generate_demo_campaign`: recordings at seed 000's torques and
bulk temperatures that cross the regime flip, half MCAP and half CAN logs of another layout
with its DBC and mapping, a housing mode taller than the mesh mode at some runs, a few
dropped frames) into ``FOLDER/campaign/``, then runs ``rigtools run`` on it into
``FOLDER/results/``: ingest, observe, calibrate, and the validation report with the truth
beside the posterior. The campaign file stays beside the recordings: edit it, or point a copy
at your own runs, and run ``rigtools run`` on it.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final

from rigtools.cli.arguments import float_in_range, int_at_least
from rigtools.cli.common import fail, output_problem, stderr_is_terminal
from rigtools.cli.run import add_pipeline_options, run_pipeline

if TYPE_CHECKING:
    from rigtools.demo.campaign import DemoRun

__all__ = ["MAX_DURATION_S", "MIN_DURATION_S", "add_parser", "run"]

#: Shortest run (s): the SDOF fits need a few seconds of averaging at 25.6 kHz.
MIN_DURATION_S: Final = 1.5
#: Longest run (s).
MAX_DURATION_S: Final = 60.0


def _duration(text: str) -> float:
    return float_in_range(text, MIN_DURATION_S, MAX_DURATION_S)


def _seed(text: str) -> int:
    return int_at_least(text, 0)


def add_parser(subparsers: Any) -> None:
    """Register the subcommand."""
    doc = (__doc__ or "").split("\n\n", 1)
    p = subparsers.add_parser(
        "demo",
        help="run the main job on the built-in demo campaign",
        description=" ".join(doc[-1].replace("``", "").split()),
    )
    p.add_argument("-o", "--output", default="demo-out", metavar="FOLDER",
                   help="output folder, created if needed (default demo-out): campaign/ "
                   "holds the generated campaign, results/ the report")
    p.add_argument("--size", choices=("full", "ci"), default="full",
                   help="full: 12 runs of 8 s and a run-up of 2 x 16 s (default); ci: 8 runs "
                   "of 3 s and a run-up of 2 x 6 s")
    p.add_argument("--duration", type=_duration, default=None, metavar="S",
                   help=f"length of each FZG-C run in seconds, {MIN_DURATION_S:g} to "
                   f"{MAX_DURATION_S:g} (default by size)")
    p.add_argument("--seed", type=_seed, default=0,
                   help="random seed of the generated campaign, an integer >= 0 (default 0)")
    p.add_argument("--no-runup", dest="runup", action="store_false",
                   help="leave out the run-up of the Kahraman-Blankenship pair and its SDOF "
                   "calibration (the FZG-C runs and the backlash calibration only; minutes "
                   "shorter)")
    add_pipeline_options(p, seed=False, jobs=min(2, os.cpu_count() or 1))
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the subcommand."""
    out = Path(args.output)
    problem = output_problem(out, folder=True)
    if problem:
        return fail(problem)
    from tqdm import tqdm

    from rigtools.demo.campaign import demo_run_count, generate_demo_campaign

    if not args.quiet:
        print(f"rigtools: generating the demo campaign ({args.size}) in {out / 'campaign'}",
              file=sys.stderr)
    n_runs = demo_run_count(args.size, runup=args.runup)
    bar = tqdm(total=n_runs, desc="generate", unit="run", file=sys.stderr,
               disable=args.quiet or not stderr_is_terminal())

    written: list[str] = []          # a disabled tqdm bar does not count

    def on_run(run: DemoRun) -> None:
        written.append(run.run_id)
        bar.update(1)
        bar.set_postfix_str(f"{run.run_id} ({run.format})", refresh=True)
        if bar.disable and not args.quiet:
            print(f"rigtools: generate [{len(written)}/{n_runs}] {run.run_id}: "
                  f"{run.file.name}", file=sys.stderr)

    with bar:
        demo = generate_demo_campaign(out / "campaign", seed=args.seed, size=args.size,
                                      duration_s=args.duration, runup=args.runup,
                                      on_run=on_run)
    code = run_pipeline(args, demo.campaign_path, out / "results", truth=demo.truth_path)
    if not args.quiet:
        print(f"\nthe campaign file: {demo.campaign_path} (edit it, or point a copy at your "
              f"own recordings, then: rigtools run {demo.campaign_path} -o results)")
    return code

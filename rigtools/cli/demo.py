"""``rigtools demo``: the main job on the built-in demo campaign.

Until the full demo campaign exists (calibration and report issues), the demo writes a small
synthetic rig run in the reference formats (MCAP with protobuf batches, BLF and candump with
the reference DBC), ingests each, prints ``info``, checks that the formats agree sample for
sample, and runs a first analysis (spectra, RMS, dominant peaks) against the known truth.
"""

from __future__ import annotations

import argparse
from typing import Any, Final

from rigtools.cli.arguments import float_in_range, int_at_least
from rigtools.cli.common import fail, output_problem

__all__ = ["MAX_DURATION_S", "MIN_DURATION_S", "add_parser", "run"]

#: Shortest run (s): the order analysis needs a speed step of 1 s of whole revolutions.
MIN_DURATION_S: Final = 1.5
#: Longest run (s): about a minute of writing and reading per 10 s, 2 GB of memory at 60 s.
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
                   help="output folder, created if needed (default demo-out)")
    p.add_argument("--duration", type=_duration, default=4.0, metavar="S",
                   help=f"length of the run in seconds, {MIN_DURATION_S:g} to "
                   f"{MAX_DURATION_S:g} (default 4)")
    p.add_argument("--seed", type=_seed, default=0,
                   help="random seed of the synthetic run, an integer >= 0 (default 0)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the subcommand."""
    problem = output_problem(args.output, folder=True)
    if problem:
        return fail(problem)
    from rigtools.demo.run import run_demo

    return run_demo(args.output, duration_s=args.duration, seed=args.seed)

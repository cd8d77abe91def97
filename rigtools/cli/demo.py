"""``rigtools demo``: the main job on the built-in demo campaign.

Until the full demo campaign exists (calibration and report issues), the demo writes a small
synthetic rig run in the reference formats (MCAP with protobuf batches, BLF and candump with
the reference DBC), ingests each, prints ``info``, checks that the formats agree sample for
sample, and runs a first analysis (spectra, RMS, dominant peaks) against the known truth.
"""

from __future__ import annotations

import argparse
from typing import Any

from rigtools.cli.arguments import positive_float

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> None:
    """Register the subcommand."""
    p = subparsers.add_parser(
        "demo",
        help="run the main job on the built-in demo campaign",
        description=__doc__.splitlines()[2] if __doc__ else None,
    )
    p.add_argument("-o", "--output", default="demo-out", help="output folder (default demo-out)")
    p.add_argument("--duration", type=positive_float, default=4.0,
                   help="length of the run (s, > 0)")
    p.add_argument("--seed", type=int, default=0, help="random seed of the synthetic run")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the subcommand."""
    from rigtools.demo.run import run_demo

    return run_demo(args.output, duration_s=args.duration, seed=args.seed)

"""``rigtools info FILE``: channels, rates, duration, counts and gaps of a recording.

The summary and its text are :mod:`rigtools.recording_summary`'s; this module parses, prints and
returns the exit code.
"""

from __future__ import annotations

import argparse
import json
from typing import Any

from rigtools.cli.common import add_read_options, read_from_args, warn_losses
from rigtools.recording_summary import format_info, json_safe, summary

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> None:
    """Register the subcommand."""
    p = subparsers.add_parser(
        "info",
        help="print channels, rates, duration, counts and gaps of a recording",
        description="Read a recording (any supported format, or a normalized .parquet) and "
        "print what it holds and what was lost.",
    )
    p.add_argument("file", help="recording file")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    add_read_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the subcommand."""
    rec = read_from_args(args)
    if args.json:
        print(json.dumps(json_safe(summary(rec)), indent=2, allow_nan=False))
    else:
        print(format_info(rec))
    warn_losses(rec)
    return 0

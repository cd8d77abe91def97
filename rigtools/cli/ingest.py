"""``rigtools ingest FILE -o OUT.parquet``: write a normalized recording.

The output path is checked before the input is read: a ``-o`` that does not end in
``.parquet`` is a usage error (exit 2); a folder, a folder that does not exist or cannot be
written is exit 3, named, without reading anything.
"""

from __future__ import annotations

import argparse
from typing import Any

from rigtools.cli.arguments import output_path
from rigtools.cli.common import (
    add_read_options,
    fail,
    output_problem,
    read_from_args,
    warn_losses,
)
from rigtools.ingest import write_parquet

__all__ = ["OUTPUT_SUFFIXES", "add_parser", "run"]

#: What ``-o`` may end with: the normalized recording is Parquet, whatever the name says.
OUTPUT_SUFFIXES = (".parquet",)


def add_parser(subparsers: Any) -> None:
    """Register the subcommand."""
    p = subparsers.add_parser(
        "ingest",
        help="read a recording and write a normalized Parquet recording",
        description="Read an MCAP or CAN log (BLF, ASC, TRC, candump, CSV; gzipped or not) and "
        "write a normalized recording (Parquet, metadata inside) that reads back exactly.",
    )
    p.add_argument("file", help="recording file")
    p.add_argument("-o", "--output", required=True, metavar="OUT.parquet",
                   type=output_path(*OUTPUT_SUFFIXES),
                   help="output file; its suffix must be .parquet (checked, with its folder, "
                   "before the input is read)")
    add_read_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the subcommand."""
    problem = output_problem(args.output)
    if problem:
        return fail(problem)
    rec = read_from_args(args)
    write_parquet(rec, args.output)
    warn_losses(rec)
    n = sum(len(c) for c in rec.channels.values())
    print(f"wrote {args.output}: {len(rec.channels)} channel(s), {n} samples, "
          f"{len(rec.slow)} slow signal(s)")
    return 0

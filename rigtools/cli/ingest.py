"""``rigtools ingest FILE -o OUT.parquet``: write a normalized recording."""

from __future__ import annotations

import argparse
from typing import Any

from rigtools.cli.common import add_read_options, read_from_args, warn_losses
from rigtools.ingest import write_parquet

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> None:
    """Register the subcommand."""
    p = subparsers.add_parser(
        "ingest",
        help="read a recording and write a normalized Parquet recording",
        description="Read an MCAP or CAN log (BLF, ASC, TRC, candump, CSV; gzipped or not) and "
        "write a normalized recording (Parquet, metadata inside) that reads back exactly.",
    )
    p.add_argument("file", help="recording file")
    p.add_argument("-o", "--output", required=True, help="output .parquet file")
    add_read_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the subcommand."""
    rec = read_from_args(args)
    write_parquet(rec, args.output)
    warn_losses(rec)
    n = sum(len(c) for c in rec.channels.values())
    print(f"wrote {args.output}: {len(rec.channels)} channel(s), {n} samples, "
          f"{len(rec.slow)} slow signal(s)")
    return 0

"""Helpers shared by subcommands: reading with the common options, loss warnings, exit codes.

Every error line goes through :func:`fail` (``rigtools: error: <one line>``).
"""

from __future__ import annotations

import argparse
import re
import sys
from typing import Final

from rigtools.ingest import Recording, read
from rigtools.recording_summary import unit_of

__all__ = [
    "EXIT_OK",
    "EXIT_UNUSABLE",
    "EXIT_USAGE",
    "add_read_options",
    "fail",
    "one_line",
    "read_from_args",
    "warn_losses",
]

#: Done (with a warning on stderr for every kind of loss).
EXIT_OK: Final = 0
#: Usage error: bad arguments (argparse's own exit code).
EXIT_USAGE: Final = 2
#: The input is unusable: a rigtools or model error names the file, the position and the cause.
EXIT_UNUSABLE: Final = 3


def add_read_options(p: argparse.ArgumentParser) -> None:
    """``--dbc``, ``--map`` and ``--format`` for subcommands that read recordings."""
    p.add_argument("--dbc", help="DBC for CAN logs (default: the reference layout)")
    p.add_argument("--map", dest="mapping", help="channel mapping file (TOML)")
    p.add_argument("--format", dest="fmt", help="force a reader (default: detect from content)")


def read_from_args(args: argparse.Namespace) -> Recording:
    """Read ``args.file`` with the common options."""
    return read(args.file, dbc=args.dbc, mapping=args.mapping, fmt=args.fmt)


def warn_losses(rec: Recording) -> None:
    """One warning line on stderr per kind of loss, so "usable with losses" is visible."""
    rep = rec.report
    for reason, n in sorted(rep.rejected.items()):
        where = rep.first_position.get(reason)
        at = f" (first at {where})" if where else ""
        print(f"rigtools: warning: {n} {unit_of(reason, rep.units)} rejected: {reason}{at}",
              file=sys.stderr)
    if rep.gaps:
        missing = sum(g.n_missing for g in rep.gaps)
        print(f"rigtools: warning: {len(rep.gaps)} gap(s) in sample counters, "
              f"{missing} sample(s) missing", file=sys.stderr)
    for w in rep.warnings:
        print(f"rigtools: warning: {one_line(w)}", file=sys.stderr)


def one_line(message: str) -> str:
    """``message`` on one line: line breaks and the indentation after them become one space."""
    return re.sub(r"\s*[\r\n]+\s*", " ", message.strip())


def fail(message: str) -> int:
    """Print ``rigtools: error: <message>`` (on one line) to stderr; return EXIT_UNUSABLE."""
    print(f"rigtools: error: {one_line(message)}", file=sys.stderr)
    return EXIT_UNUSABLE

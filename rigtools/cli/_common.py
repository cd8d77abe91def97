"""Helpers shared by subcommands: reading with the common options, loss warnings."""

from __future__ import annotations

import argparse
import sys

from rigtools.ingest import Recording, read

__all__ = ["add_read_options", "read_from_args", "unit_of", "warn_losses"]

#: Rejection reasons that count samples or points, not frames or messages.
_SAMPLE_REASONS = ("_sample", "_sample_index", "_timestamp", "inconsistent_channel_layout")


def unit_of(reason: str, units: str) -> str:
    """What a rejection count counts: samples for sample-level reasons, else ``units``."""
    return "samples" if reason.endswith(_SAMPLE_REASONS) else units


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
        print(f"rigtools: warning: {w}", file=sys.stderr)

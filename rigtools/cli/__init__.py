"""The ``rigtools`` command line.

One module per subcommand, each with ``add_parser(subparsers)`` and ``run(args) -> int``.

Exit codes:

====  ======================================================================
0     done; if anything was lost (rejected frames, gaps), a warning on stderr
2     usage error (bad arguments)
3     the input is unusable: a rigtools error names the file, position and cause
====  ======================================================================
"""

from __future__ import annotations

import argparse
import ctypes
import ctypes.util
import sys
from collections.abc import Sequence

from rigtools import __version__
from rigtools.cli import demo, info, ingest, observe, spectrum
from rigtools.errors import RigtoolsError

__all__ = ["EXIT_OK", "EXIT_UNUSABLE", "EXIT_USAGE", "main"]

EXIT_OK = 0
EXIT_USAGE = 2
EXIT_UNUSABLE = 3

_SUBCOMMANDS = (ingest, info, spectrum, observe, demo)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand registered."""
    parser = argparse.ArgumentParser(
        prog="rigtools",
        description="Spur-gear test-rig recordings: ingest, inspect, analyse.",
    )
    parser.add_argument("--version", action="version", version=f"rigtools {__version__}")
    parser.add_argument("--debug", action="store_true", help="re-raise errors with a traceback")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module in _SUBCOMMANDS:
        module.add_parser(sub)
    return parser


_M_MMAP_THRESHOLD = -3  # glibc mallopt parameter
_MMAP_THRESHOLD_BYTES = 256 * 1024


def _tune_allocator() -> None:
    """Hand large freed buffers back to the system at once (glibc only; the CLI only).

    Ingest streams batches of a few MB through NumPy. glibc raises its mmap threshold
    dynamically each time such a buffer is freed, after which later batches are served from
    the heap and freed space is not returned, so the peak resident set grows well past what
    Python holds (a 30-minute BLF: 2.3x the decoded arrays instead of 1.5x). A fixed threshold
    keeps buffers above it in their own mappings. This is a process-wide setting, so the
    library never makes it; the command line, which owns its process, does.
    """
    if not sys.platform.startswith("linux"):
        return
    name = ctypes.util.find_library("c")
    if not name:
        return
    try:
        libc = ctypes.CDLL(name)
        libc.mallopt(_M_MMAP_THRESHOLD, _MMAP_THRESHOLD_BYTES)
    except (OSError, AttributeError):  # not glibc: nothing to tune
        return


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``rigtools`` console script."""
    _tune_allocator()
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except RigtoolsError as exc:
        if args.debug:
            raise
        print(f"rigtools: error: {exc}", file=sys.stderr)
        return EXIT_UNUSABLE
    except OSError as exc:  # an output path that cannot be written, a disk that is full
        if args.debug:
            raise
        where = f"{exc.filename}: " if getattr(exc, "filename", None) else ""
        print(f"rigtools: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return EXIT_UNUSABLE
    except KeyboardInterrupt:
        print("rigtools: interrupted", file=sys.stderr)
        return 130

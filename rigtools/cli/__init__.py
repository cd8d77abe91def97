"""The ``rigtools`` command line.

One module per subcommand, each with ``add_parser(subparsers)`` and ``run(args) -> int``.

Exit codes (:mod:`rigtools.cli.common`):

====  ======================================================================
0     done; if anything was lost (rejected frames, gaps), a warning on stderr
2     usage error (bad arguments): argparse's usage message
3     the input is unusable: a rigtools error names the file, position and cause
====  ======================================================================

One error story: :func:`main` turns every error rigtools raises on purpose
(:class:`rigtools.errors.RigtoolsError`, the whole tree drawn in :mod:`rigtools.errors`), every
error the physics raises on purpose (:class:`models.errors.ModelError`: impossible geometry, a
jammed mesh, ...) and an :class:`OSError` (a file that cannot be read or written) into exit
code 3 and one line on stderr, ``rigtools: error: <message>``. Anything else is a bug and keeps
its traceback; ``--debug`` re-raises the errors above too.
"""

from __future__ import annotations

import argparse
import ctypes
import ctypes.util
import sys
from collections.abc import Sequence

from models.errors import ModelError
from rigtools import __version__
from rigtools.cli import calibrate, demo, info, ingest, observe, plan, report, run, spectrum
from rigtools.cli.common import EXIT_OK, EXIT_UNUSABLE, EXIT_USAGE, fail
from rigtools.errors import RigtoolsError

__all__ = ["EXIT_OK", "EXIT_UNUSABLE", "EXIT_USAGE", "build_parser", "main", "tune_allocator"]

_SUBCOMMANDS = (ingest, info, spectrum, observe, calibrate, plan, run, report, demo)


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


def tune_allocator() -> None:
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
    tune_allocator()
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except (RigtoolsError, ModelError) as exc:
        if args.debug:
            raise
        return fail(str(exc))
    except OSError as exc:  # an output path that cannot be written, a disk that is full
        if args.debug:
            raise
        where = f"{exc.filename}: " if getattr(exc, "filename", None) else ""
        return fail(f"{where}{exc.strerror or exc}")
    except KeyboardInterrupt:
        print("rigtools: interrupted", file=sys.stderr)
        return 130

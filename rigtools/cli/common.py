"""Helpers shared by subcommands: reading with the common options, output paths, loss warnings.

Every error line goes through :func:`fail` (``rigtools: error: <one line>``).
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from pathlib import Path
from typing import Final

from rigtools.ingest import Recording, read
from rigtools.ingest.registry import READERS
from rigtools.recording_summary import loss_warnings

__all__ = [
    "EXIT_OK",
    "EXIT_UNUSABLE",
    "EXIT_USAGE",
    "PROGRESS_MIN_BYTES",
    "add_read_options",
    "fail",
    "one_line",
    "output_problem",
    "read_from_args",
    "stderr_is_terminal",
    "warn_losses",
]

#: Done (with a warning on stderr for every kind of loss).
EXIT_OK: Final = 0
#: Usage error: bad arguments (argparse's own exit code).
EXIT_USAGE: Final = 2
#: The input is unusable: a rigtools or model error names the file, the position and the cause.
EXIT_UNUSABLE: Final = 3
#: Files from this size on (bytes) are read with a progress bar when stderr is a terminal.
PROGRESS_MIN_BYTES: Final = 16 << 20


def add_read_options(p: argparse.ArgumentParser) -> None:
    """``--dbc``, ``--map`` and ``--format`` for subcommands that read recordings."""
    p.add_argument("--dbc", help="DBC for CAN logs (default: the reference layout)")
    p.add_argument("--map", dest="mapping",
                   help="channel mapping file (TOML, data_schemas/channel_mapping.schema.json): "
                   "which CAN signals or MCAP fields make which channel")
    p.add_argument("--format", dest="fmt", choices=sorted(READERS), metavar="FORMAT",
                   help="force a reader, one of: " + ", ".join(sorted(READERS))
                   + " (default: detect from content)")


def read_from_args(args: argparse.Namespace) -> Recording:
    """Read ``args.file`` with the common options; a progress bar for a long file.

    The bar (tqdm, bytes of the file read) shows on stderr when it is a terminal and the file
    holds at least :data:`PROGRESS_MIN_BYTES`.
    """
    path = Path(args.file)
    try:
        big = path.is_file() and path.stat().st_size >= PROGRESS_MIN_BYTES
    except OSError:
        big = False
    if not (big and stderr_is_terminal()):
        return read(path, dbc=args.dbc, mapping=args.mapping, fmt=args.fmt)
    from tqdm import tqdm

    with tqdm(total=path.stat().st_size, desc=f"reading {path.name}", unit="B",
              unit_scale=True, unit_divisor=1024, file=sys.stderr, leave=False) as bar:
        def update(done: int, total: int) -> None:
            bar.update(done - bar.n)

        return read(path, dbc=args.dbc, mapping=args.mapping, fmt=args.fmt, progress=update)


def stderr_is_terminal() -> bool:
    """Whether stderr is a terminal (progress bars) rather than a file or a pipe."""
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


def output_problem(path: str | Path, *, folder: bool = False) -> str | None:
    """Why ``path`` cannot be written, or None; checked before any work.

    Parameters
    ----------
    path : str or pathlib.Path
        A file to write (or, with ``folder``, a folder to create or fill).
    folder : bool
        ``path`` is a folder: it may exist (as a folder) or be created with its parents.

    Returns
    -------
    str or None
        A message naming the path and the reason: a folder given as a file (or a file given
        as a folder), a folder that does not exist, or is not writable.
    """
    p = Path(path)
    if folder:
        if p.exists() and not p.is_dir():
            return f"{p}: expected a folder, found a file"
        base = p
        while not base.exists():  # the folder will be created with its parents
            base = base.parent
        if not base.is_dir():
            return f"{p}: cannot create the folder: {base} is a file"
        if not os.access(base, os.W_OK | os.X_OK):
            return f"{p}: cannot create or fill the folder: {base} is not writable"
        return None
    if p.is_dir():
        return f"{p}: expected a file to write, found a folder"
    parent = p.parent
    if not parent.exists():
        return f"{p}: cannot write the file: no such folder {parent}"
    if not parent.is_dir():
        return f"{p}: cannot write the file: {parent} is not a folder"
    if not os.access(parent, os.W_OK | os.X_OK):
        return f"{p}: cannot write the file: the folder {parent} is not writable"
    if p.exists() and not os.access(p, os.W_OK):
        return f"{p}: cannot write the file: it exists and is not writable"
    return None


def warn_losses(rec: Recording) -> None:
    """One warning line on stderr per kind of loss, so "usable with losses" is visible.

    Frames (or messages) and samples are counted apart
    (:func:`rigtools.recording_summary.loss_warnings`).
    """
    for line in loss_warnings(rec):
        print(f"rigtools: warning: {one_line(line)}", file=sys.stderr)


def one_line(message: str) -> str:
    """``message`` on one line: line breaks and the indentation after them become one space."""
    return re.sub(r"\s*[\r\n]+\s*", " ", message.strip())


def fail(message: str) -> int:
    """Print ``rigtools: error: <message>`` (on one line) to stderr; return EXIT_UNUSABLE."""
    print(f"rigtools: error: {one_line(message)}", file=sys.stderr)
    return EXIT_UNUSABLE

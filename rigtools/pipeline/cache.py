"""Stage keys: what a stage's output was computed from, so a re-run knows what it may reuse.

A stage output is trusted only when its key file exists and holds the key computed now:

* :func:`file_sha256` hashes an input file in chunks (memory stays flat on long recordings);
* :func:`stage_key` is the SHA-256 of a canonical JSON of the stage's inputs (file hashes,
  settings, upstream keys) and the rigtools version, so a new release recomputes everything;
* :func:`write_key` writes ``<name>.key`` LAST, after the output is in place (atomically), and
  :func:`invalidate` removes it FIRST, before an output is rewritten. An output without its
  key, or with a key that differs, is computed again: a run killed between writing an output
  and its key is never trusted.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Final

from rigtools import __version__
from rigtools.pipeline.atomic import atomic_write_text

__all__ = [
    "CHUNK_BYTES",
    "KEY_SUFFIX",
    "file_sha256",
    "invalidate",
    "is_current",
    "key_path",
    "read_key",
    "stage_key",
    "write_key",
]

#: Bytes read at a time when hashing a file.
CHUNK_BYTES: Final = 1 << 20
#: Suffix of a key file, next to the output it vouches for.
KEY_SUFFIX: Final = ".key"


def file_sha256(path: str | Path) -> str:
    """SHA-256 of a file's bytes, read in chunks of :data:`CHUNK_BYTES` (hex).

    Parameters
    ----------
    path : str or pathlib.Path

    Returns
    -------
    str
        64 hex digits.

    Raises
    ------
    OSError
        The file cannot be read.
    """
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        while chunk := fh.read(CHUNK_BYTES):
            h.update(chunk)
    return h.hexdigest()


def stage_key(stage: str, parts: Mapping[str, Any]) -> str:
    """The key of a stage output: SHA-256 of its inputs and the rigtools version.

    Parameters
    ----------
    stage : str
        The stage's name (``"ingest"``, ``"observe"``, ``"calibrate"``).
    parts : mapping
        JSON-ready description of everything the output depends on (file hashes, settings,
        the keys of the outputs it reads).

    Returns
    -------
    str
        64 hex digits; the same inputs give the same key in any process.
    """
    doc = {"stage": stage, "rigtools_version": __version__, "inputs": parts}
    text = json.dumps(doc, sort_keys=True, separators=(",", ":"), ensure_ascii=True,
                      default=str)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


def key_path(folder: str | Path, name: str) -> Path:
    """``<folder>/<name>.key``."""
    return Path(folder) / f"{name}{KEY_SUFFIX}"


def read_key(path: str | Path) -> str | None:
    """The key stored in a key file, None when absent or unreadable."""
    try:
        return Path(path).read_text(encoding="ascii").strip() or None
    except (OSError, UnicodeDecodeError):
        return None


def is_current(path: str | Path, key: str, outputs: tuple[Path, ...] = ()) -> bool:
    """Whether the key file holds ``key`` and every one of ``outputs`` exists.

    Parameters
    ----------
    path : str or pathlib.Path
        The key file.
    key : str
        The key computed now.
    outputs : tuple of pathlib.Path
        The files the key vouches for.
    """
    return read_key(path) == key and all(p.is_file() for p in outputs)


def write_key(path: str | Path, key: str) -> Path:
    """Write a key file (atomically), once the outputs it vouches for are in place."""
    return atomic_write_text(path, key + "\n")


def invalidate(path: str | Path) -> None:
    """Remove a key file before its outputs are rewritten (absent: nothing to do)."""
    with contextlib.suppress(FileNotFoundError):
        Path(path).unlink()

"""File stems of runs: a run id (any text a user typed) as a safe, unique file-name stem.

Run ids come from campaign files and may hold ``/``, spaces, quotes or ``<script>``. Every
per-run file the pipeline writes (``ingest/<stem>.parquet``, ``spectra/<stem>.parquet``, ...)
is named by :func:`run_file_stem`; the report reads the stems from ``pipeline.json`` rather
than computing them again.
"""

from __future__ import annotations

import hashlib
import re
from typing import Final

__all__ = ["STEM_MAX_PREFIX", "run_file_stem"]

#: Characters of the readable prefix kept from the run id.
STEM_MAX_PREFIX: Final = 48
_UNSAFE: Final = re.compile(r"[^A-Za-z0-9._-]+")


def run_file_stem(run_id: str) -> str:
    """The file-name stem of a run: a readable prefix and a hash that keeps stems apart.

    Parameters
    ----------
    run_id : str
        The run's id as written in the campaign.

    Returns
    -------
    str
        ``re.sub(r"[^A-Za-z0-9._-]+", "_", run_id)[:48]``, ``-`` and the first 8 hex digits
        of the SHA-256 of the id's UTF-8 bytes. Two ids that differ only in unsafe
        characters get different stems.

    Examples
    --------
    >>> run_file_stem("LS9-90C")
    'LS9-90C-572ac0b6'
    >>> run_file_stem("a/b") != run_file_stem("a_b")
    True
    """
    if not isinstance(run_id, str):
        raise TypeError(f"`run_id` must be a str, was {type(run_id).__name__}")
    prefix = _UNSAFE.sub("_", run_id)[:STEM_MAX_PREFIX]
    digest = hashlib.sha256(run_id.encode("utf-8")).hexdigest()[:8]
    return f"{prefix}-{digest}"

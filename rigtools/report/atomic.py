"""Atomic writes of the report files: a temporary name in the same folder, fsync, rename.

A report interrupted while writing leaves at most a ``<name>.tmp-<pid>`` file, never a
``report.html`` that looks complete. The pipeline has its own helper of the same kind
(``rigtools.pipeline.atomic``); the report keeps this one so it depends on no other stage.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

__all__ = ["TMP_MARKER", "remove_stale_temporaries", "write_atomic"]

#: Infix of the temporary names (``report.html.tmp-1234``).
TMP_MARKER = ".tmp-"


def _fsync_dir(folder: Path) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:  # a platform or file system without directory handles: nothing to sync
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def write_atomic(path: str | Path, data: str | bytes) -> Path:
    """Write ``data`` to ``path`` so that ``path`` is either absent, the old or the new file.

    Parameters
    ----------
    path : str or pathlib.Path
        Destination; its folder must exist.
    data : str or bytes
        Text is written as UTF-8.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    OSError
        The folder is not writable or the disk is full; the temporary file is removed.
    """
    out = Path(path)
    payload = data.encode("utf-8") if isinstance(data, str) else bytes(data)
    tmp = out.with_name(f"{out.name}{TMP_MARKER}{os.getpid()}")
    try:
        with open(tmp, "wb") as fh:
            fh.write(payload)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, out)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise
    _fsync_dir(out.parent)
    return out


def remove_stale_temporaries(folder: str | Path, names: tuple[str, ...]) -> list[Path]:
    """Remove ``<name>.tmp-<pid>`` files left by a killed writer (for each of ``names``).

    Returns
    -------
    list of pathlib.Path
        The files removed.
    """
    removed = []
    base = Path(folder)
    for name in names:
        for p in sorted(base.glob(f"{name}{TMP_MARKER}*")):
            with contextlib.suppress(OSError):
                p.unlink()
                removed.append(p)
    return removed

"""Atomic writes: a file appears under its final name complete, or not at all.

Every file the pipeline writes goes through here: the content is written to
``<name>.tmp-<pid>`` in the same folder, flushed and fsynced, then moved over the final name
with :func:`os.replace` (atomic on POSIX within one file system), and the folder is fsynced
so the rename survives a power cut. A process killed at any point leaves either the old file,
the new one, or a stray ``*.tmp-<pid>`` that nothing reads. An error while writing (a full
disk, ``ENOSPC``) removes the temporary file and is raised again as an :class:`OSError` that
names the final file.

This module is the pipeline's own; the report writes its files with its own small helper
(issue 19 contract), so neither depends on the other.
"""

from __future__ import annotations

import contextlib
import json
import os
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

__all__ = [
    "TMP_MARKER",
    "atomic_output",
    "atomic_write_bytes",
    "atomic_write_json",
    "atomic_write_text",
    "fsync_folder",
    "remove_stale_temporaries",
]

#: What a temporary file's name holds between the final name and the process id.
TMP_MARKER = ".tmp-"


def _tmp_path(path: Path) -> Path:
    return path.with_name(f"{path.name}{TMP_MARKER}{os.getpid()}")


def fsync_folder(folder: str | Path) -> None:
    """Flush a folder's entries (a rename into it) to disk; a no-op where unsupported.

    Parameters
    ----------
    folder : str or pathlib.Path
    """
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:  # some file systems do not fsync folders
        pass
    finally:
        os.close(fd)


def _fsync_file(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _named(exc: OSError, path: Path) -> OSError:
    """``exc`` naming the final file (a temporary name means nothing to a user)."""
    if exc.errno is None:
        return OSError(f"{path}: {exc}")
    return OSError(exc.errno, exc.strerror or os.strerror(exc.errno), str(path))


@contextlib.contextmanager
def atomic_output(path: str | Path) -> Iterator[Path]:
    """Write a file through a temporary path and move it into place when the block ends.

    For writers that take a path (Parquet, netCDF, PNG)::

        with atomic_output(out / "run.parquet") as tmp:
            write_parquet(rec, tmp)

    Parameters
    ----------
    path : str or pathlib.Path
        The final file; its folder must exist.

    Yields
    ------
    pathlib.Path
        The temporary path to write (same folder, ``<name>.tmp-<pid>``).

    Raises
    ------
    OSError
        Writing failed (a full disk, a folder that cannot be written): the temporary file is
        removed, the final name is untouched, and the error names the final file.
    """
    final = Path(path)
    tmp = _tmp_path(final)
    try:
        yield tmp
        if not tmp.exists():
            raise OSError(f"{final}: the writer did not write the file")
        _fsync_file(tmp)
        os.replace(tmp, final)
    except OSError as exc:
        with contextlib.suppress(OSError):
            tmp.unlink()
        if exc.filename == str(final) or (exc.errno is None and str(final) in str(exc)):
            raise
        raise _named(exc, final) from exc
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise
    fsync_folder(final.parent)


def atomic_write_bytes(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically (module notes).

    Parameters
    ----------
    path : str or pathlib.Path
    data : bytes

    Returns
    -------
    pathlib.Path
        The final path.
    """
    final = Path(path)
    with atomic_output(final) as tmp, open(tmp, "wb") as fh:
        fh.write(data)
        fh.flush()
    return final


def atomic_write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    return atomic_write_bytes(path, text.encode("utf-8"))


def atomic_write_json(path: str | Path, obj: Any,
                      default: Callable[[Any], Any] | None = None) -> Path:
    """Write ``obj`` as indented JSON (keys in insertion order, no NaN) atomically.

    Parameters
    ----------
    path : str or pathlib.Path
    obj : object
        JSON-ready (non-finite floats must have been turned into None).
    default : callable, optional
        As for :func:`json.dumps`.
    """
    text = json.dumps(obj, indent=2, allow_nan=False, ensure_ascii=False, default=default)
    return atomic_write_text(path, text + "\n")


def remove_stale_temporaries(folder: str | Path) -> int:
    """Remove ``*.tmp-<pid>`` files a killed writer left in ``folder`` (not recursive).

    Parameters
    ----------
    folder : str or pathlib.Path

    Returns
    -------
    int
        Files removed.
    """
    base = Path(folder)
    if not base.is_dir():
        return 0
    n = 0
    for f in base.glob(f"*{TMP_MARKER}*"):
        pid = f.name.rsplit(TMP_MARKER, 1)[-1]
        if not pid.isdigit() or int(pid) == os.getpid() or _alive(int(pid)):
            continue
        with contextlib.suppress(OSError):
            f.unlink()
            n += 1
    return n


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True

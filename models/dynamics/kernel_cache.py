r"""Tie the numba disk cache of a module's kernels to the other source files they inline.

numba's on-disk cache (``cache=True``) keys the entries of a kernel on a hash of the kernel's
*own* source file and on the kernel's own bytecode (numba 0.68, ``numba/core/caching.py``:
``_SourceFileBackedLocatorMixin.get_source_stamp``, ``IndexDataCacheFile``,
``Cache._index_key``). A cached kernel that calls a compiled function of another file inlines
that function's code when it is compiled (and freezes the other file's global constants it
reads); after the other file is edited, nothing numba checks has changed, and the kernel keeps
loading its stale copy from the cache.

:func:`tie_cache`, called at the bottom of the module that holds such kernels, closes that gap:

1. it hashes (sha256) the contents of the source files the module's kernels depend on: the
   given modules' files, and the files those modules are tied to in turn;
2. it compares the digest with a stamp file kept beside the kernels' cache index (numba's
   ``Cache.cache_path``), named ``<module file stem>.py<XY><abiflags>.cache-tie``: one per
   Python version, like numba's index files;
3. when the stamp is missing or differs, it flushes (``Cache.flush``) the caches of *every*
   cached kernel defined in the module's file, before any of them is called, then writes the
   stamp atomically (a temporary file, then ``os.replace``: two xdist workers may import the
   module at once; both flush, either stamp is right).

Every kernel of the module is flushed, not only those that call the other file: a kernel that
calls a kernel of its own file inlines the other file's code just as well. When nothing
changed the stamp matches and the caches are used as before (a cold compile of a walker
kernel costs about 15 s per process).

The dispatcher's cache object is ``Dispatcher._cache``, private to numba: a dispatcher without
it, or with the ``NullCache`` of ``cache=False``, is left alone. When the cache directory
cannot be used (an ``OSError`` making, reading or writing it), the stamp cannot vouch for the
cache, so the module's caches are disabled for this process (``Cache.disable``: compiled
afresh, never loaded from or saved to disk): slow, never stale, never an error.

Limit: a process started before an edit that compiles one of the kernels afterwards still
saves its old copy, under the new stamp; restart long-running processes after editing kernel
sources.

Examples
--------
The SDOF walker kernels are tied to the SDOF kernels they call:

>>> from pathlib import Path
>>> import models.dynamics.walker_kernels
>>> [Path(p).name for p in tied_sources("models.dynamics.walker_kernels")]
['sdof_kernels.py']
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib
import os
import sys
import uuid
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any, Final, Literal

from numba.core.caching import Cache
from numba.core.dispatcher import Dispatcher

__all__ = ["CacheTie", "tie_cache", "tied_sources"]

#: Name of the stamp file in the cache directory, after the module file's stem.
_STAMP: Final = (f".py{sys.version_info[0]}{sys.version_info[1]}{getattr(sys, 'abiflags', '')}"
                 ".cache-tie")
#: Module name -> absolute paths of the files its cached kernels are tied to.
_TIES: dict[str, tuple[str, ...]] = {}


@dataclass(frozen=True)
class CacheTie:
    """What :func:`tie_cache` found and did for one module.

    Attributes
    ----------
    module : str
        Dotted name of the module whose kernels are tied.
    sources : tuple of str
        Absolute paths of the files they are tied to (sorted).
    digest : str
        sha256 (hex) of those files' names and contents; ``""`` if one could not be read.
    flushed : tuple of str
        Kernels whose caches were flushed (stamp missing or different).
    disabled : tuple of str
        Kernels whose caches were disabled for this process (cache directory unusable).
    """

    module: str
    sources: tuple[str, ...]
    digest: str
    flushed: tuple[str, ...]
    disabled: tuple[str, ...]


def tied_sources(module: str) -> tuple[str, ...]:
    """Absolute paths of the files the cached kernels of ``module`` are tied to (else ``()``).

    Parameters
    ----------
    module : str
        Dotted module name.

    Returns
    -------
    tuple of str
    """
    return _TIES.get(module, ())


def tie_cache(module: str, sources: Iterable[str]) -> CacheTie:
    """Flush the cached kernels of ``module`` whenever a file in ``sources`` changed.

    Call it at the bottom of ``module`` (``tie_cache(__name__, [...])``), after its kernels
    are defined and before any is called. See the module notes.

    Parameters
    ----------
    module : str
        Dotted name of the module holding the kernels (its cached dispatchers defined in its
        own file are the ones tied).
    sources : iterable of str
        Dotted names of the modules whose compiled functions or constants those kernels use;
        the files these modules are tied to are included.

    Returns
    -------
    CacheTie
    """
    own = os.path.abspath(_file_of(module))
    files: set[str] = set()
    for name in sources:
        files.add(os.path.abspath(_file_of(name)))
        files.update(tied_sources(name))
    files.discard(own)
    tied = tuple(sorted(files))
    _TIES[module] = tied
    groups: dict[str, list[Any]] = {}  # cache directory -> dispatchers
    for obj in vars(importlib.import_module(module)).values():
        cache = getattr(obj, "_cache", None)  # numba-private; NullCache for cache=False
        if (isinstance(obj, Dispatcher) and isinstance(cache, Cache)
                and os.path.abspath(obj.py_func.__code__.co_filename) == own):
            groups.setdefault(cache.cache_path, []).append(obj)
    try:
        digest = _digest(tied)
    except OSError:
        digest = ""
    stem = os.path.splitext(os.path.basename(own))[0]
    flushed: list[str] = []
    disabled: list[str] = []
    for path, kernels in groups.items():
        names = [k.py_func.__qualname__ for k in kernels]
        state = _refresh(os.path.join(path, stem + _STAMP), kernels, digest) if digest else "failed"
        if state == "flushed":
            flushed += names
        elif state == "failed":
            for k in kernels:
                k._cache.disable()
            disabled += names
    return CacheTie(module, tied, digest, tuple(flushed), tuple(disabled))


def _file_of(module: str) -> str:
    path = getattr(importlib.import_module(module), "__file__", None)
    if path is None:
        raise ValueError(f"`module` must have a source file, {module!r} has none")
    return str(path)


def _digest(files: tuple[str, ...]) -> str:
    h = hashlib.sha256()
    for f in files:
        with open(f, "rb") as fh:
            data = fh.read()
        h.update(os.path.basename(f).encode() + b"\0" + len(data).to_bytes(8, "little") + data)
    return h.hexdigest()


def _refresh(stamp: str, kernels: list[Any], digest: str) -> Literal["fresh", "flushed", "failed"]:
    """Flush ``kernels`` and rewrite ``stamp`` unless it holds ``digest``.

    ``"failed"`` when the cache directory cannot be read or written (``OSError``).
    """
    try:
        with open(stamp, "rb") as fh:
            if fh.read().strip() == digest.encode():
                return "fresh"
    except FileNotFoundError:
        pass
    except OSError:
        return "failed"
    tmp = f"{stamp}.tmp.{uuid.uuid4().hex[:16]}"  # unique per writer, like numba's own files
    try:
        os.makedirs(os.path.dirname(stamp), exist_ok=True)
        for k in kernels:
            k._cache.flush()
        with open(tmp, "x", encoding="ascii") as fh:
            fh.write(digest + "\n")
        os.replace(tmp, stamp)
    except OSError:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        return "failed"
    return "flushed"

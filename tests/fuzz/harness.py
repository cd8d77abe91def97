"""The fuzz harness: ``rigtools.ingest.read`` on bytes, one family of the reader registry.

A *family* is a set of registered formats fuzzed together: ``"can"`` (every CAN log format:
the reader is chosen by content as ``read`` does, and the file suffix, used when the content
names no format, is picked from the input length, so the suffix fallback of ``detect_format``
is fuzzed too), and each format of :data:`rigtools.ingest.registry.READERS` alone. One
execution (:func:`one_input`) writes the bytes to a file with a suffix of the family and
reads it: only a :class:`rigtools.errors.RigtoolsError` may escape, and a Recording returned
must keep the invariants of :func:`check_recording`.

``fuzz_read.py`` hands :func:`one_input` to atheris; ``tests/ingest/test_reader_contract.py``
runs it under pytest over every family. Not a test module (no ``test_`` prefix) and free of
atheris, so pytest's doctest collection imports it cleanly.
"""

from __future__ import annotations

import atexit
import logging
import os
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from rigtools.errors import RigtoolsError
from rigtools.ingest import read
from rigtools.ingest.recording import Recording
from rigtools.ingest.registry import CAN_READERS, READERS, SUFFIXES

#: Formats fuzzed together, by family name: every CAN log format, and each format alone.
FAMILIES: dict[str, tuple[str, ...]] = {
    "can": tuple(CAN_READERS),
    **{name: (name,) for name in READERS},
}


def suffixes_of(family: str) -> tuple[str, ...]:
    """The file suffixes of the family's formats, in the registry's order."""
    return tuple(s for s, fmt in SUFFIXES.items() if fmt in FAMILIES[family])


# python-can logs every line it cannot parse; at thousands of executions a second that
# output is most of the work.
logging.getLogger("can").setLevel(logging.CRITICAL)

_DIR = Path(
    tempfile.mkdtemp(prefix="rigtools-fuzz-", dir="/dev/shm" if os.path.isdir("/dev/shm") else None)
)
atexit.register(shutil.rmtree, _DIR, True)


def check_recording(rec: object) -> None:
    """Invariants every returned Recording keeps, whatever the input.

    Raises ``AssertionError`` (a crash for the fuzzer) when one fails.
    """
    assert isinstance(rec, Recording)
    for name, ch in rec.channels.items():
        assert ch.values.dtype == np.float64 and ch.valid.dtype == np.bool_, name
        assert ch.values.shape == ch.valid.shape, name
        assert np.isfinite(ch.values[ch.valid]).all(), f"{name}: a valid sample is not finite"
        assert ch.sample_rate_Hz > 0 and np.isfinite(ch.sample_rate_Hz), name
    for name, s in rec.slow.items():
        assert s.time_s.shape == s.values.shape, name
        t = s.time_s[np.isfinite(s.time_s)]
        assert np.all(np.diff(t) >= 0), f"{name}: slow times go backwards"
    rep = rec.report
    assert rep.decoded >= 0 and all(v > 0 for v in rep.rejected.values())
    for g in rep.gaps:
        assert g.n_missing > 0, g


def read_bytes(data: bytes, suffix: str) -> None:
    """Write ``data`` to a file named ``*suffix`` and read it; only RigtoolsError may escape."""
    p = _DIR / f"input{suffix}"
    p.write_bytes(data)
    try:
        rec = read(p)
    except RigtoolsError:
        return
    check_recording(rec)


def one_input(family: str) -> Callable[[bytes], None]:
    """One execution of the harness for a family: the bytes as a file of one of its formats.

    The suffix is picked from the input length, so every suffix of the family is tried.

    Raises
    ------
    KeyError
        ``family`` is not in :data:`FAMILIES`.
    """
    suffixes = suffixes_of(family)

    def run(data: bytes) -> None:
        read_bytes(data, suffixes[len(data) % len(suffixes)])

    return run

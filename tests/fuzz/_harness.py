"""What the atheris harnesses share: ``rigtools.ingest.read`` on bytes, only rigtools' errors.

Not a test module (no ``test_`` prefix) and free of atheris, so pytest's doctest collection
imports it cleanly; ``fuzz_mcap.py`` and ``fuzz_can.py`` import atheris inside ``main()``.
"""

from __future__ import annotations

import atexit
import logging
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np

#: Suffixes tried for CAN inputs, chosen by the input length, so the suffix fallback of
#: ``detect_format`` (content that names no format) is fuzzed too.
CAN_SUFFIXES = (".blf", ".asc", ".trc", ".log", ".csv")

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
    from rigtools.ingest.recording import Recording

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
    from rigtools.errors import RigtoolsError
    from rigtools.ingest import read

    p = _DIR / f"input{suffix}"
    p.write_bytes(data)
    try:
        rec = read(p)
    except RigtoolsError:
        return
    check_recording(rec)

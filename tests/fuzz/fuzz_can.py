"""atheris harness: ``rigtools.ingest.read`` on CAN log bytes (BLF, ASC, TRC, candump, CSV).

Run it as described in ``tests/fuzz/README.md``::

    python tests/fuzz/fuzz_can.py SEEDS/can -max_total_time=600 -max_len=262144 \
        -rss_limit_mb=2048 -timeout=10

The reader is chosen by content as ``read`` does; the file suffix (used when the content names
no format) is picked from the input length, so the suffix fallback is fuzzed too. The frames
are decoded with the reference DBC. Any exception other than a
:class:`rigtools.errors.RigtoolsError`, a broken Recording invariant, too much memory or too
much time on one input is a crash.
"""

from __future__ import annotations

import sys
from pathlib import Path


def test_one_input(data: bytes) -> None:
    """One execution: the bytes as a CAN log file."""
    from _harness import CAN_SUFFIXES, read_bytes

    read_bytes(data, CAN_SUFFIXES[len(data) % len(CAN_SUFFIXES)])


def main(argv: list[str] | None = None) -> None:
    """Instrument rigtools, then hand over to libFuzzer (runs until a limit or a crash)."""
    import atheris

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    with atheris.instrument_imports(include=["rigtools", "_harness"]):
        import _harness  # noqa: F401

        import rigtools.ingest
        import rigtools.ingest.asc
        import rigtools.ingest.blf
        import rigtools.ingest.candump
        import rigtools.ingest.csv_log
        import rigtools.ingest.trc  # noqa: F401
    atheris.Setup(sys.argv if argv is None else argv, test_one_input)
    atheris.Fuzz()


if __name__ == "__main__":
    main()

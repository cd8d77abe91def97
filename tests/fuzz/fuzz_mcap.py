"""atheris harness: ``rigtools.ingest.read`` on MCAP bytes.

Run it as described in ``tests/fuzz/README.md``::

    python tests/fuzz/fuzz_mcap.py SEEDS/mcap -max_total_time=600 -max_len=262144 \
        -rss_limit_mb=2048 -timeout=10

Any exception other than a :class:`rigtools.errors.RigtoolsError`, a Recording that breaks the
invariants of ``_harness.check_recording``, more than ``-rss_limit_mb`` of memory or more than
``-timeout`` seconds on one input is a crash; libFuzzer writes the input to ``crash-*``.
"""

from __future__ import annotations

import sys
from pathlib import Path


def test_one_input(data: bytes) -> None:
    """One execution: the bytes as a ``.mcap`` file."""
    from _harness import read_bytes

    read_bytes(data, ".mcap")


def main(argv: list[str] | None = None) -> None:
    """Instrument rigtools, then hand over to libFuzzer (runs until a limit or a crash)."""
    import atheris

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    with atheris.instrument_imports(include=["rigtools", "_harness"]):
        import _harness  # noqa: F401

        import rigtools.ingest
        import rigtools.ingest.mcap  # noqa: F401
    atheris.Setup(sys.argv if argv is None else argv, test_one_input)
    atheris.Fuzz()


if __name__ == "__main__":
    main()

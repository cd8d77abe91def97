"""atheris harness: ``rigtools.ingest.read`` on bytes, for one family of the reader registry.

Run it as described in ``tests/fuzz/README.md``, the family first::

    python tests/fuzz/fuzz_read.py mcap SEEDS/mcap -max_total_time=600 -max_len=262144 \
        -rss_limit_mb=2048 -timeout=10
    python tests/fuzz/fuzz_read.py can SEEDS/can -max_total_time=600 -max_len=65536 \
        -rss_limit_mb=3072 -timeout=10

The family is ``can`` (every CAN log format; the reader is chosen by content as ``read`` does,
the file suffix picked from the input length) or the name of one registered format (``mcap``,
``parquet``, ``blf``, ...): ``harness.FAMILIES``. CAN frames are decoded with the reference DBC.
Any exception other than a :class:`rigtools.errors.RigtoolsError`, a Recording that breaks the
invariants of ``harness.check_recording``, more than ``-rss_limit_mb`` of memory or more than
``-timeout`` seconds on one input is a crash; libFuzzer writes the input to ``crash-*``.
"""

from __future__ import annotations

import sys
from pathlib import Path


def main(argv: list[str] | None = None) -> None:
    """Instrument rigtools, then hand one family's execution to libFuzzer (until a limit)."""
    import atheris

    args = list(sys.argv if argv is None else argv)
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    with atheris.instrument_imports(include=["rigtools", "harness"]):
        import harness

    if len(args) < 2 or args[1] not in harness.FAMILIES:
        raise SystemExit(f"usage: {args[0]} FAMILY [libFuzzer options] [corpus ...]; FAMILY is "
                         f"one of {', '.join(harness.FAMILIES)}")
    family = args.pop(1)
    atheris.Setup(args, harness.one_input(family))
    atheris.Fuzz()


if __name__ == "__main__":
    main()

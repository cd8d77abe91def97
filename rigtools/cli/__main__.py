"""``python -m rigtools.cli``: the same as the ``rigtools`` command."""

import sys

from rigtools.cli import main

__all__: list[str] = []

if __name__ == "__main__":
    sys.exit(main())

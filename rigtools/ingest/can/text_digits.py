"""Lookup tables for reading digits out of the bytes of text logs with NumPy.

The vectorised line parsers (:mod:`rigtools.ingest.can.asc_lines`,
:mod:`rigtools.ingest.can.candump`) turn a matrix of characters into numbers by indexing
these tables: a hex digit's value by its byte, a power of ten by its exponent.
"""

from __future__ import annotations

from typing import Final

import numpy as np

__all__ = ["HEX_VALUE", "POW10"]

#: uint8 per byte value: the value of the byte as a hex digit (either case), 255 when it is
#: not one.
HEX_VALUE: Final = np.full(256, 255, np.uint8)
for _i, _c in enumerate(b"0123456789ABCDEF"):
    HEX_VALUE[_c] = _i
for _i, _c in enumerate(b"abcdef"):
    HEX_VALUE[_c] = 10 + _i

#: int64 ``10 ** k`` for ``k`` in 0..18 (every power of ten an int64 holds).
POW10: Final = 10 ** np.arange(19, dtype=np.int64)

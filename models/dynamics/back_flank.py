"""What the back flanks carry of the drive flanks' profile errors (seed 003 Eqs. 26, 28).

Seed 003 gives no back-side geometry. The mesh cycle's profile errors (tip relief) are on the
drive flanks; the back-side contact of the SDOF models (:mod:`models.dynamics.sdof`) and of the
ITMS model (:mod:`models.dynamics.itms`) is ``min(x - e_b + b, 0)`` with the back-side offset
``e_b`` that :func:`back_flank_offset` derives from the drive-flank error, by the choice
``back_flank`` (:data:`BACK_FLANKS`).
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from models.errors import ModelError

__all__ = ["BACK_FLANKS", "BackFlank", "back_flank_offset"]

BackFlank = Literal["unmodified", "mirror", "seed"]
#: Accepted values of ``back_flank``.
BACK_FLANKS = ("unmodified", "mirror", "seed")


def back_flank_offset(error: np.ndarray, back_flank: str) -> np.ndarray:
    """Back-side offset ``e_b`` of a drive-flank profile error ``e`` (same unit).

    The back-side contact is ``min(x - e_b + b, 0)``; ``back_flank`` says what the back flanks
    carry (seed 003 gives no back-side geometry):

    * ``"unmodified"``: perfect involutes, ``e_b = 0`` -- the drive-flank relief and errors of
      the mesh cycle are not on the back flanks;
    * ``"mirror"``: the same modification on the back flanks, ``e_b = -e``: material removed
      widens the gap on both sides, so a relieved back flank touches at ``x < -b - e``;
    * ``"seed"``: seed Eq. 28 literally (``h_i`` with ``x - e_i + b``), ``e_b = e``: a
      displacement error that shifts both flanks alike -- for tip relief it *narrows* the back
      gap, which no relieved flank does.

    Parameters
    ----------
    error : numpy.ndarray
        Drive-flank profile error ``e`` (any length unit).
    back_flank : {"unmodified", "mirror", "seed"}
        What the back flanks carry.

    Returns
    -------
    numpy.ndarray
        ``e_b``, the shape and unit of ``error``.

    Raises
    ------
    ModelError
        On an unknown ``back_flank``.

    Examples
    --------
    >>> back_flank_offset(np.array([0.0, 2e-6]), "mirror").tolist()
    [-0.0, -2e-06]
    """
    if back_flank not in BACK_FLANKS:
        raise ModelError(f"`back_flank` must be one of {BACK_FLANKS}, was {back_flank!r}")
    e = np.asarray(error, dtype=float)
    if back_flank == "unmodified":
        return np.zeros_like(e)
    return -e if back_flank == "mirror" else e

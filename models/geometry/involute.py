"""The involute function and its inverse.

``inv(a) = tan(a) - a``; the inverse is found by Newton iteration, to machine precision in a few
steps, vectorised.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["inv", "inv_inverse"]


def inv(alpha_rad: ArrayLike) -> np.ndarray:
    """Involute function ``tan(alpha) - alpha`` (alpha in rad)."""
    a = np.asarray(alpha_rad, dtype=float)
    return np.tan(a) - a


def inv_inverse(value: ArrayLike) -> np.ndarray:
    """Pressure angle (rad) whose involute is ``value`` (valid for 0 <= value < ~1.5).

    Examples
    --------
    >>> round(float(np.degrees(inv_inverse(inv(np.radians(22.439))))), 9)
    22.439
    """
    v = np.asarray(value, dtype=float)
    # inv(a) ~ a^3/3 for small a gives the start; Newton on f(a) = tan a - a - v, f' = tan^2 a
    # (convex and increasing on (0, pi/2), so Newton from the right converges monotonically).
    a = np.minimum(np.cbrt(3 * np.maximum(v, 0.0)), 1.2)
    for _ in range(30):
        t = np.tan(a)
        step = np.where(t != 0, (t - a - v) / np.where(t != 0, t * t, 1.0), 0.0)
        a = a - step
        if np.all(np.abs(step) < 1e-15):
            break
    return a

"""Argument checks shared by the modules of :mod:`models.thermal`, validated at the boundary.

Each check is named after the argument it validates, returns it as a float array and raises
:class:`~models.errors.ModelError` (a ``ValueError``) whose message puts the argument in
backticks and gives the expectation and the first offending value received.

* :func:`as_finite`: any finite value (temperatures, positions, rises);
* :func:`as_positive`: finite and ``> 0`` (loads, stiffnesses, torques, inertias);
* :func:`as_nonnegative`: finite and ``>= 0`` (loads that may vanish);
* :func:`as_backlash`: a total backlash, finite and ``>= 0`` (m);
* :func:`as_closure`: a thermal closure ``Delta_1 + Delta_2``, finite of either sign (m);
* :func:`as_chi`: the thermoelastic correction factor, in ``[0, 1]``.

Examples
--------
>>> float(as_chi(0.0285))
0.0285
>>> as_backlash(-1e-6)
Traceback (most recent call last):
...
models.errors.ModelError: `backlash_m` must be finite and >= 0 (m), was -1e-06
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from models.errors import ModelError

__all__ = [
    "as_backlash",
    "as_chi",
    "as_closure",
    "as_finite",
    "as_nonnegative",
    "as_positive",
]


def _first_bad(x: np.ndarray, bad: np.ndarray) -> float:
    return float(np.broadcast_to(x, bad.shape)[bad].flat[0])


def as_finite(name: str, value: ArrayLike) -> np.ndarray:
    """``value`` as a float array when every element is finite.

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : array_like
        The argument.

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    ModelError
        If any element is NaN or infinite.
    """
    a = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(a)):
        raise ModelError(f"`{name}` must be finite, was {value!r}")
    return a


def as_positive(name: str, value: ArrayLike) -> np.ndarray:
    """``value`` as a float array when every element is finite and ``> 0``.

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : array_like
        The argument (its own unit).

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    ModelError
        Naming the first element that is not finite and positive.
    """
    x = np.asarray(value, dtype=float)
    bad = ~(np.isfinite(x) & (x > 0))
    if np.any(bad):
        raise ModelError(f"`{name}` must be finite and > 0, was {_first_bad(x, bad)!r}")
    return x


def as_nonnegative(name: str, value: ArrayLike) -> np.ndarray:
    """``value`` as a float array when every element is finite and ``>= 0``.

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : array_like
        The argument (its own unit).

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    ModelError
        Naming the first element that is negative or not finite.
    """
    x = np.asarray(value, dtype=float)
    bad = ~(np.isfinite(x) & (x >= 0))
    if np.any(bad):
        raise ModelError(f"`{name}` must be finite and >= 0, was {_first_bad(x, bad)!r}")
    return x


def as_backlash(value: ArrayLike, name: str = "backlash_m") -> np.ndarray:
    """A total backlash ``c`` (m) as a float array, finite and ``>= 0``.

    Parameters
    ----------
    value : array_like
        Backlash on the line of action (m).
    name : str
        The argument's name, for the message.

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    ModelError
        Naming the first element that is negative or not finite.
    """
    x = np.asarray(value, dtype=float)
    bad = ~(np.isfinite(x) & (x >= 0))
    if np.any(bad):
        raise ModelError(f"`{name}` must be finite and >= 0 (m), was {_first_bad(x, bad)!r}")
    return x


def as_closure(value: ArrayLike, name: str = "thermal_closure_m") -> np.ndarray:
    """A thermal closure ``Delta_1 + Delta_2`` (m) as a float array, finite (either sign).

    Parameters
    ----------
    value : array_like
        Thermal normal deformation of the pair on the line of action (m).
    name : str
        The argument's name, for the message.

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    ModelError
        Naming the first element that is not finite.
    """
    x = np.asarray(value, dtype=float)
    bad = ~np.isfinite(x)
    if np.any(bad):
        raise ModelError(f"`{name}` must be finite (m), was {_first_bad(x, bad)!r}")
    return x


def as_chi(value: ArrayLike) -> np.ndarray:
    """The thermoelastic correction factor ``chi`` (-) as a float array, in ``[0, 1]``.

    Parameters
    ----------
    value : array_like
        ``chi`` (seed 000: 0.0285).

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    ModelError
        Naming the first element outside ``[0, 1]`` or not finite.
    """
    x = np.asarray(value, dtype=float)
    bad = ~(np.isfinite(x) & (x >= 0) & (x <= 1))
    if np.any(bad):
        raise ModelError(f"`chi` must lie in [0, 1], was {_first_bad(x, bad)!r}")
    return x

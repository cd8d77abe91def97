"""Argument checks shared by the modules of :mod:`models.dynamics`, validated at the boundary.

Each check is named after what it validates; messages put the argument in backticks and give
the expectation and the value received.

* :func:`as_count`: a whole number of steps or periods, at least a minimum (refuses 2.5 and
  bools: no silent truncation);
* :func:`check_settle_args`: the tolerance and period bounds of a settle-to-steady-state loop
  (:func:`~models.dynamics.integrate.settle_periodic`, :mod:`models.dynamics.sweep`).

Examples
--------
>>> as_count("n_periods", 3.0, 1)
3
>>> as_count("n_periods", 2.5, 1)
Traceback (most recent call last):
...
models.errors.ModelError: `n_periods` must be an integer, was 2.5
"""

from __future__ import annotations

from models.errors import ModelError

__all__ = ["as_count", "check_settle_args"]


def as_count(name: str, value: float, minimum: int) -> int:
    """An integer count ``>= minimum``; refuses 2.5 (no silent truncation) and bools.

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : int or float
        The count; a float must be a whole number.
    minimum : int
        Smallest accepted count.

    Returns
    -------
    int

    Raises
    ------
    ModelError
        If ``value`` is a bool, not a whole number, or below ``minimum``.
    """
    if isinstance(value, bool) or not float(value).is_integer():
        raise ModelError(f"`{name}` must be an integer, was {value!r}")
    if int(value) < minimum:
        raise ModelError(f"`{name}` must be >= {minimum}, was {value!r}")
    return int(value)


def check_settle_args(tol: float, min_periods: int, max_periods: int) -> None:
    """Check the arguments of a loop that runs periods until the response repeats.

    Parameters
    ----------
    tol : float
        Tolerance on the repeat (non-dimensional), ``>= 0``.
    min_periods, max_periods : int
        Periods run at least / at most, ``0 <= min_periods <= max_periods``.

    Raises
    ------
    ValueError
        Naming the argument that is out of range.
    """
    if not tol >= 0:
        raise ValueError(f"`tol` must be >= 0, was {tol!r}")
    if not 0 <= min_periods <= max_periods:
        raise ValueError(
            f"need 0 <= `min_periods` <= `max_periods`, were {min_periods!r}, {max_periods!r}"
        )

r"""Mesh frequency from shaft speed and back: the one place rigtools and models compute it.

For a gear of :math:`z` teeth on a shaft turning at :math:`n` rpm the mesh frequency is

.. math:: f_m = z\,n / 60 \ (\mathrm{Hz}),

the same for both gears of a pair (:math:`z_1 n_1 = z_2 n_2`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["check_teeth", "mesh_frequency_Hz", "speed_rpm_from_mesh_frequency"]


def check_teeth(z: int) -> int:
    """``z`` as an ``int`` when it is a positive whole number of teeth, else ``ValueError``.

    >>> check_teeth(16)
    16
    """
    if isinstance(z, bool) or int(z) != z or int(z) < 1:
        raise ValueError(f"`z1` must be a positive integer number of teeth, was {z!r}")
    return int(z)


def mesh_frequency_Hz(speed_rpm: ArrayLike, z1: int) -> np.ndarray:  # noqa: N802 (unit)
    r"""Mesh frequency of a gear of ``z1`` teeth on a shaft turning at ``speed_rpm``.

    Parameters
    ----------
    speed_rpm : array_like
        Shaft speed (rpm).
    z1 : int
        Teeth of the gear on that shaft (the pinion's z1 for the pinion speed).

    Returns
    -------
    numpy.ndarray
        :math:`f_m = z_1 n_1 / 60` (Hz).

    Examples
    --------
    >>> float(mesh_frequency_Hz(1500.0, 16))  # FZG type C pinion, rigtools.demo
    400.0
    >>> float(mesh_frequency_Hz(600.0, 50))   # Kahraman-Blankenship gears, seed 003 Sec. 4
    500.0
    """
    z = check_teeth(z1)
    return np.asarray(speed_rpm, dtype=np.float64) * z / 60.0


def speed_rpm_from_mesh_frequency(mesh_frequency_Hz: ArrayLike, z1: int) -> np.ndarray:
    r"""Shaft speed :math:`n_1 = 60 f_m / z_1` (rpm) of the gear of ``z1`` teeth.

    >>> float(speed_rpm_from_mesh_frequency(400.0, 16))
    1500.0
    """
    z = check_teeth(z1)
    return 60.0 * np.asarray(mesh_frequency_Hz, dtype=np.float64) / z

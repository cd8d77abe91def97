r"""Load along the path of contact: normal load from torque, seed 000's load sharing R(theta).

Positions ``s`` are measured on the line of action from T1, the tangent point on the pinion's
base circle (:class:`~models.geometry.GearPair` convention, m). The path of contact runs from A
(start of contact, wheel tip) to E (end of contact, pinion tip); for ``1 <= eps < 2`` the
single-contact zone is B..D with B = E - p_b (LPSTC) and D = A + p_b (HPSTC).

The normalised coordinate of seed 000
-------------------------------------
The seed writes the load share as a function ``R(theta)`` with zone limits
``theta_inn``, ``theta_inn + eps - 1``, ``theta_inn + 1`` and ``theta_inn + eps``, and says
only that theta "is a parameter related to the meshing point position". The zone *lengths*
(``eps - 1``, ``2 - eps``, ``eps - 1``, summing to ``eps``) fix it: theta is the position on the
line of action in base pitches,

.. math:: \theta = s / p_b = \frac{z_1 \varphi_1}{2 \pi},

i.e. the pinion roll angle ``phi_1 = s / r_b1`` counted in angular base pitches ``2 pi / z1``,
and ``theta_inn = A / p_b`` is its value at the start of contact. With this reading the three
cases of the seed cover A..B, B..D and D..E exactly.

Properties of the seed's R (each is a test):

* ``R(A) = R(E) = 0.36``, ``R(B-) = R(D+) = 0.64``, ``R = 1`` on B..D: R rises linearly over
  the entering double-contact zone and falls linearly over the leaving one; it is continuous
  *within* each zone and jumps from 0.64 to 1 at B and D, where the other pair leaves or
  enters. That jump is physical (the other pair's share vanishes), not an extraction error.
* In double contact the two pairs are one base pitch apart (theta and theta + 1) and their
  shares add to one: ``R(theta) + R(theta + 1) = 1`` (0.36 + 0.64 at the zone ends).
* This is the linear load-sharing approximation of the gear-design literature for unmodified
  teeth (e.g. Niemann and Winter, *Maschinenelemente* II, a third to two thirds; the seed uses
  0.36 to 0.64): the load share of a pair grows with the stiffness of the pair it shares with.
  It ignores the real stiffness variation (compare the stiffness-proportional split of the
  Ishikawa compliances in :mod:`models.stiffness.ishikawa`).

Normal load from torque
-----------------------
The seed writes ``f'_n = 2 T / (d cos(alpha'))`` with the *reference* diameter ``d = z m`` and
the *operating* pressure angle (SEED-NOTES 5). The exact normal load on the line of action is
``T1 / r_b1`` (moment balance about the pinion axis; the line of action is tangent to the base
circle), equal to ``2 T / (d cos(alpha))`` and to ``2 T / (d_w cos(alpha'))`` with the
operating pitch diameter ``d_w = d cos(alpha) / cos(alpha')``. The seed's mixed form is larger
by ``cos(alpha) / cos(alpha')`` (1.7 % for FZG-C). :func:`normal_load_from_torque` is exact;
:func:`normal_load_seed_000` reproduces the printed form for comparison only.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from models.errors import ModelError
from models.geometry.gear_pair import GearPair

__all__ = [
    "SEED_000_SHARE_AT_ENDS",
    "SEED_000_SHARE_AT_SINGLE_ZONE",
    "contact_path_positions",
    "load_share_seed_000",
    "normal_load_from_torque",
    "normal_load_seed_000",
    "normalised_position",
]

#: Load share of a pair at the start and end of contact (A and E) in seed 000's R(theta).
SEED_000_SHARE_AT_ENDS = 0.36
#: Load share of a pair at the single-contact limits B (entering side) and D (leaving side).
SEED_000_SHARE_AT_SINGLE_ZONE = 0.64

_TOL_M = 1e-12


def contact_path_positions(pair: GearPair, n_points: int = 52) -> np.ndarray:
    """Equally spaced positions on the path of contact, A to E inclusive (m from T1).

    Seed 000 discretises the line of action into 52 points "from the start to the end of
    engagement"; its normalised coordinate ``Gamma_k`` is ``(k - 1) / 51`` of AE.

    Parameters
    ----------
    pair : GearPair
    n_points : int
        Number of points (>= 2), 52 in seed 000.

    Returns
    -------
    numpy.ndarray
        Shape ``(n_points,)``; ``[0]`` is A, ``[-1]`` is E.

    Examples
    --------
    >>> from models.geometry import load_gear_set
    >>> g = load_gear_set("fzg-c").pair
    >>> s = contact_path_positions(g)
    >>> len(s), bool(s[0] == g.start_of_contact), bool(s[-1] == g.end_of_contact)
    (52, True, True)
    """
    if isinstance(n_points, bool) or not isinstance(n_points, int | np.integer) or n_points < 2:
        raise ModelError(f"`n_points` must be an integer >= 2, was {n_points!r}")
    return np.linspace(pair.start_of_contact, pair.end_of_contact, int(n_points))


def normalised_position(pair: GearPair, s_m: ArrayLike) -> np.ndarray:
    """Seed 000's theta: position on the line of action in base pitches, ``s / p_b`` (-).

    Parameters
    ----------
    pair : GearPair
    s_m : array_like
        Positions from T1 (m).

    Returns
    -------
    numpy.ndarray
        ``theta = s / p_b = z1 phi_1 / (2 pi)``; ``theta_inn = A / p_b`` at the start of
        contact.
    """
    return np.asarray(s_m, dtype=float) / pair.base_pitch


def load_share_seed_000(pair: GearPair, s_m: ArrayLike) -> np.ndarray:
    r"""Load share R of one tooth pair at positions on the line of action (seed 000) (-).

    .. math::

        R(\theta) = \begin{cases}
          0.36 + 0.28 \dfrac{\theta - \theta_{inn}}{\varepsilon - 1},
              & \theta_{inn} \le \theta \le \theta_{inn} + \varepsilon - 1 \\
          1,  & \theta_{inn} + \varepsilon - 1 < \theta < \theta_{inn} + 1 \\
          0.36 - 0.28 \dfrac{\theta - \theta_{inn} - \varepsilon}{\varepsilon - 1},
              & \theta_{inn} + 1 \le \theta \le \theta_{inn} + \varepsilon
        \end{cases}

    with ``theta = s / p_b`` and ``theta_inn = A / p_b`` (see the module docstring for why).
    The zone limits B and D themselves belong to the double-contact zones (the seed's first
    and third cases are closed there), so ``R(B) = R(D) = 0.64``. Outside the path of contact
    the pair carries nothing: ``R = 0``. For ``eps = 1`` exactly the double zones shrink to A
    and E, where R is 0.36, and R is 1 in between.

    Parameters
    ----------
    pair : GearPair
        Transverse contact ratio ``1 <= eps < 2`` (the formula has no triple-contact case).
    s_m : array_like
        Positions from T1 (m).

    Returns
    -------
    numpy.ndarray
        R, same shape as ``s_m``. ``f_n = f'_n R``.

    Raises
    ------
    ModelError
        ``eps >= 2``.

    References
    ----------
    Seed 000, section "Load distribution"; G. Niemann, H. Winter, *Maschinenelemente* Bd. II,
    Springer, 1983 (linear load sharing in the double-contact zones).

    Examples
    --------
    >>> from models.geometry import load_gear_set
    >>> g = load_gear_set("fzg-c").pair
    >>> [round(float(r), 12) for r in load_share_seed_000(
    ...     g, [g.start_of_contact, g.pitch_point, g.end_of_contact])]
    [0.36, 1.0, 0.36]
    """
    eps = pair.contact_ratio
    if not eps < 2.0:
        raise ModelError(f"`pair.contact_ratio` must be < 2 for seed 000's R(theta), was {eps:.6g}")
    s = np.asarray(s_m, dtype=float)
    a, e, pb = pair.start_of_contact, pair.end_of_contact, pair.base_pitch
    b_pt, d_pt = e - pb, a + pb
    d_eps = eps - 1.0
    safe = d_eps if d_eps > 0 else 1.0
    t = (s - a) / pb  # theta - theta_inn
    rise = SEED_000_SHARE_AT_ENDS + 0.28 * t / safe
    fall = SEED_000_SHARE_AT_ENDS - 0.28 * (t - eps) / safe
    r = np.where(s <= b_pt + _TOL_M, rise, np.where(s >= d_pt - _TOL_M, fall, 1.0))
    if d_eps <= 0:
        r = np.where((s <= a + _TOL_M) | (s >= e - _TOL_M), SEED_000_SHARE_AT_ENDS, 1.0)
    inside = (s >= a - _TOL_M) & (s <= e + _TOL_M)
    return np.where(inside, r, 0.0)


def normal_load_from_torque(pair: GearPair, torque_Nm: ArrayLike, gear: int = 1) -> np.ndarray:
    r"""Exact total normal load on the line of action from a gear's torque (N).

    .. math:: F_n = T_i / r_{b,i}

    (moment balance about the axis of gear i; the line of action is tangent to the base
    circle). Equivalent to ``2 T / (d cos(alpha))`` and ``2 T / (d_w cos(alpha'))``.

    Parameters
    ----------
    pair : GearPair
    torque_Nm : array_like
        Torque on gear ``gear`` (N m).
    gear : {1, 2}
        1 for the pinion torque, 2 for the wheel torque.

    Returns
    -------
    numpy.ndarray
        Normal load (N), the whole face width.

    Examples
    --------
    >>> from models.geometry import load_gear_set
    >>> g = load_gear_set("fzg-c").pair
    >>> round(float(normal_load_from_torque(g, 381.96)), 1)
    11290.9
    """
    if gear not in (1, 2):
        raise ModelError(f"`gear` must be 1 (pinion) or 2 (wheel), was {gear!r}")
    t = np.asarray(torque_Nm, dtype=float)
    if not np.all(np.isfinite(t)):
        raise ModelError("`torque_Nm` must be finite")
    return t / pair.base_radius(gear)


def normal_load_seed_000(pair: GearPair, torque_Nm: ArrayLike) -> np.ndarray:
    """The seed's printed normal load ``f'_n = 2 T / (d cos(alpha'))`` (N), for comparison.

    ``d = z1 m`` is the pinion's reference diameter and ``alpha'`` the operating pressure
    angle; this overstates the exact :func:`normal_load_from_torque` by
    ``cos(alpha) / cos(alpha')`` whenever the centre distance differs from the reference one
    (SEED-NOTES 5). Do not use it for computation.

    Parameters
    ----------
    pair : GearPair
    torque_Nm : array_like
        Pinion torque (N m).

    Returns
    -------
    numpy.ndarray
        ``2 T / (d cos(alpha'))`` (N).
    """
    d = 2.0 * pair.reference_radius(1)
    return 2.0 * np.asarray(torque_Nm, dtype=float) / (d * math.cos(pair.operating_pressure_angle))

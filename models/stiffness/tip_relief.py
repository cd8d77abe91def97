r"""Tip relief as a profile error per tooth pair: linear, parabolic I and II (seed 003, Sec. 2.5).

A tip relief removes material from the involute over the last part of the profile, growing from
zero at the start of the modification to the amount ``delta`` at the tip (seed 003 Figs. 2-3).
In the compatibility conditions it is part of the profile error ``e`` of the tooth pair
(positive: material missing, more transmission error needed to load the pair;
:mod:`models.stiffness.load_sharing`). Along the line of action (positions ``s`` from T1, m) the
pinion's tip is at E and the wheel's tip at A, so a pair at ``s`` sees

.. math::

    e(s) = \delta_1\, f\!\left(\frac{s - s_{1}}{E - s_{1}}\right)
         + \delta_2\, f\!\left(\frac{s_{2} - s}{s_{2} - A}\right),

with ``f`` zero for a negative argument and the shapes of Fig. 3 on the normalised roll
coordinate ``xi`` in [0, 1] (start of the modification to the tip; roll angle is linear in
``s`` for both gears):

* ``"linear"``: ``f = xi``;
* ``"parabolic-1"``: ``f = xi^2``, tangent to the involute at the start (zero slope);
* ``"parabolic-2"``: ``f = 1 - sqrt(1 - xi)``, the parabola with its vertex at the tip, vertical
  (infinite slope) there.

Positions outside AE are clipped to it: the tip *corner* of a relieved tooth, which is what
touches in corner contact (:mod:`models.stiffness.corner_contact`), is relieved by the full
amount.

Normalisation (seed 003 Sec. 2.5)
---------------------------------
* **Amount** ``Delta``: ``Delta = 1`` is the conventional amount, the combined deflection at the
  highest point of single tooth contact under the design load (plus twice the spacing error,
  zero here). For ``1 < eps < 2`` the pair at HPSTC (``D = A + p_b``) carries the whole load,
  so ``delta_ref = C(D) F``. For ``2 < eps < 3`` the seed evaluates it at HP2DTC
  (``A + 2 p_b``), where two pairs share the load: in general, with ``n = floor(eps)`` and
  ``D_n = A + n p_b``,

  .. math:: \delta_{ref} = F \Big/ \sum_{k=0}^{n-1} \frac{1}{C(D_n - k p_b)} .

  Both gears get the same amount ``delta = Delta delta_ref`` (seed: "the same amount and length
  ... to the tooth tip of both gear and pinion"). This is the amount that just prevents
  premature contact: with ``Ln = 1`` the wheel tip corner of the incoming pair is relieved by
  ``C(D) F`` when the loaded pair reaches D, which equals the transmission error there. On the
  recess side the corresponding amount is ``C(B) F`` (B = LPSTC), the same for equal gears
  (Kahraman pair) but not in general.
* **Length** ``Ln``: ``Ln = 1`` relieves from HPSTC to the tip, i.e. the pinion over
  ``[D_n, E]`` and the wheel over ``[A, E - n p_b]`` (its own HPSTC); ``Ln`` scales that length
  along the line of action, equivalently in roll angle. Seed 003 quotes the starts as roll
  angles of the pinion: Ln = 1 -> 21.7 deg, Ln = 0.92 -> 22.2 deg, Ln = 1.15 -> 20.9 deg for the
  Kahraman gears (Secs. 4.2 and 5.1), which this reading reproduces (a test).

References
----------
.. [1] W. Yu, C. K. Mechefske, "Analytical modeling of spur gear corner contact effects",
   Mech. Mach. Theory 96 (2016) 146-164, Sec. 2.5, Figs. 2-3 (seed 003).
.. [2] H. H. Lin, F. B. Oswald, D. P. Townsend, "Dynamic loading of spur gears with linear or
   parabolic tooth profile modifications", Mech. Mach. Theory 29 (1994) 1115-1129.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Final, Literal, get_args

import numpy as np
from numpy.typing import ArrayLike

from models.errors import ModelError
from models.geometry.gear_pair import GearPair

__all__ = [
    "RELIEF_SHAPES",
    "ReliefShape",
    "TipRelief",
    "normalised_tip_relief",
    "reference_relief_amount",
    "relief_shape",
    "tip_relief",
]

ReliefShape = Literal["linear", "parabolic-1", "parabolic-2"]
RelievedGears = Literal["both", "pinion", "wheel"]
#: The tip-relief shapes of seed 003 Fig. 3.
RELIEF_SHAPES: Final[tuple[str, ...]] = get_args(ReliefShape)


def _check_shape(shape: str) -> None:
    if shape not in RELIEF_SHAPES:
        raise ModelError(f"`shape` must be one of {', '.join(RELIEF_SHAPES)}, was {shape!r}")


def relief_shape(xi: ArrayLike, shape: ReliefShape = "linear") -> np.ndarray:
    """Normalised relief ``f(xi)`` (-): 0 at the start of the modification, 1 at the tip.

    Parameters
    ----------
    xi : array_like
        Normalised roll coordinate, 0 at the start of the modification, 1 at the tip; values
        outside [0, 1] are clipped.
    shape : {"linear", "parabolic-1", "parabolic-2"}
        Seed 003 Fig. 3: straight line; parabola tangent to the involute at the start;
        parabola vertical at the tip.

    Returns
    -------
    numpy.ndarray

    Examples
    --------
    >>> [round(float(relief_shape(0.5, s)), 4) for s in RELIEF_SHAPES]
    [0.5, 0.25, 0.2929]
    """
    _check_shape(shape)
    x = np.clip(np.asarray(xi, dtype=float), 0.0, 1.0)
    if shape == "linear":
        return x
    if shape == "parabolic-1":
        return x * x
    return 1.0 - np.sqrt(1.0 - x)


@dataclass(frozen=True)
class TipRelief:
    """Tip relief of both gears as the profile error ``e(s)`` of a tooth pair (m).

    Call it with positions on the line of action (m from T1) to get ``e`` (m).

    Attributes
    ----------
    pinion_amount_m, wheel_amount_m : float
        Relief at the tip (m).
    pinion_start_m : float
        Position where the pinion relief starts; it grows to the pinion tip at E (m).
    wheel_start_m : float
        Position where the wheel relief starts; it grows to the wheel tip at A (m).
    start_of_contact_m, end_of_contact_m : float
        A and E (m); positions are clipped to [A, E].
    shape : str
        ``"linear"``, ``"parabolic-1"`` or ``"parabolic-2"``.
    amount : float or None
        Normalised amount ``Delta`` when built by :func:`normalised_tip_relief`.
    length : float
        Normalised length ``Ln``.
    """

    pinion_amount_m: float
    wheel_amount_m: float
    pinion_start_m: float
    wheel_start_m: float
    start_of_contact_m: float
    end_of_contact_m: float
    shape: ReliefShape = "linear"
    amount: float | None = None
    length: float = 1.0

    def pinion(self, s_m: ArrayLike) -> np.ndarray:
        """Pinion part of the relief at positions ``s`` (m)."""
        s = np.clip(np.asarray(s_m, dtype=float), self.start_of_contact_m, self.end_of_contact_m)
        span = self.end_of_contact_m - self.pinion_start_m
        return self.pinion_amount_m * relief_shape((s - self.pinion_start_m) / span, self.shape)

    def wheel(self, s_m: ArrayLike) -> np.ndarray:
        """Wheel part of the relief at positions ``s`` (m)."""
        s = np.clip(np.asarray(s_m, dtype=float), self.start_of_contact_m, self.end_of_contact_m)
        span = self.wheel_start_m - self.start_of_contact_m
        return self.wheel_amount_m * relief_shape((self.wheel_start_m - s) / span, self.shape)

    def __call__(self, s_m: ArrayLike) -> np.ndarray:
        """Profile error ``e(s)`` of a tooth pair: pinion plus wheel relief (m)."""
        return self.pinion(s_m) + self.wheel(s_m)


def _reference_point_count(pair: GearPair) -> int:
    eps = pair.contact_ratio
    n = math.floor(eps)
    if eps - n < 1e-9:
        raise ModelError(f"`pair.contact_ratio` = {eps!r} is an integer: the highest point of "
                         "single (or n-fold) contact coincides with the tip, the reference "
                         "relief length is zero")
    return n


def tip_relief(
    pair: GearPair,
    amount_m: float,
    length: float = 1.0,
    shape: ReliefShape = "linear",
    gears: RelievedGears = "both",
) -> TipRelief:
    """Tip relief with an amount in metres and the normalised length ``Ln`` of seed 003.

    Parameters
    ----------
    pair : GearPair
    amount_m : float
        Relief ``delta`` at the tip (m), >= 0, the same on each relieved gear.
    length : float
        ``Ln`` (-), > 0: 1 relieves from the highest point of single contact (HP2DTC for
        ``2 < eps < 3``) to the tip; the length along the line of action scales with it.
    shape : {"linear", "parabolic-1", "parabolic-2"}
    gears : {"both", "pinion", "wheel"}
        Which tips are relieved.

    Returns
    -------
    TipRelief

    Examples
    --------
    Seed 003 Sec. 5.1: with Ln = 1 the Kahraman pinion relief starts at a roll angle of 21.7 deg.

    >>> from models.geometry import load_gear_set
    >>> g = load_gear_set("kahraman-blankenship").pair
    >>> r = tip_relief(g, 16e-6)
    >>> round(float(np.degrees(g.roll_angle(r.pinion_start_m))), 1)
    21.7
    >>> round(float(r(g.end_of_contact)) * 1e6, 3), round(float(r(g.pitch_point)) * 1e6, 3)
    (16.0, 0.0)
    """
    _check_shape(shape)
    if not (math.isfinite(amount_m) and amount_m >= 0):
        raise ModelError(f"`amount_m` must be finite and >= 0 m, was {amount_m!r}")
    if not (math.isfinite(length) and length > 0):
        raise ModelError(f"`length` must be finite and > 0, was {length!r}")
    if gears not in get_args(RelievedGears):
        raise ModelError(f"`gears` must be one of both, pinion, wheel, was {gears!r}")
    n = _reference_point_count(pair)
    A, E, pb = pair.start_of_contact, pair.end_of_contact, pair.base_pitch
    ref_len = E - (A + n * pb)
    span = length * ref_len
    return TipRelief(
        pinion_amount_m=float(amount_m) if gears in ("both", "pinion") else 0.0,
        wheel_amount_m=float(amount_m) if gears in ("both", "wheel") else 0.0,
        pinion_start_m=E - span,
        wheel_start_m=A + span,
        start_of_contact_m=A,
        end_of_contact_m=E,
        shape=shape,
        amount=None,
        length=float(length),
    )


def reference_relief_amount(
    pair: GearPair, compliance: Callable[[np.ndarray], np.ndarray], load_N: float
) -> float:
    r"""The conventional relief amount ``delta_ref`` (``Delta = 1``) of seed 003 (m).

    Parameters
    ----------
    pair : GearPair
    compliance : callable
        Tooth-pair compliance ``C(s)`` (m/N) at positions ``s`` (m), array in, same shape out.
    load_N : float
        Design normal load ``F = T / r_b1`` (N), >= 0.

    Returns
    -------
    float
        ``F / sum_k 1 / C(D_n - k p_b)`` (m), ``k = 0..n-1``, ``n = floor(eps)``, ``D_n = A + n
        p_b``: the combined deflection at HPSTC (``C(D) F`` for ``1 < eps < 2``).

    Examples
    --------
    >>> from models.geometry import load_gear_set
    >>> g = load_gear_set("kahraman-blankenship").pair
    >>> round(reference_relief_amount(g, lambda s: np.full(np.shape(s), 3.3e-9), 4824.0) * 1e6, 2)
    15.92
    """
    if not (math.isfinite(load_N) and load_N >= 0):
        raise ModelError(f"`load_N` must be finite and >= 0 N, was {load_N!r}")
    n = _reference_point_count(pair)
    d_n = pair.start_of_contact + n * pair.base_pitch
    s = d_n - pair.base_pitch * np.arange(n)
    c = np.asarray(compliance(s), dtype=float)
    if c.shape != s.shape or not np.all(np.isfinite(c) & (c > 0)):
        raise ModelError(f"`compliance` must return finite values > 0 m/N of the input's shape "
                         f"{s.shape}, returned {c!r}")
    return float(load_N / np.sum(1.0 / c))


def normalised_tip_relief(
    pair: GearPair,
    compliance: Callable[[np.ndarray], np.ndarray],
    design_torque_Nm: float,
    amount: float = 1.0,
    length: float = 1.0,
    shape: ReliefShape = "linear",
    gears: RelievedGears = "both",
) -> TipRelief:
    """Tip relief with seed 003's normalised amount ``Delta`` and length ``Ln``.

    Parameters
    ----------
    pair : GearPair
    compliance : callable
        Tooth-pair compliance ``C(s)`` (m/N).
    design_torque_Nm : float
        Pinion design torque ``T`` (N m); ``F = T / r_b1``.
    amount : float
        ``Delta`` (-), >= 0: the relief is ``Delta * delta_ref``
        (:func:`reference_relief_amount`).
    length : float
        ``Ln`` (-), > 0.
    shape : {"linear", "parabolic-1", "parabolic-2"}
    gears : {"both", "pinion", "wheel"}

    Returns
    -------
    TipRelief
        With ``amount`` set to ``Delta``.
    """
    if not (math.isfinite(design_torque_Nm) and design_torque_Nm >= 0):
        raise ModelError(f"`design_torque_Nm` must be finite and >= 0 N m, "
                         f"was {design_torque_Nm!r}")
    if not (math.isfinite(amount) and amount >= 0):
        raise ModelError(f"`amount` must be finite and >= 0, was {amount!r}")
    ref = reference_relief_amount(pair, compliance, design_torque_Nm / pair.base_radius(1))
    r = tip_relief(pair, amount * ref, length, shape, gears)
    return TipRelief(r.pinion_amount_m, r.wheel_amount_m, r.pinion_start_m, r.wheel_start_m,
                     r.start_of_contact_m, r.end_of_contact_m, r.shape, float(amount),
                     r.length)

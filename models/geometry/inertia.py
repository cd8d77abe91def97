r"""Gear-body inertias and the equivalent mass of the mesh mode: the one convention of ``models``.

Every model that turns a mesh stiffness into a frequency (``models.thermal``'s natural
frequency, ``models.dynamics``' dimensional scaling and two-stage systems, ``rigtools``'
calibration) takes its inertias from here unless the caller gives measured ones.

The convention, :data:`EQUIVALENT_MASS_CONVENTION`
--------------------------------------------------
Each gear body is a bored disc of the face width ``b`` and its material's density:

.. math:: J = \frac{\pi}{2} \rho\, b \left(r_o^4 - r_i^4\right),

outer radius the **operating pitch radius** ``r_w = r_b / cos(alpha')`` (default) or the
reference radius ``z m / 2`` (``disc_radius="reference"``); bore radius ``r_i`` the gear's
``bore_diameter_m`` / 2, or 0.3 of its reference radius when the gear states none (the bore of
:mod:`models.stiffness.potential_energy` and :mod:`models.thermal.expansion`).

Why this one: the operating pitch circle is where the mating bodies roll, so the disc that
ends there splits the tooth ring the way the two gears share it at the mesh; a body solid to
the root circle with a half-filled tooth ring root-to-tip comes out 7 % above it for the
FZG-C pinion and 0.4 % below it for the wheel. The reference-radius disc is 6.4 % lighter on
FZG-C (``f_n`` 3 % higher). Before this module ``models.dynamics`` used the solid
reference-radius disc; that choice now needs ``disc_radius="reference"`` and an explicit
``bore_fraction=0``. A real rig gear's hub, web or shaft shoulder changes ``J`` more than either
choice: give measured or CAD inertias when they are known (a campaign's
``[calibration] inertia_kg_m2`` or ``equivalent_mass_kg``).

The equivalent mass
-------------------
The mesh spring acts on ``x = r_b1 theta_1 + r_b2 theta_2``; ``J_i theta_i'' = -r_bi k x``
gives ``x'' = -k x (r_b1^2 / J_1 + r_b2^2 / J_2)``, one mass on the spring:

.. math:: m_e = \frac{J_1 J_2}{J_1 r_{b2}^2 + J_2 r_{b1}^2}

(seed 003 Eq. 24a; ISO 6336-1:2019 clause 6.5, ``m_red = m_1 m_2 / (m_1 + m_2)`` with
``m_i = J_i / r_bi^2``).
"""

from __future__ import annotations

import math
from typing import Final, Literal

from models.errors import ModelError
from models.geometry.gear_pair import GearPair

__all__ = [
    "DEFAULT_BORE_FRACTION",
    "DISC_RADII",
    "EQUIVALENT_MASS_CONVENTION",
    "DiscRadius",
    "equivalent_mass",
    "gear_inertia",
    "pair_equivalent_mass",
]

DiscRadius = Literal["operating", "reference"]
#: Accepted outer radii of the disc.
DISC_RADII: Final[tuple[DiscRadius, ...]] = ("operating", "reference")
#: Bore of a gear that states none, as a fraction of its reference radius.
DEFAULT_BORE_FRACTION: Final[float] = 0.3
#: Name of the default convention (written into outputs that depend on it).
EQUIVALENT_MASS_CONVENTION: Final[str] = (
    "operating-pitch bored disc: J = pi/2 rho b (r_w^4 - r_i^4), r_w = r_b / cos(alpha'), "
    "r_i = bore or 0.3 r; m_e = J1 J2 / (J1 r_b2^2 + J2 r_b1^2)")


def gear_inertia(pair: GearPair, gear: int, *, disc_radius: DiscRadius = "operating",
                 bore_fraction: float | None = None) -> float:
    r"""Polar moment of inertia of gear 1 (pinion) or 2 (wheel) as a bored disc (kg m^2).

    .. math:: J = \frac{\pi}{2} \rho\, b \left(r_o^4 - r_i^4\right)

    Parameters
    ----------
    pair : GearPair
        Face width ``b`` of the pair, density of the gear's material.
    gear : {1, 2}
    disc_radius : {"operating", "reference"}
        ``r_o``: the operating pitch radius ``r_b / cos(alpha')`` (default) or ``z m / 2``.
    bore_fraction : float, optional
        Bore radius as a fraction of the reference radius, used when the gear states no
        ``bore_diameter_m``; default :data:`DEFAULT_BORE_FRACTION`. ``0`` gives a solid disc.

    Examples
    --------
    >>> from models.geometry import load_gear_set
    >>> g = load_gear_set("fzg-c").pair
    >>> round(gear_inertia(g, 1) * 1e4, 3)   # in 1e-4 kg m^2
    3.07
    """
    if isinstance(gear, bool) or gear not in (1, 2):
        raise ModelError(f"`gear` must be 1 (pinion) or 2 (wheel), was {gear!r}")
    if disc_radius == "operating":
        r_o = pair.operating_pitch_radius(gear)
    elif disc_radius == "reference":
        r_o = pair.reference_radius(gear)
    else:
        raise ModelError(f"`disc_radius` must be 'operating' or 'reference', was {disc_radius!r}")
    frac = DEFAULT_BORE_FRACTION if bore_fraction is None else float(bore_fraction)
    if not (math.isfinite(frac) and 0.0 <= frac < 1.0):
        raise ModelError(f"`bore_fraction` must lie in [0, 1), was {bore_fraction!r}")
    g = pair.pinion if gear == 1 else pair.wheel
    r_i = (g.bore_diameter_m / 2 if g.bore_diameter_m is not None
           else frac * pair.reference_radius(gear))
    if not 0 <= r_i < r_o:
        raise ModelError(f"`{'pinion' if gear == 1 else 'wheel'}.bore_diameter_m` must lie in "
                         f"[0, {2 * r_o:.6g}) m, was {2 * r_i!r}")
    return math.pi / 2 * g.material.density_kg_m3 * pair.face_width_m * (r_o**4 - r_i**4)


def equivalent_mass(inertia_pinion_kg_m2: float, inertia_wheel_kg_m2: float,
                    base_radius_pinion_m: float, base_radius_wheel_m: float) -> float:
    r"""Equivalent mass of the mesh mode on the line of action (kg).

    .. math:: m_e = \frac{J_1 J_2}{J_1 r_{b2}^2 + J_2 r_{b1}^2}

    Examples
    --------
    Two equal gears: half of ``J / r_b^2``.

    >>> round(equivalent_mass(2e-3, 2e-3, 0.05, 0.05), 12)
    0.4
    """
    vals = (("inertia_pinion_kg_m2", inertia_pinion_kg_m2),
            ("inertia_wheel_kg_m2", inertia_wheel_kg_m2),
            ("base_radius_pinion_m", base_radius_pinion_m),
            ("base_radius_wheel_m", base_radius_wheel_m))
    out = []
    for name, v in vals:
        try:
            x = math.nan if isinstance(v, bool) else float(v)
        except (TypeError, ValueError):
            x = math.nan
        if not (math.isfinite(x) and x > 0):
            raise ModelError(f"`{name}` must be a finite number > 0, was {v!r}")
        out.append(x)
    j1, j2, r1, r2 = out
    return j1 * j2 / (j1 * r2**2 + j2 * r1**2)


def pair_equivalent_mass(pair: GearPair, *, inertia_kg_m2: tuple[float, float] | None = None,
                         disc_radius: DiscRadius = "operating") -> float:
    """``m_e`` of ``pair`` (kg): from the given ``(J_1, J_2)``, else the convention's discs.

    Examples
    --------
    >>> from models.geometry import load_gear_set
    >>> g = load_gear_set("fzg-c").pair
    >>> j = (gear_inertia(g, 1), gear_inertia(g, 2))
    >>> pair_equivalent_mass(g) == equivalent_mass(*j, g.base_radius(1), g.base_radius(2))
    True
    """
    if inertia_kg_m2 is None:
        j1 = gear_inertia(pair, 1, disc_radius=disc_radius)
        j2 = gear_inertia(pair, 2, disc_radius=disc_radius)
    else:
        if len(inertia_kg_m2) != 2:
            raise ModelError(f"`inertia_kg_m2` must be a pair (J_1, J_2), was {inertia_kg_m2!r}")
        j1, j2 = (float(v) for v in inertia_kg_m2)
    return equivalent_mass(j1, j2, pair.base_radius(1), pair.base_radius(2))

r"""Ishikawa's equivalent-tooth deflection of spur gear teeth, single-tooth and pair stiffness.

Ishikawa (1951) replaces the tooth by a cantilever of simple shape whose bending, shear and
root-tilt compliances have closed forms; seed 000 uses it for the elastic stiffness of FZG-C
gears. The seed prints the four terms garbled (SEED-NOTES 1) and does not define the
equivalent tooth (SEED-NOTES 2) nor a contact term (SEED-NOTES 3); this module reconstructs
all three, derives each closed form from the beam energy and says where the seed deviates.

The equivalent tooth, in words
------------------------------
Stand the tooth upright with its centreline vertical and measure heights ``h`` up the
centreline from the root circle. From ``h = 0`` to ``h = h_r`` stands a *rectangle* of width
``S_F``. On it stands a *trapezoid*: its slanted sides are the straight lines through the
point where each flank's involute begins (the form circle, or the base circle) and the tip
corner of that flank; it is cut off at the tip circle, and its sides, extended upward, meet on
the centreline at the apex height ``h_i``. So the width at height ``h`` is

.. math::

    S(h) = S_F \quad (0 \le h \le h_r), \qquad
    S(h) = S_F \frac{h_i - h}{h_i - h_r} \quad (h_r \le h \le h_i),

``S_F`` is the chord of the tooth at the form circle and ``h_r`` the height of that chord
above the root circle. The normal load ``F_n`` acts along the line of action (the common
normal, tangent to the base circle) through the contact point; slid along its line to where
it crosses the centreline, it acts at height ``h_k`` and makes the angle ``omega_k`` with the
perpendicular to the centreline. ``F cos(omega_k)`` bends and shears the beam; the radial
component ``F sin(omega_k)`` passes through the centreline and only compresses it (Ishikawa
neglects that, and so do we). The root section rests on an elastic half-plane that tilts under
the root moment: the foundation term.

``omega_k = alpha_k - psi_k`` with the pressure angle ``cos(alpha_k) = r_b / r_k`` and the
half tooth-thickness angle ``psi_k = pi/(2z) + 2 x tan(alpha)/z + inv(alpha) - inv(alpha_k)``
at the contact radius ``r_k``, and ``h_k = r_k (cos(psi_k) - sin(psi_k) tan(omega_k)) - r_f``:
the same load angle and moment arm as ISO 6336-3's ``alpha_Fen = alpha_en - gamma_e`` and
``h_Fe`` (there for the load at the tip). The trapezoid is anchored at the form circle
(ISO 21771's ``d_Ff`` for a rack-generated gear: the end of the rack's straight flank) by
default, or at the base circle; for FZG-C the two differ by 0.04 mm (pinion) and 0.56 mm
(wheel) in radius, and the stiffness by under 1 %. Ishikawa's paper
was not available to us: this is the construction SEED-NOTES 2 proposes, which reproduces every
term's structure (the rectangle's width is the trapezoid's width at ``h_r``).

The four terms (deflection along the load, for the normal load ``F``, face width ``b``)
----------------------------------------------------------------------------------------
By Castigliano on the rectangle-plus-trapezoid beam, with moment
``M(h) = F cos(omega_k) (h_k - h)`` and shear force ``V = F cos(omega_k)`` (for
``h_k >= h_r``; ``x = (h_i - h_k)/(h_i - h_r)``):

.. math::

    \delta_{Br} &= \frac{12 F \cos^2\omega_k}{E b S_F^3}
        \left[h_k h_r (h_k - h_r) + \frac{h_r^3}{3}\right] \\
    \delta_{Bt} &= \frac{6 F \cos^2\omega_k}{E b S_F^3}
        \left[x (4 - x) - 2 \ln x - 3\right] (h_i - h_r)^3 \\
    \delta_{s}  &= \frac{2 \kappa (1 + \nu) F \cos^2\omega_k}{E b S_F}
        \left[h_r + (h_i - h_r) \ln\frac{h_i - h_r}{h_i - h_k}\right] \\
    \delta_{G}  &= \frac{24 F h_k^2 \cos^2\omega_k}{\pi E b S_F^2}

``delta_Br`` is the bending of the rectangle (``int_0^h_r``), ``delta_Bt`` that of the
trapezoid (``int_h_r^h_k``), ``delta_s`` the shear of both with shear coefficient ``kappa``
(Ishikawa's ``2(1 + nu)`` is ``kappa = 1``, shear stress ``V/A``; the Timoshenko energy value
for a rectangle is 1.2; a parameter here), ``delta_G`` the tilt ``gamma = 24 M / (pi E b S_F^2)``
of the root section times the lever ``h_k cos(omega_k)``: ``gamma`` is the surface slope at
the centre of an elastic half-plane (Flamant, plane stress) under the Navier stress
``sigma(t) = 12 M t / (b S_F^3)`` of the root section. When the load line crosses the
centreline inside the rectangle (``h_k <= h_r``) the trapezoid terms vanish and the rectangle
gives ``4 F cos^2(omega) h_k^3 / (E b S_F^3)`` and ``2 kappa (1 + nu) F cos^2(omega) h_k /
(E b S_F)``.

Where the seed's printed terms differ (each shown in ``tests/models/test_ishikawa.py``):

* ``delta_Bt`` is printed with ``(h_i - h_r)`` to the first power: not a length (the term does
  not scale as 1/length), and short of the beam integral by ``(h_i - h_r)^2``. The cube is
  implemented.
* ``delta_s`` is printed with ``ln((h_i - h_k)/(h_i - h_r))``, an argument below one: the shear
  compliance then *falls* as the load rises, and turns negative high on the tooth. The
  integral ``int dh / S(h)`` gives the reciprocal argument, implemented here.
* ``delta_G`` is printed linear in ``h_k``: dimension 1 instead of m (the tilt is proportional
  to the moment ``F h_k`` and the deflection to the lever ``h_k`` again). ``h_k^2`` is
  implemented.
* ``delta_Br`` is printed correctly.

The contact term (SEED-NOTES 3)
-------------------------------
The seed lists no contact deflection. ``include_hertz`` makes the choice explicit:

* ``False``: Ishikawa's four terms only (the seed as printed).
* ``"linear"``: the load-independent line-contact stiffness of Yang and Sun (1985),
  ``k_h = pi E b / (4 (1 - nu^2))`` for the pair, i.e. ``delta_H = 2 (1 - nu_i^2) F /
  (pi E_i b)`` for each of the two teeth (equal halves for equal materials).
* ``"weber"``: the Weber-Banaschek (1953) approach of each body's surface to a point at depth
  ``h`` (here the distance from the contact point to the tooth centreline along the load
  line): ``delta_H,i = 2 F (1 - nu_i^2) / (pi E_i b) [ln(2 h / a) - nu_i / (2 (1 - nu_i))]``
  with the Hertz half-width ``a = sqrt(4 F R / (pi b E*))``, ``1/R = 1/rho_1 + 1/rho_2``,
  ``1/E* = (1 - nu_1^2)/E_1 + (1 - nu_2^2)/E_2`` (Johnson 1985, eq. 4.43). Nonlinear in ``F``:
  give the real load.

For FZG-C (``eps = 1.44``) the mean mesh stiffness per unit face width comes out at
33 N/(mm um) without a contact term, 29 with ``"linear"`` and 23 with ``"weber"`` (at the
seed's 381.96 N m). ISO 6336-1 expects ``c_gamma_alpha = c' (0.75 eps + 0.25)``: 18.6 with the
rule-of-thumb ``c' = 14``, 21.0 with the theoretical ``c'_th = 1/q' = 15.8`` of ISO 6336-1's
regression for these teeth. Only ``"weber"`` lands within 15 % of ISO (tested): Ishikawa's
four terms alone are far too stiff, and the constant Yang-Sun contact stiffness (three times
stiffer than Weber's at this load) adds too little.

Stiffness
---------
Single-tooth stiffness ``k_Ei = F / delta_i`` (the sum of the terms for tooth i), pair stiffness
``k_EP = k_E1 k_E2 / (k_E1 + k_E2)`` (teeth in series), mesh stiffness the sum over the pairs
in contact; its mean over a mesh cycle is ``(1/p_b) int_A^E k_EP ds``.

References
----------
.. [1] J. Ishikawa, "Deflection of gear teeth" (in Japanese), Trans. JSME, 1951; as used by
   seed 000 (not consulted directly: the terms are rederived here).
.. [2] R. W. Cornell, "Compliance and stress sensitivity of spur gear teeth", ASME J. Mech.
   Des. 103 (1981) 447-459 (tooth compliance from beam, shear and foundation terms).
.. [3] C. Weber, K. Banaschek, "Formänderung und Profilrücknahme bei gerad- und
   schrägverzahnten Rädern", Schriftenreihe Antriebstechnik 11, Vieweg, 1953.
.. [4] D. C. H. Yang, Z. S. Sun, "A rotary model for spur gear dynamics", ASME J. Mech.
   Transm. Autom. Des. 107 (1985) 529-535.
.. [5] K. L. Johnson, *Contact Mechanics*, Cambridge University Press, 1985 (eq. 2.25:
   half-plane surface slope; eq. 4.43: Hertz line contact).
.. [6] ISO 6336-1:2019, clause 9 (single stiffness c', mesh stiffness c_gamma);
   ISO 6336-3:2019 (load angle, bending moment arm); ISO 21771:2007 (form diameter).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Final, Literal

import numpy as np
from numpy.typing import ArrayLike
from scipy.integrate import simpson

from models.errors import GeometryError, ModelError
from models.geometry.gear_pair import Gear, GearPair
from models.geometry.involute import inv
from models.stiffness.load_distribution import contact_path_positions, load_share_seed_000

__all__ = [
    "HERTZ_OPTIONS",
    "EquivalentTooth",
    "HertzOption",
    "IshikawaDeflection",
    "ToothPairStiffness",
    "equivalent_tooth",
    "form_radius",
    "ishikawa_deflection",
    "ishikawa_terms",
    "mean_mesh_stiffness",
    "tooth_pair_stiffness",
]

HertzOption = Literal[False, "linear", "weber"]
#: The accepted values of ``include_hertz``.
HERTZ_OPTIONS: Final[tuple[HertzOption, ...]] = (False, "linear", "weber")

_ANCHORS = ("form", "base")
_TOL_M = 1e-9  # positions this far outside AE are accepted (rounding)


# --- the equivalent tooth ---------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class EquivalentTooth:
    """Ishikawa's rectangle-plus-trapezoid tooth of one gear, and load points on it.

    Heights are measured along the tooth centreline from the root circle (m).

    Attributes
    ----------
    gear : int
        1 (pinion) or 2 (wheel).
    anchor : str
        ``"form"`` or ``"base"``: the circle on which the trapezoid's sides start.
    root_radius_m, anchor_radius_m, tip_radius_m : float
        Root, anchor (form or base) and tip radii (m).
    S_F_m : float
        Width of the rectangle, the tooth's chord at the anchor circle (m).
    h_r_m : float
        Height of the rectangle (m).
    h_i_m : float
        Height of the trapezoid's apex, where its sides meet on the centreline (m).
    h_tip_m : float
        Height of the tip corners (m); the trapezoid is cut off there.
    S_tip_m : float
        Chord of the tooth at the tip circle (m), the trapezoid's width at ``h_tip_m``.
    s_m : numpy.ndarray
        Positions on the line of action from T1 at which the load points are given (m).
    contact_radius_m : numpy.ndarray
        Radius of the contact point on this gear (m).
    h_k_m : numpy.ndarray
        Height at which the load line crosses the centreline (m).
    omega_k_rad : numpy.ndarray
        Load angle: between the load line and the perpendicular to the centreline (rad).
    contact_half_thickness_m : numpy.ndarray
        Distance of the contact point from the centreline (m); the Weber contact term uses
        ``contact_half_thickness_m / cos(omega_k)``.
    load_clamped : numpy.ndarray or None
        Positions whose load line crosses the centreline below the root circle; their load
        is taken at the root (``h_k = 0``).
    """

    gear: int
    anchor: str
    root_radius_m: float
    anchor_radius_m: float
    tip_radius_m: float
    S_F_m: float
    h_r_m: float
    h_i_m: float
    h_tip_m: float
    S_tip_m: float
    s_m: np.ndarray
    contact_radius_m: np.ndarray
    h_k_m: np.ndarray
    omega_k_rad: np.ndarray
    contact_half_thickness_m: np.ndarray
    load_clamped: np.ndarray | None = None

    def width(self, h_m: ArrayLike) -> np.ndarray:
        """Width ``S(h)`` of the equivalent tooth at heights ``h`` (m); see the module notes."""
        h = np.asarray(h_m, dtype=float)
        trap = self.S_F_m * (self.h_i_m - h) / (self.h_i_m - self.h_r_m)
        return np.where(h <= self.h_r_m, self.S_F_m, trap)


def _gear(pair: GearPair, gear: int) -> Gear:
    if isinstance(gear, bool) or gear not in (1, 2):
        raise ModelError(f"`gear` must be 1 (pinion) or 2 (wheel), was {gear!r}")
    return pair.pinion if gear == 1 else pair.wheel


def _half_angle(pair: GearPair, gear: int, r_m: ArrayLike) -> np.ndarray:
    """Half tooth-thickness angle ``psi(r)`` of the involute flank at radius ``r`` (rad)."""
    g = _gear(pair, gear)
    a0 = pair.pressure_angle_rad
    alpha_r = np.arccos(np.clip(pair.base_radius(gear) / np.asarray(r_m, float), -1.0, 1.0))
    return (math.pi / (2 * g.teeth) + 2 * g.profile_shift * math.tan(a0) / g.teeth
            + float(inv(a0)) - inv(alpha_r))


def form_radius(pair: GearPair, gear: int) -> float:
    r"""Radius of the form circle, where the generated involute begins (m).

    For a gear cut by the basic rack (dedendum ``h_fP* m``, tip radius ``rho_fP* m``), the
    rack's straight flank ends ``h_FfP = (h_fP* - rho_fP* (1 - sin(alpha))) m`` above its datum
    line; that point meets the gear on the generating line of action at

    .. math::

        r_{Ff} = \sqrt{r_b^2 + \left(r \sin\alpha - \frac{h_{FfP} - x m}{\sin\alpha}\right)^2}

    (ISO 21771, form diameter ``d_Ff``), and never below the base circle. When the gear's root
    diameter is given, the rack dedendum is the one that cuts that root:
    ``h_fP* = (z m - d_f) / (2 m) + x``.

    Parameters
    ----------
    pair : GearPair
    gear : {1, 2}

    Returns
    -------
    float
        ``r_Ff`` (m).
    """
    g = _gear(pair, gear)
    m, a0 = pair.module_m, pair.pressure_angle_rad
    h_f = g.dedendum_coeff
    if g.root_diameter_m is not None:
        h_f = (g.teeth * m - g.root_diameter_m) / (2 * m) + g.profile_shift
    h_ffp = h_f - g.root_fillet_coeff * (1 - math.sin(a0))
    rho = pair.reference_radius(gear) * math.sin(a0) - (h_ffp - g.profile_shift) * m / math.sin(a0)
    return math.hypot(pair.base_radius(gear), max(rho, 0.0))


def _as_positions(pair: GearPair, s_m: ArrayLike | None) -> np.ndarray:
    if s_m is None:
        return contact_path_positions(pair)
    s = np.asarray(s_m, dtype=float)
    if not np.all(np.isfinite(s)):
        raise ModelError("`s_m` must be finite")
    a, e = pair.start_of_contact, pair.end_of_contact
    bad = (s < a - _TOL_M) | (s > e + _TOL_M)
    if np.any(bad):
        worst = float(s[bad].flat[0])
        raise ModelError(f"`s_m` must lie on the path of contact [{a:.6g}, {e:.6g}] m from T1, "
                         f"was {worst:.6g}")
    return np.clip(s, a, e)


def equivalent_tooth(
    pair: GearPair,
    gear: int,
    s_m: ArrayLike | None = None,
    *,
    anchor: Literal["form", "base"] = "form",
) -> EquivalentTooth:
    r"""Ishikawa's equivalent tooth of gear 1 or 2, with the load points at positions ``s``.

    Construction (module docstring, "The equivalent tooth, in words"): with the gear centre at
    the origin and the tooth centreline on the y axis, a flank point at radius ``r`` is
    ``(r sin(psi), r cos(psi))``. Let F be the flank point on the anchor circle and T the tip
    corner. Then

    .. math::

        S_F = 2 x_F, \quad h_r = y_F - r_f, \quad
        h_i = y_F + x_F \frac{y_T - y_F}{x_F - x_T} - r_f

    (the apex is where the line FT meets the centreline), and for a contact at radius ``r_k``

    .. math::

        \omega_k = \alpha_k - \psi_k, \quad
        h_k = r_k \left(\cos\psi_k - \sin\psi_k \tan\omega_k\right) - r_f .

    If the anchor point lies below the root circle (``y_F < r_f``, many teeth), the rectangle
    vanishes: ``h_r = 0`` and ``S_F`` is the trapezoid's width at the root circle.

    Parameters
    ----------
    pair : GearPair
    gear : {1, 2}
        1 for the pinion, 2 for the wheel.
    s_m : array_like, optional
        Positions on the path of contact, from T1 (m). Default: the 52 points of seed 000
        (:func:`~models.stiffness.load_distribution.contact_path_positions`).
    anchor : {"form", "base"}
        Circle on which the trapezoid's sides start: the form circle (default, SEED-NOTES 2)
        or the base circle.

    Returns
    -------
    EquivalentTooth

    Raises
    ------
    ModelError
        ``gear`` not 1 or 2, an unknown ``anchor``, positions off the path of contact.
    GeometryError
        A tooth that does not taper (tip chord >= anchor chord) or a load line crossing the
        centreline outside ``[0, h_i)``.

    Examples
    --------
    >>> from models.geometry import load_gear_set
    >>> t = equivalent_tooth(load_gear_set("fzg-c").pair, 1)
    >>> round(t.S_F_m * 1e3, 3), round(t.h_r_m * 1e3, 3), round(t.h_i_m * 1e3, 3)
    (8.197, 2.422, 13.812)
    """
    _gear(pair, gear)
    if anchor not in _ANCHORS:
        raise ModelError(f"`anchor` must be one of {_ANCHORS}, was {anchor!r}")
    s = _as_positions(pair, s_m)
    rf, ra, rb = pair.root_radius(gear), pair.tip_radius(gear), pair.base_radius(gear)
    r_anchor = form_radius(pair, gear) if anchor == "form" else rb

    psi_f = float(_half_angle(pair, gear, r_anchor))
    psi_t = float(_half_angle(pair, gear, ra))
    x_f, y_f = r_anchor * math.sin(psi_f), r_anchor * math.cos(psi_f)
    x_t, y_t = ra * math.sin(psi_t), ra * math.cos(psi_t)
    if not x_t < x_f:
        raise GeometryError(f"{'pinion' if gear == 1 else 'wheel'}.tip_diameter_m", 2 * ra,
                            f"equivalent tooth does not taper: tip chord {2e3 * x_t:.4f} mm >= "
                            f"chord at the {anchor} circle {2e3 * x_f:.4f} mm")
    y_apex = y_f + x_f * (y_t - y_f) / (x_f - x_t)
    if y_f >= rf:
        s_f, h_r = 2 * x_f, y_f - rf
    else:  # anchor below the root circle: slide down the side line to the root circle
        s_f, h_r = 2 * x_f * (y_apex - rf) / (y_apex - y_f), 0.0

    r_k = pair.contact_radius(s, gear)
    alpha_k = np.arccos(rb / r_k)
    psi_k = _half_angle(pair, gear, r_k)
    omega = alpha_k - psi_k
    h_k = r_k * (np.cos(psi_k) - np.sin(psi_k) * np.tan(omega)) - rf
    h_i = y_apex - rf
    who = "pinion" if gear == 1 else "wheel"
    above = np.asarray(h_k >= h_i)
    if above.any():
        i = int(np.flatnonzero(above.ravel())[0])
        raise GeometryError(f"{who} equivalent tooth", float(np.asarray(s).ravel()[i]),
                            f"the load line crosses the centreline at h_k = "
                            f"{float(np.asarray(h_k).ravel()[i]) * 1e3:.4f} mm, at or above the "
                            f"apex h_i = {h_i * 1e3:.4f} mm")
    # Low on the flank of a strongly inclined load (large operating pressure angle, negative
    # shift, many teeth) the load line can cross the centreline just below the root circle.
    # Ishikawa's beam has no section there: the load is taken at the root (h_k = 0), where its
    # bending arm vanishes, and the positions are flagged in `load_clamped`.
    load_clamped = np.asarray(h_k < 0)
    h_k = np.maximum(h_k, 0.0)
    return EquivalentTooth(
        gear=gear, anchor=anchor, root_radius_m=rf, anchor_radius_m=r_anchor, tip_radius_m=ra,
        S_F_m=s_f, h_r_m=h_r, h_i_m=h_i, h_tip_m=y_t - rf, S_tip_m=2 * x_t,
        s_m=s, contact_radius_m=r_k, h_k_m=h_k, omega_k_rad=omega,
        contact_half_thickness_m=r_k * np.sin(psi_k),
        load_clamped=load_clamped,
    )


# --- the four terms -----------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class IshikawaDeflection:
    """Deflection of one tooth along the load, term by term (m), for the given normal load.

    Attributes
    ----------
    s_m : numpy.ndarray
        Positions from T1 (m); empty when the terms were computed from bare dimensions.
    gear : int
        1 or 2 (0 when computed from bare dimensions).
    load_N : numpy.ndarray
        Normal load on the tooth, whole face width (N).
    delta_Br_m, delta_Bt_m : numpy.ndarray
        Bending of the rectangle and of the trapezoid (m).
    delta_s_m : numpy.ndarray
        Shear (m).
    delta_G_m : numpy.ndarray
        Tilt of the foundation (m).
    delta_H_m : numpy.ndarray
        This tooth's share of the contact deflection (m); zero when ``include_hertz=False``.
    include_hertz : str or bool
        The contact option used.
    """

    s_m: np.ndarray
    gear: int
    load_N: np.ndarray
    delta_Br_m: np.ndarray
    delta_Bt_m: np.ndarray
    delta_s_m: np.ndarray
    delta_G_m: np.ndarray
    delta_H_m: np.ndarray
    include_hertz: HertzOption

    @property
    def total_m(self) -> np.ndarray:
        """``delta_Br + delta_Bt + delta_s + delta_G + delta_H`` (m)."""
        return (self.delta_Br_m + self.delta_Bt_m + self.delta_s_m + self.delta_G_m
                + self.delta_H_m)

    @property
    def stiffness_N_per_m(self) -> np.ndarray:  # noqa: N802 (unit in the name, STYLE 4.4)
        """Single-tooth stiffness ``k_E = F / delta`` (N/m).

        Inf where the load line passes through the root (no Ishikawa deflection there, see
        ``EquivalentTooth.load_clamped``).
        """
        with np.errstate(divide="ignore"):
            return self.load_N / self.total_m


def _bt_bracket(u: np.ndarray) -> np.ndarray:
    """``x (4 - x) - 2 ln x - 3`` with ``x = 1 - u``, free of cancellation for small ``u``.

    Equals ``-2 log1p(-u) - 2 u - u^2 = 2 sum_{n>=3} u^n / n``; the series is used for
    ``u < 0.05`` (30 terms: truncation below 1e-30 relative).
    """
    u = np.asarray(u, dtype=float)
    small = u < 0.05
    us = np.where(small, u, 0.0)
    series = sum(2.0 * us**n / n for n in range(3, 33))
    ul = np.where(small, 0.5, u)
    closed = -2.0 * np.log1p(-ul) - 2.0 * ul - ul**2
    return np.where(small, series, closed)


def ishikawa_terms(
    *,
    S_F_m: float,
    h_r_m: float,
    h_i_m: float,
    h_k_m: ArrayLike,
    omega_k_rad: ArrayLike,
    youngs_modulus_Pa: float,
    poisson_ratio: float,
    face_width_m: float,
    load_N: ArrayLike = 1.0,
    shear_coefficient: float = 1.0,
) -> IshikawaDeflection:
    r"""Ishikawa's four deflection terms from the equivalent tooth's dimensions (m).

    The closed forms of the module docstring (bending of the rectangle and the trapezoid,
    shear, foundation tilt), each the exact Castigliano integral over the
    rectangle-plus-trapezoid beam (tested against :func:`scipy.integrate.quad` to 1e-8).

    Parameters
    ----------
    S_F_m, h_r_m, h_i_m : float
        Width of the rectangle, its height, and the trapezoid's apex height (m);
        ``0 <= h_r < h_i``, ``S_F > 0``.
    h_k_m : array_like
        Height of the load on the centreline (m), ``0 <= h_k < h_i``.
    omega_k_rad : array_like
        Load angle (rad).
    youngs_modulus_Pa : float
    poisson_ratio : float
    face_width_m : float
    load_N : array_like
        Normal load, whole face width (N).
    shear_coefficient : float
        ``kappa`` of the shear term: 1 as Ishikawa (``2 (1 + nu)``), 1.2 for the Timoshenko
        energy of a rectangular section.

    Returns
    -------
    IshikawaDeflection
        With ``delta_H_m = 0``, ``gear = 0`` and empty ``s_m``.

    Examples
    --------
    Load at the top of a plain rectangle (``h_i`` far away plays no role when
    ``h_k = h_r``): Euler-Bernoulli ``4 F h^3 / (E b S^3)``.

    >>> d = ishikawa_terms(S_F_m=0.01, h_r_m=0.01, h_i_m=1.0, h_k_m=0.01, omega_k_rad=0.0,
    ...                    youngs_modulus_Pa=2e11, poisson_ratio=0.3, face_width_m=0.01)
    >>> round(float(d.delta_Br_m) / 2e-9, 12), float(d.delta_Bt_m)
    (1.0, 0.0)
    """
    for name, v in (("S_F_m", S_F_m), ("h_i_m", h_i_m), ("youngs_modulus_Pa", youngs_modulus_Pa),
                    ("face_width_m", face_width_m), ("shear_coefficient", shear_coefficient)):
        if not (math.isfinite(v) and v > 0):
            raise ModelError(f"`{name}` must be a finite number > 0, was {v!r}")
    if not (0 <= h_r_m < h_i_m):
        raise ModelError(f"`h_r_m` must lie in [0, h_i_m={h_i_m!r}), was {h_r_m!r}")
    if not (0 <= poisson_ratio < 0.5):
        raise ModelError(f"`poisson_ratio` must lie in [0, 0.5), was {poisson_ratio!r}")
    h_k = np.asarray(h_k_m, dtype=float)
    if np.any(~np.isfinite(h_k) | (h_k < 0) | (h_k >= h_i_m)):
        raise ModelError(f"`h_k_m` must lie in [0, h_i_m={h_i_m!r}), was {h_k!r}")
    f = np.asarray(load_N, dtype=float)
    if np.any(~np.isfinite(f) | (f <= 0)):
        raise ModelError(f"`load_N` must be finite and > 0, was {f!r}")
    om = np.asarray(omega_k_rad, dtype=float)

    S, hr, hi = float(S_F_m), float(h_r_m), float(h_i_m)
    L = hi - hr
    c = f * np.cos(om) ** 2 / (youngs_modulus_Pa * face_width_m)
    in_trap = h_k > hr
    u = np.where(in_trap, (h_k - hr) / L, 0.0)  # 1 - x

    d_br = np.where(in_trap, 12 * c / S**3 * (h_k * hr * (h_k - hr) + hr**3 / 3),
                    4 * c * h_k**3 / S**3)
    d_bt = np.where(in_trap, 6 * c / S**3 * _bt_bracket(u) * L**3, 0.0)
    d_s = 2 * shear_coefficient * (1 + poisson_ratio) * c / S * (
        np.minimum(h_k, hr) - L * np.log1p(-u))
    d_g = 24 * c * h_k**2 / (math.pi * S**2)
    shape = np.broadcast(d_br, f).shape
    return IshikawaDeflection(
        s_m=np.empty(0), gear=0, load_N=np.broadcast_to(f, shape).copy(),
        delta_Br_m=np.broadcast_to(d_br, shape).copy(),
        delta_Bt_m=np.broadcast_to(d_bt, shape).copy(),
        delta_s_m=np.broadcast_to(d_s, shape).copy(),
        delta_G_m=np.broadcast_to(d_g, shape).copy(),
        delta_H_m=np.zeros(shape), include_hertz=False,
    )


def _check_hertz(include_hertz: object) -> HertzOption:
    if include_hertz is None or include_hertz is False:
        return False
    if isinstance(include_hertz, str) and include_hertz in ("linear", "weber"):
        return include_hertz  # type: ignore[return-value]
    raise ModelError(f"`include_hertz` must be one of {HERTZ_OPTIONS}, was {include_hertz!r}")


def _contact_deflection(
    pair: GearPair, tooth: EquivalentTooth, load_N: np.ndarray, option: HertzOption
) -> np.ndarray:
    """Contact deflection of this tooth (m), see the module docstring."""
    mat = _gear(pair, tooth.gear).material
    e_i, nu_i = mat.youngs_modulus_Pa, mat.poisson_ratio
    b = pair.face_width_m
    base = 2 * load_N * (1 - nu_i**2) / (math.pi * e_i * b)
    if option is False:
        return np.zeros(np.broadcast(load_N, tooth.s_m).shape)
    if option == "linear":
        return np.broadcast_to(base, np.broadcast(load_N, tooth.s_m).shape).copy()
    m1, m2 = pair.pinion.material, pair.wheel.material
    e_star = 1.0 / ((1 - m1.poisson_ratio**2) / m1.youngs_modulus_Pa
                    + (1 - m2.poisson_ratio**2) / m2.youngs_modulus_Pa)
    rho1, rho2 = pair.curvature_radii(tooth.s_m)
    r_eq = rho1 * rho2 / (rho1 + rho2)
    a = np.sqrt(4 * load_N * r_eq / (math.pi * b * e_star))
    depth = tooth.contact_half_thickness_m / np.cos(tooth.omega_k_rad)
    return base * (np.log(2 * depth / a) - nu_i / (2 * (1 - nu_i)))


def ishikawa_deflection(
    pair: GearPair,
    s_m: ArrayLike | None,
    gear: int,
    *,
    load_N: ArrayLike = 1.0,
    include_hertz: HertzOption = False,
    shear_coefficient: float = 1.0,
    anchor: Literal["form", "base"] = "form",
) -> IshikawaDeflection:
    r"""Deflection of a tooth of gear 1 or 2 along the line of action, by Ishikawa's method.

    .. math::

        \delta = \delta_{Br} + \delta_{Bt} + \delta_s + \delta_G \; [+ \delta_H]

    with the terms and the contact options of the module docstring, on the equivalent tooth
    of :func:`equivalent_tooth`, material of the gear, face width of the pair.

    Parameters
    ----------
    pair : GearPair
    s_m : array_like or None
        Positions on the path of contact, from T1 (m); None: seed 000's 52 points.
    gear : {1, 2}
    load_N : array_like
        Normal load carried by this tooth, whole face width (N); broadcasts with ``s_m``.
        All terms but ``"weber"`` are linear in it.
    include_hertz : {False, "linear", "weber"}
        The contact term (module docstring): none (the seed), Yang-Sun's constant line-contact
        stiffness, or Weber-Banaschek's load-dependent approach.
    shear_coefficient : float
        ``kappa`` of the shear term (1: Ishikawa).
    anchor : {"form", "base"}
        See :func:`equivalent_tooth`.

    Returns
    -------
    IshikawaDeflection

    Examples
    --------
    >>> from models.geometry import load_gear_set
    >>> g = load_gear_set("fzg-c").pair
    >>> d = ishikawa_deflection(g, g.pitch_point, 1, load_N=1000.0)
    >>> round(float(d.total_m) * 1e6, 3)  # um under 1 kN
    1.19
    """
    option = _check_hertz(include_hertz)
    tooth = equivalent_tooth(pair, gear, s_m, anchor=anchor)
    mat = _gear(pair, gear).material
    f = np.asarray(load_N, dtype=float)
    terms = ishikawa_terms(
        S_F_m=tooth.S_F_m, h_r_m=tooth.h_r_m, h_i_m=tooth.h_i_m, h_k_m=tooth.h_k_m,
        omega_k_rad=tooth.omega_k_rad, youngs_modulus_Pa=mat.youngs_modulus_Pa,
        poisson_ratio=mat.poisson_ratio, face_width_m=pair.face_width_m, load_N=f,
        shear_coefficient=shear_coefficient,
    )
    d_h = _contact_deflection(pair, tooth, terms.load_N, option)
    return IshikawaDeflection(
        s_m=tooth.s_m, gear=gear, load_N=terms.load_N, delta_Br_m=terms.delta_Br_m,
        delta_Bt_m=terms.delta_Bt_m, delta_s_m=terms.delta_s_m, delta_G_m=terms.delta_G_m,
        delta_H_m=np.broadcast_to(d_h, terms.load_N.shape).copy(), include_hertz=option,
    )


# --- stiffness ----------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class ToothPairStiffness:
    """Single-tooth and pair stiffness along the path of contact.

    Attributes
    ----------
    s_m : numpy.ndarray
        Positions from T1 (m).
    load_N : numpy.ndarray
        Normal load on the pair (N).
    k_E1_N_per_m, k_E2_N_per_m : numpy.ndarray
        Single-tooth stiffness of the pinion and wheel tooth, ``F / delta_i`` (N/m).
    k_EP_N_per_m : numpy.ndarray
        Pair stiffness ``k_E1 k_E2 / (k_E1 + k_E2)`` (N/m).
    face_width_m : float
    include_hertz : str or bool
    pinion, wheel : IshikawaDeflection
        The term-by-term deflections.
    """

    s_m: np.ndarray
    load_N: np.ndarray
    k_E1_N_per_m: np.ndarray
    k_E2_N_per_m: np.ndarray
    k_EP_N_per_m: np.ndarray
    face_width_m: float
    include_hertz: HertzOption
    pinion: IshikawaDeflection
    wheel: IshikawaDeflection

    @property
    def c_EP_N_per_mm_um(self) -> np.ndarray:  # noqa: N802 (unit in the name, STYLE 4.4)
        """Pair stiffness per unit face width ``k_EP / b`` (N/(mm um); 1 N/(mm um) = 1e9 Pa)."""
        return self.k_EP_N_per_m / self.face_width_m / 1e9


def tooth_pair_stiffness(
    pair: GearPair,
    s_m: ArrayLike | None = None,
    *,
    load_N: ArrayLike = 1.0,
    include_hertz: HertzOption = False,
    shear_coefficient: float = 1.0,
    anchor: Literal["form", "base"] = "form",
) -> ToothPairStiffness:
    r"""Single-tooth stiffness ``k_E1``, ``k_E2`` and pair stiffness ``k_EP`` along the path.

    .. math::

        k_{Ei} = \frac{F}{\delta_i}, \qquad k_{EP} = \frac{k_{E1} k_{E2}}{k_{E1} + k_{E2}}
               = \frac{F}{\delta_1 + \delta_2}

    Parameters
    ----------
    pair : GearPair
    s_m : array_like, optional
        Positions from T1 (m). Default: seed 000's 52 points from A to E.
    load_N : array_like
        Normal load on the pair (N) (matters only for ``include_hertz="weber"``).
    include_hertz, shear_coefficient, anchor
        See :func:`ishikawa_deflection`.

    Returns
    -------
    ToothPairStiffness
    """
    s = _as_positions(pair, s_m)
    d1 = ishikawa_deflection(pair, s, 1, load_N=load_N, include_hertz=include_hertz,
                             shear_coefficient=shear_coefficient, anchor=anchor)
    d2 = ishikawa_deflection(pair, s, 2, load_N=load_N, include_hertz=include_hertz,
                             shear_coefficient=shear_coefficient, anchor=anchor)
    k1, k2 = d1.stiffness_N_per_m, d2.stiffness_N_per_m
    # Teeth in series as compliances: a tooth whose load line passes through its root (load
    # taken at h_k = 0, no bending arm; `equivalent_tooth(...).load_clamped`) has no Ishikawa
    # deflection there and k_E = inf; the pair is then the other tooth, never inf/inf.
    with np.errstate(divide="ignore"):
        k_ep = 1.0 / (1.0 / k1 + 1.0 / k2)
    return ToothPairStiffness(
        s_m=s, load_N=d1.load_N, k_E1_N_per_m=k1, k_E2_N_per_m=k2,
        k_EP_N_per_m=k_ep, face_width_m=pair.face_width_m,
        include_hertz=d1.include_hertz, pinion=d1, wheel=d2,
    )


def mean_mesh_stiffness(
    pair: GearPair,
    *,
    total_load_N: float | None = None,
    include_hertz: HertzOption = False,
    shear_coefficient: float = 1.0,
    anchor: Literal["form", "base"] = "form",
    points_per_zone: int = 201,
) -> float:
    r"""Mean mesh stiffness over a mesh cycle (N/m).

    Each pair runs through the whole path AE once per ``eps`` cycles while the pairs in
    contact add, so the cycle mean of the mesh stiffness is

    .. math:: \bar k = \frac{1}{p_b} \int_A^E k_{EP}(s) \, ds ,

    integrated by Simpson's rule on each zone A-B, B-D, D-E (``k_EP`` is smooth inside each).
    Divide by the face width for ISO 6336-1's ``c_gamma_alpha`` (in N/(mm um): ``/ b / 1e9``).

    Parameters
    ----------
    pair : GearPair
    total_load_N : float, optional
        Total normal load (N), shared between pairs by seed 000's R(theta); required for
        ``include_hertz="weber"`` (load-dependent), ignored by the linear options.
    include_hertz, shear_coefficient, anchor
        See :func:`ishikawa_deflection`.
    points_per_zone : int
        Odd number of Simpson nodes per zone.

    Returns
    -------
    float
        Mean mesh stiffness (N/m).
    """
    option = _check_hertz(include_hertz)
    if option == "weber" and total_load_N is None:
        raise ModelError("`total_load_N` is required with include_hertz='weber' "
                         "(the Weber contact term depends on the load), was None")
    a, e, pb = pair.start_of_contact, pair.end_of_contact, pair.base_pitch
    if total_load_N is not None and not (math.isfinite(total_load_N) and total_load_N > 0):
        raise ModelError(f"`total_load_N` must be finite and > 0, was {total_load_N!r}")
    cuts = [a, e] if pair.contact_ratio >= 2 else sorted({a, e - pb, a + pb, e})
    total = 0.0
    for lo, hi in itertools.pairwise(cuts):
        if hi - lo <= 0:
            continue
        # nodes strictly inside the zone's closure; shares evaluated just inside each end
        s = np.linspace(lo, hi, points_per_zone)
        if total_load_N is None:
            load = np.ones_like(s)
        else:
            mid = 0.5 * (lo + hi)
            s_in = np.clip(s, lo + 1e-9 * (mid - lo), hi - 1e-9 * (hi - mid))
            load = total_load_N * load_share_seed_000(pair, s_in)
        k = tooth_pair_stiffness(pair, s, load_N=load, include_hertz=option,
                                 shear_coefficient=shear_coefficient,
                                 anchor=anchor).k_EP_N_per_m
        total += float(simpson(k, x=s))
    return total / pb

r"""Potential-energy compliance of a spur tooth pair: beam, fillet foundation and Hertz terms.

Seed 003 (section 2.1, Eqs. 1-2) writes the compliance of one tooth pair at the contact point
``j`` as the deflection along the line of action per unit normal load,

.. math::

    C_j = \frac{\delta_j}{F_j}, \qquad
    \delta_j = \delta_{h} + (\delta_t)_p + (\delta_t)_g + (\delta_f)_p + (\delta_f)_g ,

Hertzian contact plus the beam deflection ``delta_t`` of each tooth (a non-uniform cantilever on
a rigid foundation) plus the deflection ``delta_f`` of each tooth's fillet foundation (an
elastic body under a rigid tooth), after Weber (1949) and Cornell (1981) (seed refs. 40-41).
This module evaluates it with the potential-energy method of Yang and Lin (1987), Tian (2004),
Chen and Shao (2011), Sainsot et al. (2004) and Liang et al. (2014), as follows.

The tooth and the load
----------------------
Stand the tooth upright: ``y`` along its centreline from the gear centre, ``x`` across it, the
tooth occupying ``|x| <= x(y)``. The flank is the involute of the base circle ``r_b``. A point of
it is fixed by its *roll angle* ``phi`` (the angle the generating line has unrolled; the
contact at a distance ``rho`` from the base-circle tangent point has ``phi = rho / r_b``):

.. math::

    \tau = \varphi - \theta_b, \quad
    x = r_b (\varphi \cos\tau - \sin\tau), \quad
    y = r_b (\varphi \sin\tau + \cos\tau), \quad
    \frac{dy}{d\varphi} = r_b\, \varphi \cos\tau ,

with the half tooth angle at the base circle

.. math:: \theta_b = \frac{\pi}{2 z} + \frac{2 x_s \tan\alpha}{z} + \operatorname{inv}\alpha .

The normal load acts along the line of action, the normal of the involute, which makes the
angle ``tau`` with the ``x`` axis (``tau = alpha_k - psi_k``, the pressure angle at the contact
radius minus the polar half-thickness angle there; this is Tian's ``alpha_1`` and ISO 6336-3's
load angle ``alpha_Fen`` when the load is at the tip). At the contact point ``(x_P, y_P)`` it
splits into the bending and shearing component ``F cos(tau)`` and the component ``F sin(tau)``
that compresses the tooth toward the centre; the bending moment on the section at height
``y`` is

.. math:: M(y) = F \left[\cos\tau_P\, (y_P - y) - \sin\tau_P\, x_P\right] .

The energy integrals
--------------------
Bending, shear (Timoshenko factor 1.2 of a rectangular section) and axial compression of the
tooth as a cantilever of width ``b``, section ``A = 2 x b`` and ``I = (2x)^3 b / 12``, give the
compliances (m/N) ``C = 2 U / F^2``:

.. math::

    C_b &= \int \frac{[\cos\tau_P (y_P - y) - \sin\tau_P x_P]^2}{E I(y)}\, dy, \\
    C_s &= \int \frac{1.2 \cos^2\tau_P}{G A(y)}\, dy, \qquad
    C_a  = \int \frac{\sin^2\tau_P}{E A(y)}\, dy ,

``G = E / (2 (1 + nu))``, taken from the root of the beam ``y_f`` to the contact point. With
``y`` a function of the roll angle these are the integrals of Tian (2004) and Wu, Zuo and Parey
(2008) (their variable is ``alpha = -tau``). Because the load line is tangent to the base
circle, its distance from the gear centre is ``r_b`` and the moment arm is simply
``cos(tau_P)(y_P - y) - sin(tau_P) x_P = r_b - y cos(tau_P)``. With ``eta = y - y_f`` and
``a = r_b - y_f cos(tau_P)`` the three integrals become combinations of four *beam moments*
that depend on the contact point only through the upper limit:

.. math::

    C_b = \frac{3}{2 E b}\left(a^2 m_0 - 2 a \cos\tau_P\, m_1 + \cos^2\tau_P\, m_2\right),
    \quad C_s = \frac{0.6 \cos^2\tau_P}{G b} m_3, \quad C_a = \frac{\sin^2\tau_P}{2 E b} m_3,

.. math:: m_k = \int_{y_f}^{y_P} \frac{\eta^k\, dy}{x^3}\ (k = 0, 1, 2), \qquad
          m_3 = \int_{y_f}^{y_P} \frac{dy}{x} .

The involute part of the moments has no elementary antiderivative (the integrands are
rational in ``phi``, ``cos`` and ``sin``). It is integrated in the roll angle by a composite
Gauss-Legendre rule: ``[phi_0, phi_tip]`` is cut into 12 equal panels whose sums are computed
once per tooth (cached), and each position adds the sum over its own partial panel with
``n_nodes`` points (8 by default). The integrands are analytic on the whole tooth (its
thickness stays positive up to the tip), so this converges geometrically: the result agrees
with adaptive quadrature of the same energy integrals, written independently in the radius
variable, to about 1e-13 (tested to 1e-9). The work is one panel per position, vectorised over
positions: about 0.4 ms for 100 positions of 3 pairs. ``integration="quad"`` integrates the
same moments with adaptive ``scipy.integrate.quad`` position by position (about 2000 times
slower), as a check for unusual geometry; there is no closed-form option because the involute
integrals have none.

The root of the beam: root circle below or above the base circle
----------------------------------------------------------------
* **Root circle below the base circle** (``r_f < r_b``: standard gears with fewer than about
  42 teeth, both FZG-C gears, and Kahraman's 50-tooth gears with their deep root). The part of
  the tooth below the base circle, where the real flank is the trochoidal fillet, is modelled
  as in the potential-energy literature after Chen and Shao (2011, 2013): a straight flank
  parallel to the centreline, of constant half-thickness ``h_b = r_b sin(theta_b)`` (the half
  chord at the base circle), from the base circle (``y_b = r_b cos(theta_b)``) down to the
  root circle (``y_f = sqrt(r_f^2 - h_b^2)``). Its moments are closed forms, with
  ``d = y_b - y_f``:

  .. math:: m_0 = \frac{d}{h_b^3}, \quad m_1 = \frac{d^2}{2 h_b^3}, \quad
            m_2 = \frac{d^3}{3 h_b^3}, \quad m_3 = \frac{d}{h_b},

  and the involute part runs from the base circle, ``phi_0 = 0``. *Why this choice*: it is the
  construction of the method the brief and seed 003 cite, it needs nothing beyond the pair's
  radii, it is continuous with the second case as ``r_f -> r_b`` (tested), and its closed form
  is exact. The real fillet flares out toward the root circle, wider than ``2 h_b``; the
  straight flank (and the involute continued down to the base circle) is narrower, so the
  beam comes out *more* compliant than with the trochoid fillet of Ma et al. (2014) that
  ``ross`` integrates (Kahraman pair at the pitch point: bending 2.09e-10 against ross's
  1.56e-10 m/N per tooth).
* **Root circle above the base circle** (``r_f >= r_b``: larger tooth numbers or positive
  shift, e.g. the 60-tooth wheel of the two-stage set). The involute reaches the root circle:
  the beam starts there, ``phi_0 = sqrt(r_f^2 - r_b^2) / r_b``, ``y_f`` is the height of that
  point, and there is no straight flank (Liang, Zuo and Pandey 2014).

Where the profile shift enters
------------------------------
Three places, all through :class:`~models.geometry.GearPair`: (1) the tooth thickness, through
``theta_b`` above (``2 x_s tan(alpha) / z``, the generated thickness; backlash thinning is not
modelled); (2) the tip and root radii (``r +- m (h* +- x_s)`` unless the diameters are given),
so the length of the beam, the root/base case and the fillet geometry; (3) the operating
pressure angle and centre distance, so the roll angles at which each tooth is loaded along
the path of contact (``rho_1 = s``, ``rho_2 = T1T2 - s``).

Fillet foundation (Sainsot, Velex and Duverger 2004)
----------------------------------------------------
The deflection along the load caused by the elastic gear body under the tooth root:

.. math::

    C_f = \frac{\cos^2\tau_P}{E b}\left[L^*\left(\frac{u_f}{S_f}\right)^2
          + M^* \frac{u_f}{S_f} + P^* (1 + Q^* \tan^2\tau_P)\right],

``S_f = 2 r_f theta_f`` the arc of the tooth root on the root circle (``theta_f`` its half
angle: ``arcsin(h_b / r_f)`` with the straight flank, ``theta_b - inv(alpha_f)`` with
``cos(alpha_f) = r_b / r_f`` when the involute reaches the root circle), ``u_f`` the distance
from the root circle to the point where the *load line* crosses the tooth centreline,
``u_f = r_b / cos(tau_P) - r_f`` (the load line is tangent to the base circle, so it crosses
the centreline at ``r_b / cos(tau_P) = y_P - x_P tan(tau_P)`` from the centre; the root moment
is ``F cos(tau_P) u_f``). The coefficients
``X* = A/theta_f^2 + B h^2 + C h/theta_f + D/theta_f + E h + F``, with ``h = r_f / r_int``
(``r_int`` the bore radius; :class:`~models.geometry.Gear` takes a bore of 0.3 d when none is
given), are Sainsot's Table 1 (``_SAINSOT``). ``P*`` grows with ``h``: the formula accounts for
the gear body down to the bore, so the bore matters (Kahraman pair: ``C_f`` falls by 25 % and
the pitch-point pair stiffness rises from 9.4 to 11.3 N/(mm um) from a bore of 0.3 d to 0.6 d).
Implementations quote the range of the fit as ``1.4 <= h <= 7`` and ``0.01 <= theta_f <= 0.12``
rad; outside it the result is an extrapolation and :attr:`ToothCompliance.fillet_extrapolated`
says so (FZG-C's 16-tooth pinion has ``theta_f = 0.13``).

Hertz and the total
-------------------
``C_h = 1 / k_h`` with the linearised line-contact stiffness ``k_h = pi b E* / 2``
(:func:`models.stiffness.hertz.hertz_stiffness`; ``pi E b / (4 (1 - nu^2))`` for one material).
The teeth and the contact are in series:

.. math:: C = C_h + \sum_{i = p, g} (C_{b,i} + C_{s,i} + C_{a,i} + C_{f,i}),
          \qquad k = 1 / C .

``E`` is Young's modulus (plane stress, the literature's choice); ``plane_strain=True`` uses
``E / (1 - nu^2)`` in the bending, axial and foundation terms (wide faces), which stiffens the
teeth by 7-8 % (steel).

Numbers
-------
Mean mesh stiffness per unit face width (mean over a cycle of the sum of ``1/C`` of the pairs in
theoretical contact), with / without the Hertz term, N/(mm um): FZG-C 14.8 / 15.7, Kahraman-
Blankenship 14.9 / 15.7. ISO 6336-1 (method B) gives ``c_gamma_alpha`` = 16.3 and 18.6 (with
each set's actual dedendum in ``C_B``). Single pair at the pitch point: FZG-C 11.5, Kahraman
9.45 (ISO ``c'`` 12.3 and 11.9). Potential-energy methods sit below ISO because the fillet
foundation (Sainsot), which includes the gear body, is the largest term (69 % of a Kahraman
tooth's compliance at the pitch point).

Positions outside the path of contact
-------------------------------------
Any position ``s`` (any array shape) is accepted and gives finite values. Each tooth's contact
point is clamped to its profile: above the tip circle it stays at the tip (the corner contact
of a tooth tip on the mating flank loads the tip corner) and below the start of the involute
(the base circle, or the root circle when that is higher) it stays there. The load angle is
that of the clamped point. The mating tooth's point keeps moving along its own flank. The
result is continuous in ``s`` and constant beyond the clamp; ``in_contact_path`` marks
``A <= s <= E`` and each tooth's ``clamped`` marks where its point was moved. Corner-contact
analysis (seed 003 section 2.3.2) evaluates the entering and leaving pairs this way; the change
of the load direction during true corner contact (the load is along the mating flank's
normal, a few degrees off the line of action) is not modelled.

References
----------
.. [1] D. C. H. Yang, J. Y. Lin, "Hertzian damping, tooth friction and bending elasticity in
   gear impact dynamics", ASME J. Mech. Transm. Autom. Des. 109 (1987) 189-196.
.. [2] X. Tian, "Dynamic simulation for system response of gearbox including localized gear
   faults", MSc thesis, University of Alberta, 2004 (bending, shear, axial integrals).
.. [3] S. Wu, M. J. Zuo, A. Parey, "Simulation of spur gear dynamics and estimation of fault
   growth", J. Sound Vib. 317 (2008) 608-624.
.. [4] Z. Chen, Y. Shao, "Dynamic simulation of spur gear with tooth root crack propagating
   along tooth width and crack depth", Eng. Fail. Anal. 18 (2011) 2149-2164; and "Mesh
   stiffness calculation of a spur gear pair with tooth profile modification and tooth root
   crack", Mech. Mach. Theory 62 (2013) 63-74 (straight flank between the root and base
   circles, fillet foundation).
.. [5] P. Sainsot, P. Velex, O. Duverger, "Contribution of gear body to tooth deflections - a
   new bidimensional analytical formula", ASME J. Mech. Des. 126 (2004) 748-752.
.. [6] X. Liang, M. J. Zuo, M. Pandey, "Analytical evaluation of time-varying mesh stiffness
   for planetary gear sets", Mech. Mach. Theory 76 (2014) 20-38 (root circle above or below
   the base circle).
.. [7] H. Ma, R. Song, X. Pang, B. Wen, "Time-varying mesh stiffness calculation of cracked
   spur gears", Eng. Fail. Anal. 44 (2014) 179-194 (trochoid fillet; the model of ross's
   ``GearElementTVMS``).
.. [8] C. Weber, "The deformation of loaded gears and the effect on their load-carrying
   capacity", Sponsored Research (Germany), British DSIR Report No. 3, 1949.
.. [9] R. W. Cornell, "Compliance and stress sensitivity of spur gear teeth", ASME J. Mech.
   Des. 103 (1981) 447-459.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from typing import Final, Literal

import numpy as np
from numpy.typing import ArrayLike

from models.errors import GeometryError, ModelError
from models.geometry.gear_pair import Gear, GearPair
from models.geometry.involute import inv
from models.stiffness.hertz import hertz_stiffness

__all__ = [
    "DEFAULT_NODES",
    "Integration",
    "PairCompliance",
    "ToothCompliance",
    "pair_compliance",
    "pair_stiffness",
    "tooth_compliance",
    "tooth_stiffness",
]

#: Gauss-Legendre points per panel on the involute part of the tooth (12 panels; relative
#: error about 1e-13 against adaptive quadrature, tested to 1e-9).
DEFAULT_NODES: Final = 8

#: Bore diameter as a fraction of the reference diameter when a gear states none
#: (:class:`~models.geometry.Gear`: "None: solid to 0.3 d").
_DEFAULT_BORE_FRACTION: Final = 0.3

#: Sainsot, Velex and Duverger (2004), Table 1: rows L*, M*, P*, Q*; columns A..F of
#: X* = A / theta_f^2 + B h^2 + C h / theta_f + D / theta_f + E h + F.
_SAINSOT: Final = np.array([
    [-5.574e-5, -1.9986e-3, -2.3015e-4, 4.7702e-3, 0.0271, 6.8045],
    [60.111e-5, 28.100e-3, -83.431e-4, -9.9256e-3, 0.1624, 0.9086],
    [-50.952e-5, 185.50e-3, 0.0538e-4, 53.300e-3, 0.2895, 0.9236],
    [-6.2042e-5, 9.0889e-3, -4.0964e-4, 7.8297e-3, -0.1472, 0.6904],
])
#: Range of the fit as quoted by implementations (h = r_f / r_int, theta_f in rad).
_SAINSOT_RANGE: Final = {"h": (1.4, 7.0), "theta_f": (0.01, 0.12)}

_SHEAR_FACTOR: Final = 1.2

#: Equal panels of the composite Gauss-Legendre rule on the involute part of the beam.
_N_PANELS: Final = 12

Integration = Literal["gauss", "quad"]


# --------------------------------------------------------------------------------------------
# results
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class ToothCompliance:
    """Compliance of one tooth loaded at positions on the line of action (m/N, whole face).

    Attributes
    ----------
    gear : int
        1 for the pinion, 2 for the wheel.
    bending_m_per_N, shear_m_per_N, axial_m_per_N : numpy.ndarray
        Beam terms ``C_b, C_s, C_a`` (involute part plus straight flank), shape of ``s_m``.
    fillet_m_per_N : numpy.ndarray
        Fillet-foundation term ``C_f`` (Sainsot et al. 2004).
    roll_angle_rad : numpy.ndarray
        Roll angle ``phi`` of the (clamped) contact point on this tooth.
    load_angle_rad : numpy.ndarray
        ``tau = phi - theta_b``: angle between the load and the normal to the tooth centreline
        (positive: the load compresses the tooth toward the gear centre).
    clamped : numpy.ndarray of bool
        True where the position lies beyond this tooth's tip or below the start of its
        involute, so that the contact point was held there.
    fillet_extrapolated : bool
        True when ``h = r_f / r_int`` or ``theta_f`` lies outside the quoted range of
        Sainsot's fit.
    """

    gear: int
    bending_m_per_N: np.ndarray
    shear_m_per_N: np.ndarray
    axial_m_per_N: np.ndarray
    fillet_m_per_N: np.ndarray
    roll_angle_rad: np.ndarray
    load_angle_rad: np.ndarray
    clamped: np.ndarray
    fillet_extrapolated: bool

    @property
    def total_m_per_N(self) -> np.ndarray:  # noqa: N802 (unit in the name)
        """Sum of the four terms (m/N)."""
        return self.bending_m_per_N + self.shear_m_per_N + self.axial_m_per_N \
            + self.fillet_m_per_N

    @property
    def stiffness_N_per_m(self) -> np.ndarray:  # noqa: N802 (unit in the name)
        """Single-tooth stiffness ``1 / total`` (N/m)."""
        return 1.0 / self.total_m_per_N


@dataclass(frozen=True, eq=False)
class PairCompliance:
    """Compliance of a tooth pair at positions on the line of action (m/N, whole face width).

    Attributes
    ----------
    s_m : numpy.ndarray
        Positions from T1 (m), as given (any shape).
    pinion, wheel : ToothCompliance
        The two teeth's bending, shear, axial and fillet terms.
    hertz_m_per_N : numpy.ndarray
        Linearised Hertz compliance ``1 / k_h``, broadcast to the shape of ``s_m`` (reported
        even when not included in the total).
    total_m_per_N : numpy.ndarray
        ``C`` of seed 003 Eq. 2: both teeth plus, if ``include_hertz``, the Hertz term.
    include_hertz : bool
    in_contact_path : numpy.ndarray of bool
        ``A <= s <= E`` (theoretical contact; outside, the values are extrapolations).
    """

    s_m: np.ndarray
    pinion: ToothCompliance
    wheel: ToothCompliance
    hertz_m_per_N: np.ndarray
    total_m_per_N: np.ndarray
    include_hertz: bool
    in_contact_path: np.ndarray

    @property
    def stiffness_N_per_m(self) -> np.ndarray:  # noqa: N802 (unit in the name)
        """Tooth-pair stiffness ``1 / C`` (N/m)."""
        return 1.0 / self.total_m_per_N


# --------------------------------------------------------------------------------------------
# the tooth as a beam
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Tooth:
    """Constants of one tooth (lengths in m, angles in rad, moduli in Pa)."""

    gear: int
    r_b: float
    r_f: float
    r_a: float
    theta_b: float       # half tooth angle at the base circle
    phi_0: float         # roll angle where the involute part of the beam starts
    phi_tip: float       # roll angle at the tip circle
    flank_half: float    # h_b, half-thickness of the straight flank (0: none)
    y_base: float        # top of the straight flank (= y at phi_0 when r_f < r_b)
    y_root: float        # bottom of the straight flank
    theta_f: float       # half angle of the tooth root on the root circle
    r_int: float         # bore radius
    e_mod: float         # E, or E / (1 - nu^2) in plane strain
    g_mod: float         # G = E / (2 (1 + nu))
    width: float

    def profile(self, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Involute half-thickness ``x``, height ``y`` and ``dy/dphi`` at roll angles ``phi``."""
        tau = phi - self.theta_b
        c, s = np.cos(tau), np.sin(tau)
        return (self.r_b * (phi * c - s), self.r_b * (phi * s + c), self.r_b * phi * c)


def _gear(pair: GearPair, gear: int) -> Gear:
    if gear not in (1, 2):
        raise ModelError(f"`gear` must be 1 (pinion) or 2 (wheel), was {gear!r}")
    return pair.pinion if gear == 1 else pair.wheel


def _tooth(pair: GearPair, gear: int, plane_strain: bool) -> _Tooth:
    g = _gear(pair, gear)
    who = "pinion" if gear == 1 else "wheel"
    r_b, r_f, r_a = pair.base_radius(gear), pair.root_radius(gear), pair.tip_radius(gear)
    a0 = pair.pressure_angle_rad
    theta_b = (math.pi / (2 * g.teeth) + 2 * g.profile_shift * math.tan(a0) / g.teeth
               + float(inv(a0)))
    if r_f < r_b:  # straight flank from the root circle up to the base circle
        h_b = r_b * math.sin(theta_b)
        if not r_f > h_b:
            raise GeometryError(f"{who}.root_diameter_m", 2 * r_f,
                                f"root circle narrower than the tooth ({2 * h_b:.6g} m)")
        phi_0 = 0.0
        y_base = r_b * math.cos(theta_b)
        y_root = math.sqrt(r_f * r_f - h_b * h_b)
        theta_f = math.asin(h_b / r_f)
    else:  # the involute reaches the root circle
        phi_0 = math.sqrt(r_f * r_f - r_b * r_b) / r_b
        h_b = 0.0
        theta_f = theta_b - (phi_0 - math.atan(phi_0))  # theta_b - inv(alpha_f)
        tau_0 = phi_0 - theta_b  # y of the involute at the root circle, = r_f cos(theta_f)
        y_base = y_root = r_b * (phi_0 * math.sin(tau_0) + math.cos(tau_0))
    bore = g.bore_diameter_m if g.bore_diameter_m is not None \
        else _DEFAULT_BORE_FRACTION * 2 * pair.reference_radius(gear)
    r_int = bore / 2
    if not 0 < r_int < r_f:
        raise GeometryError(f"{who}.bore_diameter_m", bore,
                            f"must lie in (0, root diameter {2 * r_f:.6g} m)")
    mat = g.material
    e_mod = mat.youngs_modulus_Pa / (1 - mat.poisson_ratio ** 2) if plane_strain \
        else mat.youngs_modulus_Pa
    return _Tooth(
        gear=gear, r_b=r_b, r_f=r_f, r_a=r_a, theta_b=theta_b, phi_0=phi_0,
        phi_tip=math.sqrt(r_a * r_a - r_b * r_b) / r_b, flank_half=h_b, y_base=y_base,
        y_root=y_root, theta_f=theta_f, r_int=r_int, e_mod=e_mod,
        g_mod=mat.youngs_modulus_Pa / (2 * (1 + mat.poisson_ratio)), width=pair.face_width_m,
    )


@dataclass(frozen=True)
class _Load:
    """The contact point and load direction on one tooth (arrays of the positions' shape)."""

    phi: np.ndarray
    cos: np.ndarray
    sin: np.ndarray
    clamped: np.ndarray


def _load(tooth: _Tooth, rho_m: np.ndarray) -> _Load:
    phi_raw = rho_m / tooth.r_b
    phi = np.minimum(np.maximum(phi_raw, tooth.phi_0), tooth.phi_tip)
    tau = phi - tooth.theta_b
    return _Load(phi=phi, cos=np.cos(tau), sin=np.sin(tau),
                 clamped=(phi_raw < tooth.phi_0) | (phi_raw > tooth.phi_tip))


@lru_cache(maxsize=16)
def _leggauss(n: int) -> tuple[np.ndarray, np.ndarray]:
    xi, w = np.polynomial.legendre.leggauss(n)
    xi.setflags(write=False)
    w.setflags(write=False)
    return xi, w


Profile = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]


def _moment_sums(
    profile: Profile, lo: np.ndarray, hi: np.ndarray, y_ref: float, n_nodes: int
) -> np.ndarray:
    """Gauss-Legendre sums of the four beam moments over ``[lo, hi]`` (elementwise).

    Returns shape ``lo.shape + (4,)``: ``int x^-3 dy``, ``int eta x^-3 dy``,
    ``int eta^2 x^-3 dy`` and ``int x^-1 dy`` with ``eta = y - y_ref``.
    """
    xi, w = _leggauss(n_nodes)
    half = 0.5 * (hi - lo)
    t = lo[..., None] + half[..., None] * (xi + 1.0)
    x, y, dy = profile(t)
    g = dy / x
    u = g / (x * x)
    eta = y - y_ref
    ue = u * eta
    out = np.empty((*lo.shape, 4))
    out[..., 0] = u @ w
    out[..., 1] = ue @ w
    out[..., 2] = (ue * eta) @ w
    out[..., 3] = g @ w
    out *= half[..., None]
    return out


@lru_cache(maxsize=64)
def _panel_table(
    tooth: _Tooth, n_nodes: int, n_panels: int
) -> tuple[float, np.ndarray, np.ndarray]:
    """Panel width, panel edges and cumulative moments of the involute part of ``tooth``."""
    width = (tooth.phi_tip - tooth.phi_0) / n_panels
    edges = tooth.phi_0 + width * np.arange(n_panels + 1)
    full = _moment_sums(tooth.profile, edges[:-1], edges[1:], tooth.y_root, n_nodes)
    cumulative = np.concatenate([np.zeros((1, 4)), np.cumsum(full, axis=0)])
    edges.setflags(write=False)
    cumulative.setflags(write=False)
    return width, edges, cumulative


def _moments_gauss(tooth: _Tooth, phi_load: np.ndarray, n_nodes: int,
                   n_panels: int = _N_PANELS) -> np.ndarray:
    """The four beam moments of the involute part from ``phi_0`` to ``phi_load``.

    Composite Gauss-Legendre: ``[phi_0, phi_tip]`` is cut into ``n_panels`` equal panels whose
    sums are accumulated once per tooth (cached); each position adds the sum over its own
    partial panel, so the work per position is one panel of ``n_nodes`` points.
    """
    width, edges, cumulative = _panel_table(tooth, n_nodes, n_panels)
    j = np.asarray(np.minimum(np.maximum((phi_load - tooth.phi_0) // width, 0), n_panels - 1),
                   dtype=np.intp)
    return cumulative[j] + _moment_sums(tooth.profile, np.asarray(edges[j]), phi_load,
                                        tooth.y_root, n_nodes)


def _moments_quad(profile: Profile, t0: float, y_ref: float, t_load: np.ndarray) -> np.ndarray:
    """As :func:`_moments_gauss` with adaptive ``scipy.integrate.quad``, one position at a time."""
    from scipy.integrate import quad

    def integrand(t: float, k: int) -> float:
        x, y, dy = (float(v) for v in profile(np.asarray(t)))
        return dy / x if k == 3 else (y - y_ref) ** k * dy / x ** 3

    out = np.zeros((*t_load.shape, 4))
    for idx in np.ndindex(t_load.shape):
        for k in range(4):
            out[(*idx, k)] = quad(integrand, t0, float(t_load[idx]), args=(k,),
                                   epsabs=0.0, epsrel=1e-13, limit=200)[0]
    return out


def _flank_moments(length: float, half_thickness: float) -> np.ndarray:
    """The four moments of a constant-width beam of ``length`` from ``eta = 0`` (closed form).

    ``[d / h^3, d^2 / (2 h^3), d^3 / (3 h^3), d / h]`` for ``x = h`` on ``0 <= eta <= d``.
    """
    d, h = length, half_thickness
    if d <= 0.0:
        return np.zeros(4)
    return np.array([d / h**3, d**2 / (2 * h**3), d**3 / (3 * h**3), d / h])


def _beam_compliance(
    moments: np.ndarray, arm_at_ref: np.ndarray, load: _Load, e_mod: float, g_mod: float,
    width: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Bending, shear and axial compliance (m/N) from the beam moments.

    The moment arm at height ``y = y_ref + eta`` is ``a - cos(tau_P) eta`` with
    ``a = r_b - y_ref cos(tau_P)`` (the load line is tangent to the base circle), so
    ``int arm^2 x^-3 dy = a^2 m0 - 2 a c m1 + c^2 m2``.
    """
    c, s, a = load.cos, load.sin, arm_at_ref
    m0, m1, m2, m3 = (moments[..., k] for k in range(4))
    bend = a * a * m0 - 2.0 * a * c * m1 + c * c * m2
    return (1.5 * bend / (e_mod * width),
            0.5 * _SHEAR_FACTOR * c * c * m3 / (g_mod * width),
            0.5 * s * s * m3 / (e_mod * width))


def _sainsot_coefficients(h: float, theta_f: float) -> np.ndarray:
    """``[L*, M*, P*, Q*]`` of Sainsot et al. (2004) at ``h = r_f / r_int`` and ``theta_f``."""
    basis = np.array([1 / theta_f ** 2, h * h, h / theta_f, 1 / theta_f, h, 1.0])
    return np.asarray(_SAINSOT @ basis)


def _fillet_extrapolated(tooth: _Tooth) -> bool:
    h = tooth.r_f / tooth.r_int
    (h_lo, h_hi), (t_lo, t_hi) = _SAINSOT_RANGE["h"], _SAINSOT_RANGE["theta_f"]
    return not (h_lo <= h <= h_hi and t_lo <= tooth.theta_f <= t_hi)


def _fillet(tooth: _Tooth, load: _Load) -> np.ndarray:
    """Fillet-foundation compliance of Sainsot et al. (2004) (module docstring)."""
    lc, mc, pc, qc = _sainsot_coefficients(tooth.r_f / tooth.r_int, tooth.theta_f)
    tan = load.sin / load.cos
    u = tooth.r_b / load.cos - tooth.r_f
    ratio = u / (2 * tooth.r_f * tooth.theta_f)
    return load.cos ** 2 / (tooth.e_mod * tooth.width) * (
        lc * ratio ** 2 + mc * ratio + pc * (1 + qc * tan ** 2))


# --------------------------------------------------------------------------------------------
# validation
# --------------------------------------------------------------------------------------------
def _as_positions(s_m: ArrayLike) -> np.ndarray:
    s = np.asarray(s_m, dtype=float)
    if not np.all(np.isfinite(s)):
        raise ModelError(f"`s_m` must be finite positions (m), got {np.sum(~np.isfinite(s))} "
                         "non-finite values")
    return s


def _check_integration(integration: object, n_nodes: object) -> None:
    if integration not in ("gauss", "quad"):
        raise ModelError(f"`integration` must be 'gauss' or 'quad', was {integration!r}")
    if isinstance(n_nodes, bool) or not isinstance(n_nodes, int | np.integer) \
            or not 2 <= int(n_nodes) <= 200:
        raise ModelError(f"`n_nodes` must be an integer in [2, 200], was {n_nodes!r}")


# --------------------------------------------------------------------------------------------
# public functions
# --------------------------------------------------------------------------------------------
def tooth_compliance(
    pair: GearPair,
    s_m: ArrayLike,
    gear: int,
    *,
    integration: Integration = "gauss",
    n_nodes: int = DEFAULT_NODES,
    plane_strain: bool = False,
) -> ToothCompliance:
    r"""Bending, shear, axial and fillet-foundation compliance of one tooth (m/N).

    Parameters
    ----------
    pair : GearPair
        The gear pair (SI units).
    s_m : array_like
        Positions on the line of action, from T1 (m); any shape, values outside the path of
        contact allowed (the contact point is clamped to the profile, see the module
        docstring).
    gear : int
        1 (pinion: contact at roll distance ``s``) or 2 (wheel: ``T1T2 - s``).
    integration : {"gauss", "quad"}
        ``"gauss"``: fixed Gauss-Legendre in the roll angle, vectorised (default).
        ``"quad"``: adaptive ``scipy.integrate.quad`` per position (slow; a check).
    n_nodes : int
        Gauss-Legendre points per panel on the involute part (``"gauss"`` only).
    plane_strain : bool
        Use ``E / (1 - nu^2)`` instead of ``E`` in the bending, axial and fillet terms.

    Returns
    -------
    ToothCompliance
        Arrays of the shape of ``s_m``.

    Notes
    -----
    .. math:: C_i = C_{b,i} + C_{s,i} + C_{a,i} + C_{f,i}

    with the beam integrals of Tian (2004) from the root of the beam (straight flank below the
    base circle, after Chen and Shao 2011) to the contact point and the fillet term of Sainsot
    et al. (2004); see the module docstring for the equations.

    Examples
    --------
    >>> from models.geometry import load_gear_set
    >>> pair = load_gear_set("kahraman-blankenship").pair
    >>> c = tooth_compliance(pair, [pair.start_of_contact, pair.end_of_contact], gear=1)
    >>> bool(c.total_m_per_N[1] > 2 * c.total_m_per_N[0])  # loaded at its tip: most compliant
    True
    """
    _check_integration(integration, n_nodes)
    s = _as_positions(s_m)
    tooth = _tooth(pair, gear, bool(plane_strain))
    rho = s if gear == 1 else pair.line_of_action_length - s
    load = _load(tooth, rho)
    if integration == "gauss":
        moments = _moments_gauss(tooth, load.phi, int(n_nodes))
    else:
        moments = _moments_quad(tooth.profile, tooth.phi_0, tooth.y_root, load.phi)
    moments = moments + _flank_moments(tooth.y_base - tooth.y_root, tooth.flank_half)
    bending, shear, axial = _beam_compliance(moments, tooth.r_b - tooth.y_root * load.cos,
                                             load, tooth.e_mod, tooth.g_mod, tooth.width)
    return ToothCompliance(
        gear=gear,
        bending_m_per_N=bending,
        shear_m_per_N=shear,
        axial_m_per_N=axial,
        fillet_m_per_N=_fillet(tooth, load),
        roll_angle_rad=load.phi,
        load_angle_rad=load.phi - tooth.theta_b,
        clamped=load.clamped,
        fillet_extrapolated=_fillet_extrapolated(tooth),
    )


def pair_compliance(
    pair: GearPair,
    s_m: ArrayLike,
    *,
    include_hertz: bool = True,
    integration: Integration = "gauss",
    n_nodes: int = DEFAULT_NODES,
    plane_strain: bool = False,
) -> PairCompliance:
    r"""Compliance of one tooth pair at positions on the line of action (m/N).

    Parameters
    ----------
    pair : GearPair
        The gear pair (SI units).
    s_m : array_like
        Positions from T1 (m), any shape (e.g. ``(n_positions, n_pairs)`` for the pairs of a
        mesh cycle); positions outside ``[A, E]`` are allowed and give finite, continuous
        values (each tooth's contact point is clamped to its profile; see the module
        docstring and :attr:`PairCompliance.in_contact_path`).
    include_hertz : bool
        Add the linearised Hertz compliance ``1 / k_h`` to the total.
    integration : {"gauss", "quad"}
        Fixed Gauss-Legendre (vectorised, default) or adaptive ``scipy.integrate.quad`` per
        position (slow, for checks).
    n_nodes : int
        Gauss-Legendre points per panel on each involute part (``"gauss"`` only).
    plane_strain : bool
        ``E / (1 - nu^2)`` in the bending, axial and fillet terms (default: plane stress).

    Returns
    -------
    PairCompliance

    Notes
    -----
    Seed 003 Eqs. 1-2:

    .. math::

        C = \frac{1}{k_h} + \sum_{i=p,g}\left(\frac{1}{k_{b,i}} + \frac{1}{k_{s,i}}
            + \frac{1}{k_{a,i}} + \frac{1}{k_{f,i}}\right),
        \qquad k_h = \frac{\pi E b}{4 (1 - \nu^2)} .

    Examples
    --------
    Single-pair stiffness per unit face width at the pitch point of the Kahraman-Blankenship
    pair (N/(mm um); ISO 6336-1's single stiffness is ``c' ~ 14``):

    >>> from models.geometry import load_gear_set
    >>> pair = load_gear_set("kahraman-blankenship").pair
    >>> c = pair_compliance(pair, pair.pitch_point)
    >>> round(float(c.stiffness_N_per_m / pair.face_width_m / 1e9), 2)
    9.45
    >>> pair_compliance(pair, pair.pair_positions([0.0, 0.5], n_pairs=3)).total_m_per_N.shape
    (2, 3)
    """
    _check_integration(integration, n_nodes)
    s = _as_positions(s_m)
    kw = {"integration": integration, "n_nodes": n_nodes, "plane_strain": plane_strain}
    pin = tooth_compliance(pair, s, 1, **kw)  # type: ignore[arg-type]
    whl = tooth_compliance(pair, s, 2, **kw)  # type: ignore[arg-type]
    m1, m2 = pair.pinion.material, pair.wheel.material
    c_h = 1.0 / hertz_stiffness(pair.face_width_m, m1.youngs_modulus_Pa, m1.poisson_ratio,
                                m2.youngs_modulus_Pa, m2.poisson_ratio)
    total = pin.total_m_per_N + whl.total_m_per_N
    if include_hertz:
        total = total + c_h
    tol = 1e-12 * pair.line_of_action_length
    return PairCompliance(
        s_m=s,
        pinion=pin,
        wheel=whl,
        hertz_m_per_N=np.full(s.shape, c_h),
        total_m_per_N=total,
        include_hertz=bool(include_hertz),
        in_contact_path=(s >= pair.start_of_contact - tol) & (s <= pair.end_of_contact + tol),
    )


def tooth_stiffness(
    pair: GearPair,
    s_m: ArrayLike,
    gear: int,
    *,
    integration: Integration = "gauss",
    n_nodes: int = DEFAULT_NODES,
    plane_strain: bool = False,
) -> np.ndarray:
    """Single-tooth stiffness ``1 / C_i`` of the pinion (1) or wheel (2) (N/m), no Hertz term.

    Parameters as :func:`tooth_compliance`.

    Examples
    --------
    >>> from models.geometry import load_gear_set
    >>> pair = load_gear_set("kahraman-blankenship").pair
    >>> k1 = tooth_stiffness(pair, pair.pitch_point, 1)
    >>> bool(np.isclose(k1, tooth_stiffness(pair, pair.pitch_point, 2)))  # equal gears
    True
    """
    return tooth_compliance(pair, s_m, gear, integration=integration, n_nodes=n_nodes,
                            plane_strain=plane_strain).stiffness_N_per_m


def pair_stiffness(
    pair: GearPair,
    s_m: ArrayLike,
    *,
    include_hertz: bool = True,
    integration: Integration = "gauss",
    n_nodes: int = DEFAULT_NODES,
    plane_strain: bool = False,
) -> np.ndarray:
    """Tooth-pair stiffness ``1 / C`` (N/m); parameters as :func:`pair_compliance`.

    Examples
    --------
    >>> from models.geometry import load_gear_set
    >>> pair = load_gear_set("fzg-c").pair
    >>> k = pair_stiffness(pair, np.linspace(pair.start_of_contact, pair.end_of_contact, 5))
    >>> k.shape, bool(np.all(k > 0))
    ((5,), True)
    """
    return pair_compliance(pair, s_m, include_hertz=include_hertz, integration=integration,
                           n_nodes=n_nodes, plane_strain=plane_strain).stiffness_N_per_m

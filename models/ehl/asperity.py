r"""Greenwood-Tripp asperity contact, film/asperity load sharing, mixed friction (seed 002).

Greenwood-Tripp integrals (Greenwood & Tripp 1970-71, "The contact of two nominally flat rough
surfaces", Proc. IMechE 185, 625-633), Gaussian summit heights in units of ``sigma``:

.. math:: F_n(t) = \frac{1}{\sqrt{2\pi}}\int_t^\infty (s - t)^n e^{-s^2/2}\, ds,

evaluated here with ``s = t + y^2`` (smooth integrand) by 96-point Gauss-Legendre quadrature,
vectorised over ``t``; ``F_0``, ``F_1``, ``F_2`` also have closed forms
(``F_2 = (1 + t^2) F_0 - t phi(t)``) used by the tests.

Asperity pressure (Greenwood-Tripp; in the form of Gelinck & Schipper 2000, Tribol. Int. 33,
175-181, and Akbarzadeh & Khonsari 2008, ASME J. Tribol. 130, 041503):

.. math::

    p_a = \frac{16\sqrt{2}\,\pi}{15} (n_s\beta_s\sigma_s)^2 \sqrt{\frac{\sigma_s}{\beta_s}}\,
          E^*\, F_{5/2}\!\left(\frac{h - d_d}{\sigma_s}\right),\qquad E^* = E'/2.

Seed 002 prints the prefactor as ``sqrt(8)/(15 pi) n^2 beta^1.5 sigma^2.5 E'``; with
``E' = 2 E*`` Greenwood-Tripp's ``16 sqrt(2) pi / 15`` with ``E*`` equals ``8 sqrt(2) pi / 15``
with ``E'``; the seed's ``1/pi`` is taken as a typesetting slip. Seed 002 gives
``sigma = 0.4 um`` (per surface; composite ``sigma_s = 0.4 sqrt(2) um``) and the asperity
radius ``beta_s = 6 um`` but no asperity density; ``n_s beta_s sigma_s = 0.05`` (the usual
0.03-0.05 of Greenwood & Williamson / Johnson et al. 1972) is assumed and is a parameter.

Load sharing (Johnson, Greenwood & Poon 1972, Wear 19, 91-108; Gelinck & Schipper 2000):
``F = F_h + F_a``, ``F_h = F / gamma_1``, ``F_a = F / gamma_2``, ``1/gamma_1 + 1/gamma_2 = 1``.
The film is Moes' film (with ``C_t``) for load ``w / gamma_1`` and modulus ``E' / gamma_1``;
the asperities carry ``w / gamma_2 = 2 b p_a(h_c)`` over the Hertz band ``2 b``,
``b = sqrt(8 w R / (pi E'))`` (invariant under the scaling). The single unknown
``x = 1/gamma_2 in [0, 1)`` is found by vectorised bisection on
``r(x) = x w - 2 b p_a(h_c(x))``.

Mixed friction law (stated model, after seed 002's ``f = B int tau dx / F_d + f_a / gamma_2``):

.. math::

    f = \lambda\left[\frac{2 b\, \tau_h}{w} + \frac{f_a}{\gamma_2}\right],\quad
    \tau_h = \min\left(\mu_e(\bar p_h, T, \dot\gamma)\,\dot\gamma,\; \Lambda_L \bar p_h\right),
    \quad \dot\gamma = \frac{|u_1 - u_2|}{h_c},\quad \bar p_h = \frac{w}{2 b\,\gamma_1},

a uniform Carreau shear stress over the Hertz band at the film's mean pressure, capped by a
limiting shear stress ``Lambda_L p`` (Bair & Winer 1979), plus the boundary friction of the
asperity share. ``lambda = sign(u_1 - u_2)`` is the direction factor: negative in approach,
zero at the pitch point, positive in recess (``u_1`` the pinion flank's velocity).

Where the friction level comes from: with seed 002's lubricant (``G_cr = 31 kPa``, Doolittle-
Tait ``alpha_0 = 19 /GPa``) the Carreau stress at the film's mean pressure exceeds
``Lambda_L p`` over most of seed 002's path of contact (2000 rpm, single-pair load, 9 equally
spaced points: 8 capped with ``mu_R = 1.42 Pa s``, 6 with 0.142 Pa s), so the film friction
there is ``Lambda_L / gamma_1`` and its level is that of the *assumed* ``Lambda_L = 0.07``,
not of the rheology; only near the pitch point, where the sliding vanishes, is it viscous.
The model has **no flash temperature**: seed 002's film energy equation and Jaeger's
moving-source surface temperatures are not solved; the shear is evaluated at the inlet
temperature (the thermal factor ``C_t`` acts on the film thickness only). A thermal model
would lower the viscous stress where the sliding is high.

The film stiffness of the mixed contact, ``k_h = -dF/dh_c`` with the load split re-solved at
``F (1 +- e)``, is :func:`mixed_film_stiffness`.

Roughness: seed 002's "surface roughness RMS 0.4 um" is read as each flank's RMS (composite
``sigma_s = 0.57 um``); if it is the composite value, ``Lambda`` is ``sqrt(2)`` higher and the
asperity share much lower everywhere.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from models.ehl.film import central_film_thickness, composite_roughness, film_stiffness_from_steps
from models.ehl.lubricant import SEED_002_LUBRICANT, Lubricant
from models.errors import ModelError

if TYPE_CHECKING:
    from models.geometry.gear_pair import GearPair

__all__ = [
    "ETA_BETA_SIGMA_DEFAULT",
    "SEED_002_ROUGHNESS",
    "MixedContact",
    "Roughness",
    "asperity_pressure",
    "greenwood_tripp_integral",
    "mixed_contact",
    "mixed_contact_along_path",
    "mixed_film_stiffness",
]

#: Assumed ``n_s beta_s sigma_s`` (-): seed 002 gives no asperity density.
ETA_BETA_SIGMA_DEFAULT = 0.05

_GL_X, _GL_W = np.polynomial.legendre.leggauss(96)


def greenwood_tripp_integral(n: float, t: ArrayLike) -> np.ndarray:
    """Greenwood-Tripp integral ``F_n(t)`` (-) for ``n >= 0``, vectorised over ``t``.

    Parameters
    ----------
    n : float
        Order (e.g. 2 or 5/2).
    t : array_like
        Dimensionless separation ``h / sigma`` (-).
    """
    # t above 40 gives F_n < 1e-300 (0 in double precision); capping it avoids overflow of the
    # square below for the very thick films of nearly unloaded contacts
    t = np.asarray(t, float)
    t = np.where(t > 40.0, 40.0, t)
    # s = t + y^2: integrand 2 y^(2n+1) exp(-(t + y^2)^2 / 2), y in [0, Y]; the Gaussian factor
    # is below 1e-40 for t + y^2 > 13.6.
    Y = np.sqrt(np.maximum(0.0, -t) + 13.6)[..., None]
    y = 0.5 * Y * (_GL_X + 1)
    f = 2 * y ** (2 * n + 1) * np.exp(-0.5 * (t[..., None] + y * y) ** 2)
    return 0.5 * Y[..., 0] * (f @ _GL_W) / math.sqrt(2 * math.pi)


@dataclass(frozen=True)
class Roughness:
    """Surface roughness of the pair (SI units).

    Attributes
    ----------
    sigma_1_m, sigma_2_m : float
        RMS roughness of each flank (m).
    asperity_radius_m : float
        Summit radius ``beta_s`` (m).
    eta_beta_sigma : float
        ``n_s beta_s sigma_s`` (-).
    d_d_m : float
        Offset between mean summit and mean surface height ``d_d`` (m); 0 by default.
    """

    sigma_1_m: float = 0.4e-6
    sigma_2_m: float = 0.4e-6
    asperity_radius_m: float = 6e-6
    eta_beta_sigma: float = ETA_BETA_SIGMA_DEFAULT
    d_d_m: float = 0.0

    def __post_init__(self) -> None:
        vals = (self.sigma_1_m, self.sigma_2_m, self.asperity_radius_m, self.eta_beta_sigma)
        if not all(math.isfinite(v) and v >= 0 for v in vals) or not math.isfinite(self.d_d_m):
            raise ModelError(f"Roughness values must be finite and >= 0, got {self!r}")
        if not (self.sigma_m > 0 and self.asperity_radius_m > 0):
            raise ModelError("Roughness needs a composite sigma > 0 and an asperity radius > 0")

    @property
    def sigma_m(self) -> float:
        """Composite RMS roughness ``sqrt(sigma_1^2 + sigma_2^2)`` (m)."""
        return float(composite_roughness(self.sigma_1_m, self.sigma_2_m))


#: Seed 002: 0.4 um RMS on each flank, 6 um asperity radius.
SEED_002_ROUGHNESS = Roughness()


def asperity_pressure(
    h_m: ArrayLike, reduced_modulus_Pa: ArrayLike, roughness: Roughness = SEED_002_ROUGHNESS
) -> np.ndarray:
    """Greenwood-Tripp nominal asperity pressure ``p_a(h)`` (Pa); formula in the module docstring.

    Parameters
    ----------
    h_m : array_like
        Separation of the mean surfaces (m) (the central film thickness).
    reduced_modulus_Pa : array_like
        ``E'`` (Pa), ``2/E' = sum (1 - nu^2)/E``.
    roughness : Roughness
    """
    s = roughness.sigma_m
    K = (
        16
        * math.sqrt(2)
        * math.pi
        / 15
        * roughness.eta_beta_sigma**2
        * math.sqrt(s / roughness.asperity_radius_m)
    )
    t = (np.asarray(h_m, float) - roughness.d_d_m) / s
    return K * 0.5 * np.asarray(reduced_modulus_Pa, float) * greenwood_tripp_integral(2.5, t)


@dataclass(frozen=True)
class MixedContact:
    """Mixed-EHL state of a line contact (arrays broadcast over the inputs).

    Attributes
    ----------
    h_c_m : numpy.ndarray
        Central film thickness with load sharing and ``C_t`` (m).
    gamma_1, gamma_2 : numpy.ndarray
        Load-sharing factors ``F_h = F/gamma_1``, ``F_a = F/gamma_2`` (-).
    film_parameter : numpy.ndarray
        ``Lambda = h_c / sigma_s`` (-).
    asperity_pressure_Pa : numpy.ndarray
        Nominal asperity pressure (Pa).
    hertz_half_width_m : numpy.ndarray
        ``b`` (m).
    film_shear_stress_Pa : numpy.ndarray
        ``tau_h`` (Pa), magnitude.
    friction : numpy.ndarray
        Signed friction coefficient ``f`` (-), ``sign(u1 - u2)``.
    C_t : numpy.ndarray
        Thermal factor of the film (-).
    """

    h_c_m: np.ndarray
    gamma_1: np.ndarray
    gamma_2: np.ndarray
    film_parameter: np.ndarray
    asperity_pressure_Pa: np.ndarray
    hertz_half_width_m: np.ndarray
    film_shear_stress_Pa: np.ndarray
    friction: np.ndarray
    C_t: np.ndarray


def mixed_contact(
    load_per_width_N_m: ArrayLike,
    reduced_radius_m: ArrayLike,
    u1_m_s: ArrayLike,
    u2_m_s: ArrayLike,
    reduced_modulus_Pa: float,
    lubricant: Lubricant = SEED_002_LUBRICANT,
    roughness: Roughness = SEED_002_ROUGHNESS,
    inlet_temperature_K: float | None = None,
    asperity_friction: float = 0.1,
    limiting_shear_coeff: float = 0.07,
    thermal: bool = True,
    iterations: int = 60,
) -> MixedContact:
    """Load split between film and asperities and the mixed friction coefficient.

    Parameters
    ----------
    load_per_width_N_m : array_like
        Total normal load per face width ``w = F/B`` (N/m), > 0.
    reduced_radius_m : array_like
        ``R`` (m).
    u1_m_s, u2_m_s : array_like
        Flank velocities of pinion and wheel (m/s).
    reduced_modulus_Pa : float
        ``E'`` (Pa).
    lubricant, roughness : Lubricant, Roughness
    inlet_temperature_K : float or None
        Inlet temperature (K); None: ``T_R``. The film shear is evaluated at this temperature.
    asperity_friction : float
        Boundary friction coefficient ``f_a`` (-); 0.1 assumed (not in the seed).
    limiting_shear_coeff : float
        ``Lambda_L`` (-); 0.07 assumed.
    thermal : bool
        Apply ``C_t``.
    iterations : int
        Bisection steps on ``1/gamma_2`` (60 resolve it to double precision).

    Returns
    -------
    MixedContact
    """
    T = lubricant.T_ref_K if inlet_temperature_K is None else float(inlet_temperature_K)
    w, R, u1, u2 = np.broadcast_arrays(
        *(np.asarray(a, float) for a in (load_per_width_N_m, reduced_radius_m, u1_m_s, u2_m_s))
    )
    E = float(reduced_modulus_Pa)
    b = np.sqrt(8 * w * R / (math.pi * E))

    def film(x: np.ndarray):
        g1 = 1.0 / (1.0 - x)
        return central_film_thickness(w / g1, R, u1, u2, E / g1, lubricant, T, thermal)

    def residual(x: np.ndarray) -> np.ndarray:
        return x * w - 2 * b * asperity_pressure(film(x).h_c_m, E, roughness)

    lo = np.zeros_like(w)
    hi = np.full_like(w, 1.0 - 1e-12)
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        neg = residual(mid) < 0
        lo = np.where(neg, mid, lo)
        hi = np.where(neg, hi, mid)
    x = 0.5 * (lo + hi)
    st = film(x)
    h = st.h_c_m
    pa = asperity_pressure(h, E, roughness)
    g1 = 1.0 / (1.0 - x)
    with np.errstate(divide="ignore"):
        g2 = 1.0 / x
    p_h = w / (2 * b * g1)
    rate = np.abs(u1 - u2) / h
    mu = lubricant.viscosity(p_h, T)
    tau = np.minimum(lubricant.effective_viscosity(mu, rate) * rate, limiting_shear_coeff * p_h)
    f = np.sign(u1 - u2) * (2 * b * tau / w + asperity_friction * x)
    return MixedContact(h, g1, g2, h / roughness.sigma_m, pa, b, tau, f, st.C_t)


def mixed_contact_along_path(
    pair: GearPair,
    s_m: ArrayLike,
    pinion_speed_rpm: float,
    load_N: ArrayLike,
    **kwargs: Any,
) -> MixedContact:
    """:func:`mixed_contact` at positions ``s`` on the line of action of a :class:`GearPair`.

    Parameters
    ----------
    pair : models.geometry.GearPair
        Uses ``curvature_radii``, ``surface_velocities``, the face width and the pinion's
        material for ``E' = E / (1 - nu^2)`` (both gears of the same material).
    s_m : array_like
        Positions from T1 (m).
    pinion_speed_rpm : float
    load_N : array_like
        Normal load of the tooth pair (N), e.g. ``T_1 / r_b1`` in single contact.
    **kwargs
        Passed to :func:`mixed_contact`.
    """
    r1, r2 = pair.curvature_radii(s_m)
    R = r1 * r2 / (r1 + r2)
    u1, u2 = pair.surface_velocities(s_m, pinion_speed_rpm)
    mat = pair.pinion.material
    E = mat.youngs_modulus_Pa / (1 - mat.poisson_ratio**2)
    w = np.asarray(load_N, float) / pair.face_width_m
    return mixed_contact(w, R, u1, u2, E, **kwargs)


def mixed_film_stiffness(
    load_N: ArrayLike,
    face_width_m: float,
    reduced_radius_m: ArrayLike,
    u1_m_s: ArrayLike,
    u2_m_s: ArrayLike,
    reduced_modulus_Pa: float,
    *,
    rel_step: float = 1e-2,
    **kwargs: Any,
) -> tuple[MixedContact, np.ndarray]:
    """Mixed contact at the load ``F`` and its film stiffness ``k_h = -dF/dh_c`` (N/m).

    The load split is solved at ``F``, ``F (1 + e)`` and ``F (1 - e)`` (one vectorised call of
    :func:`mixed_contact`) and ``k_h`` follows from the three central films by
    :func:`models.ehl.film.film_stiffness_from_steps` (seed 002's ``k_h = dF/dh_c``). Where the
    asperities carry nothing this is :func:`models.ehl.film.film_stiffness` with the same step.
    This is what the decoupling loop (:func:`models.dynamics.tribo_ehl_coupling.contact_cycle`)
    uses.

    Parameters
    ----------
    load_N : array_like
        Tooth-pair load ``F`` (N), > 0.
    face_width_m : float
        Face width ``B`` (m); ``w = F / B``.
    reduced_radius_m, u1_m_s, u2_m_s, reduced_modulus_Pa
        As in :func:`mixed_contact`.
    rel_step : float
        Relative load step ``e`` (-); the loop's default is 1e-2.
    **kwargs
        Passed to :func:`mixed_contact` (lubricant, roughness, inlet temperature, friction
        constants, thermal switch).

    Returns
    -------
    tuple
        The :class:`MixedContact` at ``F`` and ``k_h`` (N/m), both shaped like the
        broadcast inputs.
    """
    F, R, u1, u2 = np.broadcast_arrays(
        *(np.asarray(a, float) for a in (load_N, reduced_radius_m, u1_m_s, u2_m_s))
    )
    shape = F.shape
    F, R, u1, u2 = (a.ravel() for a in (F, R, u1, u2))
    scale = np.repeat([1.0, 1.0 + rel_step, 1.0 - rel_step], F.size)
    mc = mixed_contact(
        np.tile(F, 3) * scale / face_width_m,
        np.tile(R, 3),
        np.tile(u1, 3),
        np.tile(u2, 3),
        reduced_modulus_Pa,
        **kwargs,
    )
    n = F.size
    h0, hp, hm = mc.h_c_m[:n], mc.h_c_m[n : 2 * n], mc.h_c_m[2 * n :]
    k = film_stiffness_from_steps(F, hm, h0, hp, rel_step)
    centre = MixedContact(
        *(np.asarray(getattr(mc, f.name))[:n].reshape(shape) for f in fields(MixedContact))
    )
    return centre, k.reshape(shape)

r"""EHL line-contact film: Moes central film thickness, thermal factor C_t, Lambda, film stiffness.

Moes' central film thickness for an isothermal Newtonian smooth line contact (Moes 1992,
"Optimum similarity analysis with applications to elastohydrodynamic lubrication", Wear 159,
57-66; Venner & Lubrecht 2000, *Multilevel Methods in Lubrication*, Elsevier, ch. 6; also the
tribonet.org "EHL film thickness calculator: line contact" page). Groups (``E'`` with
``2/E' = (1-nu_1^2)/E_1 + (1-nu_2^2)/E_2``, ``R`` the reduced radius, ``u_m`` the mean
entrainment velocity ``(u_1 + u_2)/2``, ``w`` the load per unit face width):

.. math::

    U = \frac{\mu_0 u_m}{E' R},\quad W = \frac{w}{E' R},\quad G = \alpha E',\quad
    M = W (2U)^{-1/2},\quad L = G (2U)^{1/4},\quad H = \frac{h}{R}(2U)^{-1/2},

.. math::

    H_c = \left[\left(H_{RI}^{7/3} + H_{EI}^{7/3}\right)^{3s/7}
          + \left(H_{RP}^{-7/2} + H_{EP}^{-7/2}\right)^{-2s/7}\right]^{1/s},

``H_RI = 3 M^-1`` (rigid-isoviscous, Martin 1916), ``H_EI = 2.621 M^-1/5`` (elastic-isoviscous,
Herrebrugh 1968), ``H_RP = 1.287 L^2/3`` (rigid-piezoviscous, Blok 1952), ``H_EP = 1.311
M^-1/8 L^3/4`` (elastic-piezoviscous, Ertel-Grubin 1949), ``s = 3/2 [1 + exp(-1.2 H_EI/H_RI)]``.
In Dowson-Higginson groups ``H_EP`` reads ``h/R = 2^{3/4} 1.311 (GU)^{3/4} W^{-1/8}``.
Seed 002's ``2.621 U^0.67 G^0.53 W^-0.067 (1 - 0.61 e^{-0.73 kappa})`` is the Hamrock-Dowson
point-contact fit with Moes' ``H_EI`` constant substituted; it has an ellipticity and no line
contact meaning, so it is not used.

Thermal reduction (seed 002; Hsu & Lee 1994, "An efficient algorithm for thermal
elastohydrodynamic lubrication under rolling/sliding line contacts", ASME J. Tribol. 116,
762-769; a Gupta et al. 1992 type inlet-heating factor):

.. math::

    C_t = \frac{1}{1 + 0.0766\, G^{0.687} W^{0.447} L_c^{0.527} e^{0.875 S_r}},\qquad
    L_c = \frac{\beta \mu_0 u_m^2}{\kappa_f},\quad S_r = \frac{|u_1 - u_2|}{u_m},

with ``beta = -d ln(mu)/dT`` of the lubricant at the inlet state and the Hamrock ``G``, ``W``
above. ``h_c = C_t h_c,iso``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from models.ehl.lubricant import SEED_002_LUBRICANT, Lubricant

__all__ = [
    "FilmState",
    "central_film_thickness",
    "composite_roughness",
    "film_parameter",
    "film_stiffness",
    "film_stiffness_from_steps",
    "moes_central_film",
    "moes_groups",
    "thermal_reduction_factor",
]


def moes_groups(U: ArrayLike, G: ArrayLike, W: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Moes' ``M = W (2U)^-1/2`` and ``L = G (2U)^1/4`` (-) from Hamrock's U, G, W (-)."""
    U2 = 2 * np.asarray(U, float)
    return np.asarray(W, float) / np.sqrt(U2), np.asarray(G, float) * U2**0.25


def moes_central_film(M: ArrayLike, L: ArrayLike) -> np.ndarray:
    """Moes' dimensionless central film ``H_c = h_c/R (2U)^-1/2`` for a line contact (-).

    Evaluated in logarithms (``logaddexp``), so that very light loads (``M -> 0``, where
    ``H_RI^(7/3)`` overflows a double) give the rigid-isoviscous limit ``3/M`` instead of inf.

    Parameters
    ----------
    M, L : array_like
        Moes load and lubricant parameters (-), ``M > 0``, ``L >= 0``.

    Returns
    -------
    numpy.ndarray
        ``H_c`` (-); see the module docstring for the formula and sources.
    """
    M = np.asarray(M, float)
    L = np.asarray(L, float)
    # in logarithms: the powers overflow for very light loads (M -> 0, H_RI = 3/M -> inf)
    lnM = np.log(M)
    ln_ri = math.log(3.0) - lnM
    ln_ei = math.log(2.621) - 0.2 * lnM
    with np.errstate(divide="ignore"):
        lnL = np.log(L)  # -inf when L = 0: the piezoviscous part vanishes
    ln_rp = math.log(1.287) + (2 / 3) * lnL
    ln_ep = math.log(1.311) - 0.125 * lnM + 0.75 * lnL
    s = 1.5 * (1 + np.exp(-1.2 * np.exp(ln_ei - ln_ri)))
    with np.errstate(invalid="ignore"):
        ln_iso = (3 * s / 7) * np.logaddexp((7 / 3) * ln_ri, (7 / 3) * ln_ei)
        ln_piezo = (-2 * s / 7) * np.logaddexp(-3.5 * ln_rp, -3.5 * ln_ep)
    ln_piezo = np.where(np.isnan(ln_piezo), -np.inf, ln_piezo)
    return np.exp(np.logaddexp(ln_iso, ln_piezo) / s)


def thermal_reduction_factor(
    G: ArrayLike, W: ArrayLike, L_c: ArrayLike, slide_roll: ArrayLike
) -> np.ndarray:
    """Seed 002's / Hsu-Lee thermal reduction factor ``C_t`` (-); formula in the module docstring.

    Parameters
    ----------
    G, W : array_like
        Hamrock material and load parameters (-).
    L_c : array_like
        Thermal load parameter ``beta mu_0 u_m^2 / kappa_f`` (-).
    slide_roll : array_like
        Slide-to-roll ratio ``|u_1 - u_2| / u_m`` (-).
    """
    return 1.0 / (
        1.0
        + 0.0766
        * np.asarray(G, float) ** 0.687
        * np.asarray(W, float) ** 0.447
        * np.asarray(L_c, float) ** 0.527
        * np.exp(0.875 * np.abs(slide_roll))
    )


@dataclass(frozen=True)
class FilmState:
    """Central film of a line contact (SI units; arrays broadcast over the inputs).

    Attributes
    ----------
    h_c_m : numpy.ndarray
        Central film thickness including ``C_t`` (m).
    h_iso_m : numpy.ndarray
        Isothermal Moes film (m).
    C_t : numpy.ndarray
        Thermal reduction factor (-).
    U, G, W, M, L, L_c, slide_roll : numpy.ndarray
        Dimensionless groups (-).
    """

    h_c_m: np.ndarray
    h_iso_m: np.ndarray
    C_t: np.ndarray
    U: np.ndarray
    G: np.ndarray
    W: np.ndarray
    M: np.ndarray
    L: np.ndarray
    L_c: np.ndarray
    slide_roll: np.ndarray


def central_film_thickness(
    load_per_width_N_m: ArrayLike,
    reduced_radius_m: ArrayLike,
    u1_m_s: ArrayLike,
    u2_m_s: ArrayLike,
    reduced_modulus_Pa: ArrayLike,
    lubricant: Lubricant = SEED_002_LUBRICANT,
    inlet_temperature_K: float | None = None,
    thermal: bool = True,
) -> FilmState:
    """Moes central film thickness with the thermal factor ``C_t`` (m).

    Parameters
    ----------
    load_per_width_N_m : array_like
        Load carried by the film per unit face width ``w`` (N/m), > 0.
    reduced_radius_m : array_like
        ``R = rho_1 rho_2 / (rho_1 + rho_2)`` (m), > 0.
    u1_m_s, u2_m_s : array_like
        Surface (rolling) velocities of the flanks (m/s); ``u_m = (u1 + u2)/2 > 0``.
    reduced_modulus_Pa : array_like
        ``E'`` (Pa), ``2/E' = sum (1 - nu^2)/E``.
    lubricant : Lubricant
        Inlet viscosity ``mu_0 = mu(0, T_in)`` from Doolittle-Tait; ``alpha`` from its table.
    inlet_temperature_K : float or None
        Inlet (bulk oil) temperature (K); None: the lubricant's reference temperature.
    thermal : bool
        Apply ``C_t`` (True) or return the isothermal film (``C_t = 1``).
    """
    T = lubricant.T_ref_K if inlet_temperature_K is None else float(inlet_temperature_K)
    w = np.asarray(load_per_width_N_m, float)
    R = np.asarray(reduced_radius_m, float)
    u1 = np.asarray(u1_m_s, float)
    u2 = np.asarray(u2_m_s, float)
    E = np.asarray(reduced_modulus_Pa, float)
    um = 0.5 * (u1 + u2)
    mu0 = lubricant.viscosity(0.0, T)
    U = mu0 * um / (E * R)
    W = w / (E * R)
    G = lubricant.alpha_per_Pa * E
    M, L = moes_groups(U, G, W)
    h_iso = moes_central_film(M, L) * R * np.sqrt(2 * U)
    beta = lubricant.temperature_viscosity_coefficient(T)
    L_c = beta * mu0 * um**2 / lubricant.conductivity_W_mK
    sr = np.abs(u1 - u2) / um
    C_t = thermal_reduction_factor(G, W, L_c, sr) if thermal else np.ones_like(h_iso)
    b = np.broadcast_arrays(h_iso, C_t, U, G, W, M, L, L_c, sr)
    return FilmState(b[0] * b[1], *b)


def composite_roughness(sigma_1_m: ArrayLike, sigma_2_m: ArrayLike) -> np.ndarray:
    """``sigma = sqrt(sigma_1^2 + sigma_2^2)`` (m)."""
    return np.hypot(np.asarray(sigma_1_m, float), np.asarray(sigma_2_m, float))


def film_parameter(h_c_m: ArrayLike, sigma_1_m: ArrayLike, sigma_2_m: ArrayLike) -> np.ndarray:
    """Film parameter ``Lambda = h_c / sqrt(sigma_1^2 + sigma_2^2)`` (-) (seed 002).

    ``Lambda < 1`` boundary, ``1..3`` mixed, ``> 3`` full film. Seed 002's "surface roughness
    RMS 0.4 um" is read as each flank's ``sigma`` (composite 0.57 um); if it were the composite
    value, every ``Lambda`` of the shipped cases would be ``sqrt(2)`` higher.
    """
    return np.asarray(h_c_m, float) / composite_roughness(sigma_1_m, sigma_2_m)


def film_stiffness_from_steps(
    load_N: ArrayLike,
    h_minus_m: ArrayLike,
    h_0_m: ArrayLike,
    h_plus_m: ArrayLike,
    rel_step: float,
) -> np.ndarray:
    r"""Film stiffness ``k_h = -dF/dh_c`` (N/m) from films at ``F (1 - e)``, ``F``, ``F (1 + e)``.

    Seed 002's ``k_h = dF_d/dh_c = (F/h_c) (d ln F / d ln h_c)`` in magnitude,

    .. math:: k_h = \frac{F}{h_c}\left|\frac{d\ln h_c}{d\ln F}\right|^{-1},\qquad
              \frac{d\ln h_c}{d\ln F} \approx
              \frac{\ln h_+ - \ln h_-}{\ln(1 + e) - \ln(1 - e)},

    a central difference in ``ln F`` (second order in ``e``). The one implementation of the
    difference: :func:`film_stiffness` (smooth film) and
    :func:`models.ehl.asperity.mixed_film_stiffness` (mixed contact, used by the decoupling
    loop) both call it.

    Parameters
    ----------
    load_N : array_like
        Load ``F`` (N) (or per width: the result then is per width).
    h_minus_m, h_0_m, h_plus_m : array_like
        Central film at ``F (1 - e)``, ``F``, ``F (1 + e)`` (m).
    rel_step : float
        ``e`` (-), in (0, 1).
    """
    if not 0 < rel_step < 1:
        raise ValueError(f"`rel_step` must be in (0, 1), was {rel_step!r}")
    F = np.asarray(load_N, float)
    hm = np.asarray(h_minus_m, float)
    hp = np.asarray(h_plus_m, float)
    slope = (np.log(hp) - np.log(hm)) / (math.log1p(rel_step) - math.log1p(-rel_step))
    with np.errstate(divide="ignore"):
        return F / (np.asarray(h_0_m, float) * np.abs(slope))


def film_stiffness(
    load_N: ArrayLike,
    face_width_m: float,
    reduced_radius_m: ArrayLike,
    u1_m_s: ArrayLike,
    u2_m_s: ArrayLike,
    reduced_modulus_Pa: ArrayLike,
    lubricant: Lubricant = SEED_002_LUBRICANT,
    inlet_temperature_K: float | None = None,
    thermal: bool = True,
    rel_step: float = 1e-3,
) -> np.ndarray:
    r"""Normal stiffness of the smooth EHL film ``k_h = -dF/dh_c`` (N/m), seed 002's model.

    .. math:: k_h = -\frac{dF}{dh_c} = \frac{F}{h_c}\left|\frac{d\ln h_c}{d\ln F}\right|^{-1}

    with ``h_c(F)`` the film of :func:`central_film_thickness` at fixed kinematics (Moes with
    ``C_t``), the logarithmic slope by :func:`film_stiffness_from_steps` (step ``rel_step``).
    The film is the smooth full film (no asperity share); the mixed contact's stiffness, which
    the decoupling loop uses, is :func:`models.ehl.asperity.mixed_film_stiffness` (equal to
    this one where the asperities carry nothing). Limits: ``k_h = F/h_c`` in the
    rigid-isoviscous regime (``h ~ 1/F``), ``8 F/h_c`` in the elastic-piezoviscous one
    (``h ~ F^-1/8``, isothermal).

    Parameters
    ----------
    load_N : array_like
        Normal tooth-pair load ``F`` (N), > 0.
    face_width_m : float
        Face width ``B`` (m).
    reduced_radius_m, u1_m_s, u2_m_s, reduced_modulus_Pa, lubricant, inlet_temperature_K,
    thermal
        As in :func:`central_film_thickness`.
    rel_step : float
        Relative load step of the difference (-).
    """
    F = np.asarray(load_N, float)
    args = (
        reduced_radius_m,
        u1_m_s,
        u2_m_s,
        reduced_modulus_Pa,
        lubricant,
        inlet_temperature_K,
        thermal,
    )
    hp = central_film_thickness(F * (1 + rel_step) / face_width_m, *args).h_c_m
    hm = central_film_thickness(F * (1 - rel_step) / face_width_m, *args).h_c_m
    h0 = central_film_thickness(F / face_width_m, *args).h_c_m
    return film_stiffness_from_steps(F, hm, h0, hp, rel_step)

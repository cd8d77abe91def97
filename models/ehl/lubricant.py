r"""Lubricant of seed 002: Doolittle-Tait viscosity and Carreau-Yasuda effective viscosity.

Doolittle free-volume viscosity with the Tait equation of state (Bair 2007, *High Pressure
Rheology for Quantitative Elastohydrodynamics*, ch. 6; Habchi, Bair et al. 2010, Tribol. Int.
43, 1842), in the form

.. math::

    \frac{V}{V_R} = [1 + a_V (T - T_R)]\left[1 - \frac{1}{1 + K_0'}
        \ln\!\left(1 + \frac{p}{K_0}(1 + K_0')\right)\right],
    \qquad K_0 = K_{00}\, e^{-\beta_K T},

.. math::

    \mu = \mu_R \exp\!\left[B R_0\left(\frac{1}{\frac{V/V_R}{1 + \varepsilon (T - T_R)} - R_0}
        - \frac{1}{1 - R_0}\right)\right],

so that ``mu(p = 0, T_R) = mu_R`` exactly. Seed 002's lubricant table gives all parameters
(:data:`SEED_002_LUBRICANT`), with two corrections of the extracted values:

* ``beta_K`` is taken as **6.0e-3 /K**, not the printed 6.0e-4 /K (an extraction error: a
  decimal place lost). With 6.0e-3, ``K_0 = K_00 exp(-beta_K T_R) = 1.424 GPa`` and the
  initial pressure-viscosity coefficient of the Doolittle-Tait model at ``T_R``,
  ``alpha_0 = d ln(mu)/dp |_(p=0)``, is 19.0 /GPa: exactly the table's own
  ``alpha = 19 /GPa`` (used in the Moes groups). Hand derivation: at ``p = 0`` and ``T_R``
  ``d(V/V_R)/dp = -1/K_0`` and ``d ln(mu)/d(V/V_R) = -B R_0 / (1 - R_0)^2``, so
  ``alpha_0 = B R_0 / ((1 - R_0)^2 K_0) = 27.09 / K_0``. With the printed 6.0e-4,
  ``K_0 = 9.33 GPa`` gives ``alpha_0 = 2.9 /GPa``, inconsistent with the table's 19 /GPa, and a
  viscosity only 9x the inlet one at 1 GPa (1.6e4x with 6.0e-3): friction collapses.
* ``mu_R = 1.42 Pa s`` at 348.15 K is kept as the default because the seed prints it, but it is
  **suspect**: with ``rho_f = 864 kg/m^3`` it is 1640 cSt at 75 degC, over 100x an aerospace
  turbine/gear oil (MIL-PRF-23699 type oils: about 5 cSt at 100 degC, 10 cSt near 75 degC),
  and it puts seed 002's own pair in full-film lubrication (``Lambda`` 3.6-7) with a film only 8-38x
  stiffer than the mesh, against the seed's statements (mixed regime, film stiffness "two
  orders of magnitude" above the mesh stiffness). 0.142 Pa s (ten times lower, as if a decimal
  place were lost) reproduces those statements; the shipped case ``seed-002-tribo-mixed`` uses
  it (:mod:`models.dynamics.tribo_case`).

The Doolittle-Tait viscosity enters only the film's shear stress (friction); the Moes film uses
``mu(0, T_in)`` and ``alpha``, so ``beta_K`` does not change the film thickness.

Non-Newtonian behaviour: the **Carreau(-Yasuda, a = 2)** generalised-Newtonian model of the seed,
``mu_e = mu [1 + (mu gamma_dot / G_cr)^2]^((n - 1)/2)`` with ``n = 0.74`` and
``G_cr = 31 kPa`` (Bair 2007; seed 002). Not an Eyring model. 31 kPa is low for a base oil
(Newtonian limits of mineral and synthetic base oils are usually of order MPa) but of the order
reported for polymer-containing oils, whose polymer shear-thins at low stress; it is kept as
printed. At seed 002's contact pressures the Carreau shear stress then exceeds the limiting
shear stress almost everywhere, and the friction is set by the limiting-shear cap of
:func:`models.ehl.mixed_contact` (see there).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from models.errors import ModelError

__all__ = ["SEED_002_LUBRICANT", "Lubricant"]


@dataclass(frozen=True)
class Lubricant:
    """Lubricant properties (SI units).

    Attributes
    ----------
    mu_ref_Pas : float
        Reference viscosity ``mu_R`` at ``p = 0``, ``T_R`` (Pa s); seed 002's printed 1.42 is
        suspect (module docstring).
    T_ref_K : float
        Reference temperature ``T_R`` (K).
    B0, R0 : float
        Doolittle parameters ``B`` and ``R_0 = V_inf,R / V_R`` (-).
    epsilon_per_K : float
        Thermal expansivity of the occupied volume ``epsilon`` (1/K).
    K0_prime : float
        Tait ``K_0'`` (-).
    K00_Pa : float
        Tait bulk modulus ``K_00`` (Pa).
    beta_K_per_K : float
        Temperature coefficient of ``K_0`` (1/K); 6.0e-3 (seed 002 prints 6.0e-4, an
        extraction error, see the module docstring).
    a_V_per_K : float
        Volume expansivity ``a_V`` (1/K).
    n_power : float
        Carreau power-law index ``n`` (-).
    G_cr_Pa : float
        Carreau critical shear stress/modulus ``G_cr`` (Pa).
    alpha_per_Pa : float
        Pressure-viscosity coefficient for the film formula (1/Pa).
    conductivity_W_mK, density_kg_m3, specific_heat_J_kgK : float
        ``kappa_f``, ``rho_f``, ``c_f``.
    """

    mu_ref_Pas: float = 1.42
    T_ref_K: float = 348.15
    B0: float = 4.423
    R0: float = 0.6694
    epsilon_per_K: float = -8.0e-4
    K0_prime: float = 12.82
    K00_Pa: float = 11.5e9
    beta_K_per_K: float = 6.0e-3
    a_V_per_K: float = 7.0e-4
    n_power: float = 0.74
    G_cr_Pa: float = 31.0e3
    alpha_per_Pa: float = 19.0e-9
    conductivity_W_mK: float = 0.14
    density_kg_m3: float = 864.0
    specific_heat_J_kgK: float = 2000.0

    def __post_init__(self) -> None:
        positive = (
            "mu_ref_Pas",
            "T_ref_K",
            "B0",
            "K0_prime",
            "K00_Pa",
            "G_cr_Pa",
            "alpha_per_Pa",
            "conductivity_W_mK",
            "density_kg_m3",
            "specific_heat_J_kgK",
        )
        for name in positive:
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ModelError(f"Lubricant.{name} must be finite and > 0, was {v!r}")
        if not 0 < self.R0 < 1:
            raise ModelError(f"Lubricant.R0 must be in (0, 1), was {self.R0!r}")
        if not 0 < self.n_power <= 1:
            raise ModelError(f"Lubricant.n_power must be in (0, 1], was {self.n_power!r}")
        for name in ("epsilon_per_K", "beta_K_per_K", "a_V_per_K"):
            if not math.isfinite(getattr(self, name)):
                raise ModelError(f"Lubricant.{name} must be finite")

    def relative_volume(self, p_Pa: ArrayLike, T_K: ArrayLike) -> np.ndarray:
        """Tait relative volume ``V / V_R`` (-) at pressure ``p`` (Pa) and temperature ``T`` (K)."""
        p = np.asarray(p_Pa, float)
        T = np.asarray(T_K, float)
        K0 = self.K00_Pa * np.exp(-self.beta_K_per_K * T)
        Kp = self.K0_prime
        return (1 + self.a_V_per_K * (T - self.T_ref_K)) * (
            1 - np.log1p(p / K0 * (1 + Kp)) / (1 + Kp)
        )

    def viscosity(self, p_Pa: ArrayLike, T_K: ArrayLike) -> np.ndarray:
        """Doolittle-Tait low-shear viscosity ``mu(p, T)`` (Pa s); see the module docstring.

        Parameters
        ----------
        p_Pa : array_like
            Pressure (Pa), >= 0.
        T_K : array_like
            Temperature (K).
        """
        T = np.asarray(T_K, float)
        x = self.relative_volume(p_Pa, T) / (1 + self.epsilon_per_K * (T - self.T_ref_K))
        expo = self.B0 * self.R0 * (1 / (x - self.R0) - 1 / (1 - self.R0))
        return self.mu_ref_Pas * np.exp(expo)

    def temperature_viscosity_coefficient(
        self, T_K: ArrayLike, p_Pa: ArrayLike = 0.0
    ) -> np.ndarray:
        """``beta = -d ln(mu) / dT`` (1/K) by a central difference of :meth:`viscosity`."""
        T = np.asarray(T_K, float)
        d = 1e-2
        up, down = self.viscosity(p_Pa, T + d), self.viscosity(p_Pa, T - d)
        return -(np.log(up) - np.log(down)) / (2 * d)

    def pressure_viscosity_coefficient(self, T_K: ArrayLike, p_Pa: ArrayLike = 0.0) -> np.ndarray:
        """Local ``d ln(mu) / dp`` (1/Pa) of the Doolittle-Tait model (one-sided at p = 0)."""
        p = np.asarray(p_Pa, float)
        d = 1e5
        return (np.log(self.viscosity(p + d, T_K)) - np.log(self.viscosity(p, T_K))) / d

    def effective_viscosity(self, mu_Pas: ArrayLike, shear_rate_per_s: ArrayLike) -> np.ndarray:
        r"""Carreau effective viscosity (Pa s).

        .. math:: \mu_e = \mu\left[1 + \left(\frac{\mu\dot\gamma}{G_{cr}}\right)^2\right]^{(n-1)/2}

        Parameters
        ----------
        mu_Pas : array_like
            Low-shear viscosity (Pa s).
        shear_rate_per_s : array_like
            Shear rate (1/s); its magnitude is used.
        """
        mu = np.asarray(mu_Pas, float)
        g = np.abs(np.asarray(shear_rate_per_s, float))
        return mu * (1 + (mu * g / self.G_cr_Pa) ** 2) ** ((self.n_power - 1) / 2)


#: Seed 002's lubricant table.
SEED_002_LUBRICANT = Lubricant()

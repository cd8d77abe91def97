r"""Dimensional view of the non-dimensional SDOF/ITMS models (seed 003 Eqs. 24, 27).

The models of :mod:`models.dynamics.sdof` run in ``tau = omega_n t`` and ``x = DTE / L``. Here:

.. math::

    m = \frac{J_1 J_2}{J_1 R_2^2 + J_2 R_1^2} \quad (\text{Eq. 24a}), \qquad
    \omega_n = \sqrt{k_0 / m}, \qquad c = 2 \zeta m \omega_n \quad (\text{Eq. 27}),

    f_m = \frac{\Lambda \omega_n}{2 \pi} \ (\mathrm{Hz}), \qquad
    n_1 = \frac{60 f_m}{z_1} \ (\mathrm{rpm}), \qquad \mathrm{DTE} = L x ,

with ``R_i`` the base radii, ``k_0`` the model's reference stiffness (``mean_stiffness_N_m``)
and ``L`` its length scale.

Which ``k_0``: by default (:func:`~models.dynamics.sdof.sdof_from_mesh_cycle`,
``reference_stiffness="model"``, seed Eqs. 27, 30, 31) each model's own mean stiffness. For the
VVMS and LSTE models that is a secant stiffness of the loaded static transmission error, which
holds the profile errors (seed Eq. 20b as written): on the Kahraman pair at 340 N m a rigid
5 um error on every pair makes ``k_0`` 25 % softer (3.26e8 -> 2.43e8 N/m), tip relief
``Delta = 1`` 44 % softer (1.83e8 N/m, ``omega_n`` -25 %), while the FVMS and ITMS models keep
the error-free mean FVMS (2.99e8 N/m). ``omega_n`` -- hence the Hz and rpm of a given
``Lambda`` -- then differs between models and with relief and load; to compare models on one
axis build them with ``reference_stiffness="fvms"`` (or a given ``k_0``). The
``damping_N_s_m`` follows the same ``k_0``.

The gear inertias default to the package's convention (:mod:`models.geometry.inertia`:
operating-pitch discs of the face width less the bore, 0.3 of the reference radius when the
gear states none) -- the gear body alone; a test rig adds shafts and hubs, so pass measured
``J_1``, ``J_2`` when known (the natural frequency scales as ``1 / sqrt(m)``). Until this
convention was shared the default here was the solid reference-radius disc, 6 % lighter on
FZG-C; ``gear_inertia(pair, i, disc_radius="reference", bore_fraction=0)`` gives it back.

References
----------
.. [1] W. Yu, C. K. Mechefske, Mech. Mach. Theory 96 (2016) 146-164, Eqs. 24, 27 (seed 003).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from models.dynamics.sdof import DynamicModel
from models.dynamics.sweep import SweepResult
from models.errors import ModelError
from models.geometry import kinematics
from models.geometry.gear_pair import GearPair
from models.geometry.inertia import equivalent_mass, gear_inertia

__all__ = [
    "DimensionalScaling",
    "DimensionalSweep",
    "dimensional_scaling",
    "to_dimensional",
]


@dataclass(frozen=True)
class DimensionalScaling:
    """Converts between the non-dimensional model and the rig.

    Attributes
    ----------
    mass_kg : float
        Equivalent mass ``m`` (Eq. 24a).
    omega_n_rad_s : float
        ``sqrt(k_0 / m)``.
    mean_stiffness_N_m : float
        ``k_0``, the model's reference stiffness (module notes: for VVMS / LSTE by default a
        secant stiffness that holds the profile errors).
    damping_N_s_m : float
        ``c = 2 zeta m omega_n``.
    length_scale_m : float
        ``L``.
    pinion_teeth : int
        ``z_1``.
    inertias_kg_m2 : tuple of float
        ``(J_1, J_2)`` used.
    base_radius_1_m : float
        ``R_1``: the static load is ``f_0 = T_1 / R_1`` (Eq. 24b).
    """

    mass_kg: float
    omega_n_rad_s: float
    mean_stiffness_N_m: float
    damping_N_s_m: float
    length_scale_m: float
    pinion_teeth: int
    inertias_kg_m2: tuple[float, float]
    base_radius_1_m: float

    def nondimensional_force(self, torque_Nm: float) -> float:
        """``tilde F = T_1 / (R_1 k_0 L)`` (Eqs. 24b, 27) for a pinion torque (N m)."""
        return float(torque_Nm) / (
            self.base_radius_1_m * self.mean_stiffness_N_m * self.length_scale_m
        )

    @property
    def natural_frequency_Hz(self) -> float:  # noqa: N802 (unit in the name)
        """``omega_n / (2 pi)`` (Hz): the mesh frequency at ``Lambda = 1``."""
        return self.omega_n_rad_s / (2 * math.pi)

    def mesh_frequency_Hz(self, lam: ArrayLike) -> np.ndarray:  # noqa: N802 (unit in the name)
        """Mesh frequency ``f_m = Lambda omega_n / (2 pi)`` (Hz)."""
        return np.asarray(lam, dtype=float) * self.natural_frequency_Hz

    def pinion_rpm(self, lam: ArrayLike) -> np.ndarray:
        """Pinion speed ``60 f_m / z_1`` (rpm)."""
        return kinematics.speed_rpm_from_mesh_frequency(self.mesh_frequency_Hz(lam),
                                                        self.pinion_teeth)

    def frequency_ratio_from_Hz(self, f_m_Hz: ArrayLike) -> np.ndarray:  # noqa: N802 (unit)
        """``Lambda`` of a mesh frequency ``f_m`` (Hz)."""
        return np.asarray(f_m_Hz, dtype=float) / self.natural_frequency_Hz

    def frequency_ratio_from_rpm(self, pinion_rpm: ArrayLike) -> np.ndarray:
        """``Lambda`` of a pinion speed (rpm)."""
        return self.frequency_ratio_from_Hz(
            kinematics.mesh_frequency_Hz(pinion_rpm, self.pinion_teeth)
        )

    def dte_m(self, x: ArrayLike) -> np.ndarray:
        """DTE (m) of a non-dimensional ``x``."""
        return np.asarray(x, dtype=float) * self.length_scale_m

    def dte_um(self, x: ArrayLike) -> np.ndarray:
        """DTE (um) of a non-dimensional ``x``."""
        return self.dte_m(x) * 1e6


def dimensional_scaling(
    model: DynamicModel,
    pair: GearPair,
    *,
    J1_kg_m2: float | None = None,
    J2_kg_m2: float | None = None,
) -> DimensionalScaling:
    """Scaling of ``model`` (built for ``pair``) with the gear inertias (default: discs).

    Parameters
    ----------
    model : SDOFModel or ITMSModel
        With ``mean_stiffness_N_m`` (``k_0``) and ``length_scale_m`` set, as from
        :func:`~models.dynamics.sdof.sdof_from_mesh_cycle`.
    pair : GearPair
    J1_kg_m2, J2_kg_m2 : float, optional
        Polar inertias of pinion and wheel (kg m^2); default
        :func:`models.geometry.gear_inertia` (the package's convention).

    Examples
    --------
    Two equal gears: ``m = J / (2 R^2)``.

    >>> from models.geometry import load_gear_set
    >>> from models.dynamics import SDOFModel
    >>> g = load_gear_set("kahraman-blankenship").pair
    >>> s = dimensional_scaling(SDOFModel(0.02, 0.1, 1.0, mean_stiffness_N_m=3e8,
    ...                                   length_scale_m=68e-6), g)
    >>> from models.geometry import gear_inertia
    >>> J = gear_inertia(g, 1)
    >>> bool(np.isclose(s.mass_kg, J / (2 * g.base_radius(1) ** 2)))
    True
    >>> float(np.round(s.pinion_rpm(1.0) / 60 * 50 / s.natural_frequency_Hz, 12))
    1.0
    """
    k0 = float(model.mean_stiffness_N_m)
    if not (math.isfinite(k0) and k0 > 0):
        raise ModelError(f"the model's `mean_stiffness_N_m` must be finite and > 0, was {k0!r}")
    J1 = gear_inertia(pair, 1) if J1_kg_m2 is None else float(J1_kg_m2)
    J2 = gear_inertia(pair, 2) if J2_kg_m2 is None else float(J2_kg_m2)
    m = equivalent_mass(J1, J2, pair.base_radius(1), pair.base_radius(2))
    wn = math.sqrt(k0 / m)
    return DimensionalScaling(
        mass_kg=m,
        omega_n_rad_s=wn,
        mean_stiffness_N_m=k0,
        damping_N_s_m=2 * model.zeta * m * wn,
        length_scale_m=float(model.length_scale_m),
        pinion_teeth=int(pair.pinion.teeth),
        inertias_kg_m2=(J1, J2),
        base_radius_1_m=pair.base_radius(1),
    )


@dataclass(frozen=True)
class DimensionalSweep:
    """A :class:`~models.dynamics.sweep.SweepResult` in rig units.

    Attributes
    ----------
    mesh_frequency_Hz, pinion_rpm : numpy.ndarray
        Per point, in sweep order.
    arms_um, mean_dte_um : numpy.ndarray
        Arms and mean DTE (um).
    amplitudes_um : numpy.ndarray
        ``(n, 3)`` mesh-harmonic amplitudes (um).
    contact_loss, backside_impact : numpy.ndarray
        Flags (bool).
    period : numpy.ndarray
        Response period in mesh periods (0 aperiodic).
    result : SweepResult
        The non-dimensional result.
    scaling : DimensionalScaling
    """

    mesh_frequency_Hz: np.ndarray
    pinion_rpm: np.ndarray
    arms_um: np.ndarray
    mean_dte_um: np.ndarray
    amplitudes_um: np.ndarray
    contact_loss: np.ndarray
    backside_impact: np.ndarray
    period: np.ndarray
    result: SweepResult
    scaling: DimensionalScaling


def to_dimensional(result: SweepResult, scaling: DimensionalScaling) -> DimensionalSweep:
    """The sweep in Hz, rpm and um (the scaling must have the sweep's length scale)."""
    if not math.isclose(result.length_scale_m, scaling.length_scale_m, rel_tol=1e-12):
        raise ModelError(
            f"length scales differ: sweep {result.length_scale_m!r} m, scaling "
            f"{scaling.length_scale_m!r} m"
        )
    return DimensionalSweep(
        mesh_frequency_Hz=scaling.mesh_frequency_Hz(result.frequency),
        pinion_rpm=scaling.pinion_rpm(result.frequency),
        arms_um=scaling.dte_um(result.arms),
        mean_dte_um=scaling.dte_um(result.mean_dte),
        amplitudes_um=scaling.dte_um(result.amplitudes),
        contact_loss=result.contact_loss,
        backside_impact=result.backside_impact,
        period=result.period,
        result=result,
        scaling=scaling,
    )

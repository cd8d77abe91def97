r"""Six-DOF tribo-dynamic spur-pair model of seed 002: equations, tables and builder.

Degrees of freedom (seed 002): translations ``x_p, y_p, x_g, y_g`` of pinion and wheel
(``x`` along the line of action, ``y`` perpendicular to it, positive in the direction of the
flanks' rolling velocity at the contact) and rotations ``theta_p, theta_g``. The dynamic
transmission error (DTE) is the seed's

.. math:: \delta = r_{bp}\theta_p - r_{bg}\theta_g + x_p - x_g .

Tooth pair ``i`` (one per *slot* of :func:`~models.stiffness.mesh_cycle.prepare_mesh_cycle`,
theoretical path only) carries

.. math:: N_i = k_i(t)\, D(s; b) + c_i(t)\,\dot s, \qquad s = \delta - e(t), \qquad
          k_i = \frac{k_{mi} k_{hi}}{k_{mi} + k_{hi}}, \qquad
          c_i = c_m \frac{k_i}{\sum_j k_j},

with ``k_mi`` the tooth-pair mesh stiffness at the pair's position, ``k_hi`` the EHL film
stiffness in series (seed 002), ``D`` the continuous dead zone of
:func:`models.dynamics.sdof.dead_zone` (half gap ``b``; the seed's "displacement function
considering backlash"), ``e`` the static transmission error, and the mesh damping ``c_m``
shared in proportion to stiffness so that the total viscous damping is ``c_m`` at all times.
The damping acts on ``s' = delta' - e'`` as seed 002 writes it (``c_i s'``, with ``s`` the
difference between dynamic and static transmission error); the option
``TriboDynamics.damp_relative_rate = False`` puts it on ``delta'`` instead, the form of the
Kahraman-Singh SDOF model of :mod:`models.dynamics.sdof` (the two coincide for a constant
``e``, e.g. the shipped cases, which have no error). The sliding
friction force of pair ``i`` acts along ``y`` (seed 002's ``F_f = lambda f F_d``):

.. math:: F_{fi} = \mu_i \max(N_i, 0), \qquad \mu_i = \lambda_i f_i,

with ``mu_i`` the *signed* mixed-EHL friction coefficient of
:func:`models.ehl.mixed_contact` (``lambda = sign(u_p - u_g)``: negative in approach, positive in
recess, changing sign at the pitch point). Its arms are the profile radii of curvature of the
contact point, ``rho_pi = s_i`` and ``rho_gi = T_1T_2 - s_i`` (``s`` measured from T1).

Equations of motion (Newton; bearings as springs/dampers ``k_b, c_b`` per direction):

.. math::

    I_p\ddot\theta_p = T_p - r_{bp}\textstyle\sum N_i - \sum F_{fi}\rho_{pi}, \qquad
    I_g\ddot\theta_g = r_{bg}\textstyle\sum N_i + \sum F_{fi}\rho_{gi} - T_g,

    m_p\ddot x_p + c_{bx}\dot x_p + k_{bx}x_p = -\textstyle\sum N_i, \qquad
    m_g\ddot x_g + c_{bx}\dot x_g + k_{bx}x_g = +\textstyle\sum N_i,

    m_p\ddot y_p + c_{by}\dot y_p + k_{by}y_p = -\textstyle\sum F_{fi}, \qquad
    m_g\ddot y_g + c_{by}\dot y_g + k_{by}y_g = +\textstyle\sum F_{fi},

which are seed 002's ``x`` and ``y`` equations term by term. The rotations enter only through
``q = r_bp theta_p - r_bg theta_g`` (the rigid-body rotation at constant speed is eliminated,
as the seed does with its DTE equation and equivalent mass ``m_e``); with
``T_g = T_p r_bg / r_bp`` (nominal load ``W_0 = T_p / r_bp``):

.. math:: \ddot q = \frac{W_0 - \sum N_i}{m_e}
          - \sum_i F_{fi}\left(\frac{r_{bp}\rho_{pi}}{I_p} + \frac{r_{bg}\rho_{gi}}{I_g}\right),
          \qquad m_e = \frac{I_p I_g}{I_g r_{bp}^2 + I_p r_{bg}^2}.

State ``(q, x_p, x_g, y_p, y_g)`` and velocities: ten first-order equations. With rigid
bearings the translations are held at zero, and with ``mu = 0`` and ``k_h = inf`` the model
is exactly the SDOF model ``m_e q'' + c_m q' + k(t) D(q - e) = W_0`` of
:mod:`models.dynamics.sdof` when the damping is on the DTE rate (``damp_relative_rate =
False``; tested numerically), and ``m_e s'' + c_m s' + k(t) D(s) = W_0 - m_e e''`` (seed 002's
DTE equation) with the default.

Choices where the seed is silent or garbled:

* the mesh excitation is parametric at the nominal speed: tooth-pair positions, mesh
  stiffness, arms, film stiffness and friction are periodic tables over one mesh period, not
  functions of the vibration (the vibration velocities are mm/s against m/s of rolling);
* the friction normal force is the compressive part ``max(N_i, 0)`` of the pair load (a pair
  that separates carries no friction); the viscous mesh damping acts at all times
  (Kahraman-Singh), so the mesh force may be slightly tensile just after separation;
* the mean friction torque is not balanced by the output torque (the drive holds the speed);
  only its fluctuation about the rigid-body motion is modelled, through ``q``.

Time integration (compiled RK4 to the periodic steady state, the plain-Python reference) is in
:mod:`models.dynamics.tribo_integrate`; :func:`tribo_rhs` is the right-hand side in plain
Python that :meth:`TriboDynamics.ode` and the reference evaluate.

References
----------
.. [1] Seed 002: six-DOF tribo-dynamic model of a spur pair with mixed EHL (aerospace pair,
   28/28 teeth, m = 3.175 mm).
.. [2] A. Kahraman, R. Singh, J. Sound Vib. 142 (1990) 49-75 (dead-zone backlash).
.. [3] S. Li, A. Kahraman, "A tribo-dynamic model of a spur gear pair", J. Sound Vib. 332
   (2013) 4963-4978 (the structure followed by seed 002).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from models.errors import ModelError
from models.geometry.gear_pair import GearPair
from models.stiffness.mesh_cycle import prepare_mesh_cycle, tabulate_compliance
from models.stiffness.potential_energy import pair_compliance

__all__ = [
    "N_STATE",
    "TriboDynamics",
    "auto_steps_per_period",
    "build_tribo_dynamics",
    "series_stiffness",
    "static_state",
    "tribo_rhs",
]

#: Length of the state vector ``(q, x_p, x_g, y_p, y_g, q', x_p', x_g', y_p', y_g')``.
N_STATE = 10


def series_stiffness(k_mesh_N_m: np.ndarray, k_film_N_m: np.ndarray) -> np.ndarray:
    """Seed 002's comprehensive stiffness ``k = k_m k_h / (k_m + k_h)`` (N/m).

    ``k_h = inf`` (rigid film) gives ``k_m``; ``k_m = 0`` (pair not in contact) gives 0.
    """
    km = np.asarray(k_mesh_N_m, float)
    kh = np.asarray(k_film_N_m, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        k = 1.0 / (1.0 / km + 1.0 / kh)
    return np.where(km > 0, np.where(np.isinf(kh), km, k), 0.0)


@dataclass(frozen=True)
class TriboDynamics:
    """Six-DOF tribo-dynamic model over one mesh period (SI units; equations in the module doc).

    Tables have ``2 N`` rows: row ``j`` is time ``j T_m / (2N)`` (cycle phase ``j / 2N``), the
    half steps of the RK4 with ``N`` steps per mesh period; columns are tooth-pair slots.

    Attributes
    ----------
    mesh_period_s : float
        Mesh period ``T_m`` (s).
    load_N : float
        Nominal normal load ``W_0 = T_p / r_bp`` (N).
    base_radius_p_m, base_radius_g_m : float
        ``r_bp``, ``r_bg`` (m).
    mass_p_kg, mass_g_kg : float
        Masses (kg).
    inertia_p_kgm2, inertia_g_kgm2 : float
        Polar moments of inertia (kg m^2).
    bearing_stiffness_x_N_m, bearing_stiffness_y_N_m : float
        Bearing stiffness along / across the line of action (N/m), same for both gears.
    bearing_damping_x_Ns_m, bearing_damping_y_Ns_m : float
        Bearing damping (N s/m).
    mesh_damping_Ns_m : float
        Total mesh damping ``c_m`` on the DTE (N s/m).
    half_backlash_m : float
        Half gap ``b`` on the line of action (m), >= 0.
    mesh_stiffness_N_m : numpy.ndarray
        ``k_mi`` per slot, ``(2N, n_slots)`` (N/m); 0 where the pair is not in contact.
    film_stiffness_N_m : numpy.ndarray
        ``k_hi`` per slot (N/m); ``inf`` is a rigid film.
    friction : numpy.ndarray
        Signed friction coefficient ``mu_i = lambda_i f_i`` per slot (-).
    arm_p_m, arm_g_m : numpy.ndarray
        Friction arms ``rho_pi``, ``rho_gi`` per slot (m).
    error_m : numpy.ndarray
        Static transmission error ``e`` at the half steps, ``(2N,)`` (m).
    positions_m : numpy.ndarray
        Positions of the slots on the line of action from T1, ``(2N, n_slots)`` (m); NaN in a
        hand-made model without geometry.
    rigid_bearings : bool
        Hold the translations at zero (infinitely stiff bearings).
    damp_relative_rate : bool
        True (default, seed 002): the mesh damping acts on ``s' = delta' - e'``, the rate of
        the seed's ``s = delta - e``; False: on the DTE rate ``delta'`` (the Kahraman-Singh
        form of :mod:`models.dynamics.sdof`). The two coincide when ``e`` is constant, as in
        the shipped cases (seed 002 gives no error amplitudes).
    """

    mesh_period_s: float
    load_N: float
    base_radius_p_m: float
    base_radius_g_m: float
    mass_p_kg: float
    mass_g_kg: float
    inertia_p_kgm2: float
    inertia_g_kgm2: float
    bearing_stiffness_x_N_m: float
    bearing_stiffness_y_N_m: float
    bearing_damping_x_Ns_m: float
    bearing_damping_y_Ns_m: float
    mesh_damping_Ns_m: float
    half_backlash_m: float
    mesh_stiffness_N_m: np.ndarray
    film_stiffness_N_m: np.ndarray
    friction: np.ndarray
    arm_p_m: np.ndarray
    arm_g_m: np.ndarray
    error_m: np.ndarray
    positions_m: np.ndarray
    rigid_bearings: bool = False
    damp_relative_rate: bool = True

    def __post_init__(self) -> None:
        km = np.asarray(self.mesh_stiffness_N_m)
        if km.ndim != 2 or km.shape[0] < 8 or km.shape[0] % 2:
            raise ModelError(
                f"TriboDynamics tables must be (2N, n_slots) with N >= 4, got shape {km.shape}"
            )
        for name in ("film_stiffness_N_m", "friction", "arm_p_m", "arm_g_m", "positions_m"):
            if np.shape(getattr(self, name)) != km.shape:
                raise ModelError(
                    f"`{name}` must have the shape {km.shape} of the mesh "
                    f"stiffness table, got {np.shape(getattr(self, name))}"
                )
        if np.shape(self.error_m) != (km.shape[0],):
            raise ModelError(f"`error_m` must have shape ({km.shape[0]},)")
        if not (np.all(km >= 0) and np.all(np.asarray(self.film_stiffness_N_m) > 0)):
            raise ModelError("mesh stiffness must be >= 0 and film stiffness > 0 (inf allowed)")
        positive = (
            "mesh_period_s",
            "base_radius_p_m",
            "base_radius_g_m",
            "mass_p_kg",
            "mass_g_kg",
            "inertia_p_kgm2",
            "inertia_g_kgm2",
        )
        for name in positive:
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ModelError(f"`{name}` must be finite and > 0, was {v!r}")
        for name in (
            "bearing_stiffness_x_N_m",
            "bearing_stiffness_y_N_m",
            "bearing_damping_x_Ns_m",
            "bearing_damping_y_Ns_m",
            "mesh_damping_Ns_m",
            "half_backlash_m",
        ):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ModelError(f"`{name}` must be finite and >= 0, was {v!r}")

    # --- derived -------------------------------------------------------------------------
    @property
    def steps_per_period(self) -> int:
        """RK4 steps per mesh period ``N``."""
        return int(np.shape(self.mesh_stiffness_N_m)[0] // 2)

    @property
    def step_s(self) -> float:
        """RK4 step ``h = T_m / N`` (s)."""
        return self.mesh_period_s / self.steps_per_period

    @property
    def equivalent_mass_kg(self) -> float:
        """``m_e = I_p I_g / (I_g r_bp^2 + I_p r_bg^2)`` (kg), seed 002."""
        Ip, Ig = self.inertia_p_kgm2, self.inertia_g_kgm2
        return Ip * Ig / (Ig * self.base_radius_p_m**2 + Ip * self.base_radius_g_m**2)

    @property
    def combined_stiffness_N_m(self) -> np.ndarray:  # noqa: N802 (unit in the name)
        """``k_i`` per slot at the half steps (N/m): mesh and film in series."""
        return series_stiffness(self.mesh_stiffness_N_m, self.film_stiffness_N_m)

    def params(self) -> np.ndarray:
        """Scalar parameters for the kernels, in their order."""
        return np.array(
            [
                self.load_N,
                self.equivalent_mass_kg,
                self.base_radius_p_m,
                self.base_radius_g_m,
                self.inertia_p_kgm2,
                self.inertia_g_kgm2,
                self.mass_p_kg,
                self.mass_g_kg,
                self.bearing_stiffness_x_N_m,
                self.bearing_stiffness_y_N_m,
                self.bearing_damping_x_Ns_m,
                self.bearing_damping_y_Ns_m,
                self.mesh_damping_Ns_m,
                self.half_backlash_m,
                1.0 if self.rigid_bearings else 0.0,
            ],
            float,
        )

    @property
    def error_rate_m_s(self) -> np.ndarray:
        """``de/dt`` at the half steps (m/s): spectral derivative of the periodic ``error_m``.

        Exact for an error given as a Fourier series below the table's Nyquist harmonic (seed
        002 models ``e(t)`` as a Fourier series); the Nyquist harmonic is dropped.
        """
        e = np.asarray(self.error_m, float)
        n2 = e.size
        spec = np.fft.rfft(e)
        harm = np.arange(spec.size)
        if n2 % 2 == 0:
            harm[-1] = 0
        return np.fft.irfft(spec * (2j * math.pi * harm / self.mesh_period_s), n2)

    def tables(self) -> tuple[np.ndarray, ...]:
        """``(k, mu, rho_p, rho_g, e, e_damped)`` as contiguous float arrays for the kernels.

        ``e_damped`` is the error rate the mesh damping subtracts from the DTE rate:
        :attr:`error_rate_m_s` when :attr:`damp_relative_rate`, else zeros.
        """
        c = np.ascontiguousarray
        ed = self.error_rate_m_s if self.damp_relative_rate else np.zeros(np.shape(self.error_m))
        return (
            c(self.combined_stiffness_N_m, float),
            c(self.friction, float),
            c(self.arm_p_m, float),
            c(self.arm_g_m, float),
            c(self.error_m, float),
            c(ed, float),
        )

    def with_lubrication(
        self, film_stiffness_N_m: np.ndarray, friction: np.ndarray
    ) -> TriboDynamics:
        """The same model with new film-stiffness and friction tables."""
        return replace(
            self,
            film_stiffness_N_m=np.asarray(film_stiffness_N_m, float),
            friction=np.asarray(friction, float),
        )

    def ode(self) -> Callable[[float, np.ndarray], np.ndarray]:
        """Right-hand side ``f(t, y)`` at continuous time ``t`` (s) for ``solve_ivp``.

        The tables are interpolated linearly and periodically between the half steps, so at
        the half steps this is exactly the right-hand side the RK4 kernels evaluate.
        """
        n2 = np.shape(self.error_m)[0]
        T = self.mesh_period_s
        k, mu, a1, a2, e, ed = self.tables()
        p = self.params().tolist()

        def f(t: float, y: np.ndarray) -> np.ndarray:
            pos = (t / T * n2) % n2
            j0 = math.floor(pos) % n2
            j1 = (j0 + 1) % n2
            w = pos - math.floor(pos)
            kk, mm, aa1, aa2 = (((1 - w) * a[j0] + w * a[j1])[None, :] for a in (k, mu, a1, a2))
            ee = [(1 - w) * e[j0] + w * e[j1]]
            eed = [(1 - w) * ed[j0] + w * ed[j1]]
            dy = np.empty(N_STATE)
            tribo_rhs(np.asarray(y, float), 0, kk, mm, aa1, aa2, ee, eed, p, dy)
            return dy

        return f


def static_state(model: TriboDynamics) -> np.ndarray:
    """Static equilibrium at the mean combined stiffness, no friction (a start for settling).

    ``delta_s = b + W_0 / k_mean + mean(e)``; bearings deflect by ``W_0 / k_bx`` (pinion back
    along the line of action, wheel forward); velocities zero.
    """
    k_mean = float(np.mean(model.combined_stiffness_N_m.sum(axis=1)))
    if not k_mean > 0:
        raise ModelError("the model has no mesh stiffness")
    delta = model.half_backlash_m + model.load_N / k_mean + float(np.mean(model.error_m))
    y = np.zeros(N_STATE)
    if not model.rigid_bearings and model.bearing_stiffness_x_N_m > 0:
        xb = model.load_N / model.bearing_stiffness_x_N_m
        y[1], y[2] = -xb, xb
    y[0] = delta - y[1] + y[2]
    return y


def tribo_rhs(y, j, K, MU, A1, A2, E, ED, p, dy) -> None:
    """Right-hand side of the ten first-order equations (module docstring), in plain Python.

    The plain-Python twin of the compiled right-hand side of
    :mod:`models.dynamics.tribo_integrate` (same operations, same order); used by
    :meth:`TriboDynamics.ode` and :func:`~models.dynamics.tribo_integrate.tribo_periods_reference`.

    Parameters
    ----------
    y : sequence of float
        State ``(q, x_p, x_g, y_p, y_g)`` and velocities (m, m/s), length 10.
    j : int
        Row of the tables (half step) to evaluate at.
    K, MU, A1, A2 : sequence of sequences of float
        Rows of :meth:`TriboDynamics.tables`: combined stiffness ``k_i`` (N/m), signed friction
        ``mu_i`` (-), arms ``rho_pi``, ``rho_gi`` (m), per slot.
    E, ED : sequence of float
        Static transmission error (m) and the error rate the damping subtracts (m/s).
    p : sequence of float
        :meth:`TriboDynamics.params`.
    dy : mutable sequence of float
        Receives the derivatives (m/s, m/s^2), length 10.
    """
    W0, me, r1, r2, I1, I2 = p[0], p[1], p[2], p[3], p[4], p[5]
    mp, mg, kbx, kby, cbx, cby, cm, b = p[6], p[7], p[8], p[9], p[10], p[11], p[12], p[13]
    d = y[0] + y[1] - y[2]
    dd = y[5] + y[6] - y[7] - ED[j]
    u = d - E[j]
    f = u - b if u > b else (u + b if u < -b else 0.0)
    Kj, MUj, A1j, A2j = K[j], MU[j], A1[j], A2[j]
    ns = len(Kj)
    ksum = 0.0
    for i in range(ns):
        ksum += Kj[i]
    ftot = ffr = tfr = 0.0
    for i in range(ns):
        ki = Kj[i]
        if ki > 0.0:
            ni = ki * f + cm * ki / ksum * dd
            ftot += ni
            if ni > 0.0:
                fr = MUj[i] * ni
                ffr += fr
                tfr += fr * (r1 * A1j[i] / I1 + r2 * A2j[i] / I2)
    for i in range(5):
        dy[i] = y[i + 5]
    dy[5] = (W0 - ftot) / me - tfr
    if p[14] > 0.5:
        dy[6] = dy[7] = dy[8] = dy[9] = 0.0
    else:
        dy[6] = (-cbx * y[6] - kbx * y[1] - ftot) / mp
        dy[7] = (-cbx * y[7] - kbx * y[2] + ftot) / mg
        dy[8] = (-cby * y[8] - kby * y[3] - ffr) / mp
        dy[9] = (-cby * y[9] - kby * y[4] + ffr) / mg


# ----------------------------------------------------------------------------- builder
def auto_steps_per_period(
    mesh_period_s: float, highest_rad_s: float, max_omega_h: float = 0.5, multiple: int = 128
) -> int:
    """Steps per mesh period so that ``omega_max h <= max_omega_h``, a multiple of ``multiple``.

    RK4 is stable to ``omega h = 2.8``; at 0.5 its amplitude error per step on the stiffest
    (bearing) mode is about ``(omega h)^6 / 144 = 1e-4``. The multiple lets the EHL be sampled
    at ``multiple`` equally spaced steps (:mod:`models.dynamics.tribo_ehl_coupling`).
    """
    n = math.ceil(mesh_period_s * highest_rad_s / max_omega_h / multiple)
    return int(multiple) * max(1, n)


def build_tribo_dynamics(
    pair: GearPair,
    *,
    torque_Nm: float,
    pinion_speed_rpm: float,
    mass_p_kg: float,
    mass_g_kg: float,
    inertia_p_kgm2: float,
    inertia_g_kgm2: float,
    bearing_stiffness_x_N_m: float,
    bearing_stiffness_y_N_m: float,
    bearing_damping_ratio: float,
    mesh_damping_ratio: float,
    half_backlash_m: float,
    compliance=None,
    steps_per_period: int | None = None,
    rigid_bearings: bool = False,
) -> TriboDynamics:
    """The six-DOF model of a gear pair with dry, frictionless contact (``k_h = inf``, ``mu = 0``).

    Parameters
    ----------
    pair : GearPair
    torque_Nm : float
        Pinion torque ``T_p`` (N m), > 0 (drive-side contact); ``W_0 = T_p / r_bp``.
    pinion_speed_rpm : float
        Pinion speed (rpm); mesh period ``60 / (z_p n)``.
    mass_p_kg, mass_g_kg, inertia_p_kgm2, inertia_g_kgm2 : float
        Masses (kg) and polar inertias (kg m^2).
    bearing_stiffness_x_N_m, bearing_stiffness_y_N_m : float
        Bearing stiffness along / across the line of action (N/m).
    bearing_damping_ratio : float
        ``c_b = 2 zeta_b sqrt(k_b m)`` per gear and direction, with ``m`` the mean of the
        two masses (seed 002 gives no bearing damping).
    mesh_damping_ratio : float
        ``c_m = 2 zeta sqrt(k_mean m_e)`` with ``k_mean`` the cycle mean of the dry mesh
        stiffness (seed 002: damping ratio 0.1); fixed through the decoupling loop.
    half_backlash_m : float
        Half gap on the line of action (m).
    compliance : callable, optional
        Tooth-pair compliance ``C(s)`` (m/N); default the potential-energy model of
        :func:`models.stiffness.potential_energy.pair_compliance` (with Hertz), tabulated.
    steps_per_period : int, optional
        RK4 steps per mesh period; default :func:`auto_steps_per_period` on the bearing and
        mesh modes.
    rigid_bearings : bool
        Infinitely stiff bearings (translations held at zero).

    Raises
    ------
    ModelError
        A non-positive torque, mass or inertia, or a negative stiffness, damping ratio or
        backlash.
    """
    for name, v, strict in (
        ("torque_Nm", torque_Nm, True),
        ("mass_p_kg", mass_p_kg, True),
        ("mass_g_kg", mass_g_kg, True),
        ("inertia_p_kgm2", inertia_p_kgm2, True),
        ("inertia_g_kgm2", inertia_g_kgm2, True),
        ("bearing_stiffness_x_N_m", bearing_stiffness_x_N_m, False),
        ("bearing_stiffness_y_N_m", bearing_stiffness_y_N_m, False),
        ("bearing_damping_ratio", bearing_damping_ratio, False),
        ("mesh_damping_ratio", mesh_damping_ratio, False),
        ("half_backlash_m", half_backlash_m, False),
    ):
        if not (math.isfinite(v) and (v > 0 if strict else v >= 0)):
            raise ModelError(f"`{name}` must be finite and {'>' if strict else '>='} 0, was {v!r}")
    if compliance is None:
        compliance = tabulate_compliance(
            pair, lambda s: pair_compliance(pair, s).total_m_per_N, 201
        )
    if not (math.isfinite(pinion_speed_rpm) and pinion_speed_rpm > 0):
        raise ModelError(f"`pinion_speed_rpm` must be > 0, was {pinion_speed_rpm!r}")
    T = pair.mesh_period(pinion_speed_rpm)
    r1, r2 = pair.base_radius(1), pair.base_radius(2)
    me = inertia_p_kgm2 * inertia_g_kgm2 / (inertia_g_kgm2 * r1**2 + inertia_p_kgm2 * r2**2)
    # a coarse cycle to size the step from the stiffest mode
    geo0 = prepare_mesh_cycle(pair, compliance, n_phases=64, corner_contact=False)
    kmax = float(np.where(geo0.in_path, 1 / geo0.compliance_m_N, 0).sum(axis=1).max())
    m_min = min(mass_p_kg, mass_g_kg)
    kb = 0.0 if rigid_bearings else max(bearing_stiffness_x_N_m, bearing_stiffness_y_N_m)
    w_max = math.sqrt(kmax / me + (kb + kmax) / m_min)
    n = int(steps_per_period) if steps_per_period is not None else auto_steps_per_period(T, w_max)
    if n < 4:
        raise ModelError(f"`steps_per_period` must be >= 4, was {steps_per_period!r}")
    geo = prepare_mesh_cycle(pair, compliance, n_phases=2 * n, corner_contact=False)
    km = np.where(geo.in_path, 1.0 / geo.compliance_m_N, 0.0)
    s = geo.positions_m
    k_mean = float(km.sum(axis=1).mean())
    m_mean = 0.5 * (mass_p_kg + mass_g_kg)

    def c_b(k: float) -> float:
        return 2 * bearing_damping_ratio * math.sqrt(k * m_mean)

    return TriboDynamics(
        mesh_period_s=T,
        load_N=float(torque_Nm) / r1,
        base_radius_p_m=r1,
        base_radius_g_m=r2,
        mass_p_kg=float(mass_p_kg),
        mass_g_kg=float(mass_g_kg),
        inertia_p_kgm2=float(inertia_p_kgm2),
        inertia_g_kgm2=float(inertia_g_kgm2),
        bearing_stiffness_x_N_m=float(bearing_stiffness_x_N_m),
        bearing_stiffness_y_N_m=float(bearing_stiffness_y_N_m),
        bearing_damping_x_Ns_m=c_b(bearing_stiffness_x_N_m),
        bearing_damping_y_Ns_m=c_b(bearing_stiffness_y_N_m),
        mesh_damping_Ns_m=2 * mesh_damping_ratio * math.sqrt(k_mean * me),
        half_backlash_m=float(half_backlash_m),
        mesh_stiffness_N_m=km,
        film_stiffness_N_m=np.full(km.shape, np.inf),
        friction=np.zeros(km.shape),
        arm_p_m=s.copy(),
        arm_g_m=pair.line_of_action_length - s,
        error_m=np.zeros(2 * n),
        positions_m=s.copy(),
        rigid_bearings=bool(rigid_bearings),
    )

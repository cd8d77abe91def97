r"""Two-stage torsional gear model with backlash, non-dimensional (seed 001, two-stage model).

Physical model (seed 001): four rigid gears, torsion only; gears 2 and 3 sit on one rigid
intermediate shaft (``theta_3 = theta_2``, inertia ``J_23 = J_2 + J_3``); input torque ``T_1``
on gear 1, load ``T_2`` on gear 4. Mesh forces on the lines of action

.. math:: P_{12} = k_{12}(t) f(q_1 - e_{12}(t); b_{12}) + c_{12} \dot q_1, \qquad
          P_{34} = k_{34}(t) f(q_3 - e_{34}(t); b_{34}) + c_{34} \dot q_3

with the DTEs ``q_1 = r_1 theta_1 - r_2 theta_2`` and ``q_3 = r_3 theta_2 - r_4 theta_4``
(base radii) and ``f`` the continuous dead zone of :func:`models.dynamics.sdof.dead_zone`
(SEED-NOTES 16, instead of the seed's printed ``h k (x - e)``). The seed's printed six-state
system (states ``q_1, q_1', q_s, q_s', q_3, q_3'``) has a third coordinate, the twist ``q_s``
of the intermediate shaft between gears 2 and 3, coupled linearly (its ``K_12 x_3``,
``(K_21 + K_23) x_3``, ``K_32 x_3``): four gears minus the rigid-body mode. With the seed's
stated assumption of rigid shafts, ``q_s = 0`` and it reduces exactly to the equations below
(derivation in :class:`SixStateSystem`, which also integrates the six states with a finite
shaft stiffness as a plain reference; the tests show the DTEs converge to this model as
``O((omega_n / omega_shaft)^2)``). Newton for ``J_1``, ``J_23``, ``J_4`` and subtracting gives
the reduction to the two relative coordinates (the rigid-body mode drops out):

.. math:: \ddot q_1 + P_{12}/m_1 = r_1 T_1 / J_1 + a P_{34}, \qquad
          \ddot q_3 + P_{34}/m_3 = r_4 T_2 / J_4 + a P_{12}

with ``1/m_1 = r_1^2/J_1 + r_2^2/J_23``, ``1/m_3 = r_3^2/J_23 + r_4^2/J_4``, ``a = r_2 r_3/J_23``.

Scaling: ``x_1 = q_1 / L``, ``x_3 = q_3 / L``, ``tau = omega_n t`` with
``omega_n = sqrt(k_1 / m_1)`` (``k_1`` the mean stiffness of stage 1). Then, with ``'`` for
``d/dtau``, the equations implemented are

.. math::
    x_1'' + g_1 = F_1 + \mu_1 g_3, \qquad x_3'' + g_3 = F_3 + \mu_3 g_1,

    g_1 = 2\zeta_1 x_1' + \kappa_1(\tau)\, f(x_1 - \varepsilon_1(\tau); \beta_1),

    g_3 = 2\zeta_3 \Omega\, x_3' + \Omega^2 \kappa_3(\tau)\, f(x_3 - \varepsilon_3(\tau); \beta_3),

* ``zeta_1 = c_12 / (2 m_1 omega_n)``, ``Omega^2 = k_3 / (m_3 omega_n^2)`` (stage-2 natural
  frequency relative to stage 1), ``zeta_3 = c_34 / (2 m_3 Omega omega_n)``;
* ``mu_1 = a m_3``, ``mu_3 = a m_1`` the coupling through the intermediate shaft
  (``mu_1 mu_3 < 1`` physically; ``mu = 0`` gives two independent SDOF oscillators);
* ``F_1 = r_1 T_1 / (J_1 omega_n^2 L)``, ``F_3 = r_4 T_2 / (J_4 omega_n^2 L)``;
  ``beta_i = b_i / L`` half gaps, ``varepsilon_i = e_i / L``;
* ``kappa_i = k_i(t) / k_i^{mean} = 1 + sum harmonics`` (:class:`Harmonics`) plus the
  optional thermal part ``k_w / k_i^{mean}`` (seed: ``k = k_t + k_w``), also a
  :class:`Harmonics` (a constant thermal stiffness is a series with mean only);
* stage 1 meshes at ``Lambda`` (period ``2 pi / Lambda`` in ``tau``); stage 2 at
  ``(p/q) Lambda`` with ``p/q = z_3/z_2`` reduced, so the excitation repeats every ``q``
  stage-1 mesh periods (one *system period*).

Damping acts on ``x'`` (``c q'``, the relative velocity of the gear bodies). Seed 001's
printed state variable is ``u = q - e`` (its error enters as the forcing
``F_e omega^2 cos(omega t)``, which is ``-e''``) with the damping on ``u'``; the two differ by
the forcing term ``2 zeta eps'``, of the order of ``zeta Lambda eps``. Kept: the mesh
damper acts on the bodies' motion; ``max |u|`` is reported alongside ``max |x|``
(:class:`TwoStageResponse`).

The integrator is the fixed-step RK4 of :mod:`models.dynamics.integrate` with the step a
whole fraction of the stage-1 mesh period; tables of ``kappa`` and ``varepsilon`` at the
``2 q N`` half steps of a system period, compiled (numba, :mod:`models.dynamics.two_stage_kernels`)
and plain-Python reference with the same operations in the same order. The step must keep
``h omega_max <= MAX_STEP_OMEGA`` (= 1) for the stiffest mode over the cycle
(:func:`highest_frequency_bound`, :func:`min_steps_per_period`), else
:class:`~models.errors.ModelError`: a fixed number of steps per mesh period is too few at low
mesh frequency, and RK4 diverges beyond ``h omega = 2.83``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from models.dynamics.checks import as_count
from models.dynamics.two_stage_kernels import rk4_system_periods
from models.errors import ModelError
from models.geometry.inertia import gear_inertia
from models.stiffness.mesh_cycle import Harmonics

__all__ = [
    "MAX_STEP_OMEGA",
    "MeshStage",
    "SixStateSystem",
    "TwoStageModel",
    "TwoStageResponse",
    "highest_frequency_bound",
    "min_steps_per_period",
    "natural_frequencies",
    "rigid_shaft_model",
    "six_state_from_gear_sets",
    "six_state_reference",
    "static_state",
    "two_stage_from_gear_sets",
    "two_stage_periods",
    "two_stage_periods_reference",
    "two_stage_steady_response",
]


def _unit() -> Harmonics:
    return Harmonics(1.0, np.zeros(0), np.zeros(0))


def _zero() -> Harmonics:
    return Harmonics(0.0, np.zeros(0), np.zeros(0))


def _check_mesh_ratio(ratio) -> tuple[int, int]:
    """``(p, q)`` as coprime positive integers, else :class:`ModelError`.

    A non-integer would be truncated by the tables; a common factor (``(2, 4)``) would make
    the tables span ``q`` stage-1 periods where ``q / gcd`` suffice, so a period-1 response
    would be read as one Poincare point per *two* true system periods.
    """
    try:
        p, q = ratio
    except (TypeError, ValueError):
        raise ModelError(f"`mesh_ratio` must be a pair of integers (p, q), was {ratio!r}") from None
    ints = all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) for v in (p, q))
    if not (ints and p >= 1 and q >= 1):
        raise ModelError(f"`mesh_ratio` must be two positive integers (p, q), was {ratio!r}")
    if math.gcd(int(p), int(q)) != 1:
        raise ModelError(
            f"`mesh_ratio` {ratio!r} must be reduced (gcd(p, q) = 1): with a common factor the "
            "system period would be counted as a multiple of the true one"
        )
    return int(p), int(q)


@dataclass(frozen=True)
class MeshStage:
    """One mesh, non-dimensional.

    Attributes
    ----------
    zeta : float
        Damping ratio of the stage (-).
    backlash : float
        Half gap ``beta = b / L`` (-), >= 0; 0 gives a linear spring.
    stiffness : Harmonics
        ``k_t / k_mean`` over the stage's mesh-cycle phase (mean 1 for a normalised series).
    error : Harmonics
        Static transmission error ``e / L`` over the mesh-cycle phase.
    thermal : Harmonics or None
        Temperature stiffness ``k_w / k_mean`` (seed: ``k = k_t + k_w``); ``None``: none.
    """

    zeta: float
    backlash: float
    stiffness: Harmonics = field(default_factory=_unit)
    error: Harmonics = field(default_factory=_zero)
    thermal: Harmonics | None = None

    def __post_init__(self) -> None:
        if not (self.zeta >= 0 and self.backlash >= 0):
            raise ModelError("MeshStage needs zeta >= 0 and backlash >= 0")

    def kappa(self, phase: np.ndarray) -> np.ndarray:
        """``kappa = k_t/k_mean + k_w/k_mean`` at cycle phases ``phase`` (-)."""
        k = np.asarray(self.stiffness(phase), dtype=float)
        if self.thermal is not None:
            k = k + np.asarray(self.thermal(phase), dtype=float)
        return k


@dataclass(frozen=True)
class TwoStageModel:
    """Non-dimensional two-stage model (equations in the module docstring).

    Attributes
    ----------
    stage1, stage2 : MeshStage
    force1, force2 : float
        ``F_1``, ``F_3`` (-).
    omega2 : float
        ``Omega``: stage-2 natural frequency over stage 1's (-), > 0.
    coupling1, coupling2 : float
        ``mu_1`` (stage-2 force in stage-1 equation), ``mu_3`` (the converse).
    mesh_ratio : tuple[int, int]
        ``(p, q)``: stage-2 mesh frequency is ``p/q`` times stage 1's.
    """

    stage1: MeshStage
    stage2: MeshStage
    force1: float
    force2: float
    omega2: float = 1.0
    coupling1: float = 0.0
    coupling2: float = 0.0
    mesh_ratio: tuple[int, int] = (1, 1)

    def __post_init__(self) -> None:
        _check_mesh_ratio(self.mesh_ratio)
        if not self.omega2 > 0:
            raise ModelError("TwoStageModel needs omega2 > 0")
        if not self.coupling1 * self.coupling2 < 1:
            raise ModelError("coupling1 * coupling2 must be < 1 (positive-definite mass)")

    def tables(self, steps_per_period: int) -> np.ndarray:
        """``(4, 2 q N)``: ``kappa_1, eps_1, kappa_3, eps_3`` at the half steps of a system period.

        Half step ``j`` is ``tau = j h / 2``, ``h = 2 pi / (Lambda N)``; stage-1 phase
        ``j / (2N)`` and stage-2 phase ``p j / (2 q N)``, both taken modulo 1 on the integer grid.
        """
        p, q = (int(v) for v in self.mesh_ratio)
        n = int(steps_per_period)
        j = np.arange(2 * q * n)
        ph1 = (j % (2 * n)) / (2 * n)
        ph3 = ((p * j) % (2 * q * n)) / (2 * q * n)
        return np.ascontiguousarray(
            np.vstack(
                [
                    self.stage1.kappa(ph1),
                    self.stage1.error(ph1),
                    self.stage2.kappa(ph3),
                    self.stage2.error(ph3),
                ]
            ),
            dtype=float,
        )

    def params(self) -> np.ndarray:
        """``(zeta1, b1, zeta3, b3, F1, F3, Omega, mu1, mu3)`` for the kernels."""
        s1, s2 = self.stage1, self.stage2
        return np.array(
            [
                s1.zeta,
                s1.backlash,
                s2.zeta,
                s2.backlash,
                self.force1,
                self.force2,
                self.omega2,
                self.coupling1,
                self.coupling2,
            ],
            dtype=float,
        )


#: Largest ``h omega_max`` the fixed-step RK4 is run with (``h`` the step in ``tau``,
#: ``omega_max`` the bound of :func:`highest_frequency_bound`). RK4 is unstable on an
#: undamped mode beyond ``h omega = 2 sqrt(2) = 2.83``; at ``h omega = 1`` it damps that mode
#: by 0.6 % per step and shifts its frequency by 0.6 % (amplification factor
#: ``|1 - z^2/2 + z^4/24 + i (z - z^3/6)|`` at ``z = 1``), less than the 5 % damping per
#: radian the default ``zeta = 0.05`` gives it physically.
MAX_STEP_OMEGA = 1.0


def _kappa_bound(s: MeshStage) -> float:
    """Bound of ``|kappa|`` over the cycle: ``|mean|`` plus the sum of harmonic amplitudes."""
    amp = float(np.sum(np.abs(s.stiffness.amplitude)))
    if s.thermal is not None:
        amp += float(np.sum(np.abs(s.thermal.amplitude)))
    return abs(_mean_kappa(s)) + amp


def _stiffness_matrix(model: TwoStageModel, k1: float, k3: float) -> np.ndarray:
    w, mu1, mu3 = model.omega2, model.coupling1, model.coupling2
    return np.array([[k1, -mu1 * w * w * k3], [-mu3 * k1, w * w * k3]])


def natural_frequencies(model: TwoStageModel) -> np.ndarray:
    """Undamped natural frequencies of the mean-stiffness linearisation, units of ``omega_n``.

    The drive-flank contact linearisation of the module's equations with ``kappa_i`` at its
    mean (thermal mean included): ``x'' + K x = 0``, ``K = [[k_1, -mu_1 Omega^2 k_3],
    [-mu_3 k_1, Omega^2 k_3]]``; returns ``sqrt(eig(K))`` sorted (shape ``(2,)``). These are
    the system's two torsional modes; ``omega_n = sqrt(k_1 / m_1)`` (the scale) is not one
    of them when the stages are coupled. Times ``omega_n / (2 pi)``: Hz.
    """
    k = _stiffness_matrix(model, _mean_kappa(model.stage1), _mean_kappa(model.stage2))
    return np.sort(np.sqrt(np.linalg.eigvals(k).real))


def highest_frequency_bound(model: TwoStageModel) -> float:
    """Bound on the highest natural frequency over the mesh cycle (units of ``omega_n``).

    As :func:`natural_frequencies` with each ``kappa_i`` at its upper bound over the cycle
    (mean plus the sum of the harmonic amplitudes, thermal part included; eigenvalue moduli,
    so an unstable, negative-stiffness mode counts by its growth rate). It grows without
    bound as seed 001's ``k_w`` diverges near the initial temperature, which is why the RK4
    step is chosen from it (:func:`min_steps_per_period`).
    """
    k = _stiffness_matrix(model, _kappa_bound(model.stage1), _kappa_bound(model.stage2))
    return float(np.sqrt(np.max(np.abs(np.linalg.eigvals(k)))))


def min_steps_per_period(model: TwoStageModel, frequency: float) -> int:
    """Fewest RK4 steps per stage-1 mesh period with ``h omega_max <= MAX_STEP_OMEGA``.

    ``h = 2 pi / (Lambda N)``, so ``N >= 2 pi omega_max / (Lambda MAX_STEP_OMEGA)``
    (``frequency`` is ``Lambda``, ``omega_max`` from :func:`highest_frequency_bound`).
    """
    if not frequency > 0:
        raise ModelError(f"`frequency` must be > 0, was {frequency!r}")
    w = highest_frequency_bound(model)
    return max(4, math.ceil(2.0 * math.pi * w / (frequency * MAX_STEP_OMEGA) - 1e-9))


def _setup(model: TwoStageModel, frequency: float, steps_per_period: int):
    n = as_count("steps_per_period", steps_per_period, 4)
    if not frequency > 0:
        raise ModelError("need frequency > 0")
    h = 2.0 * math.pi / (frequency * n)
    hw = h * highest_frequency_bound(model)
    if not hw <= MAX_STEP_OMEGA:
        raise ModelError(
            f"RK4 step too long for the stiffest mode: h omega_max = {hw:.3g} > "
            f"{MAX_STEP_OMEGA} with {n} steps per mesh period at Lambda = {frequency:.4g}; "
            f"use steps_per_period >= {min_steps_per_period(model, frequency)}"
        )
    return model.params(), model.tables(n), h


def two_stage_periods(
    model: TwoStageModel,
    frequency: float,
    y0,
    n_periods: int,
    *,
    steps_per_period: int = 128,
    record: bool = False,
) -> tuple[np.ndarray, np.ndarray | None]:
    """Integrate ``n_periods`` *system* periods (``q`` stage-1 mesh periods each), compiled.

    ``frequency`` is ``Lambda`` (stage-1 mesh frequency over ``omega_n``); ``y0`` is
    ``(x1, x1', x3, x3')``; ``steps_per_period`` counts RK4 steps per stage-1 mesh period.
    Returns the Poincare points ``(n_periods, 4)`` and, with ``record``, ``(x1, u1, x3, u3)``
    at every step start (``u = x - eps``), shape ``(n_periods q N, 4)``.
    """
    P, T, h = _setup(model, frequency, steps_per_period)
    y = np.asarray(y0, dtype=float).reshape(4)
    pts, hist = rk4_system_periods(y, P, T, h, as_count("n_periods", n_periods, 1), bool(record))
    return pts, (hist if record else None)


def two_stage_periods_reference(
    model: TwoStageModel, frequency: float, y0, n_periods: int, *, steps_per_period: int = 128
) -> np.ndarray:
    """Same scheme, same operation order, plain Python: Poincare points ``(n_periods, 4)``."""
    P, T, h = _setup(model, frequency, steps_per_period)
    z1, b1_, z3, b3_, F1, F3, Om, mu1, mu3 = P.tolist()
    K1, E1, K3, E3 = (row.tolist() for row in T)
    m = len(K1) // 2

    def dz(u, b):
        return u - b if u > b else (u + b if u < -b else 0.0)

    def acc(x1, v1, x3, v3, j):
        g1 = 2.0 * z1 * v1 + K1[j] * dz(x1 - E1[j], b1_)
        g3 = 2.0 * z3 * Om * v3 + Om * Om * K3[j] * dz(x3 - E3[j], b3_)
        return F1 - g1 + mu1 * g3, F3 - g3 + mu3 * g1

    x1, v1, x3, v3 = (float(v) for v in np.asarray(y0, dtype=float).reshape(4))
    pts = np.empty((n_periods, 4))
    for s in range(n_periods):
        for j in range(m):
            j0, j1, j2 = 2 * j, 2 * j + 1, (2 * j + 2) % (2 * m)
            a1, c1 = acc(x1, v1, x3, v3, j0)
            x1b, v1b = x1 + 0.5 * h * v1, v1 + 0.5 * h * a1
            x3b, v3b = x3 + 0.5 * h * v3, v3 + 0.5 * h * c1
            a2, c2 = acc(x1b, v1b, x3b, v3b, j1)
            x1c, v1c = x1 + 0.5 * h * v1b, v1 + 0.5 * h * a2
            x3c, v3c = x3 + 0.5 * h * v3b, v3 + 0.5 * h * c2
            a3, c3 = acc(x1c, v1c, x3c, v3c, j1)
            x1d, v1d = x1 + h * v1c, v1 + h * a3
            x3d, v3d = x3 + h * v3c, v3 + h * c3
            a4, c4 = acc(x1d, v1d, x3d, v3d, j2)
            x1, v1, x3, v3 = (
                x1 + h / 6.0 * (v1 + 2.0 * v1b + 2.0 * v1c + v1d),
                v1 + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4),
                x3 + h / 6.0 * (v3 + 2.0 * v3b + 2.0 * v3c + v3d),
                v3 + h / 6.0 * (c1 + 2.0 * c2 + 2.0 * c3 + c4),
            )
        pts[s] = (x1, v1, x3, v3)
    return pts


# ----------------------------------------------------------------------------- steady response
@dataclass(frozen=True)
class TwoStageResponse:
    """Steady response at one mesh frequency (non-dimensional, units of ``L``).

    Index 0 is stage 1, index 1 stage 2.

    Attributes
    ----------
    frequency : float
        ``Lambda`` (-).
    peak : tuple of 2 float
        ``max |x|`` over the recorded RK4 step starts: the peak |DTE| ``q / L``, static
        deflection, half backlash and static error included (seed 001's "maximum amplitude
        of the dynamic transmission error" read as the peak of ``q``). NaN if diverged.
    amplitude : tuple of 2 float
        Half the peak-to-peak of ``x`` (the vibration alone).
    contact_loss, back_contact : tuple of 2 bool
        ``|x - eps| <= beta`` at some recorded step (with ``beta > 0``); ``x - eps < -beta``
        (back-side impact).
    state : numpy.ndarray
        ``(x1, x1', x3, x3')`` at the end.
    history : numpy.ndarray
        ``(x1, u1, x3, u3)`` over the recorded periods, ``u = x - eps``.
    peak_deflection : tuple of 2 float
        ``max |u|``, ``u = x - eps``: seed 001's state variable (its printed equations put
        the error on the right-hand side as ``F_e omega^2 cos``, i.e. they integrate
        ``u = q - e``); NaN if diverged.
    diverged : bool
        The state or the record turned non-finite (NaN/inf): the step is too long for the
        stiffest mode or the model is unstable; all peaks are then NaN.
    """

    frequency: float
    peak: tuple[float, float]
    amplitude: tuple[float, float]
    contact_loss: tuple[bool, bool]
    back_contact: tuple[bool, bool]
    state: np.ndarray
    history: np.ndarray
    peak_deflection: tuple[float, float] = (math.nan, math.nan)
    diverged: bool = False


def two_stage_steady_response(
    model: TwoStageModel,
    frequency: float,
    y0=None,
    *,
    transient_periods: int = 200,
    record_periods: int = 20,
    steps_per_period: int = 128,
) -> TwoStageResponse:
    """Drop ``transient_periods`` system periods, then record ``record_periods`` of them.

    ``y0`` defaults to the static equilibrium with mean stiffness and no error (drive-side
    contact): ``g_1 = (F_1 + mu_1 F_3)/(1 - mu_1 mu_3)``, ``g_3 = F_3 + mu_3 g_1``.
    ``steps_per_period`` must keep ``h omega_max <= MAX_STEP_OMEGA``
    (:func:`min_steps_per_period`), else :class:`~models.errors.ModelError`. A response that
    still turns non-finite is returned with ``diverged`` set and NaN peaks.
    """
    n_trans = as_count("transient_periods", transient_periods, 0)
    n_rec = as_count("record_periods", record_periods, 1)
    if y0 is None:
        y0 = static_state(model)
    start = np.asarray(y0, dtype=float).reshape(4)
    if n_trans > 0:
        pts, _ = two_stage_periods(
            model, frequency, start, n_trans, steps_per_period=steps_per_period
        )
        start = pts[-1]
    pts2, hist = two_stage_periods(
        model, frequency, start, n_rec, steps_per_period=steps_per_period, record=True
    )
    assert hist is not None
    b = (model.stage1.backlash, model.stage2.backlash)
    diverged = not (np.all(np.isfinite(hist)) and np.all(np.isfinite(pts2[-1])))
    nan2 = (math.nan, math.nan)
    if diverged:
        return TwoStageResponse(
            float(frequency),
            nan2,
            nan2,
            (False, False),
            (False, False),
            pts2[-1],
            hist,
            nan2,
            True,
        )
    peak = (float(np.max(np.abs(hist[:, 0]))), float(np.max(np.abs(hist[:, 2]))))
    peak_u = (float(np.max(np.abs(hist[:, 1]))), float(np.max(np.abs(hist[:, 3]))))
    amp = (float(np.ptp(hist[:, 0]) / 2), float(np.ptp(hist[:, 2]) / 2))

    def lost(i: int) -> bool:
        return bool(b[i] > 0 and np.any(np.abs(hist[:, 2 * i + 1]) <= b[i]))

    def behind(i: int) -> bool:
        return bool(np.any(hist[:, 2 * i + 1] < -b[i]))

    loss = (lost(0), lost(1))
    back = (behind(0), behind(1))
    return TwoStageResponse(float(frequency), peak, amp, loss, back, pts2[-1], hist, peak_u)


def static_state(model: TwoStageModel) -> np.ndarray:
    """Static equilibrium ``(x1, 0, x3, 0)`` at mean stiffness (thermal mean included), no error."""
    mu1, mu3 = model.coupling1, model.coupling2
    g1 = (model.force1 + mu1 * model.force2) / (1 - mu1 * mu3)
    g3 = model.force2 + mu3 * g1
    k1 = _mean_kappa(model.stage1)
    k3 = _mean_kappa(model.stage2)
    x1 = g1 / k1
    x3 = g3 / (model.omega2**2 * k3)
    x1 += math.copysign(model.stage1.backlash, x1)
    x3 += math.copysign(model.stage2.backlash, x3)
    return np.array([x1, 0.0, x3, 0.0])


def _mean_kappa(s: MeshStage) -> float:
    return s.stiffness.mean + (s.thermal.mean if s.thermal is not None else 0.0)


# ----------------------------------------------------------------------------- six states
@dataclass(frozen=True)
class SixStateSystem:
    r"""Seed 001's six-state system, dimensional: four gears, flexible intermediate shaft.

    The seed's state vector is ``(x_1, ..., x_6) = (q_1, q_1', q_s, q_s', q_3, q_3')``: the
    stage-1 DTE, the twist ``q_s = theta_2 - theta_3`` of the intermediate shaft between gears
    2 and 3, and the stage-2 DTE ``q_3 = r_3 theta_3 - r_4 theta_4``. Newton for
    ``J_1 .. J_4`` with the shaft torque ``S = k_s q_s + c_s q_s'`` gives

    .. math::
        \ddot q_1 + P_{12}\left(\tfrac{r_1^2}{J_1} + \tfrac{r_2^2}{J_2}\right)
            &= \tfrac{r_1 T_1}{J_1} + \tfrac{r_2}{J_2} S, \\
        \ddot q_s + S\left(\tfrac{1}{J_2} + \tfrac{1}{J_3}\right)
            &= \tfrac{r_2}{J_2} P_{12} + \tfrac{r_3}{J_3} P_{34}, \\
        \ddot q_3 + P_{34}\left(\tfrac{r_3^2}{J_3} + \tfrac{r_4^2}{J_4}\right)
            &= \tfrac{r_4 T_2}{J_4} + \tfrac{r_3}{J_3} S,

    term for term the seed's printed system: ``dx_2/dt`` holds ``f_12`` and the linear
    ``K_12 x_3`` (shaft) but no ``f_34``; ``dx_4/dt`` holds ``-(K_21 + K_23) x_3`` with both
    backlash functions; ``dx_6/dt`` holds ``f_34`` and ``K_32 x_3``; the cross-damping terms
    ``xi_12 x_4``, ``xi_21 x_2``, ``xi_22 x_6``, ``xi_32 x_4`` are the shaft and mesh dampings.
    The rigid-body rotation is the fourth coordinate that drops out. The seed also states
    "shafts and bearings are assumed to be rigid": ``k_s -> inf`` forces ``q_s = 0`` and the
    shaft torque to ``S = (J_3 r_2 P_12 + J_2 r_3 P_34)/(J_2 + J_3)``; put into the first and
    third equations this is exactly the two-coordinate model of this module with
    ``J_23 = J_2 + J_3`` (:func:`rigid_shaft_model`). The six-state form is integrated here
    in a plain reference (:func:`six_state_reference`, scipy's DOP853) so that the reduction
    is checked numerically; the compiled kernels use the rigid-shaft reduction.

    Attributes
    ----------
    inertia_kg_m2 : tuple of 4 float
        ``J_1 .. J_4`` (kg m^2).
    base_radius_m : tuple of 4 float
        ``r_1 .. r_4`` (m), lever arms on the lines of action.
    mesh_stiffness_N_m : tuple of 2 float
        Mean mesh stiffnesses ``k_12``, ``k_34`` (N/m); ``k(t) = k_mean kappa(t)``.
    mesh_damping_N_s_m : tuple of 2 float
        ``c_12``, ``c_34`` (N s/m).
    shaft_stiffness_Nm_rad, shaft_damping_Nms_rad : float
        Intermediate shaft ``k_s`` (N m/rad; ``math.inf`` for the rigid shaft of the seed's
        assumption, reduction only) and ``c_s`` (N m s/rad).
    half_backlash_m : tuple of 2 float
        ``b_12``, ``b_34`` (m).
    input_torque_Nm, load_torque_Nm : float
        ``T_1`` on gear 1 and ``T_2`` on gear 4 (N m).
    stiffness, error_m, thermal : tuples of 2
        Normalised stiffness ``k_t / k_mean`` and thermal ``k_w / k_mean`` series, and the
        static transmission errors in metres, over each stage's mesh-cycle phase.
    mesh_ratio : tuple[int, int]
        ``(p, q)``: stage-2 mesh frequency is ``p/q`` times stage 1's.
    """

    inertia_kg_m2: tuple[float, float, float, float]
    base_radius_m: tuple[float, float, float, float]
    mesh_stiffness_N_m: tuple[float, float]
    mesh_damping_N_s_m: tuple[float, float]
    shaft_stiffness_Nm_rad: float
    shaft_damping_Nms_rad: float
    half_backlash_m: tuple[float, float]
    input_torque_Nm: float
    load_torque_Nm: float
    stiffness: tuple[Harmonics, Harmonics] = (_unit(), _unit())
    error_m: tuple[Harmonics, Harmonics] = (_zero(), _zero())
    thermal: tuple[Harmonics | None, Harmonics | None] = (None, None)
    mesh_ratio: tuple[int, int] = (1, 1)

    def __post_init__(self) -> None:
        vals = (*self.inertia_kg_m2, *self.base_radius_m, *self.mesh_stiffness_N_m)
        if not all(v > 0 and math.isfinite(v) for v in vals):
            raise ModelError("SixStateSystem needs finite positive inertias, radii, stiffnesses")
        if not self.shaft_stiffness_Nm_rad > 0:
            raise ModelError("`shaft_stiffness_Nm_rad` must be > 0 (math.inf: rigid shaft)")
        if min(*self.mesh_damping_N_s_m, self.shaft_damping_Nms_rad, *self.half_backlash_m) < 0:
            raise ModelError("SixStateSystem needs damping and backlash >= 0")
        _check_mesh_ratio(self.mesh_ratio)


def _stage(h: Harmonics | None, ph):
    return 0.0 if h is None else float(h(ph))


def six_state_reference(
    system: SixStateSystem,
    mesh_frequency_rad_s: float,
    y0,
    t_s,
    *,
    rtol: float = 1e-10,
    atol: float = 1e-16,
    max_steps_per_period: int = 64,
) -> np.ndarray:
    """Integrate the six-state system (class docstring) with scipy's DOP853, plain Python.

    ``mesh_frequency_rad_s`` is the stage-1 mesh frequency (rad/s; stage 1 at phase 0 at
    ``t = 0``, stage 2 at ``p/q`` of it); ``y0`` is ``(q1, q1', qs, qs', q3, q3')`` in
    (m, m/s, rad, rad/s, m, m/s); ``t_s`` the output times (s, increasing, from 0).
    Returns the states at ``t_s``, shape ``(len(t_s), 6)``. The step is limited to
    ``1 / max_steps_per_period`` of a stage-1 mesh period so the backlash kinks are resolved.
    """
    from scipy.integrate import solve_ivp

    sy = system
    if not math.isfinite(sy.shaft_stiffness_Nm_rad):
        raise ModelError("six_state_reference needs a finite shaft stiffness")
    J1, J2, J3, J4 = sy.inertia_kg_m2
    r1, r2, r3, r4 = sy.base_radius_m
    k1, k3 = sy.mesh_stiffness_N_m
    c1, c3 = sy.mesh_damping_N_s_m
    ks, cs = sy.shaft_stiffness_Nm_rad, sy.shaft_damping_Nms_rad
    b1, b3 = sy.half_backlash_m
    p, q = sy.mesh_ratio
    w = float(mesh_frequency_rad_s)

    def dz(u: float, b: float) -> float:
        return u - b if u > b else (u + b if u < -b else 0.0)

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        ph1 = (w * t / (2 * math.pi)) % 1.0
        ph3 = (p * w * t / (2 * math.pi * q)) % 1.0
        kap1 = float(sy.stiffness[0](ph1)) + _stage(sy.thermal[0], ph1)
        kap3 = float(sy.stiffness[1](ph3)) + _stage(sy.thermal[1], ph3)
        P12 = k1 * kap1 * dz(y[0] - float(sy.error_m[0](ph1)), b1) + c1 * y[1]
        P34 = k3 * kap3 * dz(y[4] - float(sy.error_m[1](ph3)), b3) + c3 * y[5]
        S = ks * y[2] + cs * y[3]
        a1 = sy.input_torque_Nm * r1 / J1 + r2 / J2 * S - P12 * (r1**2 / J1 + r2**2 / J2)
        a_s = r2 / J2 * P12 + r3 / J3 * P34 - S * (1 / J2 + 1 / J3)
        a3 = sy.load_torque_Nm * r4 / J4 + r3 / J3 * S - P34 * (r3**2 / J3 + r4**2 / J4)
        return np.array([y[1], a1, y[3], a_s, y[5], a3])

    t = np.asarray(t_s, dtype=float)
    sol = solve_ivp(
        rhs,
        (0.0, float(t[-1])),
        np.asarray(y0, dtype=float).reshape(6),
        method="DOP853",
        t_eval=t,
        rtol=rtol,
        atol=atol,
        max_step=2 * math.pi / (w * max_steps_per_period),
    )
    if not sol.success:
        raise ModelError(f"six_state_reference failed: {sol.message}")
    return np.asarray(sol.y.T)


def rigid_shaft_model(
    system: SixStateSystem, length_scale_m: float | None = None
) -> tuple[TwoStageModel, dict]:
    """The seed's rigid-shaft limit of ``system``: the non-dimensional :class:`TwoStageModel`.

    ``J_23 = J_2 + J_3`` (shaft stiffness ignored), ``m_1``, ``m_3``, ``a`` as in the module
    docstring, ``omega_n = sqrt(k_12 / m_1)``, ``zeta_1 = c_12 / (2 sqrt(k_12 m_1))``,
    ``zeta_3 = c_34 / (2 sqrt(k_34 m_3))``; ``L`` is ``length_scale_m`` or the stage-1 half
    backlash. Returns the model and the scales ``omega_n`` (rad/s), ``L`` (m), ``m1``,
    ``m3`` (kg), ``J`` (``J_1, J_23, J_4``), ``T2`` (N m).
    """
    sy = system
    J1, J2, J3, J4 = sy.inertia_kg_m2
    r1, r2, r3, r4 = sy.base_radius_m
    J23 = J2 + J3
    m1 = 1.0 / (r1**2 / J1 + r2**2 / J23)
    m3 = 1.0 / (r3**2 / J23 + r4**2 / J4)
    a = r2 * r3 / J23
    k1, k3 = sy.mesh_stiffness_N_m
    c1, c3 = sy.mesh_damping_N_s_m
    wn = math.sqrt(k1 / m1)
    L = sy.half_backlash_m[0] if length_scale_m is None else float(length_scale_m)
    if not L > 0:
        raise ModelError("length scale must be > 0 (give length_scale_m when backlash is 0)")

    def scaled(hh: Harmonics) -> Harmonics:
        return Harmonics(hh.mean / L, np.asarray(hh.amplitude) / L, np.asarray(hh.phase_rad))

    st, er, th = sy.stiffness, sy.error_m, sy.thermal
    b1, b3 = sy.half_backlash_m
    z1 = c1 / (2 * math.sqrt(k1 * m1))
    z3 = c3 / (2 * math.sqrt(k3 * m3))
    model = TwoStageModel(
        stage1=MeshStage(z1, b1 / L, st[0], scaled(er[0]), th[0]),
        stage2=MeshStage(z3, b3 / L, st[1], scaled(er[1]), th[1]),
        force1=r1 * sy.input_torque_Nm / (J1 * wn**2 * L),
        force2=r4 * sy.load_torque_Nm / (J4 * wn**2 * L),
        omega2=math.sqrt(k3 / (m3 * wn**2)),
        coupling1=a * m3,
        coupling2=a * m1,
        mesh_ratio=sy.mesh_ratio,
    )
    scales = {
        "omega_n": wn,
        "L": L,
        "m1": m1,
        "m3": m3,
        "J": (J1, J23, J4),
        "T2": sy.load_torque_Nm,
    }
    return model, scales


# ----------------------------------------------------------------------------- gear sets
def six_state_from_gear_sets(
    stage1_set,
    stage2_set,
    *,
    mean_stiffness_N_m: tuple[float, float],
    input_torque_Nm: float,
    half_backlash_m: tuple[float, float],
    zeta: tuple[float, float] = (0.05, 0.05),
    shaft_stiffness_Nm_rad: float = math.inf,
    shaft_damping_Nms_rad: float = 0.0,
    stiffness: tuple[Harmonics, Harmonics] | None = None,
    error_m: tuple[Harmonics, Harmonics] | None = None,
    thermal: tuple[Harmonics | None, Harmonics | None] = (None, None),
) -> SixStateSystem:
    """:class:`SixStateSystem` from two :class:`~models.geometry.GearSet` s (gears 1-2, 3-4).

    Gear bodies as the package's discs (:func:`models.geometry.gear_inertia`: operating pitch
    radius less the bore), base radii as lever arms, load torque
    ``T_2 = T_1 (r_2 r_4)/(r_1 r_3)`` (static balance), mesh damping from the damping ratios
    of the rigid-shaft reduction, ``c_i = 2 zeta_i sqrt(k_i m_i)``.
    """
    p1, p2 = stage1_set.pair, stage2_set.pair
    r = (p1.base_radius(1), p1.base_radius(2), p2.base_radius(1), p2.base_radius(2))
    J = (gear_inertia(p1, 1), gear_inertia(p1, 2), gear_inertia(p2, 1), gear_inertia(p2, 2))
    J23 = J[1] + J[2]
    m1 = 1.0 / (r[0] ** 2 / J[0] + r[1] ** 2 / J23)
    m3 = 1.0 / (r[2] ** 2 / J23 + r[3] ** 2 / J[3])
    k1, k3 = mean_stiffness_N_m
    z2, z3 = p1.wheel.teeth, p2.pinion.teeth
    g = math.gcd(z3, z2)
    return SixStateSystem(
        inertia_kg_m2=J,
        base_radius_m=r,
        mesh_stiffness_N_m=(float(k1), float(k3)),
        mesh_damping_N_s_m=(2 * zeta[0] * math.sqrt(k1 * m1), 2 * zeta[1] * math.sqrt(k3 * m3)),
        shaft_stiffness_Nm_rad=shaft_stiffness_Nm_rad,
        shaft_damping_Nms_rad=shaft_damping_Nms_rad,
        half_backlash_m=(float(half_backlash_m[0]), float(half_backlash_m[1])),
        input_torque_Nm=float(input_torque_Nm),
        load_torque_Nm=float(input_torque_Nm) * r[1] * r[3] / (r[0] * r[2]),
        stiffness=stiffness or (_unit(), _unit()),
        error_m=error_m or (_zero(), _zero()),
        thermal=thermal,
        mesh_ratio=(z3 // g, z2 // g),
    )


def two_stage_from_gear_sets(
    stage1_set,
    stage2_set,
    *,
    mean_stiffness_N_m: tuple[float, float],
    input_torque_Nm: float,
    half_backlash_m: tuple[float, float],
    zeta: tuple[float, float] = (0.05, 0.05),
    length_scale_m: float | None = None,
    stiffness: tuple[Harmonics, Harmonics] | None = None,
    error_m: tuple[Harmonics, Harmonics] | None = None,
    thermal: tuple[Harmonics | None, Harmonics | None] = (None, None),
) -> tuple[TwoStageModel, dict]:
    """Build the model from two :class:`~models.geometry.GearSet` s (gears 1-2 and 3-4).

    :func:`six_state_from_gear_sets` with a rigid intermediate shaft (seed 001's assumption),
    reduced by :func:`rigid_shaft_model`: gear bodies as the package's discs
    (:func:`models.geometry.gear_inertia`: ``J = pi rho w (r_w^4 - r_i^4) / 2``, operating pitch
    radius less the bore, face width of the pair), base radii as lever arms,
    load torque ``T_2 = T_1 (r_2 r_4)/(r_1 r_3)``. ``stiffness`` are normalised series
    (mean 1), ``error_m`` in metres, ``thermal`` normalised by the stage mean stiffness.
    Returns the model and a dict of the dimensional scales (``omega_n``, ``L``, ``m1``,
    ``m3``, inertias ``J = (J_1, J_23, J_4)``, ``T2``).
    """
    system = six_state_from_gear_sets(
        stage1_set,
        stage2_set,
        mean_stiffness_N_m=mean_stiffness_N_m,
        input_torque_Nm=input_torque_Nm,
        half_backlash_m=half_backlash_m,
        zeta=zeta,
        stiffness=stiffness,
        error_m=error_m,
        thermal=thermal,
    )
    return rigid_shaft_model(system, length_scale_m)

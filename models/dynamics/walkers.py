r"""Frequency sweeps of many SDOF parameter sets ("walkers") in one compiled call.

A run-up calibration (issue 20) evaluates the FVMS, VVMS or LSTE model of one pair at one
torque for many parameter sets at once (the walkers of an ensemble sampler). This module
sweeps them all in one numba call, ``prange`` over the walkers, with no Python per walker.

Parameters of a walker (all dimensional, arrays of shape ``(W,)``):

* ``zeta``: damping ratio with respect to the reference stiffness ``k_ref = s kbar_F0``;
* ``stiffness_scale`` ``s``: every tooth compliance is ``C / s``;
* ``fluctuation_scale`` ``eps``: multiplies the alternating part of the mesh stiffness (FVMS,
  VVMS) and of the displacement excitation (LSTE; the FVMS gear error too);
* ``backlash_m``: the total backlash ``2 b`` on the line of action (m).

**Stiffness scale, exactly.** With compliance ``C / s`` at pinion torque ``T`` the load
sharing is that of compliance ``C`` at ``T / s`` (loads divided by ``s``, transmission error
unchanged), so the model with scale ``s`` is the cycle at ``T / s`` with its stiffnesses
multiplied by ``s``. Non-dimensionally, with ``k_ref = s kbar_F0`` (``kbar_F0`` the mean
error-free FVMS, load independent), it is :func:`~models.dynamics.sdof.sdof_from_mesh_cycle`
of the cycle at ``T / s`` with ``reference_stiffness = kbar_F0``, and

.. math:: \omega_n = \sqrt{s \bar k_{F0} / m_e}, \qquad \Lambda = 2 \pi f_m / \omega_n,
          \qquad \tilde F = F_0 / (s \bar k_{F0} L),

``F_0 = T / r_{b1}``, ``m_e`` from :func:`models.geometry.inertia.pair_equivalent_mass`
unless given. A :class:`CycleBank` holds those non-dimensional curves at ``J`` log-spaced
nodes ``s_j`` (default 65 over [0.3, 3]); the kernel interpolates them in ``log s`` (4-point
Lagrange) per walker. The length scale ``L`` is the bank's ``F_0 / kbar_F0`` (static mean
deflection at the nominal torque); amplitudes are returned in metres.

**Path.** ``mesh_frequency_Hz`` is the run's path in time order, it may go up and then down
(run-up and run-down); every walker starts from the static state ``x = b + F + mean(e)``,
``x' = 0`` at the first point and carries its state along the path, as the rig does, so the
up branch and the down branch (jumps, hysteresis) both appear.

**Methods.** ``method="shooting"`` (``"auto"``, the default, is the same for every model):
the first point of the path, and every point after a period-n, aperiodic or unsettled
response, is settled by time integration from the entry state (no period-1 orbit to
continue: the physical transient decides the attractor). Every other point, whose entry
state lies on the previous point's period-1 orbit, is a Newton solve of the period-1
Poincare map from the entry state ``y0`` (RK4 on the state and its variational equations,
the very RK4 step of the settling kernel), accepted only when all four hold:

1. ``|P(y*) - y*| < tol max(1, |y*|)`` (units of ``L``);
2. both Floquet multipliers inside the unit circle (the orbit is stable);
3. the *continuation guard*: ``|y* - y0|`` within ``WALKER_GUARD`` = 0.5 of the previous
   orbit's range over its period, per coordinate (``x`` and ``x'``), plus ``1e-3 L``: the
   orbit continues the branch being followed (a far fixed point is a branch switch or a
   fold, left to the integration);
4. the *basin check* in the orbit's quadratic Lyapunov function ``V(d) = d^T P d``
   (``P - M^T P M = I``, ``M`` the monodromy matrix at ``y*``): one plain period from
   ``y_k`` reduces it by at least half the linearised decrease, ``V(P(y_k) - y*) <= V(y_k -
   y*) - |y_k - y*|^2 / 2``, either at once from the entry state, or for 2 consecutive
   periods of the physical transient followed from it for at most 12 plain periods; and
   ``V`` must by then have fallen to a tenth of its value at the entry state, unless the
   entry state lies within 5 % of the continuation guard of the orbit (a small step of the
   path). The transient is then in the orbit's linear neighbourhood, where it goes to that
   orbit. (Decrease
   alone was not enough: after a large step of the path, an entry state beyond the basin
   boundary could show it for a period or two on its way to the other attractor; in the
   reduced SBC's 16-point sweeps two of six true curves had a point on the wrong branch.)

Each Newton iterate ``y_(k+1)`` is verified with the *recorded* plain period from it (its end
state is ``P(y_(k+1))``; ``verify_record=True``, the default): when its residual is below
``tol``, conditions 2-4 are judged with ``M(y_k)``, the monodromy matrix of the last Newton
iterate, instead of ``M(y_(k+1))`` (an approximation of order ``|y_(k+1) - y_k|``), and the
recorded period is the point's output; otherwise Newton continues from ``y_(k+1)``. An
accepted point costs one variational and one plain period (3 period-equivalents) instead of
two and one (5) with ``verify_record=False``. Measured (issue 20, helper speed7; 32 walkers
near the demo's posterior and 32 broad, zeta 0.01-0.06, s 0.7-1.2, on the demo's run-up,
893 nodes, and on the SBC-like paths at 100, 200 and 300 N m, 626 nodes; FVMS, VVMS,
LSTE): no jump window changed in 1536 walker-directions, ``|Delta log mu|`` at window points
off jumps 0 at the median and p99, at most 5e-6 (FVMS; 3e-14 for VVMS and LSTE): the
accepted iterates are the same, only conditions 2-4 could decide otherwise, and did not.
Cost: 1.4-1.5 times fewer period-equivalents per window point for VVMS and LSTE, 1.2-1.35
for FVMS (whose settled points dominate).

**Skipped continuation nodes.** With ``record`` (False at the run-up's continuation nodes,
whose outputs are unused), a continuation node is skipped (no solve: the state is carried
unchanged, the outputs are the last solved node's, ``periods_run`` 0, ``solved`` False) when

* the last solved node was a Newton orbit (never after a settled node: no multipliers) whose
  multipliers are clear of 1 and -1: ``|det(M -+ I)| >= WALKER_FOLD_MARGIN (1 - sqrt(det
  M))^2`` with the margin 1, i.e. not a real pair splitting towards a fold or a flip;
* the step in ``ln f_m`` from it to the next node is at most ``WALKER_SKIP_STEP`` = 3 %, and
* the orbit's predicted move over that step, its move from the entry state at the last
  solved node per unit ``ln f_m`` times the step, is at most ``WALKER_SKIP_MOVE`` = 2.5 % of
  the continuation guard (half the basin check's linear neighbourhood): a step-size control
  that stops skipping where the branch turns fast, near its fold.

Window nodes (``record`` True) and the last node are always solved. The multipliers alone
did not foresee the folds of these non-smooth models (the pair stays complex up to a node or
two before them): with a 3 % step and no move bound, 17 of 64 walker-directions near the
demo's posterior changed jump window whatever the margin (0.5-30 on that ratio, or its real
pair form); with the move bound at 5 % of the guard, 20 of 64 at 200 N m (VVMS); at 3 %, 5
of 1100. At 2.5 % (the default): 2 of 1536 walker-directions changed jump window (0.13 %,
LSTE at 100 N m), ``|Delta log mu|`` off jumps p50 1e-14, p99 1e-13, at most 5e-5; cost
1.6-2.05 times fewer period-equivalents per window point than ``verify_record=False`` with
every node solved for VVMS and LSTE (1.3-1.95 for FVMS); see the module's tests and
``tests/benchmarks/bench_runup_sweep.py``.

Otherwise (a jump, a period-n, aperiodic or unstable response, or a transient that does not
reach the orbit's neighbourhood) the point is settled by time integration, continuing the
transient from where the basin check left it, with the project's settling kernel
(:func:`~models.dynamics.sdof_kernels.settle_kernel`, tolerance ``tol``, at least
``min_periods``, at most ``max_periods``). One period (whole response periods after a
settle) is recorded for the DFT of mesh harmonics 1-3 and the contact flags (every step
checked on its cubic Hermite interpolant). ``method="integrate"`` settles every point.

**Error contract** (checked by ``tests/models/test_walkers.py`` against
:func:`sweep_walkers_reference`, the plain per-walker loop of
:func:`~models.dynamics.sweep.sweep` on the exact cycle at ``T / s``, 128 steps, tol 1e-6):

* a point is either a period-1 orbit that passed 1-4 (2-4 judged with the monodromy of the
  last Newton iterate under ``verify_record``), or the settle kernel's result from the entry
  state (the same algorithm as the plain sweep), or a skipped continuation node (``solved``
  False, outputs not to be used); ``converged`` is False where neither
  gave a periodic response within ``max_periods`` (its amplitudes are then those of the last
  period run and must not be trusted);
* away from jumps the amplitudes differ from the reference by the discretisation (64 against
  128 steps per period), the bank interpolation and the tolerance: within 0.5 % at
  64 steps (measured, ``tests/benchmarks/bench_runup_sweep.py``, 16 walkers x 200 points at
  340 N m: p99 0.03-0.05 %, worst 0.18 % for FVMS, 0.06 % for VVMS and LSTE);
* a jump may come up to 2 grid points earlier or later than in the reference (near a fold the
  settled state depends on the tolerance), and at most 0.5 % of the points may sit on another
  attractor than the reference's (an off-jump point above 0.5 %, or an unmatched jump).
  Measured with ``"auto"`` (issue 20, helper H1b): FVMS 14 of 15440 points (0.09 %; at
  most 0.21 % in any of 10 sets: the benchmark's 16 walkers, the test's, and 8 sets of 12
  walkers with zeta 0.01-0.05, s 0.6-1.6, eps 0.5-1.5, 2b 0-300 um, at 100, 220 and
  340 N m), VVMS and LSTE 0-2 of 3200 / 1440. Without the first-point integration, FVMS
  shooting put whole branch stretches on another attractor (Newton from the static state
  found the small orbit where the transient reaches the large one);
* cost: 10-14 period-equivalents per point for FVMS (7-8 for VVMS and LSTE) against ~70
  (at twice the steps) for the reference, as measured with ``verify_record=False`` (the
  record verification removes about 2 per Newton point, skipping continuation nodes more;
  "Methods"), but a walker whose response is aperiodic pays up
  to ``max_periods`` at each such point, like the reference;
* points where neither Newton nor settling finds a periodic response have ``converged``
  False; a response that grows without bound (a parametric instability of the linear model at
  near-zero backlash) gives non-finite amplitudes there;
* ``stiffness_scale`` outside the bank's ``scale_range`` raises ``ValueError`` (never
  extrapolated); non-finite or non-positive inputs raise ``ValueError``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Final

import numpy as np
from numpy.typing import ArrayLike

from models.dynamics.sdof import SDOFModel, sdof_from_mesh_cycle
from models.dynamics.sweep import sweep
from models.dynamics.walker_kernels import walker_sweep_kernel
from models.errors import ModelError
from models.geometry.gear_pair import GearPair
from models.geometry.inertia import pair_equivalent_mass
from models.stiffness.mesh_cycle import (
    Harmonics,
    MeshCycleGeometry,
    prepare_mesh_cycle,
    tabulate_compliance,
)
from models.stiffness.potential_energy import pair_compliance

__all__ = [
    "KINDS",
    "METHODS",
    "CycleBank",
    "SweepAgreement",
    "WalkerSweep",
    "cycle_bank",
    "sweep_agreement",
    "sweep_walkers",
    "sweep_walkers_reference",
]

#: Models a :class:`CycleBank` can hold.
KINDS = ("fvms", "vvms", "lste")
#: ``method`` values of :func:`sweep_walkers`.
METHODS = ("auto", "shooting", "integrate")
#: Newton iterations per point before the kernel falls back to settling.
WALKER_NEWTON: Final = 8
#: Continuation guard of the shooting: a Newton orbit's Poincare point must lie within
#: ``WALKER_GUARD`` times the previous orbit's range (per coordinate) of the entry state, plus
#: ``WALKER_GUARD_FLOOR`` (units of ``L``).
WALKER_GUARD: Final = 0.5
WALKER_GUARD_FLOOR: Final = 1e-3
#: Plain periods of the transient the basin check may follow, and the consecutive periods that
#: must pass it there (item 4 of the module notes; the contraction to a tenth is the kernel's
#: ``_BASIN_CONTRACTION``).
WALKER_BASIN_PERIODS: Final = 12
WALKER_BASIN_REPEATS: Final = 2
#: Continuation nodes (``record`` False) are skipped while the step in ``ln f_m`` from the last
#: solved node to the next node stays within ``WALKER_SKIP_STEP`` ...
WALKER_SKIP_STEP: Final = 0.03
#: ... and that node was a Newton orbit whose multipliers keep ``|det(M -+ I)| >=
#: WALKER_FOLD_MARGIN (1 - sqrt(det M))^2`` (far from a fold or flip; module notes).
WALKER_FOLD_MARGIN: Final = 1.0
#: ... and the orbit's predicted move over that step (its move from the entry state at the last
#: solved node per unit ``ln f_m``, times the step) stays within this fraction of the guard.
WALKER_SKIP_MOVE: Final = 0.025


@dataclass(frozen=True, eq=False)
class CycleBank:
    """Non-dimensional mesh-cycle curves of one model, pair and torque at stiffness-scale nodes.

    Attributes
    ----------
    kind : str
        ``"fvms"``, ``"vvms"`` or ``"lste"``.
    torque_Nm : float
        Nominal pinion torque ``T`` (N m).
    equivalent_mass_kg : float
        ``m_e`` (kg).
    reference_stiffness_N_m : float
        ``kbar_F0``: mean error-free FVMS of the pair (N/m); ``k_ref = s kbar_F0``.
    scales : numpy.ndarray
        ``(J,)`` nodes ``s_j`` (-), log-spaced, increasing.
    length_scale_m : float
        ``L = F_0 / kbar_F0`` (m), ``F_0 = T / r_b1``: the unit of the kernel's DTE.
    load_N : float
        ``F_0`` (N).
    """

    kind: str
    torque_Nm: float
    equivalent_mass_kg: float
    reference_stiffness_N_m: float
    scales: np.ndarray
    length_scale_m: float
    load_N: float
    _geometry: MeshCycleGeometry = field(repr=False)
    _series: tuple[tuple[Harmonics, Harmonics, Harmonics], ...] = field(repr=False)
    _model_mean: np.ndarray = field(repr=False)
    _tables: dict[int, tuple[np.ndarray, ...]] = field(default_factory=dict, repr=False)

    def natural_frequency_Hz(self, stiffness_scale: ArrayLike) -> np.ndarray:  # noqa: N802
        """``sqrt(s kbar_F0 / m_e) / (2 pi)`` (Hz): the common frequency axis of all models."""
        s = np.asarray(stiffness_scale, dtype=float)
        return np.asarray(
            np.sqrt(s * self.reference_stiffness_N_m / self.equivalent_mass_kg) / (2 * math.pi)
        )

    def model_natural_frequency_Hz(self, stiffness_scale: ArrayLike) -> np.ndarray:  # noqa: N802
        """``sqrt(s k_model(T / s) / m_e) / (2 pi)`` (Hz), the model's own mean stiffness.

        ``k_model`` is the mean FVMS, the mean VVMS, or ``F / mean(LSTE)`` of the cycle at
        ``T / s`` (interpolated between the nodes in ``log s``, linearly).
        """
        s = self.check_scales(stiffness_scale)
        ratio = np.interp(np.log(s), np.log(self.scales), self._model_mean)
        return np.asarray(self.natural_frequency_Hz(s) * np.sqrt(ratio))

    def check_scales(self, stiffness_scale: ArrayLike) -> np.ndarray:
        """``stiffness_scale`` as a float array; ``ValueError`` outside the nodes' range."""
        s = np.asarray(stiffness_scale, dtype=float)
        lo, hi = float(self.scales[0]), float(self.scales[-1])
        if not (np.all(np.isfinite(s)) and np.all(s >= lo * (1 - 1e-12))
                and np.all(s <= hi * (1 + 1e-12))):
            raise ValueError(
                f"`stiffness_scale` must lie in the bank's range [{lo:g}, {hi:g}]; got "
                f"[{np.nanmin(s):g}, {np.nanmax(s):g}] (build the bank with a wider "
                "`scale_range`)"
            )
        return s

    def tables(self, steps_per_period: int) -> tuple[np.ndarray, ...]:
        """``(kbank, ebank, bbank, cos, sin)`` at ``steps_per_period`` steps (cached).

        ``kbank``, ``ebank``, ``bbank`` are ``(J, 2 N)``: ``tilde k``, ``tilde e`` and the
        back-side offset at the RK4 half steps; ``cos``, ``sin`` ``(3, N)`` the DFT rows.
        """
        n = int(steps_per_period)
        if n != steps_per_period or n < 4:
            raise ValueError(f"`steps_per_period` must be an integer >= 4, was "
                             f"{steps_per_period!r}")
        if n not in self._tables:
            phase = np.arange(2 * n) / (2 * n)
            rows = [[np.asarray(c(phase), dtype=float) for c in node] for node in self._series]
            k, e, b = (np.ascontiguousarray(np.array([r[i] for r in rows])) for i in range(3))
            arg = 2 * np.pi * np.arange(1, 4)[:, None] * np.arange(n)[None, :] / n
            self._tables[n] = (k, e, b, np.ascontiguousarray(np.cos(arg)),
                               np.ascontiguousarray(np.sin(arg)))
        return self._tables[n]

    def walker_model(self, zeta: float, stiffness_scale: float, fluctuation_scale: float,
                     backlash_m: float) -> SDOFModel:
        """The plain :class:`~models.dynamics.sdof.SDOFModel` of one walker (exact cycle).

        The cycle at ``T / s`` solved anew (no interpolation), ``reference_stiffness =
        kbar_F0``, ``length_scale_m = L``, alternating parts scaled by ``fluctuation_scale``.
        """
        s = float(self.check_scales(stiffness_scale))
        cycle = self._geometry.solve(self.torque_Nm / s)
        base = sdof_from_mesh_cycle(
            cycle, self.kind, zeta=float(zeta), backlash_m=0.5 * float(backlash_m),
            length_scale_m=self.length_scale_m,
            reference_stiffness=self.reference_stiffness_N_m,
        )
        eps = float(fluctuation_scale)
        return SDOFModel(
            zeta=base.zeta, force=base.force, backlash=base.backlash,
            stiffness=_scaled(base.stiffness, eps), error=_scaled(base.error, eps),
            length_scale_m=base.length_scale_m, mean_stiffness_N_m=base.mean_stiffness_N_m,
            kind=base.kind,
            back_error=None if base.back_error is None else _scaled(base.back_error, eps),
        )


def _scaled(h: object, eps: float) -> Harmonics:
    if not isinstance(h, Harmonics):
        raise ModelError("walker models use the Fourier series of the cycle")
    return Harmonics(h.mean, np.asarray(h.amplitude) * eps, np.asarray(h.phase_rad))


def _node_series(model: SDOFModel) -> tuple[Harmonics, Harmonics, Harmonics]:
    k, e = model.stiffness, model.error
    b = e if model.back_error is None else model.back_error
    if not all(isinstance(c, Harmonics) for c in (k, e, b)):
        raise ModelError("walker models use the Fourier series of the cycle")
    return k, e, b  # type: ignore[return-value]


def cycle_bank(
    pair: GearPair,
    torque_Nm: float,
    kind: str,
    *,
    equivalent_mass_kg: float | None = None,
    scale_range: tuple[float, float] = (0.3, 3.0),
    nodes: int = 65,
    n_phases: int = 200,
) -> CycleBank:
    """The :class:`CycleBank` of ``kind`` for ``pair`` at ``torque_Nm``.

    Parameters
    ----------
    pair : GearPair
        The pair (error-free involutes, corner contact, potential-energy compliance with Hertz,
        :func:`models.stiffness.pair_compliance`).
    torque_Nm : float
        Pinion torque ``T`` (N m), > 0.
    kind : {"fvms", "vvms", "lste"}
        The SDOF model.
    equivalent_mass_kg : float, optional
        ``m_e`` (kg); default :func:`models.geometry.inertia.pair_equivalent_mass`.
    scale_range : tuple of float
        ``(s_min, s_max)`` of the nodes (-), ``0 < s_min < s_max``.
    nodes : int
        Number of log-spaced nodes, >= 4.
    n_phases : int
        Phases of each mesh cycle.

    Returns
    -------
    CycleBank

    Raises
    ------
    ValueError
        On a bad kind, torque, mass, range or node count.
    """
    if kind not in KINDS:
        raise ValueError(f"`kind` must be one of {KINDS}, was {kind!r}")
    T = float(torque_Nm)
    if not (math.isfinite(T) and T > 0):
        raise ValueError(f"`torque_Nm` must be finite and > 0, was {torque_Nm!r}")
    lo, hi = (float(v) for v in scale_range)
    if not (0 < lo < hi and math.isfinite(hi)):
        raise ValueError(f"`scale_range` must be 0 < s_min < s_max, was {scale_range!r}")
    if int(nodes) != nodes or nodes < 4:
        raise ValueError(f"`nodes` must be an integer >= 4, was {nodes!r}")
    m_e = pair_equivalent_mass(pair) if equivalent_mass_kg is None else float(equivalent_mass_kg)
    if not (math.isfinite(m_e) and m_e > 0):
        raise ValueError(f"`equivalent_mass_kg` must be finite and > 0, was {m_e!r}")
    comp = tabulate_compliance(pair, lambda s: pair_compliance(pair, s).total_m_per_N)
    geo = prepare_mesh_cycle(pair, comp, n_phases=n_phases)
    k_f0 = float(geo.solve(T).fvms_harmonics.mean)  # the FVMS does not depend on the load
    load = T / geo.base_radius_1_m
    length = load / k_f0
    scales = np.exp(np.linspace(math.log(lo), math.log(hi), int(nodes)))
    series = []
    model_mean = np.empty(scales.size)
    for j, s in enumerate(scales):
        m = sdof_from_mesh_cycle(geo.solve(T / s), kind, zeta=0.0, backlash_m=0.0,
                                 length_scale_m=length, reference_stiffness=k_f0)
        series.append(_node_series(m))
        model_mean[j] = series[-1][0].mean
    return CycleBank(
        kind=kind, torque_Nm=T, equivalent_mass_kg=m_e, reference_stiffness_N_m=k_f0,
        scales=scales, length_scale_m=length, load_N=load, _geometry=geo,
        _series=tuple(series), _model_mean=model_mean,
    )


@dataclass(frozen=True, eq=False)
class WalkerSweep:
    """Sweeps of ``W`` walkers along one path of ``N`` mesh frequencies.

    Attributes
    ----------
    amplitude_m : numpy.ndarray
        ``(W, N, 3)`` peak DTE amplitudes of mesh harmonics 1-3 (m).
    contact_loss : numpy.ndarray
        ``(W, N)`` bool: the drive flanks separate during the recorded period(s).
    backside_impact : numpy.ndarray
        ``(W, N)`` bool: the back flanks touch.
    converged : numpy.ndarray
        ``(W, N)`` bool: a periodic response was found (Newton or settled with period > 0).
    newton_fraction : float
        Fraction of the solved points accepted from Newton shooting (0 for ``"integrate"``
        and the reference).
    periods_run : numpy.ndarray
        ``(W, N)`` int: mesh-period equivalents spent per point (a variational period
        counts 2).
    solved : numpy.ndarray
        ``(W, N)`` bool: the point was solved; False at a skipped continuation node (its
        outputs are the last solved point's, ``periods_run`` 0).
    newton : numpy.ndarray
        ``(W, N)`` bool: the point was accepted from Newton shooting.
    """

    amplitude_m: np.ndarray
    contact_loss: np.ndarray
    backside_impact: np.ndarray
    converged: np.ndarray
    newton_fraction: float
    periods_run: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), dtype=np.int64))
    solved: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), dtype=np.bool_))
    newton: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), dtype=np.bool_))


def _zero_sweep(shape: tuple[int, ...]) -> WalkerSweep:
    """A :class:`WalkerSweep` of ``shape`` ``(W, N)`` with zeroed arrays, to be filled."""
    return WalkerSweep(
        amplitude_m=np.zeros((*shape, 3)),
        contact_loss=np.zeros(shape, dtype=np.bool_),
        backside_impact=np.zeros(shape, dtype=np.bool_),
        converged=np.zeros(shape, dtype=np.bool_),
        newton_fraction=0.0,
        periods_run=np.zeros(shape, dtype=np.int64),
        solved=np.ones(shape, dtype=np.bool_),
        newton=np.zeros(shape, dtype=np.bool_),
    )


def _walker_inputs(
    bank: CycleBank, mesh_frequency_Hz: ArrayLike, zeta: ArrayLike, stiffness_scale: ArrayLike,
    fluctuation_scale: ArrayLike, backlash_m: ArrayLike,
) -> tuple[np.ndarray, ...]:
    f = np.asarray(mesh_frequency_Hz, dtype=float)
    if f.ndim != 1 or f.size == 0 or not (np.all(np.isfinite(f)) and np.all(f > 0)):
        raise ValueError("`mesh_frequency_Hz` must be a non-empty 1-D array of finite values > 0")
    arrays = np.broadcast_arrays(*(np.atleast_1d(np.asarray(a, dtype=float)) for a in
                                   (zeta, stiffness_scale, fluctuation_scale, backlash_m)))
    z, s, e, b = (np.ascontiguousarray(a) for a in arrays)
    if z.ndim != 1:
        raise ValueError("walker parameters must be scalars or 1-D arrays of one length")
    for name, a, low in (("zeta", z, 0.0), ("fluctuation_scale", e, 0.0),
                         ("backlash_m", b, 0.0)):
        if not (np.all(np.isfinite(a)) and np.all(a >= low)):
            raise ValueError(f"`{name}` must be finite and >= 0")
    s = bank.check_scales(s)
    lam = 2 * np.pi * f[None, :] / (2 * np.pi * bank.natural_frequency_Hz(s)[:, None])
    return f, z, s, e, b, np.ascontiguousarray(lam)


def sweep_walkers(
    bank: CycleBank,
    mesh_frequency_Hz: ArrayLike,
    *,
    zeta: ArrayLike,
    stiffness_scale: ArrayLike,
    fluctuation_scale: ArrayLike,
    backlash_m: ArrayLike,
    steps_per_period: int = 64,
    method: str = "auto",
    tol: float = 1e-6,
    min_periods: int = 4,
    max_periods: int = 1000,
    record: ArrayLike | None = None,
    verify_record: bool = True,
) -> WalkerSweep:
    """Sweep every walker along the time-ordered path ``mesh_frequency_Hz`` (one compiled call).

    Parameters
    ----------
    bank : CycleBank
        Model, pair and torque (:func:`cycle_bank`).
    mesh_frequency_Hz : array_like
        ``(N,)`` mesh frequencies in time order (Hz), > 0; may go up then down.
    zeta, stiffness_scale, fluctuation_scale, backlash_m : array_like
        ``(W,)`` per walker (or scalars, broadcast): damping ratio w.r.t. ``s kbar_F0`` (-),
        stiffness scale ``s`` (-, inside the bank's range), fluctuation scale ``eps`` (-),
        total backlash ``2 b`` on the line of action (m).
    steps_per_period : int
        RK4 steps per mesh period (>= 4).
    method : {"auto", "shooting", "integrate"}
        See the module notes; ``"auto"`` is ``"shooting"`` (continuation-guarded Newton
        shooting with the settling fallback) for every model.
    tol : float
        Newton residual and settling tolerance (units of ``L``).
    min_periods, max_periods : int
        Bounds of the settling fallback (mesh periods).
    record : array_like of bool, optional
        ``(N,)``: False marks a continuation node, whose outputs are not used; such a node
        may be skipped far from folds (module notes, "Skipped continuation nodes"). None:
        every node is solved.
    verify_record : bool
        Check each Newton iterate with the recorded period (module notes, "Methods"); False:
        with a second variational period, as before issue 20's item 4.

    Returns
    -------
    WalkerSweep

    Raises
    ------
    ValueError
        Bad arguments, ``stiffness_scale`` outside the bank's range.
    """
    if method not in METHODS:
        raise ValueError(f"`method` must be one of {METHODS}, was {method!r}")
    if not (math.isfinite(tol) and tol > 0):
        raise ValueError(f"`tol` must be finite and > 0, was {tol!r}")
    if not (1 <= int(min_periods) <= int(max_periods)):
        raise ValueError("need 1 <= min_periods <= max_periods")
    shoot = method in ("shooting", "auto")
    _, z, s, e, b, lam = _walker_inputs(bank, mesh_frequency_Hz, zeta, stiffness_scale,
                                        fluctuation_scale, backlash_m)
    if record is None:
        keep = np.ones(lam.shape[1], dtype=np.bool_)
        skip_step = 0.0
    else:
        keep = np.ascontiguousarray(record, dtype=np.bool_)
        if keep.shape != (lam.shape[1],):
            raise ValueError(f"`record` must have the path's shape ({lam.shape[1]},), was "
                             f"{keep.shape}")
        skip_step = float(WALKER_SKIP_STEP)
    kbank, ebank, bbank, cs, sn = bank.tables(steps_per_period)
    out = _zero_sweep(lam.shape)
    newton = out.newton
    L = bank.length_scale_m
    force = np.ascontiguousarray(bank.load_N / (s * bank.reference_stiffness_N_m * L))
    walker_sweep_kernel(
        np.ascontiguousarray(np.log(bank.scales)), kbank, ebank, bbank,
        np.ascontiguousarray(np.log(s)), e, z, force, np.ascontiguousarray(0.5 * b / L), lam,
        cs, sn, float(tol), bool(shoot), WALKER_NEWTON, int(min_periods), int(max_periods),
        WALKER_GUARD, WALKER_GUARD_FLOOR, WALKER_BASIN_PERIODS, WALKER_BASIN_REPEATS,
        bool(verify_record), keep, skip_step, float(WALKER_SKIP_MOVE), float(WALKER_FOLD_MARGIN),
        out.amplitude_m, out.contact_loss, out.backside_impact, out.converged, newton,
        out.periods_run, out.solved,
    )
    frac = float(newton[out.solved].mean()) if out.solved.any() else 0.0
    return replace(out, amplitude_m=out.amplitude_m * L, newton_fraction=frac)


def sweep_walkers_reference(
    bank: CycleBank,
    mesh_frequency_Hz: ArrayLike,
    *,
    zeta: ArrayLike,
    stiffness_scale: ArrayLike,
    fluctuation_scale: ArrayLike,
    backlash_m: ArrayLike,
    steps_per_period: int = 128,
    tol: float = 1e-6,
    min_periods: int = 10,
    max_periods: int = 1000,
    record_periods: int = 4,
) -> WalkerSweep:
    """The plain per-walker loop: :meth:`CycleBank.walker_model` and :func:`~.sweep.sweep`.

    Same path, same scaling and start as :func:`sweep_walkers`, but each walker's model is
    built in Python from the exact cycle at ``T / s`` (no bank interpolation) and swept by the
    project's time-integration sweep with its defaults (128 steps, tol 1e-6, at least 10
    periods, 4 recorded): the "full sweep" the fast kernel is measured against.

    Returns
    -------
    WalkerSweep
        ``newton_fraction`` 0.
    """
    _, z, s, e, b, lam = _walker_inputs(bank, mesh_frequency_Hz, zeta, stiffness_scale,
                                        fluctuation_scale, backlash_m)
    out = _zero_sweep(lam.shape)
    for w in range(lam.shape[0]):
        model = bank.walker_model(z[w], s[w], e[w], b[w])
        r = sweep(model, lam[w], steps_per_period=steps_per_period, tol=tol,
                  min_periods=min_periods, max_periods=max_periods,
                  record_periods=record_periods)
        out.amplitude_m[w] = r.amplitudes * r.length_scale_m
        out.contact_loss[w] = r.contact_loss
        out.backside_impact[w] = r.backside_impact
        out.converged[w] = r.converged
        out.periods_run[w] = r.periods
    return out


@dataclass(frozen=True)
class SweepAgreement:
    """How a walker sweep agrees with a reference sweep of the same walkers and path.

    Compared quantity: the acceleration-weighted amplitude ``sqrt(sum_h (h^2 A_h)^2)`` (what
    the housing accelerometers see, up to ``(2 pi f_m)^2`` and the gain), point by point in
    path order. A *jump* of a walker's curve is a step ``|Delta ln a| > jump_threshold``
    between neighbouring path points; a point is *near a jump* within ``jump_window`` points
    of a jump of either curve. Points where either sweep did not converge are left out.

    Attributes
    ----------
    points : int
        All points ``W N``.
    compared : int
        Points where both converged.
    near_jump : int
        Compared points near a jump.
    relative_error : numpy.ndarray
        ``(W, N)`` ``|a - a_ref| / a_ref`` (NaN where not compared).
    p99_off_jump, worst_off_jump : float
        99th percentile and maximum of the relative error away from jumps (-).
    off_jump_over : int
        Points away from jumps with relative error above ``off_jump_tolerance`` (another
        attractor, or worse than the tolerance).
    over_10pct_near_jump, over_10pct_off_jump : int
        Points above 10 % near and away from jumps.
    unmatched_jumps : int
        Jumps of either curve with no jump of the same sign in the other within
        ``jump_window`` points (at half the threshold).
    """

    points: int
    compared: int
    near_jump: int
    relative_error: np.ndarray
    p99_off_jump: float
    worst_off_jump: float
    off_jump_over: int
    over_10pct_near_jump: int
    over_10pct_off_jump: int
    unmatched_jumps: int


def _weighted(amplitude_m: np.ndarray) -> np.ndarray:
    h = np.arange(1, 4)
    return np.asarray(np.sqrt(np.sum((amplitude_m * h**2) ** 2, axis=-1)))


def sweep_agreement(
    result: WalkerSweep,
    reference: WalkerSweep,
    *,
    jump_threshold: float = 0.3,
    jump_window: int = 2,
    off_jump_tolerance: float = 0.005,
) -> SweepAgreement:
    """Compare ``result`` with ``reference`` (same walkers and path): :class:`SweepAgreement`."""
    a = _weighted(result.amplitude_m)
    r = _weighted(reference.amplitude_m)
    if a.shape != r.shape:
        raise ValueError("`result` and `reference` must have the same walkers and path")
    ok = result.converged & reference.converged & (r > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(ok, np.abs(a - r) / r, np.nan)
        la, lr = np.log(np.maximum(a, 1e-300)), np.log(np.maximum(r, 1e-300))
    da, dr = np.diff(la, axis=1), np.diff(lr, axis=1)
    near = np.zeros(a.shape, dtype=bool)
    unmatched = 0
    n = a.shape[1]
    for d, other in ((dr, da), (da, dr)):
        for w, i in zip(*np.nonzero(np.abs(d) > jump_threshold), strict=True):
            near[w, max(0, i - jump_window): min(n, i + jump_window + 2)] = True
            lo, hi = max(0, i - jump_window), min(n - 1, i + jump_window + 1)
            seg = other[w, lo:hi]
            same = (np.sign(seg) == np.sign(d[w, i])) & (np.abs(seg) > 0.5 * jump_threshold)
            if not np.any(same):
                unmatched += 1
    off = ok & ~near
    e_off = rel[off]
    return SweepAgreement(
        points=int(a.size),
        compared=int(ok.sum()),
        near_jump=int((ok & near).sum()),
        relative_error=rel,
        p99_off_jump=float(np.quantile(e_off, 0.99)) if e_off.size else 0.0,
        worst_off_jump=float(e_off.max()) if e_off.size else 0.0,
        off_jump_over=int(np.sum(e_off > off_jump_tolerance)),
        over_10pct_near_jump=int(np.sum(rel[ok & near] > 0.1)),
        over_10pct_off_jump=int(np.sum(e_off > 0.1)),
        unmatched_jumps=unmatched,
    )

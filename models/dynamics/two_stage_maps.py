r"""Peak-DTE maps over mesh frequency x bulk temperature and bifurcation data (seed 001).

Seed 001 studies its two-stage torsional model (:mod:`models.dynamics.two_stage`) "across
parameter planes defined by mesh frequency and bulk (body) temperature" through "the maximum
amplitude of the dynamic transmission error", and reports jumps (bifurcations) between regimes.
This module computes the maps in parallel over the model at each bulk temperature
(:mod:`models.dynamics.two_stage_thermal`: the shipped gear sets ``two-stage-45-steel`` and
``two-stage-45-steel-stage2``, seed 001's parameter table and temperature stiffness), and
returns Poincare samples for bifurcation diagrams.

Computation
-----------
The map is a grid of steady responses, the state carried along frequency within a row
(up-sweep, or down), the rows (temperatures) independent: a numba ``prange`` over rows
(``parallel=True``), each row serial. The per-point work is the compiled RK4 of
:func:`models.dynamics.two_stage_periods` (the same kernel,
:mod:`models.dynamics.two_stage_kernels`, so a map point is bit for bit
:func:`~models.dynamics.two_stage_steady_response` from the same start with the same steps
per period), the serial and the parallel drivers run the same row function, so their
results are identical. The RK4 step is set per frequency column so that ``h omega_max <= 1``
for the stiffest mode over the cycle (:func:`~models.dynamics.two_stage.min_steps_per_period`):
at low mesh frequency a fixed number of steps per mesh period would make the step too long
and the integration diverge. A point whose state still turns non-finite is flagged in
``PeakDTEMap.diverged`` with NaN results, and the next point restarts from its static state.

Peak DTE is ``max |q|`` over the recorded periods at the RK4 step starts (metres), static
deflection, backlash offset and static error included; ``peak_deflection_m`` is ``max |u|``,
``u = q - e``, seed 001's state variable (its equations put the error on the right-hand side
as ``F_e omega^2 cos``). Contact loss and back-side contact flags are those of
:class:`~models.dynamics.TwoStageResponse`. The Poincare samples are the DTEs at the end of
each recorded *system* period (``q`` stage-1 mesh periods, the period of the combined
excitation): one distinct value per frequency for a period-1 response, ``n`` for period
``n``, a cloud for chaos.

References
----------
.. [1] Seed 001, "Nonlinear Dynamics of Spur Gear Systems: The Critical Role of Contact
   Temperature" (two-stage model, temperature stiffness, maps over mesh frequency and bulk
   temperature).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from models.dynamics.checks import as_count
from models.dynamics.two_stage import min_steps_per_period, natural_frequencies, static_state
from models.dynamics.two_stage_kernels import (
    allocate_map_outputs,
    map_rows_parallel,
    map_rows_serial,
)
from models.dynamics.two_stage_thermal import (
    TwoStageThermalSetup,
    two_stage_models_at_temperature,
)
from models.errors import ModelError

__all__ = [
    "Bifurcation",
    "MapGrid",
    "PeakDTEMap",
    "bifurcation_over_frequency",
    "bifurcation_over_temperature",
    "peak_dte_map",
    "prepare_map_grid",
]


# ----------------------------------------------------------------------------- maps
@dataclass(frozen=True)
class PeakDTEMap:
    """Steady response of both stages over a grid of mesh frequency x bulk temperature.

    Arrays are indexed ``[temperature, frequency, stage]`` (stage 0: gears 1-2, 1: gears 3-4).

    Attributes
    ----------
    frequency_Hz : numpy.ndarray
        Stage-1 mesh frequencies (Hz), shape ``(n_f,)``; stage 2 meshes at ``p/q`` of them.
    temperature_C : numpy.ndarray
        Bulk temperatures (deg C), shape ``(n_t,)``.
    frequency_ratio : numpy.ndarray
        ``Lambda = 2 pi f / omega_n`` (-), shape ``(n_f,)``.
    natural_frequency_Hz : float
        ``omega_n / (2 pi)``, ``omega_n = sqrt(k_1 / m_1)`` with stage 1's mean ``k_t`` (Hz):
        the frequency *scale* of the non-dimensional model, not a mode of the coupled system
        (see ``mode_frequency_Hz``).
    mode_frequency_Hz : numpy.ndarray
        The two undamped natural frequencies of the mean-stiffness system, thermal part
        included (:func:`~models.dynamics.two_stage.natural_frequencies`) (Hz), shape
        ``(n_t, n_f, 2)`` (the flash part of ``k_w`` may depend on the speed).
    peak_dte_m : numpy.ndarray
        Peak ``|DTE|`` ``max |q|`` over the recorded periods at the RK4 step starts (m),
        shape ``(n_t, n_f, 2)``: static deflection, half backlash and static error included.
        NaN where ``diverged``.
    peak_deflection_m : numpy.ndarray
        ``max |u|``, ``u = q - e`` (m), same shape: seed 001's state variable (see
        :class:`~models.dynamics.two_stage.TwoStageResponse`). NaN where ``diverged``.
    amplitude_m : numpy.ndarray
        Half peak-to-peak DTE (m), same shape.
    contact_loss, back_contact : numpy.ndarray of bool
        Teeth separated inside the backlash / hit the back flank, same shape.
    poincare_m : numpy.ndarray
        DTE at the end of each recorded system period (m), shape ``(n_t, n_f, n_rec, 2)``.
    diverged : numpy.ndarray of bool
        Shape ``(n_t, n_f)``: the state or record turned non-finite; results NaN, and the
        next point of the row started from its static state instead of this one's.
    steps_per_period : numpy.ndarray of int
        RK4 steps per stage-1 mesh period used in each frequency column, shape ``(n_f,)``:
        at least the requested number, more where the stiffest mode needs it
        (``h omega_max <= MAX_STEP_OMEGA``,
        :func:`~models.dynamics.two_stage.min_steps_per_period`).
    mesh_ratio : tuple[int, int]
        ``(p, q)``; a system period is ``q`` stage-1 mesh periods.
    direction : {"up", "down"}
        Sweep direction along frequency within a row.
    continuation : bool
        State carried from one frequency to the next (else each point from static).
    """

    frequency_Hz: np.ndarray
    temperature_C: np.ndarray
    frequency_ratio: np.ndarray
    natural_frequency_Hz: float
    peak_dte_m: np.ndarray
    amplitude_m: np.ndarray
    contact_loss: np.ndarray
    back_contact: np.ndarray
    poincare_m: np.ndarray
    mesh_ratio: tuple[int, int]
    direction: str
    continuation: bool
    setup: TwoStageThermalSetup = field(repr=False, default_factory=TwoStageThermalSetup)
    peak_deflection_m: np.ndarray = field(default_factory=lambda: np.empty((0, 0, 2)))
    diverged: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), dtype=bool))
    steps_per_period: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    mode_frequency_Hz: np.ndarray = field(default_factory=lambda: np.empty((0, 0, 2)))


def _as_axis(name: str, v) -> np.ndarray:
    a = np.atleast_1d(np.asarray(v, dtype=float))
    if a.ndim != 1 or a.size == 0 or not np.all(np.isfinite(a)):
        raise ModelError(f"`{name}` must be a non-empty 1-d array of finite numbers")
    return a


@dataclass(frozen=True)
class MapGrid:
    """The models at every point of a peak-DTE map, as the map kernels' arrays.

    Built by :func:`prepare_map_grid`; ``n_t`` temperatures, ``n_f`` frequencies, all
    non-dimensional as :mod:`models.dynamics.two_stage`.

    Attributes
    ----------
    Y0 : numpy.ndarray
        Static state of each point, shape ``(n_t, n_f, 4)``.
    P : numpy.ndarray
        Model parameters of each point (``TwoStageModel.params()``), shape ``(n_t, n_f, 9)``.
    T : numpy.ndarray
        Half-step tables of each point, padded to the longest column, shape
        ``(n_t, n_f, 4, 2 q max(steps))``.
    M : numpy.ndarray of int
        Half steps per system period of each column, ``2 q steps``, shape ``(n_f,)``.
    H : numpy.ndarray
        RK4 step of each column, shape ``(n_f,)``.
    order : numpy.ndarray of int
        Order in which a row visits the frequency columns (up or down).
    lam : numpy.ndarray
        ``Lambda`` of each column (stage-1 mesh frequency over ``omega_n``), shape ``(n_f,)``.
    steps : numpy.ndarray of int
        RK4 steps per stage-1 mesh period of each column, shape ``(n_f,)``.
    modes : numpy.ndarray
        Non-dimensional natural frequencies of each point, shape ``(n_t, n_f, 2)``.
    scales : dict
        Scales of the first row's models (``"L"`` in m, ``"omega_n"`` in rad/s, ...).
    mesh_ratio : tuple of int
        ``(p, q)``; a system period is ``q`` stage-1 mesh periods.
    """

    Y0: np.ndarray
    P: np.ndarray
    T: np.ndarray
    M: np.ndarray
    H: np.ndarray
    order: np.ndarray
    lam: np.ndarray
    steps: np.ndarray
    modes: np.ndarray
    scales: dict
    mesh_ratio: tuple[int, int]

    def kernel_args(self) -> tuple:
        """The grid arguments of the map kernels, in order."""
        return self.Y0, self.P, self.T, self.M, self.H, self.order


def prepare_map_grid(
    setup: TwoStageThermalSetup, f: np.ndarray, t: np.ndarray, n: int, direction: str
) -> MapGrid:
    """Models at every grid point, as the kernels' arrays (static states, params, tables).

    Column ``j`` runs ``N_j = max(n, min_steps_per_period)`` RK4 steps per stage-1 mesh
    period (the largest over the temperatures), its tables padded to the longest column.

    Parameters
    ----------
    setup : TwoStageThermalSetup
        Model inputs.
    f : numpy.ndarray
        Stage-1 mesh frequencies (Hz), shape ``(n_f,)``, > 0.
    t : numpy.ndarray
        Bulk temperatures (deg C), shape ``(n_t,)``.
    n : int
        Least RK4 steps per stage-1 mesh period.
    direction : {"up", "down"}
        Order in which a row visits the frequencies.

    Returns
    -------
    MapGrid
    """
    rows = [two_stage_models_at_temperature(setup, float(tc), f) for tc in t]
    m0, sc0, _ = rows[0][0]
    p, q = m0.mesh_ratio
    lam = np.array([lam for _, _, lam in rows[0]])
    steps = np.array(
        [max(n, *(min_steps_per_period(row[j][0], lam[j]) for row in rows)) for j in range(f.size)],
        dtype=np.int64,
    )
    Y0 = np.empty((t.size, f.size, 4))
    P = np.empty((t.size, f.size, 9))
    T = np.zeros((t.size, f.size, 4, 2 * q * int(steps.max())))
    modes = np.empty((t.size, f.size, 2))
    for i, row in enumerate(rows):
        for j, (model, _, _) in enumerate(row):
            Y0[i, j] = static_state(model)
            P[i, j] = model.params()
            T[i, j, :, : 2 * q * steps[j]] = model.tables(int(steps[j]))
            modes[i, j] = natural_frequencies(model)
    order = np.arange(f.size) if direction == "up" else np.arange(f.size)[::-1].copy()
    M = (2 * q * steps).astype(np.int64)
    H = 2.0 * math.pi / (lam * steps)
    return MapGrid(Y0, P, T, M, H, order, lam, steps, modes, sc0, (int(p), int(q)))


def peak_dte_map(
    frequencies_Hz,
    temperatures_C,
    setup: TwoStageThermalSetup | None = None,
    *,
    transient_periods: int = 200,
    record_periods: int = 20,
    steps_per_period: int = 64,
    direction: Literal["up", "down"] = "up",
    continuation: bool = True,
    parallel: bool = True,
) -> PeakDTEMap:
    """Peak DTE of both stages over mesh frequency x bulk temperature (module docstring).

    Parameters
    ----------
    frequencies_Hz : array_like
        Stage-1 mesh frequencies (Hz), > 0, swept in the given order (``"up"``) or reversed.
    temperatures_C : array_like
        Bulk temperatures (deg C), above ``setup.initial_temperature_C`` when thermal (and
        high enough for ``setup.max_thermal_ratio``).
    setup : TwoStageThermalSetup or None
        Model inputs; None: the defaults.
    transient_periods, record_periods : int
        System periods dropped at each point, then recorded (the first point of a row
        starts from the static state; with ``continuation`` the others from the previous
        point's final state, or from their static state after a diverged point).
    steps_per_period : int
        Least RK4 steps per stage-1 mesh period; a column gets more where the stiffest mode
        needs them (``PeakDTEMap.steps_per_period``).
    direction : {"up", "down"}
        Frequency sweep direction within each row.
    continuation : bool
        Carry the state along the row (hysteresis and coexisting branches show up).
    parallel : bool
        numba ``prange`` over the temperature rows; False: the same row function serially.

    Returns
    -------
    PeakDTEMap
    """
    s = setup or TwoStageThermalSetup()
    f = _as_axis("frequencies_Hz", frequencies_Hz)
    t = _as_axis("temperatures_C", temperatures_C)
    if np.any(f <= 0):
        raise ModelError("`frequencies_Hz` must be > 0")
    if direction not in ("up", "down"):
        raise ModelError(f"`direction` must be 'up' or 'down', was {direction!r}")
    n = as_count("steps_per_period", steps_per_period, 4)
    n_rec = as_count("record_periods", record_periods, 1)
    n_trans = as_count("transient_periods", transient_periods, 0)
    grid = prepare_map_grid(s, f, t, n, direction)
    out = allocate_map_outputs(t.size, f.size, n_rec)
    kernel: Callable[..., None] = map_rows_parallel if parallel else map_rows_serial
    kernel(*grid.kernel_args(), bool(continuation), n_trans, n_rec, *out)
    p, q = grid.mesh_ratio
    sc0 = grid.scales
    peak, peak_u, amp, loss, back, div, poinc = out
    L = sc0["L"]
    wn_hz = sc0["omega_n"] / (2 * math.pi)
    return PeakDTEMap(
        frequency_Hz=f,
        temperature_C=t,
        frequency_ratio=grid.lam,
        natural_frequency_Hz=wn_hz,
        peak_dte_m=peak * L,
        amplitude_m=amp * L,
        contact_loss=loss,
        back_contact=back,
        poincare_m=poinc * L,
        mesh_ratio=(int(p), int(q)),
        direction=direction,
        continuation=bool(continuation),
        setup=s,
        peak_deflection_m=peak_u * L,
        diverged=div,
        steps_per_period=grid.steps,
        mode_frequency_Hz=grid.modes * wn_hz,
    )


# ----------------------------------------------------------------------------- bifurcation
@dataclass(frozen=True)
class Bifurcation:
    """Poincare samples of the DTE over one control parameter (bifurcation diagram data).

    Attributes
    ----------
    parameter : numpy.ndarray
        Control parameter values, shape ``(n,)``, in ``parameter_unit``.
    parameter_name, parameter_unit : str
        ``"mesh frequency"``/``"Hz"`` or ``"bulk temperature"``/``"deg C"``.
    fixed : float
        The other parameter's value (deg C or Hz).
    samples_m : numpy.ndarray
        DTE at the end of each recorded system period (m), shape ``(n, n_rec, 2)``.
    contact_loss, back_contact : numpy.ndarray of bool
        Shape ``(n, 2)``.
    direction : str
        Sweep direction (frequency sweeps); ``"independent"`` for temperature sweeps.
    """

    parameter: np.ndarray
    parameter_name: str
    parameter_unit: str
    fixed: float
    samples_m: np.ndarray
    contact_loss: np.ndarray
    back_contact: np.ndarray
    direction: str

    def distinct_counts(self, rtol: float = 1e-6) -> np.ndarray:
        """Distinct Poincare values per parameter and stage, shape ``(n, 2)`` (1: period 1).

        Two samples count as one if they differ by less than ``rtol`` times the stage's
        largest ``|DTE|`` sample.
        """
        out = np.empty(self.samples_m.shape[::2], dtype=int)
        for st in range(2):
            scale = max(float(np.max(np.abs(self.samples_m[..., st]))), 1e-300)
            for i in range(self.samples_m.shape[0]):
                v = np.sort(self.samples_m[i, :, st])
                out[i, st] = 1 + int(np.sum(np.diff(v) > rtol * scale))
        return out


def bifurcation_over_frequency(
    frequencies_Hz,
    temperature_C: float,
    setup: TwoStageThermalSetup | None = None,
    *,
    transient_periods: int = 300,
    record_periods: int = 40,
    steps_per_period: int = 64,
    direction: Literal["up", "down"] = "up",
) -> Bifurcation:
    """Poincare samples over mesh frequency at one bulk temperature (state carried along)."""
    m = peak_dte_map(
        frequencies_Hz,
        [temperature_C],
        setup,
        transient_periods=transient_periods,
        record_periods=record_periods,
        steps_per_period=steps_per_period,
        direction=direction,
        continuation=True,
        parallel=False,
    )
    return Bifurcation(
        m.frequency_Hz,
        "mesh frequency",
        "Hz",
        float(temperature_C),
        m.poincare_m[0],
        m.contact_loss[0],
        m.back_contact[0],
        direction,
    )


def bifurcation_over_temperature(
    frequency_Hz: float,
    temperatures_C,
    setup: TwoStageThermalSetup | None = None,
    *,
    transient_periods: int = 300,
    record_periods: int = 40,
    steps_per_period: int = 64,
    parallel: bool = True,
) -> Bifurcation:
    """Poincare samples over bulk temperature at one mesh frequency.

    Each temperature starts from its static state (temperatures are rows of the map, run in
    parallel), so no hysteresis along temperature is followed.
    """
    m = peak_dte_map(
        [frequency_Hz],
        temperatures_C,
        setup,
        transient_periods=transient_periods,
        record_periods=record_periods,
        steps_per_period=steps_per_period,
        continuation=False,
        parallel=parallel,
    )
    return Bifurcation(
        m.temperature_C,
        "bulk temperature",
        "deg C",
        float(frequency_Hz),
        m.poincare_m[:, 0],
        m.contact_loss[:, 0],
        m.back_contact[:, 0],
        "independent",
    )

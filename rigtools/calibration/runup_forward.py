r"""From SDOF parameters to modelled Arms along each run-up's mesh-frequency path.

For one SDOF model (``fvms``, ``vvms`` or ``lste``) and each run-up curve
(:class:`~rigtools.calibration.runup_data.RunUpCurve`), a bank of mesh cycles of the run's
gear pair at the run's torque (:func:`models.dynamics.walkers.cycle_bank`) and one sweep of
all walkers along the run's time-ordered mesh-frequency path
(:func:`models.dynamics.walkers.sweep_walkers`: the state is carried from point to point, up
then down, so the run-up rows meet the up branch and the run-down rows the down branch). The
sweep gives the peak DTE amplitudes ``D_h`` (m) of mesh harmonics ``h = 1..3``; the housing
acceleration of harmonic ``h`` on channel ``c`` is ``G_c (2 pi h f_m)^2 D_h`` (PLAN section 1:
the alternating mesh force is ``-m_e`` times the DTE acceleration, the housing accelerance is
flat over the band), so the gain-free Arms at a mesh frequency is

.. math:: a(f_m) = (2\pi f_m)^2 \sqrt{\sum_{h=1}^{3} h^4 D_h(f_m)^2}

and the value the likelihood compares with point ``i``, a window along the ramp, is its
power mean over the window (:mod:`rigtools.calibration.runup_data`, "Windows"):

.. math:: \mu_i = \Big(\sum_j W_j\, a(f_{ij})^2\Big)^{1/2}

with ``f_ij`` the mesh frequency at the window's nodes (one node, weight 1, where they
coincide: speed steps, model-only points). The sweep runs through every node in time order,
with continuation nodes (weight 0) wherever two nodes lie more than :data:`MAX_PATH_STEP`
apart in ``ln f_m``, so that the model follows its branches to their folds as the ramp does.

Conventions: ``zeta`` is relative to ``k_ref = s kbar_F0`` (``kbar_F0`` the mean error-free
FVMS mesh stiffness of the pair at the run's torque), ``m_e`` the pair's equivalent mass
(:func:`models.geometry.pair_equivalent_mass`, or the ``[calibration]`` override for runs on
the campaign's gear set), the stiffness scale ``s`` exact through the cycle at ``T / s``;
``backlash`` is the total ``2b`` on the line of action.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Final

import numpy as np
from numpy.typing import ArrayLike

from models.dynamics.walkers import CycleBank, cycle_bank, sweep_walkers
from models.geometry import GearPair
from rigtools.calibration.runup_data import WINDOW_WEIGHTS, RunUpCurve

__all__ = [
    "DIRECTIONS",
    "HYSTERESIS_LOG",
    "MAX_PATH_STEP",
    "RunSweep",
    "RunUpForward",
    "WindowPath",
    "acceleration_arms",
    "build_forward",
    "jump_frequencies",
    "window_path",
]

#: The directions with a jump frequency.
DIRECTIONS = ("up", "down")
#: A point is in the hysteresis band when the other direction differs from it by more than
#: this in ``log Arms`` (10 %, the tolerance of :func:`models.dynamics.sweep.hysteresis_bands`).
HYSTERESIS_LOG: Final = 0.1
#: Largest step of ``ln f_m`` between the nodes a sweep runs through. A steady sweep follows
#: a branch to its fold only in small steps: after a large one, the entry state near a fold
#: lies outside the shrinking basin of the branch being followed, and the model jumps early
#: (on the demo's run-up, steps of 3.8 % and of 1 % both put the down-sweep jump before the
#: window that holds the measured one, 3.6 times off there; 0.3 % and 0.1 % put it inside,
#: 1.12 times off, the window mean's own error).
MAX_PATH_STEP: Final = 0.003


def acceleration_arms(amplitude_m: ArrayLike, mesh_frequency_Hz: ArrayLike) -> np.ndarray:
    """Gain-free housing Arms ``(2 pi f_m)^2 sqrt(sum_h h^4 D_h^2)`` (m/s^2 per unit gain).

    Parameters
    ----------
    amplitude_m : array_like
        ``(..., N, 3)`` peak DTE amplitudes of harmonics 1..3 (m).
    mesh_frequency_Hz : array_like
        ``(N,)``.

    Returns
    -------
    numpy.ndarray
        ``(..., N)``.

    Examples
    --------
    >>> a = acceleration_arms([[1e-6, 0.0, 0.0]], [1000.0])
    >>> round(float(a[0]), 6) == round((2 * math.pi * 1000.0) ** 2 * 1e-6, 6)
    True
    """
    d = np.asarray(amplitude_m, dtype=float)
    f = np.asarray(mesh_frequency_Hz, dtype=float)
    h4 = np.array([1.0, 16.0, 81.0])
    return (2.0 * math.pi * f) ** 2 * np.sqrt(np.sum(h4 * d * d, axis=-1))


def _other_direction(y: np.ndarray, f: np.ndarray, at: np.ndarray,
                     other: np.ndarray) -> np.ndarray:
    """``y[..., other]`` interpolated linearly in ``ln f`` at the points ``at``; NaN outside.

    ``y`` is ``(..., N)``; a NaN at an ``other`` point makes the values next to it NaN.
    """
    lf = np.log(f)
    o = other[np.argsort(lf[other], kind="stable")]
    x, xo = lf[at], lf[o]
    out = np.full((*y.shape[:-1], at.size), np.nan)
    if o.size < 2:
        return out
    j = np.clip(np.searchsorted(xo, x, side="right") - 1, 0, o.size - 2)
    span = xo[j + 1] - xo[j]
    inside = (x >= xo[0]) & (x <= xo[-1]) & (span > 0)
    w = np.where(inside, (x - xo[j]) / np.where(span > 0, span, 1.0), 0.0)
    v = y[..., o[j]] * (1.0 - w) + y[..., o[j + 1]] * w
    out[..., inside] = v[..., inside]
    return out


def jump_frequencies(log_arms: ArrayLike, mesh_frequency_Hz: ArrayLike,
                     direction: ArrayLike, *, channels_first: bool = False,
                     brackets: bool = False) -> dict[str, np.ndarray]:
    """Where each direction jumps: its step out of the hysteresis band, the largest such.

    A jump is a fold: the curve leaves the branch it followed for the other direction's. So
    a point of one direction lies in the **hysteresis band** when the other direction's curve,
    interpolated in ``ln f_m`` at its mesh frequency, differs from it by more than
    :data:`HYSTERESIS_LOG` in ``log Arms`` (gains cancel: the difference is taken per
    channel, then averaged over the channels observed). A direction's jump is the step,
    between neighbours in time order, from a point in the band to one out of it (the jumping
    curve leaves the band at its fold; the other enters it smoothly); when there are several,
    the one leaving the largest band (the sum of ``|difference|`` over its run of band points:
    over a fold the branches are far apart for several points, while a narrow peak that the
    two directions cross at other frequencies looks like a band of one point, where the
    interpolation cuts its top). Not the largest step of all: on a thinned curve the steep
    flank of a super-harmonic peak outdoes the step over a fold (on the demo's run-up the up
    jump at 2985 Hz falls between points at 2947 and 3142 Hz, a step of 0.33 in
    ``log Arms``, while the flank at 1410-1505 Hz steps by 1.1, with no hysteresis there).

    Parameters
    ----------
    log_arms : array_like
        ``(..., N)`` along the path in time order; NaN where unknown (a pair with a NaN is
        skipped).
    mesh_frequency_Hz : array_like
        ``(N,)``.
    direction : array_like
        ``(N,)`` of ``"up"``, ``"down"``, ``"hold"`` (or None).
    channels_first : bool
        ``log_arms`` is ``(C, N)`` measured curves: the step between two neighbours, and the
        difference from the other direction, are means over the channels observed at both
        (so a channel missing at one point, with its own gain, makes no step), and one
        frequency is returned per direction.
    brackets : bool
        Return the two neighbours' mesh frequencies, ``(..., 2)`` (lower, higher), instead of
        their geometric mean.

    Returns
    -------
    dict
        ``"up"``/``"down"`` -> ``(...)`` geometric mean of the two mesh frequencies around
        the jump (Hz), or ``(..., 2)`` with ``brackets``; NaN when the direction has no two
        neighbouring points or no step out of a hysteresis band (no jump).
    """
    y = np.asarray(log_arms, dtype=float)
    f = np.asarray(mesh_frequency_Hz, dtype=float)
    d = np.asarray(direction, dtype=object)
    out: dict[str, np.ndarray] = {}
    lead = y.shape[1:-1] if channels_first else y.shape[:-1]
    tail = (2,) if brackets else ()
    for name in DIRECTIONS:
        own = np.flatnonzero(d == name)
        other = np.flatnonzero(d == ("down" if name == "up" else "up"))
        pair = np.flatnonzero((d[:-1] == name) & (d[1:] == name))
        if pair.size == 0 or other.size < 2:
            out[name] = np.full((*lead, *tail), np.nan)
            continue
        gap = np.full(y.shape, np.nan)
        gap[..., own] = y[..., own] - _other_direction(y, f, own, other)
        step = y[..., pair + 1] - y[..., pair]
        if channels_first:
            step, gap = (_channel_mean(v) for v in (step, gap))
        with np.errstate(invalid="ignore"):
            band = np.abs(gap) > HYSTERESIS_LOG
        known = np.isfinite(gap)
        leaves = band[..., pair] & known[..., pair + 1] & ~band[..., pair + 1]
        area = _band_area(gap, band, own)[..., pair]
        size = np.where(leaves & np.isfinite(step), area, -1.0)
        k = np.argmax(size, axis=-1)
        found = np.take_along_axis(size, k[..., None], axis=-1)[..., 0] >= 0.0
        lo, hi = f[pair][k], f[pair + 1][k]
        if brackets:
            fj = np.stack([np.minimum(lo, hi), np.maximum(lo, hi)], axis=-1)
            out[name] = np.where(found[..., None], fj, np.nan)
        else:
            out[name] = np.where(found, np.sqrt(lo * hi), np.nan)
    return out


def _band_area(gap: np.ndarray, band: np.ndarray, own: np.ndarray) -> np.ndarray:
    """``sum |gap|`` over the run of band points ending at each point of ``own``, ``(..., N)``.

    ``own`` in time order; a run is broken by a point out of the band or a gap in ``own``
    (another direction between); 0 out of the band.
    """
    area = np.zeros(gap.shape)
    run = np.zeros(gap.shape[:-1])
    prev = -2
    for i in own:
        inside = band[..., i]
        run = np.where(inside, (run if i == prev + 1 else 0.0) + np.abs(gap[..., i]), 0.0)
        area[..., i] = run
        prev = i
    return area


def _channel_mean(v: np.ndarray) -> np.ndarray:
    """Mean over axis 0 of the finite values; NaN where none."""
    ok = np.isfinite(v)
    with np.errstate(invalid="ignore"):
        return np.where(ok.any(axis=0), np.where(ok, v, 0.0).sum(axis=0)
                        / np.maximum(ok.sum(axis=0), 1), np.nan)


@dataclass(frozen=True, eq=False)
class WindowPath:
    """The path a sweep runs for one curve: every window node in time order.

    Attributes
    ----------
    mesh_frequency_Hz : numpy.ndarray
        ``(P,)`` the swept nodes (Hz).
    starts : numpy.ndarray
        ``(N,)`` index of each point's first node (a point's nodes are contiguous: the
        continuation nodes that lead to it, weight 0, then its window nodes).
    weights : numpy.ndarray
        ``(P,)`` each node's weight in its point's power mean (they sum to 1 per point; 0 for
        continuation nodes).
    """

    mesh_frequency_Hz: np.ndarray
    starts: np.ndarray
    weights: np.ndarray

    def power_mean(self, arms: np.ndarray) -> np.ndarray:
        """``(..., P)`` Arms at the nodes -> ``(..., N)`` root of the weighted power mean."""
        a = np.where(self.weights > 0, np.asarray(arms, dtype=float), 0.0)
        return np.sqrt(np.add.reduceat(self.weights * a * a, self.starts, axis=-1))

    def any(self, flags: np.ndarray) -> np.ndarray:
        """``(..., P)`` bool -> ``(..., N)``: true at some window node of the point."""
        f = np.asarray(flags, dtype=bool) & (self.weights > 0)
        return np.logical_or.reduceat(f, self.starts, axis=-1)

    def all(self, flags: np.ndarray) -> np.ndarray:
        """``(..., P)`` bool -> ``(..., N)``: true at every window node of the point."""
        f = np.asarray(flags, dtype=bool) | (self.weights <= 0)
        return np.logical_and.reduceat(f, self.starts, axis=-1)


def window_path(curve: RunUpCurve, *, max_step: float = MAX_PATH_STEP,
                rel_tolerance: float = 1e-9) -> WindowPath:
    """The nodes of every point of ``curve`` in time order, with continuation nodes between.

    Parameters
    ----------
    curve : RunUpCurve
    max_step : float
        Largest step in ``ln f_m`` between swept nodes: where two consecutive nodes are
        farther apart, continuation nodes (weight 0) are inserted at equal steps of
        ``ln f_m`` (:data:`MAX_PATH_STEP`).
    rel_tolerance : float
        Window nodes closer than this (relative) to the point's middle node are one node.

    Returns
    -------
    WindowPath
    """
    nodes = curve.nodes_Hz
    w = np.asarray(WINDOW_WEIGHTS, dtype=float)
    mid = nodes[:, len(w) // 2]
    spread = np.max(np.abs(nodes - mid[:, None]), axis=1) > rel_tolerance * mid
    freq: list[np.ndarray] = []
    weight: list[np.ndarray] = []
    starts = np.empty(nodes.shape[0], dtype=np.int64)
    at = 0
    last = math.nan
    for i, wide in enumerate(spread):
        own, own_w = (nodes[i], w) if wide else (mid[i:i + 1], np.ones(1))
        starts[i] = at
        if math.isfinite(last):
            gap = math.log(own[0]) - math.log(last)
            k = math.ceil(abs(gap) / max_step) - 1
            if k > 0:
                fill = np.exp(math.log(last) + gap * np.arange(1, k + 1) / (k + 1))
                freq.append(fill)
                weight.append(np.zeros(k))
                at += k
        freq.append(own)
        weight.append(own_w)
        at += own.size
        last = float(own[-1])
    return WindowPath(np.concatenate(freq), starts, np.concatenate(weight))


@dataclass(frozen=True, eq=False)
class RunSweep:
    """The modelled run-up of one run for ``W`` parameter sets.

    Attributes
    ----------
    log_mu : numpy.ndarray
        ``(W, N)`` log of the gain-free Arms (:func:`acceleration_arms`), NaN/inf where the
        sweep failed.
    backside_impact : numpy.ndarray
        ``(W, N)`` bool: a back flank was reached at the point.
    contact_loss : numpy.ndarray
        ``(W, N)`` bool.
    converged : numpy.ndarray
        ``(W, N)`` bool: the point settled on a periodic orbit.
    """

    log_mu: np.ndarray
    backside_impact: np.ndarray
    contact_loss: np.ndarray
    converged: np.ndarray


@dataclass(frozen=True, eq=False)
class RunUpForward:
    """One SDOF model over every run-up curve.

    Attributes
    ----------
    kind : {"fvms", "vvms", "lste"}
    curves : tuple of RunUpCurve
    banks : tuple of CycleBank
        One per curve (the run's pair and torque).
    steps_per_period : int
    """

    kind: str
    curves: tuple[RunUpCurve, ...]
    banks: tuple[CycleBank, ...]
    steps_per_period: int

    @cached_property
    def paths(self) -> tuple[WindowPath, ...]:
        """The swept path of every curve (:func:`window_path`), built once."""
        return tuple(window_path(c) for c in self.curves)

    @property
    def scale_range(self) -> tuple[float, float]:
        """Stiffness scales every bank covers (outside: no model)."""
        lo = max(float(np.min(b.scales)) for b in self.banks)
        hi = min(float(np.max(b.scales)) for b in self.banks)
        return lo, hi

    def sweeps(self, zeta: ArrayLike, stiffness_scale: ArrayLike, fluctuation_scale: ArrayLike,
               backlash_m: ArrayLike) -> tuple[RunSweep, ...]:
        """Sweep every run for ``W`` parameter sets (arrays ``(W,)``; backlash total, m)."""
        z = np.ascontiguousarray(zeta, dtype=float)
        s = np.ascontiguousarray(stiffness_scale, dtype=float)
        e = np.ascontiguousarray(fluctuation_scale, dtype=float)
        b = np.ascontiguousarray(backlash_m, dtype=float)
        out = []
        for path, bank in zip(self.paths, self.banks, strict=True):
            sw = sweep_walkers(bank, path.mesh_frequency_Hz, zeta=z, stiffness_scale=s,
                               fluctuation_scale=e, backlash_m=b,
                               steps_per_period=self.steps_per_period,
                               record=path.weights > 0)
            with np.errstate(invalid="ignore", over="ignore"):
                a = path.power_mean(acceleration_arms(sw.amplitude_m, path.mesh_frequency_Hz))
            with np.errstate(divide="ignore", invalid="ignore"):
                log_mu = np.where(a > 0, np.log(a), -np.inf)
            out.append(RunSweep(log_mu=log_mu, backside_impact=path.any(sw.backside_impact),
                                contact_loss=path.any(sw.contact_loss),
                                converged=path.all(sw.converged)))
        return tuple(out)

    def natural_frequency_Hz(self, stiffness_scale: ArrayLike) -> np.ndarray:  # noqa: N802
        """``sqrt(s kbar_F0 / m_e) / 2 pi`` with the first run's bank (Hz)."""
        return np.asarray(self.banks[0].natural_frequency_Hz(stiffness_scale), dtype=float)

    def model_natural_frequency_Hz(self, stiffness_scale: ArrayLike) -> np.ndarray:  # noqa: N802
        """Per run, with the model's own mean stiffness at ``T / s``: ``(R, ...)`` (Hz)."""
        return np.stack([np.asarray(b.model_natural_frequency_Hz(stiffness_scale), dtype=float)
                         for b in self.banks])


def build_forward(kind: str, curves: Sequence[RunUpCurve], pairs: Mapping[str, GearPair],
                  masses_kg: Mapping[str, float | None], *,
                  steps_per_period: int) -> RunUpForward:
    """The banks of one model for every curve.

    Parameters
    ----------
    kind : {"fvms", "vvms", "lste"}
    curves : sequence of RunUpCurve
    pairs : mapping
        Run id -> the run's gear pair.
    masses_kg : mapping
        Run id -> ``m_e`` override (None: the package's convention).
    steps_per_period : int

    Returns
    -------
    RunUpForward
    """
    banks = tuple(cycle_bank(pairs[c.run_id], float(c.torque_Nm), kind,
                             equivalent_mass_kg=masses_kg.get(c.run_id)) for c in curves)
    return RunUpForward(kind=kind, curves=tuple(curves), banks=banks,
                        steps_per_period=int(steps_per_period))

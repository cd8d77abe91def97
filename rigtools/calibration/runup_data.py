r"""Run-up data: the ``arms`` rows of a run turned into the curve the SDOF models are fitted to.

The SDOF run-up calibration compares the single-DOF models with the Arms measured along a
run's speed, up and down (issue 20). This module takes the observations table
(``data_schemas/observations.schema.json``) and gives, per run, one :class:`RunUpCurve`: the
mesh-frequency path in time order the model sweeps (carrying its state, so that the run-up
rows meet the model's up branch and the run-down rows its down branch), the direction of each
point, and the observed Arms and harmonic amplitudes per channel.

Rules
-----
* **Rows used**: ``quantity = "arms"`` rows that are not failed, with a finite ``arms_m_s2``,
  a positive ``mesh_frequency_Hz`` and a ``step_start_s`` (windows along a ramp,
  ``segment = "ramp"``, or speed steps, ``segment = "step"``). Rows of one window or step
  (the same ``step_start_s``) on several channels make one point; a channel without a row there
  is NaN at it. ``low_snr`` rows are kept (counted in the notes); rows whose third harmonic lies
  above the resampler's passband (``above_passband``: ``arms_m_s2`` NaN) are left out and
  counted in the notes.
* **Time order** by ``step_start_s``; ``time_s`` is the middle of the window or step.
* **Direction** from the rows' ``direction`` column (:mod:`rigtools.campaign.observe_orders`),
  computed here the same way for a table written before it existed.
* **Thinning**: each stretch of one direction in time order is reduced, when its direction
  has more than ``max_speed_points`` points, to one window per equal bin of :math:`\ln f_m`
  (of time for ``"hold"`` stretches), in proportion to the stretch's share of the direction's
  points: the window nearest the bin's median. Real windows, not medians over a bin: a median
  of the Arms over a bin as wide as a resonance is no value the model gives at any one mesh
  frequency (it flattened the superharmonic peaks and biased the damping by 2 % on the
  demo's run-up).
* **Windows**: a ramp window is one Hann-windowed order spectrum over ``R`` whole
  revolutions, from ``step_start_s`` to ``step_stop_s``, whose band power is the
  :math:`w^2`-weighted mean of the power along the window *in angle* (the readout band holds
  the slow amplitude modulation: :data:`rigtools.campaign.observe_orders.RAMP_BAND_BINS`). The
  model's value for the window is therefore :math:`\sum_j W_j\,\mu(f_m(t_j))^2` under the
  root, :math:`t_j` the time at which the window has turned the fraction
  :math:`\tfrac12 + \nu_j` of its angle :math:`\theta(t) = \int f_m\,dt`, with
  :math:`\nu = (-\tfrac14, 0, \tfrac14)` (:data:`WINDOW_NODES`) and the weights
  :math:`W = (w, 1 - 2w, w)`, :math:`w = 2/3 - 5/\pi^2` (:data:`WINDOW_WEIGHTS`), which
  integrate every cubic exactly against :math:`\sin^4(\pi u)` (its variance about the
  middle is :math:`1/12 - 5/(8\pi^2)`). :math:`f_m(t)` is the piecewise-linear interpolant of
  the ramp windows' (middle time, :math:`f_m`); a speed step keeps its own :math:`f_m` at
  every node. This is what makes a window that straddles a jump, or a resonance peak
  narrower than a few windows, comparable with the periodic steady sweep (on the demo's
  run-up the window over the down jump was 3.6 times the model at its middle, 1.12 times
  its window mean). Angle, not time: a slow window spends more time at its low-speed end
  than its angle weight gives it, and on the demo's run-up (windows of 8 revolutions spanning
  up to 20 % of :math:`f_m` below 1 kHz, where the Arms rises as :math:`f_m^2` or faster)
  nodes at equal fractions of the duration left the windows' steady-sweep means 1-2 % under
  the analysed values; at equal fractions of the angle, within 0.5 %.
* **Gaps**: where consecutive points are more than :data:`BRIDGE_FACTOR` times the median
  spacing in :math:`\ln f_m` (of the up and down points) apart, model-only points (observed
  NaN) are inserted at equal steps of :math:`\ln f_m` no longer than that median, so the
  model's continuation never jumps; a gap wider than :data:`MAX_GAP_FRACTION` of the run's
  span in :math:`\ln f_m` refuses the run.
* **Refused runs** (item 7 of the issue; :class:`RunUpDataError`, naming the run): no usable
  speed signal (every arms row failed), fewer than ``min_speed_points`` usable points, a span
  :math:`\max f_m / \min f_m` under ``min_span``, a gap as above, no torque, no gear set.
  Whether a ramp reaches the resonance needs the model; :func:`has_interior_maximum` is the
  data's side of that check.

Errors::

    RigtoolsError
    └── CalibrationError (ValueError)
        └── RunUpDataError               a run cannot give a run-up curve; names the run
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Final

import numpy as np
import pandas as pd

from rigtools.calibration.errors import CalibrationError
from rigtools.calibration.runup_config import RunUpSettings
from rigtools.campaign.manifest import AnalysisSettings, Campaign
from rigtools.campaign.observe_orders import DIRECTIONS, ramp_directions, step_directions

__all__ = [
    "BRIDGE_FACTOR",
    "MAX_GAP_FRACTION",
    "SPEED_FAILURE_FLAGS",
    "WINDOW_NODES",
    "WINDOW_WEIGHTS",
    "RunUpCurve",
    "RunUpData",
    "RunUpDataError",
    "direction_stretches",
    "has_interior_maximum",
    "prepare_runup",
    "prepare_runups",
    "runup_runs",
]

#: Consecutive points farther apart than this many median spacings (in ln f_m) are a gap,
#: bridged by model-only points.
BRIDGE_FACTOR: Final = 1.5
#: A gap wider than this fraction of the run's span in ln f_m refuses the run.
MAX_GAP_FRACTION: Final = 0.25
#: Quadrature nodes of a ramp window, fractions of its duration from its middle (module notes).
WINDOW_NODES: Final = (-0.25, 0.0, 0.25)
#: Weights of :data:`WINDOW_NODES` for the Hann window's power weight ``sin^4`` (module notes).
WINDOW_WEIGHTS: Final = (2.0 / 3.0 - 5.0 / math.pi ** 2, 2.0 * (5.0 / math.pi ** 2) - 1.0 / 3.0,
                         2.0 / 3.0 - 5.0 / math.pi ** 2)
#: Points a window's angle is integrated over to place :data:`WINDOW_NODES` (module notes).
_ANGLE_GRID: Final = 129
#: Flags of failed arms rows that mean the run has no usable speed signal.
SPEED_FAILURE_FLAGS: Final = ("speed_missing", "no_speed_step", "arms_failed")
#: The interior maximum of Arms / f_m^2 must stand this much (factor) above both ends.
_PEAK_MARGIN: Final = 1.1
#: Harmonic amplitude columns, h = 1, 2, 3.
_HARMONIC_COLUMNS: Final = ("a1_m_s2", "a2_m_s2", "a3_m_s2")


class RunUpDataError(CalibrationError):
    """A run cannot give a run-up curve (no usable speed, too few points, gaps ...).

    Parameters
    ----------
    detail : str
        What is wrong.
    run : str
        The run at fault.

    Examples
    --------
    >>> str(RunUpDataError("3 usable speed points, fewer than min_speed_points = 20",
    ...                    run="KB-ramp"))
    "run 'KB-ramp': 3 usable speed points, fewer than min_speed_points = 20"
    """

    def __init__(self, detail: str, *, run: str | None = None, key: str | None = None) -> None:
        super().__init__(detail, run=run, key=key)

    def __reduce__(self) -> tuple[Any, ...]:
        return (_rebuild, (self.detail, self.run, self.key))


def _rebuild(detail: str, run: str | None, key: str | None) -> RunUpDataError:
    return RunUpDataError(detail, run=run, key=key)


@dataclass(frozen=True, eq=False)
class RunUpCurve:
    """One run's measured run-up curve, in time order, on the path the model sweeps.

    Attributes
    ----------
    run_id : str
    gear_set : str
        The run's gear set as the campaign writes it (a shipped name or a path), or as given.
    torque_Nm : float
        The run's pinion torque (N m).
    channels : tuple of str
        Accelerometer channels, in table order.
    mesh_frequency_Hz : numpy.ndarray
        Mesh frequency of each point (Hz), shape ``(N,)``, time order, bridging points
        included: the path the model sweeps from the static state at the first point.
    time_s : numpy.ndarray
        Middle of each point's window or step from the start of the recording (s), ``(N,)``;
        bridging points interpolated.
    direction : numpy.ndarray
        ``"up"``, ``"down"`` or ``"hold"`` per point, ``(N,)`` (dtype object).
    observed : numpy.ndarray
        Arms per channel and point (m/s^2), ``(C, N)``; NaN where not observed (bridging
        points, a channel without a row there).
    harmonics : numpy.ndarray
        Peak amplitudes of mesh harmonics 1..3 per channel and point (m/s^2), ``(C, N, 3)``;
        NaN where missing.
    notes : tuple of str
        What was left out, bridged or thinned.
    window_mesh_frequency_Hz : numpy.ndarray, optional
        ``(N, 3)`` mesh frequency at each point's :data:`WINDOW_NODES` (Hz); the model's value
        at the point is the :data:`WINDOW_WEIGHTS` mean of its power there (module notes).
        None: every node at the point's ``mesh_frequency_Hz`` (speed steps).
    """

    run_id: str
    gear_set: str
    torque_Nm: float
    channels: tuple[str, ...]
    mesh_frequency_Hz: np.ndarray
    time_s: np.ndarray
    direction: np.ndarray
    observed: np.ndarray
    harmonics: np.ndarray
    notes: tuple[str, ...] = ()
    window_mesh_frequency_Hz: np.ndarray | None = None

    @property
    def n_points(self) -> int:
        """Points of the path (bridging points included)."""
        return int(self.mesh_frequency_Hz.shape[0])

    @property
    def nodes_Hz(self) -> np.ndarray:  # noqa: N802
        """``(N, 3)`` mesh frequency at each point's window nodes (Hz)."""
        if self.window_mesh_frequency_Hz is None:
            f = np.asarray(self.mesh_frequency_Hz, dtype=float)
            return np.repeat(f[:, None], len(WINDOW_NODES), axis=1)
        return np.asarray(self.window_mesh_frequency_Hz, dtype=float)

    @property
    def observed_mask(self) -> np.ndarray:
        """``(N,)`` bool: points observed on at least one channel (not bridging points)."""
        return np.any(np.isfinite(self.observed), axis=0)


@dataclass(frozen=True, eq=False)
class RunUpData:
    """The run-up curves of a campaign, and the runs refused.

    Attributes
    ----------
    curves : tuple of RunUpCurve
        In the order the runs first appear in the table.
    refused : dict
        Run id -> the message of its :class:`RunUpDataError` (naming the run).
    notes : tuple of str
        Each curve's notes, prefixed with its run.
    """

    curves: tuple[RunUpCurve, ...]
    refused: dict[str, str]
    notes: tuple[str, ...] = ()

    def curve(self, run_id: str) -> RunUpCurve:
        """The curve of run ``run_id`` (KeyError when there is none)."""
        for c in self.curves:
            if c.run_id == run_id:
                return c
        raise KeyError(run_id)


# --------------------------------------------------------------------------------------------
# which runs


def _arms_rows(observations: pd.DataFrame) -> pd.DataFrame:
    missing = [c for c in ("run_id", "quantity", "status") if c not in observations]
    if missing:
        raise CalibrationError(f"the observations table has no column {missing[0]!r} "
                               "(data_schemas/observations.schema.json)")
    return observations.loc[observations["quantity"] == "arms"]


def _num(df: pd.DataFrame, col: str) -> np.ndarray:
    if col not in df:
        return np.full(len(df), np.nan)
    return pd.to_numeric(df[col], errors="coerce").to_numpy(np.float64, na_value=np.nan)


def _usable(rows: pd.DataFrame) -> np.ndarray:
    arms, f, t0 = _num(rows, "arms_m_s2"), _num(rows, "mesh_frequency_Hz"), _num(rows,
                                                                                   "step_start_s")
    return ((rows["status"] != "failed").to_numpy() & np.isfinite(arms) & (arms >= 0)
            & np.isfinite(f) & (f > 0) & np.isfinite(t0))


def _flags(rows: pd.DataFrame) -> list[set[str]]:
    if "quality_flags" not in rows:
        return [set() for _ in range(len(rows))]
    return [set(str(q).split(";")) - {""} if q is not None else set()
            for q in rows["quality_flags"]]


def _candidate(rows: pd.DataFrame) -> bool:
    """A run's arms rows look like a run-up (ramp windows, several steps, or a lost speed)."""
    seg = rows["segment"] if "segment" in rows else pd.Series([None] * len(rows))
    if (seg == "ramp").any():
        return True
    steps = rows.loc[(seg == "step").to_numpy() & _usable(rows)]
    if np.unique(np.round(_num(steps, "step_start_s"), 6)).size >= 2:
        return True
    failed = (rows["status"] == "failed").to_numpy()
    return bool(failed.all() and any(f & set(SPEED_FAILURE_FLAGS) for f in _flags(rows)))


def runup_runs(observations: pd.DataFrame, *, min_span: float | None = None) -> list[str]:
    """Runs whose usable arms rows (ramp windows or speed steps) span ``min_span`` or more.

    Parameters
    ----------
    observations : pandas.DataFrame
        The observations table.
    min_span : float, optional
        Least ratio max/min of the mesh frequency on one channel (default
        ``RunUpSettings().min_span``, 1.3).

    Returns
    -------
    list of str
        Run ids in the order they first appear in the table.
    """
    span = RunUpSettings().min_span if min_span is None else float(min_span)
    arms = _arms_rows(observations)
    out = []
    for run_id, rows in arms.groupby("run_id", sort=False):
        ok = rows.loc[_usable(rows)]
        if "channel" not in ok:
            continue
        for _, ch in ok.groupby("channel", sort=False):
            f = _num(ch, "mesh_frequency_Hz")
            if f.size >= 2 and f.max() / f.min() >= span:
                out.append(str(run_id))
                break
    return out


# --------------------------------------------------------------------------------------------
# one run


def _nanmedian(a: np.ndarray, axis: int) -> np.ndarray:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN slices give NaN, as meant
        return np.nanmedian(a, axis=axis)


@dataclass(frozen=True)
class _Points:
    t_start: np.ndarray   # (N,)
    t_mid: np.ndarray     # (N,)
    f: np.ndarray         # (N,)
    direction: np.ndarray  # (N,) object
    obs: np.ndarray       # (C, N)
    harm: np.ndarray      # (C, N, 3)
    nodes: np.ndarray     # (N, 3) mesh frequency at the window's quadrature nodes

    def select(self, idx: np.ndarray | slice) -> _Points:
        """The points ``idx`` (indices or a slice, in the order given)."""
        return _Points(self.t_start[idx], self.t_mid[idx], self.f[idx], self.direction[idx],
                       self.obs[:, idx], self.harm[:, idx], self.nodes[idx])


def _window_nodes(t_start: np.ndarray, t_stop: np.ndarray, t_mid: np.ndarray, f: np.ndarray,
                  ramp: np.ndarray) -> np.ndarray:
    """Mesh frequency at :data:`WINDOW_NODES` of each ramp window, ``(N, 3)`` (module notes).

    ``f_m(t)`` is the piecewise-linear interpolant of the ramp windows' (middle, f_m) in time
    order, extended linearly beyond the first and last middles (the ends of the first and
    last windows); the node ``nu`` of a window is where it has turned ``1/2 + nu`` of its angle
    ``int f_m dt`` (trapezoidal on :data:`_ANGLE_GRID` points a window, exact to ~1e-6 of
    the window for a piecewise-linear ``f_m``). A step or a window without a stop time keeps
    its own ``f_m`` at every node.
    """
    nu = np.asarray(WINDOW_NODES)
    nodes = np.repeat(f[:, None], nu.size, axis=1)
    use = ramp & np.isfinite(t_stop) & (t_stop > t_start)
    if np.count_nonzero(ramp) < 2 or not use.any():
        return nodes
    order = np.argsort(t_mid[ramp], kind="stable")
    tr, fr = t_mid[ramp][order], f[ramp][order]
    g = np.linspace(0.0, 1.0, _ANGLE_GRID)
    tg = t_start[use][:, None] + g[None, :] * (t_stop - t_start)[use][:, None]
    fg = _interp_extended(tg, tr, fr)
    step = 0.5 * (fg[:, 1:] + fg[:, :-1]) * np.diff(tg, axis=1)
    theta = np.concatenate([np.zeros((tg.shape[0], 1)), np.cumsum(step, axis=1)], axis=1)
    target = (nu + 0.5)[None, :] * theta[:, -1:]
    at = np.stack([np.interp(target[i], theta[i], tg[i]) for i in range(tg.shape[0])])
    nodes[use] = _interp_extended(at, tr, fr)
    return nodes


def _interp_extended(x: np.ndarray, xp: np.ndarray, fp: np.ndarray) -> np.ndarray:
    """``np.interp`` with the end segments extended linearly (``xp`` increasing, >= 2 knots).

    Floored at half the smallest ``fp``: half a window beyond a noisy end segment must not
    reach a mesh frequency the sweep cannot take.
    """
    y = np.interp(x, xp, fp)
    lo, hi = x < xp[0], x > xp[-1]
    if xp[1] > xp[0]:
        y[lo] = fp[0] + (x[lo] - xp[0]) * (fp[1] - fp[0]) / (xp[1] - xp[0])
    if xp[-1] > xp[-2]:
        y[hi] = fp[-1] + (x[hi] - xp[-1]) * (fp[-1] - fp[-2]) / (xp[-1] - xp[-2])
    return np.maximum(y, 0.5 * float(np.min(fp)))


def _points(rows: pd.DataFrame, channels: list[str], rel_tolerance: float) -> _Points:
    """One point per window or step (rows of one ``step_start_s``), in time order."""
    t0 = np.round(_num(rows, "step_start_s"), 6)
    keys, inverse = np.unique(t0, return_inverse=True)
    n, c = keys.size, len(channels)
    t1 = _num(rows, "step_stop_s")
    f = _num(rows, "mesh_frequency_Hz")
    arms = _num(rows, "arms_m_s2")
    harm = np.stack([_num(rows, h) for h in _HARMONIC_COLUMNS], axis=1)
    ch_index = {ch: i for i, ch in enumerate(channels)}
    ci = np.array([ch_index[str(ch)] for ch in rows["channel"]], dtype=np.int64)
    obs = np.full((c, n), np.nan)
    hh = np.full((c, n, 3), np.nan)
    obs[ci, inverse] = arms
    hh[ci, inverse] = harm
    f_pt = np.full(n, np.nan)
    t_mid = np.full(n, np.nan)
    t_stop = np.full(n, np.nan)
    given = np.full(n, None, dtype=object)
    seg = (rows["segment"] if "segment" in rows else pd.Series([None] * len(rows))).to_numpy()
    ramp = np.zeros(n, dtype=bool)
    dirs = rows["direction"].to_numpy(object) if "direction" in rows else np.full(len(rows),
                                                                                None, object)
    for k in range(n):
        sel = inverse == k
        f_pt[k] = float(np.median(f[sel]))
        stop = t1[sel]
        stop = stop[np.isfinite(stop)]
        if stop.size:
            t_stop[k] = float(np.median(stop))
        t_mid[k] = 0.5 * (keys[k] + t_stop[k]) if stop.size else keys[k]
        ramp[k] = bool(np.any(seg[sel] == "ramp"))
        d = [str(v) for v in dirs[sel] if isinstance(v, str) and v in DIRECTIONS]
        if d:
            given[k] = max(set(d), key=d.count)
    missing = np.array([v is None for v in given])
    if missing.any():
        computed = (ramp_directions(t_mid, f_pt, rel_tolerance) if ramp.any() or
                    not np.any(seg == "step") else
                    step_directions(60.0 * f_pt, rel_tolerance))
        given[missing] = computed[missing]
        given[np.array([v is None for v in given])] = "hold"
    return _Points(keys, t_mid, f_pt, given, obs, hh,
                   _window_nodes(keys, t_stop, t_mid, f_pt, ramp))


def direction_stretches(direction: np.ndarray) -> list[tuple[int, int]]:
    """``(start, stop)`` of each run of one direction in time order.

    Parameters
    ----------
    direction : numpy.ndarray
        ``(N,)``.

    Returns
    -------
    list of tuple of int

    Examples
    --------
    >>> direction_stretches(np.array(["up", "up", "down"], dtype=object))
    [(0, 2), (2, 3)]
    """
    out = []
    start = 0
    for i in range(1, direction.size + 1):
        if i == direction.size or direction[i] != direction[start]:
            out.append((start, i))
            start = i
    return out


def _representative(x: np.ndarray, group: np.ndarray) -> int:
    """The member of ``group`` whose ``x`` is nearest the group's median (the earlier on a tie)."""
    return int(group[np.argmin(np.abs(x[group] - np.median(x[group])))])


def _thin(p: _Points, max_points: int) -> tuple[_Points, list[str]]:
    """Each direction thinned to about ``max_points`` windows (module notes)."""
    stretches = direction_stretches(p.direction)
    totals: dict[str, int] = {}
    for a, b in stretches:
        totals[str(p.direction[a])] = totals.get(str(p.direction[a]), 0) + (b - a)
    keep: list[np.ndarray] = []
    kept: dict[str, int] = {}
    for a, b in stretches:
        d = str(p.direction[a])
        n = b - a
        n_bins = n if totals[d] <= max_points else max(1, int(max_points * n / totals[d]))
        if n_bins >= n:
            chosen = np.arange(a, b)
        else:
            x = p.t_mid[a:b] if d == "hold" else np.log(p.f[a:b])
            if d == "hold":
                groups = [g for g in np.array_split(np.arange(n), n_bins) if g.size]
            else:
                edges = np.linspace(x.min(), x.max(), n_bins + 1)
                which = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, n_bins - 1)
                groups = [g for g in (np.flatnonzero(which == j) for j in range(n_bins))
                          if g.size]
            chosen = a + np.sort([_representative(x, g) for g in groups])
        keep.append(chosen)
        kept[d] = kept.get(d, 0) + chosen.size
    notes = [f"{total} {d} points thinned to {kept[d]} (in each of equal bins of "
             f"{'time' if d == 'hold' else 'ln f_m'}, the window nearest the bin's median; "
             f"max_speed_points = {max_points})"
             for d, total in totals.items() if total > max_points]
    return p.select(np.concatenate(keep)), notes


def _concat(pieces: Sequence[_Points]) -> _Points:
    def cat(name: str, axis: int) -> np.ndarray:
        return np.concatenate([getattr(pc, name) for pc in pieces], axis=axis)

    return _Points(cat("t_start", 0), cat("t_mid", 0), cat("f", 0), cat("direction", 0),
                   cat("obs", 1), cat("harm", 1), cat("nodes", 0))


def _bridge(p: _Points, run_id: str) -> tuple[_Points, list[str]]:
    """Model-only points across gaps in ln f_m; RunUpDataError for a gap over the limit."""
    lf = np.log(p.f)
    step = np.abs(np.diff(lf))
    if step.size == 0:
        return p, []
    sweeping = np.array([d != "hold" for d in p.direction])
    both = sweeping[:-1] & sweeping[1:]
    ref = step[both & (step > 0)]
    if ref.size == 0:
        ref = step[step > 0]
    if ref.size == 0:
        return p, []
    med = float(np.median(ref))
    span = float(lf.max() - lf.min())
    gaps = np.flatnonzero(step > BRIDGE_FACTOR * med)
    if not gaps.size:
        return p, []
    worst = int(gaps[np.argmax(step[gaps])])
    if step[worst] > MAX_GAP_FRACTION * span:
        f0, f1 = p.f[worst], p.f[worst + 1]
        raise RunUpDataError(
            f"a gap in the run-up curve from {f0:.0f} to {f1:.0f} Hz (mesh frequency, "
            f"{100 * step[worst] / span:.0f} % of the run's span in ln f_m) between "
            f"{p.t_mid[worst]:.2f} and {p.t_mid[worst + 1]:.2f} s: more than "
            f"{100 * MAX_GAP_FRACTION:.0f} % of the span cannot be bridged", run=run_id)
    c = p.obs.shape[0]
    pieces: list[_Points] = []
    start = 0
    described = []
    n_new = 0
    for g in gaps:
        pieces.append(p.select(slice(start, g + 1)))
        k = math.ceil(step[g] / med) - 1
        u = np.arange(1, k + 1) / (k + 1)
        d = "up" if lf[g + 1] > lf[g] else "down"
        f_new = np.exp(lf[g] + u * (lf[g + 1] - lf[g]))
        pieces.append(_Points(p.t_start[g] + u * (p.t_start[g + 1] - p.t_start[g]),
                              p.t_mid[g] + u * (p.t_mid[g + 1] - p.t_mid[g]), f_new,
                              np.full(k, d, dtype=object), np.full((c, k), np.nan),
                              np.full((c, k, 3), np.nan),
                              np.repeat(f_new[:, None], len(WINDOW_NODES), axis=1)))
        described.append(f"{p.f[g]:.0f}-{p.f[g + 1]:.0f} Hz")
        n_new += k
        start = int(g) + 1
    pieces.append(p.select(slice(start, None)))
    note = (f"{gaps.size} gap(s) in the mesh frequency bridged by {n_new} model-only "
            f"point(s) (no observation): {', '.join(described)}")
    return _concat(pieces), [note]


def _gear_set_name(gear_sets: Campaign | Mapping[str, str], run_id: str) -> str:
    if isinstance(gear_sets, Campaign):
        try:
            return gear_sets.gear_set_for(run_id)
        except KeyError:
            raise RunUpDataError(f"not a run of the campaign {gear_sets.name!r} (no gear set)",
                                 run=run_id) from None
    if run_id not in gear_sets:
        raise RunUpDataError("no gear set given for the run", run=run_id)
    return str(gear_sets[run_id])


def _no_speed_message(rows: pd.DataFrame) -> str:
    msgs = [str(m) for m in rows.get("message", pd.Series(dtype=object)) if m]
    why = "; ".join(dict.fromkeys(msgs)) or "every arms row failed"
    return f"no usable speed signal, so no run-up curve ({why})"


def prepare_runup(observations: pd.DataFrame, run_id: str, gear_set: str,
                  settings: RunUpSettings | None = None, *,
                  rel_tolerance: float | None = None) -> RunUpCurve:
    """The run-up curve of one run (module notes for the rules).

    Parameters
    ----------
    observations : pandas.DataFrame
        The observations table.
    run_id : str
    gear_set : str
        The run's gear set (as written in the campaign, or a shipped name).
    settings : RunUpSettings, optional
        ``[calibration.runup]`` (default: its defaults).
    rel_tolerance : float, optional
        Relative tolerance of ``"hold"`` when the table has no ``direction`` column (default
        ``[analysis] step_rel_tolerance``'s default, 0.01).

    Returns
    -------
    RunUpCurve

    Raises
    ------
    RunUpDataError
        The run has no arms rows, no usable speed signal, fewer than ``min_speed_points``
        usable points, a span under ``min_span``, a gap over :data:`MAX_GAP_FRACTION` of its
        span, or no torque. The message names the run.
    """
    cfg = RunUpSettings() if settings is None else settings
    tol = AnalysisSettings().step_rel_tolerance if rel_tolerance is None else rel_tolerance
    arms = _arms_rows(observations)
    rows = arms.loc[arms["run_id"].astype(str) == str(run_id)]
    if rows.empty:
        raise RunUpDataError("no arms rows (is [sensors] speed set?)", run=run_id)
    usable = _usable(rows)
    flags = _flags(rows)
    notes: list[str] = []
    if not usable.any():
        failed = (rows["status"] == "failed").to_numpy()
        if failed.all() or any(f & set(SPEED_FAILURE_FLAGS) for f in flags):
            raise RunUpDataError(_no_speed_message(rows.loc[failed]), run=run_id)
        raise RunUpDataError("no arms row with a finite Arms (a mesh harmonic above the "
                             "resampler's passband in every row?)", run=run_id)
    n_failed = int(np.count_nonzero((rows["status"] == "failed").to_numpy()))
    passband = np.array(["above_passband" in f for f in flags]) & ~usable
    if n_failed:
        notes.append(f"{n_failed} failed arms row(s) left out")
    if passband.any():
        notes.append(f"{int(np.count_nonzero(passband))} arms row(s) left out: a mesh harmonic "
                     "above the resampler's passband (a3 NaN)")
    other = ~usable & ~passband & (rows["status"] != "failed").to_numpy()
    if other.any():
        notes.append(f"{int(np.count_nonzero(other))} arms row(s) left out: no finite Arms, "
                     "mesh frequency or start time")
    ok = rows.loc[usable]
    low = int(sum("low_snr" in f for f, u in zip(flags, usable, strict=True) if u))
    if low:
        notes.append(f"{low} arms row(s) kept with low_snr (weakest harmonic near the floor)")
    channels = list(dict.fromkeys(str(c) for c in ok["channel"]))
    torque = _num(ok, "torque_Nm")
    torque = torque[np.isfinite(torque)]
    if not torque.size:
        raise RunUpDataError("no torque_Nm on its arms rows (the model needs the torque)",
                             run=run_id)
    pts = _points(ok, channels, tol)
    n = pts.f.size
    if n < cfg.min_speed_points:
        raise RunUpDataError(f"{n} usable speed point(s), fewer than min_speed_points = "
                             f"{cfg.min_speed_points} ([calibration.runup])", run=run_id)
    ratio = float(pts.f.max() / pts.f.min())
    if ratio < cfg.min_span:
        raise RunUpDataError(f"the mesh frequency spans {pts.f.min():.0f}-{pts.f.max():.0f} Hz "
                             f"(max/min {ratio:.3g}), less than min_span = {cfg.min_span:g} "
                             "([calibration.runup]): not a run-up", run=run_id)
    pts, bin_notes = _thin(pts, cfg.max_speed_points)
    pts, gap_notes = _bridge(pts, run_id)
    return RunUpCurve(
        run_id=str(run_id), gear_set=gear_set, torque_Nm=float(np.median(torque)),
        channels=tuple(channels), mesh_frequency_Hz=pts.f, time_s=pts.t_mid,
        direction=pts.direction.astype(object), observed=pts.obs, harmonics=pts.harm,
        notes=tuple([*notes, *bin_notes, *gap_notes]), window_mesh_frequency_Hz=pts.nodes)


def prepare_runups(observations: pd.DataFrame, gear_sets: Campaign | Mapping[str, str],
                   settings: RunUpSettings | None = None, *,
                   runs: Sequence[str] | None = None) -> RunUpData:
    """The run-up curves of a campaign's runs; the runs that cannot give one, refused.

    Parameters
    ----------
    observations : pandas.DataFrame
        The observations table.
    gear_sets : Campaign or mapping
        The campaign (each run's gear set from :meth:`Campaign.gear_set_for`), or run id ->
        gear-set name.
    settings : RunUpSettings, optional
        ``[calibration.runup]`` (default: its defaults).
    runs : sequence of str, optional
        The runs to prepare, each refused with its reason when it cannot give a curve.
        Default: every run whose arms rows look like a run-up (ramp windows, two or more speed
        steps, or every row failed for want of a speed signal).

    Returns
    -------
    RunUpData
        Never raises for a bad run: its :class:`RunUpDataError` message is in ``refused``.
    """
    cfg = RunUpSettings() if settings is None else settings
    arms = _arms_rows(observations)
    tol = AnalysisSettings().step_rel_tolerance
    meta = observations.attrs.get("rigtools", {}) if hasattr(observations, "attrs") else {}
    try:
        tol = float(meta["campaign"]["analysis"]["step_rel_tolerance"])
    except (KeyError, TypeError, ValueError):
        pass
    if runs is None:
        chosen = [str(r) for r, rows in arms.groupby("run_id", sort=False) if _candidate(rows)]
    else:
        chosen = [str(r) for r in runs]
    curves: list[RunUpCurve] = []
    refused: dict[str, str] = {}
    notes: list[str] = []
    for run_id in chosen:
        try:
            gs = _gear_set_name(gear_sets, run_id)
            curve = prepare_runup(observations, run_id, gs, cfg, rel_tolerance=tol)
        except RunUpDataError as exc:
            refused[run_id] = str(exc)
            continue
        curves.append(curve)
        notes.extend(f"run {run_id!r}: {n}" for n in curve.notes)
    return RunUpData(curves=tuple(curves), refused=refused, notes=tuple(notes))


# --------------------------------------------------------------------------------------------
# checks for the calibration


def has_interior_maximum(curve: RunUpCurve) -> bool:
    r"""Whether the measured :math:`A_{rms} / f_m^2` peaks inside the run's speed range.

    Below the resonance the housing acceleration of a quasi-static DTE grows as
    :math:`f_m^2`; a run whose :math:`A_{rms}/f_m^2` is largest at an end of its range has
    not reached (or not come back from) the mesh resonance. Each channel's
    :math:`\ln(A_{rms}/f_m^2)` is taken relative to its median, the channels' median per point
    smoothed by a running median of five points in order of :math:`f_m`, and the maximum must
    lie off the lowest and highest 5 % of the points (at least one each side) and stand a
    factor of 1.1 above both ends.

    Parameters
    ----------
    curve : RunUpCurve

    Returns
    -------
    bool
    """
    f = np.asarray(curve.mesh_frequency_Hz, np.float64)
    obs = np.asarray(curve.observed, np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        y = np.where(np.isfinite(obs) & (obs > 0), np.log(obs) - 2.0 * np.log(f), np.nan)
    y = y - _nanmedian(y, axis=1)[:, None]
    comb = _nanmedian(y, axis=0)
    ok = np.isfinite(comb)
    if np.count_nonzero(ok) < 5:
        return False
    order = np.argsort(f[ok], kind="stable")
    v = comb[ok][order]
    n = v.size
    w = 2
    smooth = np.array([np.median(v[max(0, i - w):i + w + 1]) for i in range(n)])
    edge = max(1, n // 20)
    i_max = int(np.argmax(smooth))
    if not edge <= i_max < n - edge:
        return False
    ends = max(float(np.max(smooth[:edge])), float(np.max(smooth[-edge:])))
    return bool(smooth[i_max] > ends + math.log(_PEAK_MARGIN))

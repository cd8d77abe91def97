r"""From the observations table to what the calibration fits: runs, conditions, candidate peaks.

Input: the observations table of ``rigtools observe`` as a DataFrame
(``data_schemas/observations.schema.json``). Used columns: ``run_id``, ``quantity``,
``status``, ``message``, ``channel``, ``torque_Nm``, ``bulk_temperature_C``,
``oil_temperature_C``, ``f_n_Hz``, ``f_n_std_Hz``, ``prominence_dB``, ``quality_flags``.

Runs, in order of first appearance. A run is **left out**, with the reason recorded (and
listed in ``summary.json``), when:

* its ``run`` row has ``status == "failed"`` (the reason is the row's message);
* its torque or bulk temperature is missing, NaN or not a number (conditions repeat on every
  row; the first finite value is used), or the torque is not > 0;
* it has no usable natural-frequency row: none at all, none on the configured channels, or
  only failed rows / rows without a positive finite ``f_n_Hz``;
* every candidate lies outside a configured ``band_Hz``.

No run left: :class:`~rigtools.calibration.errors.CalibrationError` listing each run's reason.

Candidates: every usable natural-frequency row of the run, all channels (the likelihood's
mixture decides which, if any, is the mesh mode). ``f_n_std_Hz`` missing or not > 0 counts as
0 (the model-error term still widens the likelihood).

The band the peaks were searched in matters: a mesh mode predicted inside it should have
been seen, one predicted outside could not have been. It is ``band_Hz`` when configured, else
the ``f_range_Hz`` of the analysis settings the table carries (``df.attrs["rigtools"]
["campaign"]["analysis"]``, as ``read_observations`` returns them), else ``[1 Hz, 1.25
f_max]`` with ``f_max`` the highest candidate of the campaign: the analysis searches from the
first bins up, and nothing was found above ``f_max``. (A band cut tightly around the candidates
would let a fit "hide" the mesh mode below them at no cost.)

The background: recurring peaks
-------------------------------
A peak that is not the mesh mode is *background*: a spurious peak, with density uniform on the
band, ``U = 1 / (f_hi - f_lo)``, or an observation of a structural (housing, shaft) mode,
which recurs at one frequency whatever the load and temperature. With
``structural_modes = "auto"`` (default) recurring groups are found in the table: sorted
candidate frequencies are split where consecutive ones differ by more than 1 %; a group
spanning at most 3 % that holds peaks of at least ``max(3, R / 2)`` runs, under at least two
distinct conditions (torque or temperature), is *recurring* (at most the three largest), with
centre ``h_k`` the median and width ``s_k = max(1.4826 MAD, median fit sd, 0.2 % h_k)``.

A recurring group is either a structural mode, its peaks then having the narrow density
``N(f | h_k, s_k)``, or it is not (its peaks are ordinary candidates with density ``U``, free to
be the mesh mode). Which, the data decide: the likelihood marginalises this campaign-level
choice over all ``2^K`` configurations (equal prior weight; :mod:`rigtools.calibration.
likelihood`). Why it matters: a peak that stays put while the load changes is what the tangent
reading predicts for the mesh mode, and it fits it with the housing mode's tiny scatter; with a
uniform background only, that reading would "win" by explaining the housing mode and calling
the real, load-dependent mesh mode noise. With the structural alternative the housing mode is
explained as such, and a moving peak present in every run cannot be dismissed cheaply. When
the mesh mode itself does not move (``c = c*`` or the tangent reading true), the configuration
in which its group is *not* structural explains the data far better, so its information is
kept.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

import numpy as np
import pandas as pd

from rigtools.calibration.config import CalibrationConfig
from rigtools.calibration.errors import CalibrationError

__all__ = [
    "BAND_LOW_HZ",
    "BAND_MARGIN",
    "GROUP_GAP",
    "GROUP_SPAN",
    "MAX_STRUCTURAL_MODES",
    "REQUIRED_COLUMNS",
    "CalibrationData",
    "Candidates",
    "RunConditions",
    "StructuralMode",
    "find_structural_modes",
    "prepare_data",
]

#: Consecutive sorted candidates further apart than this (relative) start a new group.
GROUP_GAP: Final = 0.01
#: A structural mode's group spans at most this (relative).
GROUP_SPAN: Final = 0.03
#: At most this many recurring groups (the likelihood sums over 2^K configurations).
MAX_STRUCTURAL_MODES: Final = 3

#: Columns the calibration reads.
REQUIRED_COLUMNS = ("run_id", "quantity", "status", "channel", "torque_Nm",
                    "bulk_temperature_C", "f_n_Hz")
#: Default band: up to the highest candidate times this factor ...
BAND_MARGIN = 1.25
#: ... from this frequency (Hz).
BAND_LOW_HZ = 1.0


@dataclass(frozen=True, eq=False)
class RunConditions:
    """Conditions of the runs that enter the fit.

    Attributes
    ----------
    run_id : tuple of str
    torque_Nm, bulk_temperature_C, oil_temperature_C : numpy.ndarray
        Shape ``(R,)``; oil NaN where not logged.
    """

    run_id: tuple[str, ...]
    torque_Nm: np.ndarray
    bulk_temperature_C: np.ndarray
    oil_temperature_C: np.ndarray

    @property
    def n_runs(self) -> int:
        """``R``."""
        return len(self.run_id)


@dataclass(frozen=True, eq=False)
class Candidates:
    """Candidate peaks of each run, padded to ``J`` (the most of any run).

    Attributes
    ----------
    f_Hz, sd_Hz : numpy.ndarray
        ``(R, J)``; padding holds 1.0 and 0.0 (masked).
    mask : numpy.ndarray
        Bool ``(R, J)``, True for a real candidate.
    channel : numpy.ndarray
        Object ``(R, J)``, the channel of each candidate (None in padding).
    row : numpy.ndarray
        Int ``(R, J)``: position of the row in the observations table (-1 in padding).
    prominence_dB : numpy.ndarray
        ``(R, J)``, NaN where unknown.
    count : numpy.ndarray
        Candidates per run, ``(R,)``.
    band_Hz : (float, float)
        Band of the background density.
    log_background : numpy.ndarray
        ``ln b(f)`` of each candidate (ln 1/Hz) under each configuration of the recurring
        groups, ``(Z, R, J)`` with ``Z = 2^K`` (0 in padding): configuration ``z`` takes group
        ``k`` as a structural mode when bit ``k`` of ``z`` is set.
    group : numpy.ndarray
        Int ``(R, J)``: the recurring group of each candidate, -1 for none.
    structural_modes : tuple of StructuralMode
        The recurring groups.
    """

    f_Hz: np.ndarray
    sd_Hz: np.ndarray
    mask: np.ndarray
    channel: np.ndarray
    row: np.ndarray
    prominence_dB: np.ndarray
    count: np.ndarray
    band_Hz: tuple[float, float]
    log_background: np.ndarray
    group: np.ndarray
    structural_modes: tuple[StructuralMode, ...] = ()

    @property
    def n_configurations(self) -> int:
        """``Z = 2^K``."""
        return int(self.log_background.shape[0])


@dataclass(frozen=True)
class StructuralMode:
    """A peak that recurs at one frequency across runs and conditions (module notes).

    Attributes
    ----------
    frequency_Hz : float
        Median of the group.
    width_Hz : float
        Standard deviation of its background density component.
    n_peaks : int
        Candidates in the group.
    n_runs : int
        Runs holding one of them.
    """

    frequency_Hz: float
    width_Hz: float
    n_peaks: int
    n_runs: int


@dataclass(frozen=True, eq=False)
class CalibrationData:
    """The fit's view of an observations table.

    Attributes
    ----------
    runs : RunConditions
    candidates : Candidates
    left_out : dict
        Run id -> reason, for runs not fitted, in table order.
    notes : tuple of str
        What was adjusted on the way (missing sd, rows outside the band).
    """

    runs: RunConditions
    candidates: Candidates
    left_out: dict[str, str]
    notes: tuple[str, ...]


def _first_finite(values: pd.Series) -> float:
    for v in values:
        try:
            x = float(v)
        except (TypeError, ValueError):
            continue
        if math.isfinite(x):
            return x
    return math.nan


def prepare_data(observations: pd.DataFrame, config: CalibrationConfig) -> CalibrationData:
    """Runs, conditions and candidate peaks for the fit (module notes for the rules).

    Parameters
    ----------
    observations : pandas.DataFrame
        The observations table.
    config : CalibrationConfig
        ``channels`` and ``band_Hz`` are used.

    Returns
    -------
    CalibrationData

    Raises
    ------
    CalibrationError
        A required column is missing, or no run is usable (each run's reason is listed).
    """
    if not isinstance(observations, pd.DataFrame):
        raise CalibrationError(f"the observations must be a pandas DataFrame, was "
                               f"{type(observations).__name__}")
    missing = [c for c in REQUIRED_COLUMNS if c not in observations.columns]
    if missing:
        raise CalibrationError(f"the observations table lacks the column(s) "
                               f"{', '.join(missing)} (data_schemas/observations.schema.json)")
    obs = observations.reset_index(drop=True)
    if obs.empty:
        raise CalibrationError("the observations table has no rows")
    run_order = list(dict.fromkeys(str(r) for r in obs["run_id"]))
    left_out: dict[str, str] = {}
    notes: list[str] = []
    kept: list[tuple[str, float, float, float, pd.DataFrame]] = []
    channels = set(config.channels)
    quantity = obs["quantity"].astype(str)
    status = obs["status"].astype(str)
    for run_id in run_order:
        rows = obs[obs["run_id"].astype(str) == run_id]
        q = quantity.loc[rows.index]
        st = status.loc[rows.index]
        run_rows = rows[q == "run"]
        if len(run_rows) and (st.loc[run_rows.index] == "failed").any():
            msg = ""
            if "message" in rows.columns:
                msg = str(run_rows["message"].iloc[0] or "").strip()
            left_out[run_id] = f"the run failed in the observations stage: {msg or 'no reason'}"
            continue
        torque = _first_finite(rows["torque_Nm"])
        temp = _first_finite(rows["bulk_temperature_C"])
        oil = _first_finite(rows["oil_temperature_C"]) if "oil_temperature_C" in rows else math.nan
        if not math.isfinite(torque):
            left_out[run_id] = "torque_Nm is missing or NaN"
            continue
        if not torque > 0:
            left_out[run_id] = f"torque_Nm must be > 0, was {torque:g}"
            continue
        if not math.isfinite(temp):
            left_out[run_id] = "bulk_temperature_C is missing or NaN"
            continue
        nf = rows[(q == "natural_frequency")]
        if nf.empty:
            left_out[run_id] = "no natural-frequency rows"
            continue
        if channels:
            nf = nf[nf["channel"].astype(str).isin(channels)]
            if nf.empty:
                left_out[run_id] = (f"no natural-frequency rows on the configured channels "
                                    f"({', '.join(sorted(channels))})")
                continue
        f = pd.to_numeric(nf["f_n_Hz"], errors="coerce")
        ok = (st.loc[nf.index] != "failed") & np.isfinite(f) & (f > 0)
        nf = nf[ok.to_numpy()]
        if nf.empty:
            left_out[run_id] = "no usable natural-frequency row (all failed or without f_n_Hz)"
            continue
        kept.append((run_id, torque, temp, oil, nf))
    if not kept:
        reasons = "; ".join(f"{r}: {why}" for r, why in left_out.items())
        raise CalibrationError(f"no run of the observations table can be fitted ({reasons})")
    all_f = np.concatenate([pd.to_numeric(nf["f_n_Hz"]).to_numpy(float)
                            for *_, nf in kept])
    band = _band(observations, config, all_f)
    per_run = []
    n_no_sd = 0
    n_outside = 0
    for run_id, torque, temp, oil, nf in kept:
        f = pd.to_numeric(nf["f_n_Hz"]).to_numpy(float)
        inside = (f >= band[0]) & (f <= band[1])
        n_outside += int((~inside).sum())
        if not inside.any():
            left_out[run_id] = (f"every natural-frequency row lies outside band_Hz = "
                                f"[{band[0]:g}, {band[1]:g}] Hz")
            continue
        nf = nf[inside]
        f = f[inside]
        sd = (pd.to_numeric(nf["f_n_std_Hz"], errors="coerce").to_numpy(float)
              if "f_n_std_Hz" in nf else np.full(f.shape, np.nan))
        bad = ~(np.isfinite(sd) & (sd > 0))
        n_no_sd += int(bad.sum())
        sd = np.where(bad, 0.0, sd)
        prom = (pd.to_numeric(nf["prominence_dB"], errors="coerce").to_numpy(float)
                if "prominence_dB" in nf else np.full(f.shape, np.nan))
        per_run.append((run_id, torque, temp, oil, f, sd, nf["channel"].to_numpy(object),
                        np.asarray(nf.index), prom))
    if not per_run:
        reasons = "; ".join(f"{r}: {why}" for r, why in left_out.items())
        raise CalibrationError(f"no run of the observations table can be fitted ({reasons})")
    if n_no_sd:
        notes.append(f"{n_no_sd} natural-frequency row(s) without a positive f_n_std_Hz: "
                     "their fit uncertainty counts as 0 (the model-error term remains)")
    if n_outside:
        notes.append(f"{n_outside} natural-frequency row(s) outside band_Hz = "
                     f"[{band[0]:g}, {band[1]:g}] Hz are not candidates")
    n_r = len(per_run)
    n_j = max(len(p[4]) for p in per_run)
    f_arr = np.ones((n_r, n_j))
    sd_arr = np.zeros((n_r, n_j))
    mask = np.zeros((n_r, n_j), dtype=bool)
    chan = np.full((n_r, n_j), None, dtype=object)
    row = np.full((n_r, n_j), -1, dtype=np.int64)
    prom_arr = np.full((n_r, n_j), np.nan)
    for i, (_, _, _, _, f, sd, ch, idx, prom) in enumerate(per_run):
        k = len(f)
        f_arr[i, :k], sd_arr[i, :k], mask[i, :k] = f, sd, True
        chan[i, :k] = ch
        row[i, :k] = idx
        prom_arr[i, :k] = prom
    runs = RunConditions(
        run_id=tuple(p[0] for p in per_run),
        torque_Nm=np.array([p[1] for p in per_run]),
        bulk_temperature_C=np.array([p[2] for p in per_run]),
        oil_temperature_C=np.array([p[3] for p in per_run]),
    )
    order = {r: i for i, r in enumerate(run_order)}
    left_sorted = dict(sorted(left_out.items(), key=lambda kv: order[kv[0]]))
    modes: tuple[StructuralMode, ...] = ()
    if config.structural_modes == "auto":
        modes = find_structural_modes(f_arr, sd_arr, mask, runs.torque_Nm,
                                      runs.bulk_temperature_C)
    group, log_b = _log_background(f_arr, mask, band, modes)
    if modes:
        notes.append("recurring peaks (structural mode or not, decided by the fit): " +
                     ", ".join(f"{m.frequency_Hz:.5g} Hz ({m.n_runs} runs)" for m in modes))
    cands = Candidates(f_Hz=f_arr, sd_Hz=sd_arr, mask=mask, channel=chan, row=row,
                       prominence_dB=prom_arr, count=mask.sum(axis=1), band_Hz=band,
                       log_background=log_b, group=group, structural_modes=modes)
    return CalibrationData(runs=runs, candidates=cands, left_out=left_sorted,
                           notes=tuple(notes))


def _band(observations: pd.DataFrame, config: CalibrationConfig,
          all_f: np.ndarray) -> tuple[float, float]:
    if config.band_Hz is not None:
        return config.band_Hz
    meta = observations.attrs.get("rigtools") if hasattr(observations, "attrs") else None
    f_range = None
    if isinstance(meta, dict):
        analysis = (meta.get("campaign") or {}).get("analysis") or {}
        f_range = analysis.get("f_range_Hz") if isinstance(analysis, dict) else None
    if f_range is not None and len(f_range) == 2 and 0 < f_range[0] < f_range[1]:
        return float(f_range[0]), float(f_range[1])
    return BAND_LOW_HZ, float(all_f.max()) * BAND_MARGIN


def find_structural_modes(f_Hz: np.ndarray, sd_Hz: np.ndarray, mask: np.ndarray,
                          torque_Nm: np.ndarray,
                          temperature_C: np.ndarray) -> tuple[StructuralMode, ...]:
    """Recurring peaks: groups at one frequency across runs and conditions (module notes).

    Parameters
    ----------
    f_Hz, sd_Hz, mask : numpy.ndarray
        Candidates ``(R, J)``.
    torque_Nm, temperature_C : numpy.ndarray
        Conditions ``(R,)``.

    Returns
    -------
    tuple of StructuralMode
    """
    n_r = f_Hz.shape[0]
    r_idx, j_idx = np.nonzero(mask)
    if r_idx.size == 0:
        return ()
    f = f_Hz[r_idx, j_idx]
    order = np.argsort(f, kind="stable")
    f, r_idx, sd = f[order], r_idx[order], sd_Hz[r_idx[order], j_idx[order]]
    cuts = np.flatnonzero(np.diff(np.log(f)) > GROUP_GAP) + 1
    need = max(3, int(np.ceil(0.5 * n_r)))
    modes = []
    for g in np.split(np.arange(f.size), cuts):
        fg = f[g]
        runs = np.unique(r_idx[g])
        conditions = {(float(torque_Nm[r]), float(temperature_C[r])) for r in runs}
        if runs.size < need or len(conditions) < 2 or np.log(fg[-1] / fg[0]) > GROUP_SPAN:
            continue
        centre = float(np.median(fg))
        mad = 1.4826 * float(np.median(np.abs(fg - centre)))
        width = max(mad, float(np.median(sd[g])), 0.002 * centre)
        modes.append(StructuralMode(centre, width, int(g.size), int(runs.size)))
    modes.sort(key=lambda m: -m.n_peaks)
    return tuple(modes[:MAX_STRUCTURAL_MODES])


def _log_background(f_Hz: np.ndarray, mask: np.ndarray, band: tuple[float, float],
                    modes: tuple[StructuralMode, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Group of each candidate and ``ln b`` per configuration ``(2^K, R, J)``."""
    log_u = -np.log(band[1] - band[0])
    group = np.full(f_Hz.shape, -1, dtype=np.int64)
    log_s = np.zeros(f_Hz.shape)
    for k, m in enumerate(modes):
        lo, hi = m.frequency_Hz * np.exp(-GROUP_SPAN), m.frequency_Hz * np.exp(GROUP_SPAN)
        member = mask & (f_Hz >= lo) & (f_Hz <= hi) & (group < 0)
        group[member] = k
        z = (f_Hz - m.frequency_Hz) / m.width_Hz
        log_s = np.where(member, -0.5 * z * z - np.log(m.width_Hz * np.sqrt(2.0 * np.pi)),
                         log_s)
    n_z = 2 ** len(modes)
    out = np.empty((n_z, *f_Hz.shape))
    for cfg in range(n_z):
        structural = np.array([(cfg >> k) & 1 for k in range(len(modes))], dtype=bool)
        is_s = (group >= 0) & structural[np.maximum(group, 0)] if modes else \
            np.zeros(f_Hz.shape, dtype=bool)
        out[cfg] = np.where(mask, np.where(is_s, log_s, log_u), 0.0)
    return group, out

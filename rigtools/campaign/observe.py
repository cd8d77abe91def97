r"""The observations table: one tidy table per campaign, the input of calibration and reports.

:func:`observe_campaign` reads every run of a :class:`~rigtools.campaign.Campaign`
(:func:`read_run`: :func:`rigtools.ingest.read` with the run's effective sensors), analyses its
accelerometer channels (:func:`observe_recording`
(:func:`~rigtools.analysis.recording.analyse_recording`: Welch PSD, RMS, natural frequencies with
damping and uncertainties; :func:`~rigtools.analysis.orders.step_levels`: mesh harmonics and
Arms per speed step) and collects the numbers in one long :class:`pandas.DataFrame`.
:func:`observe_run` is the two steps for one run; a pipeline that keeps the recording between
them (normalized Parquet) calls :func:`read_run` and :func:`observe_recording` apart.

Layout
------
A long table with a ``quantity`` column; the columns, their units and their meaning are the
contract ``data_schemas/observations.schema.json`` (column order and dtypes come from it):

==================  ==========================================================================
quantity            rows
==================  ==========================================================================
``run``             one per run: conditions, duration, ingest losses, provenance; the one row
                    of a run that could not be read (``status = "failed"``, ``message`` says
                    why, naming the file)
``rms``             one per run x channel: full-band RMS (time domain and Parseval) and the
                    channel's quality (gaps, clipping, Welch windows, dropped segments)
``natural_frequency``
                    one per structural PSD peak of a channel (``mode_index`` 0, 1, ... by
                    frequency; ``peak_kind = "structural"``): ``f_n_Hz``, ``f_n_std_Hz``,
                    ``zeta``, ``zeta_std`` (SDOF fit of the ``response`` column), half-power
                    damping, prominence. A broad peak is a mode wherever it sits; a mesh or
                    shaft line on it is masked out of its fit and flags it ``at_mesh_line``
``line``            one per line that sits on a mode (within its half-power band): ``f_Hz``,
                    ``peak_kind`` (``mesh_harmonic``, ``mesh_sideband``, ``shaft_harmonic``,
                    ``tonal``), prominence, and the ``mode_index`` of the mode it sits on
``arms``            one per channel x speed step (``segment = "step"``, ``step_index``), when
                    ``[sensors] speed`` is set: step speed, mesh frequency, amplitudes of mesh
                    harmonics 1-3 and :math:`A_{rms} = \sqrt{A_1^2 + A_2^2 + A_3^2}`; when the
                    speed has no plateau (a ramped run-up), one per channel x window of
                    ``revs_per_block`` revolutions along the ramp (``segment = "ramp"``,
                    :func:`~rigtools.analysis.orders.run_up_curve`), with the window's speed
                    and mesh frequency
==================  ==========================================================================

Conditions (``torque_Nm``, ``bulk_temperature_C``, ``oil_temperature_C``, ``speed_rpm``),
provenance (``source_file``, ``source_sha256``, ``reader``, ``rigtools_version``) and the
channel's quality counts repeat on every row, so a row stands alone after any filter. Columns
that do not apply to a row's quantity are null (NaN for floats).

Quality flags
-------------
Four boolean columns (``flag_gaps``, ``flag_clipping``, ``flag_low_snr``,
``flag_windows_dropped``) and the full list in ``quality_flags`` (``;``-separated, vocabulary
:data:`~rigtools.campaign.observation_table.FLAGS`). ``status`` is ``"ok"`` (no flag),
``"flagged"`` (a value, with flags) or ``"failed"`` (no value; ``message`` says why). A
``run`` row is ``"flagged"`` as soon as any row of the run is failed or flagged: its flags are
the union of theirs and its message counts them per channel. Low SNR: a natural frequency whose
peak prominence, or a mesh harmonic whose level (its local floor subtracted) above the
order-spectrum floor (in the same bandwidth), is under ``[analysis] low_snr_dB`` (default
10 dB). A flag means a user should
look: a mode merely near a mesh harmonic is not flagged (only a mesh or shaft line found on
it, within its half-power band, is), and a sample rate estimated from stamps that fit a
uniform grid (to within half a sample, the logger clock drifting by at most 100 ppm) is not
worth a warning (stamps that do not fit flag the run ``time_base_irregular``).

Failures
--------
A run that cannot be read or analysed becomes a failed ``run`` row and the campaign goes on.
A channel that cannot be analysed (constant, too short, missing, unit not an acceleration)
gets a failed ``rms`` row; a speed signal that is missing gives failed ``arms`` rows (and a
run warning). When the speed varies beyond ``[analysis] step_rel_tolerance`` the mesh line
sweeps the spectrum, so natural-frequency rows are flagged ``speed_varies``. Nothing is dropped
silently.

Files
-----
The ``arms`` rows are made by :mod:`rigtools.campaign.observe_orders`; a row's status from its
flags by :mod:`rigtools.campaign.observation_rows`. The table's columns, flags and result
classes are in
:mod:`rigtools.campaign.observation_table`; its files in
:mod:`rigtools.campaign.observation_files`: :func:`~rigtools.campaign.write_observations`
writes Parquet with the schema JSON in the file metadata (``rigtools.observations.schema``) and
the resolved campaign, analysis settings and library versions (``rigtools.observations``);
:func:`~rigtools.campaign.read_observations` reads it back and
:func:`~rigtools.campaign.validate_observations` checks a table against the schema.
"""

from __future__ import annotations

import ast
import math
import re
from collections.abc import Callable, Mapping, Sequence
from typing import Any, Final

import numpy as np

from models.geometry import mesh_frequency_Hz
from rigtools import __version__
from rigtools.analysis.peak_results import LINE_KINDS, Peak, PeakAnalysis
from rigtools.analysis.recording import ChannelAnalysis, analyse_recording
from rigtools.analysis.speed import SpeedProfile, SpeedStep, detect_speed_steps, speed_profile
from rigtools.campaign.manifest import CONDITION_KEYS, Campaign, CampaignRun
from rigtools.campaign.observation_rows import ACCEL_TO_M_S2, finite_or_none, row_status
from rigtools.campaign.observation_table import (
    FLAGS,
    SCHEMA,
    Observations,
    RunObservations,
    to_frame,
)
from rigtools.campaign.observe_orders import HARMONICS, arms_rows
from rigtools.errors import MissingSpeedError, RigtoolsError
from rigtools.ingest import RunMetadata, read
from rigtools.ingest.reader import versions
from rigtools.ingest.recording import IngestReport, Recording

__all__ = ["observations_metadata", "observe_campaign", "observe_recording", "observe_run",
           "read_run"]


_TORQUE_TO_NM: Final[dict[str, float]] = {
    "N.m": 1.0, "Nm": 1.0, "N m": 1.0, "N·m": 1.0, "N*m": 1.0, "kN.m": 1e3, "kNm": 1e3,
}
_TEMPERATURE_OFFSET_C: Final[dict[str, float]] = {
    "degC": 0.0, "°C": 0.0, "C": 0.0, "deg C": 0.0, "celsius": 0.0, "K": -273.15,
}
#: Lines that flag the mode they sit on ``at_mesh_line``.
_MESH_LINES: Final = ("mesh_harmonic", "mesh_sideband", "shaft_harmonic")
#: The MCAP reader's notes on a sample rate estimated from the stamps, and on samples moved.
_ESTIMATED_RATE: Final = re.compile(r"topic ('(?:[^'\\]|\\.)*'|\"(?:[^\"\\]|\\.)*\"): "
                                    r"(?:sample rate \S+ Hz estimated from|"
                                    r"(?P<moved>\d+) Imu sample\(s\) jittered)")
#: A time base fits its stamps when none is farther than this fraction of a sample from it
#: (after the clock drift) ...
_STAMP_FIT_SAMPLES: Final = 0.5
#: ... and the logger clock drifts from the sample clock by at most this (ppm): a frequency
#: scale error of 0.01 %, a tenth of the 0.1 % natural frequencies are held to.
_MAX_DRIFT_PPM: Final = 100.0


# --------------------------------------------------------------------------------------------
# one run


def _signal_mean(rec: Recording, name: str, key: str) -> tuple[float | None, str | None]:
    """Mean of a slow signal in the unit ``key`` names; (None, why) when it cannot be had."""
    if key == "speed_rpm":
        try:
            prof = speed_profile(rec, name)
        except (MissingSpeedError, ValueError) as exc:
            return None, str(exc)
        v = prof.speed_rpm[np.isfinite(prof.speed_rpm)]
        return (float(np.mean(v)), None) if v.size else (None, f"{name!r} holds no value")
    if name not in rec.slow:
        return None, (f"{key} names slow signal {name!r}, not in the recording (it holds: "
                      f"{', '.join(sorted(rec.slow)) or 'none'})")
    s = rec.slow[name]
    vals = np.asarray(s.values, np.float64)
    vals = vals[np.isfinite(vals)]
    if not vals.size:
        return None, f"slow signal {name!r} holds no finite value"
    unit = s.unit.strip()
    if key == "torque_Nm":
        if unit not in _TORQUE_TO_NM:
            return None, (f"slow signal {name!r} is in {unit!r}, not a torque unit "
                          f"({', '.join(_TORQUE_TO_NM)})")
        return float(np.mean(vals)) * _TORQUE_TO_NM[unit], None
    if unit not in _TEMPERATURE_OFFSET_C:
        return None, (f"slow signal {name!r} is in {unit!r}, not a temperature unit "
                      f"({', '.join(_TEMPERATURE_OFFSET_C)})")
    return float(np.mean(vals)) + _TEMPERATURE_OFFSET_C[unit], None


def _failed_run(base: dict[str, Any], run: CampaignRun, reason: str) -> RunObservations:
    msg = f"{run.file}: {reason}" if str(run.file) not in reason else reason
    row = {**base, "quantity": "run", "status": "failed", "message": msg,
           "_flags": ["run_failed"]}
    return RunObservations(run.id, str(run.file), (row_status(row),), analysed=False, error=msg)


def _base_row(campaign: Campaign, run: CampaignRun) -> dict[str, Any]:
    return {
        "campaign": campaign.name, "run_id": run.id, "source_file": run.file_as_written,
        "rigtools_version": __version__,
        **{k: v for k, v in run.numeric_conditions().items()},
    }


def read_run(campaign: Campaign, run: CampaignRun) -> Recording:
    """Read a run's recording with the run's effective sensors.

    Parameters
    ----------
    campaign : Campaign
    run : CampaignRun

    Returns
    -------
    Recording
        :func:`rigtools.ingest.read` of ``run.file`` with the DBC, mapping and forced format
        of :meth:`Campaign.sensors_for`, and the run's metadata (id, rig, gear set, numeric
        conditions).

    Raises
    ------
    RecordingFormatError
        The file is missing, not a recording, or unusable (and the other errors of
        :func:`rigtools.ingest.read`: a DBC or mapping that does not fit, an OS error).
    """
    s = campaign.sensors_for(run)
    meta = RunMetadata(run_id=run.id, rig=campaign.rig or None,
                       gear_set=campaign.gear_set_for(run.id), conditions=run.numeric_conditions())
    return read(run.file, dbc=s.dbc, mapping=s.mapping, fmt=s.format, metadata=meta)


def observe_run(campaign: Campaign, run: CampaignRun, *, raise_errors: bool = False
                ) -> RunObservations:
    """Read and analyse one run of a campaign into rows of the observations table.

    :func:`read_run` then :func:`observe_recording`.

    Parameters
    ----------
    campaign : Campaign
    run : CampaignRun
    raise_errors : bool
        Re-raise instead of recording a failure (for debugging).

    Returns
    -------
    RunObservations
        Never raises for a bad run (unless ``raise_errors``): the failure is a failed ``run``
        row naming the file and the reason.
    """
    try:
        rec = read_run(campaign, run)
    except Exception as exc:
        return _failure(campaign, run, _base_row(campaign, run), exc, raise_errors)
    return observe_recording(campaign, run, rec, raise_errors=raise_errors)


def observe_recording(campaign: Campaign, run: CampaignRun, rec: Recording, *,
                      raise_errors: bool = False) -> RunObservations:
    """Analyse a run's recording into rows of the observations table.

    Everything :func:`observe_run` does after reading: conditions named as slow signals, the
    speed profile and its steps, the spectra, peaks and modes of the run's accelerometer
    channels (:meth:`Campaign.sensors_for`: the run's ``accel`` when it overrides it), Arms per
    step, and the run row with the ingest's losses.

    Parameters
    ----------
    campaign : Campaign
    run : CampaignRun
    rec : Recording
        The run's recording (:func:`read_run`, or the normalized Parquet it was saved as).
    raise_errors : bool
        Re-raise instead of recording a failure (for debugging).

    Returns
    -------
    RunObservations
        With ``spectra`` holding each analysed channel's Welch PSD. Never raises for a bad
        run (unless ``raise_errors``): the failure is a failed ``run`` row.
    """
    base = _base_row(campaign, run)
    try:
        return _observe_recording(campaign, run, rec, base)
    except Exception as exc:
        return _failure(campaign, run, base, exc, raise_errors)


def _failure(campaign: Campaign, run: CampaignRun, base: dict[str, Any], exc: Exception,
             raise_errors: bool) -> RunObservations:
    """The failed run an exception makes (re-raised when ``raise_errors``)."""
    if raise_errors:
        raise exc
    if isinstance(exc, RigtoolsError | OSError | ValueError):
        reason = str(exc)
        if isinstance(exc, OSError) and not isinstance(exc, RigtoolsError):
            reason = f"{exc.strerror or exc}"
        return _failed_run(base, run, reason)
    # a bug: record it loudly, keep the other runs
    return _failed_run(base, run, f"internal error {type(exc).__name__}: {exc} (rerun "
                       "with --debug for a traceback, and please report it)")


def _observe_recording(campaign: Campaign, run: CampaignRun, rec: Recording,
                       base: dict[str, Any]) -> RunObservations:
    s, a = campaign.sensors_for(run), campaign.analysis
    where = "[[run]] accel" if "accel" in run.overrides else "[sensors] accel"
    prov = rec.provenance
    base.update(source_sha256=prov.source_sha256, reader=prov.reader)
    run_flags: list[str] = []
    notes: list[str] = []  # problems that flag rows but do not fail the run

    # conditions given as signal names
    for key in CONDITION_KEYS:
        v = getattr(run, key)
        if isinstance(v, str):
            val, why = _signal_mean(rec, v, key)
            base[key] = val
            if why:
                run_flags.append("condition_unresolved")
                notes.append(why)

    # speed: the run's pinion speed, else the mean of the speed signal; teeth of the run's pair
    pair = campaign.gear_for(run.id).pair
    z1, z2 = int(pair.pinion.teeth), int(pair.wheel.teeth)
    z_tracked = z1 if s.speed_shaft == "pinion" else z2
    profile: SpeedProfile | None = None
    speed_error: str | None = None
    if s.speed is not None:
        try:
            profile = speed_profile(rec, s.speed, pulses_per_rev=s.pulses_per_rev)
        except (MissingSpeedError, ValueError) as exc:
            speed_error = str(exc)
            run_flags.append("speed_missing")
            notes.append(f"speed signal {s.speed!r} unusable, no Arms: {speed_error}")
    if base.get("speed_rpm") is None and profile is not None:
        v = profile.speed_rpm[np.isfinite(profile.speed_rpm)]
        if v.size:
            base["speed_rpm"] = float(np.mean(v)) * (z_tracked / z1)
    pinion_rpm = base.get("speed_rpm")
    f_mesh = None if pinion_rpm is None else float(mesh_frequency_Hz(pinion_rpm, z1))
    shafts = [] if f_mesh is None else [f_mesh / z1, f_mesh / z2]  # f_shaft = f_mesh / z
    base["mesh_frequency_Hz"] = f_mesh

    # channels
    if s.accel:
        names = [c for c in s.accel if c in rec.channels]
        missing = [c for c in s.accel if c not in rec.channels]
    else:
        names = [c for c in rec.channels if c != s.speed]
        missing = []
    rows: list[dict[str, Any]] = []
    for c in missing:
        run_flags.append("channel_missing")
        msg = (f"channel {c!r} named in {where} is not in the recording (it holds: "
               f"{', '.join(sorted(rec.channels)) or 'none'})")
        notes.append(msg)
        rows.append(row_status({**base, "channel": c, "quantity": "rms", "status": "failed",
                                "message": msg, "_flags": ["channel_missing"]}))
    analysis = analyse_recording(
        rec, channels=names, nperseg=a.nperseg, mesh_frequency_Hz=f_mesh,
        shaft_frequencies_Hz=shafts, prominence_dB=a.prominence_dB, f_range_Hz=a.f_range_Hz,
        max_peaks=a.max_peaks, max_mesh_order=a.max_mesh_order, response=a.response,
        errors="flag") if names else None
    t0 = min((float(c.time_s[0]) if len(c) else c.start_time_s
              for c in rec.channels.values()), default=0.0)
    steps: tuple[SpeedStep, ...] = ()
    if profile is not None:
        steps = detect_speed_steps(profile, rel_tolerance=a.step_rel_tolerance,
                                   min_duration_s=a.min_step_duration_s)
    speed_note = None if profile is None else _speed_varies(profile, a.step_rel_tolerance, z1,
                                                             z_tracked)
    n_ok = 0
    spectra = {name: (np.asarray(ca.spectrum.freq_Hz, np.float64),
                      np.asarray(ca.spectrum.psd_per_Hz, np.float64), ca.spectrum.psd_unit)
               for name, ca in (analysis.channels.items() if analysis is not None else ())
               if ca.spectrum is not None}
    for name, ca in (analysis.channels.items() if analysis is not None else ()):
        ch_rows, ok = _channel_rows(base, rec, ca, campaign, speed_note)
        n_ok += ok
        rows.extend(ch_rows)
        if ca.error:
            notes.append(ca.error)
        if s.speed is not None and ok:
            rows.extend(arms_rows(base, rec, name, ch_rows[0], profile, speed_error, steps,
                                  z_tracked, z1, t0, campaign))

    # the run row
    rep = rec.report
    if rep.n_rejected:
        run_flags.append("ingest_losses")
    if rep.gaps:
        run_flags.append("gaps")
    kept, irregular = _time_base_warnings(rep, rec)
    if irregular:
        run_flags.append("time_base_irregular")
    notes.extend(kept)
    if rep.n_rejected:
        notes.append(f"{rep.n_rejected} {rep.units} rejected at ingest: " + ", ".join(
            f"{n} {reason}" for reason, n in sorted(rep.rejected.items())))
    if rep.gaps:
        notes.append(f"{len(rep.gaps)} gap(s) in sample counters, "
                     f"{sum(g.n_missing for g in rep.gaps)} sample(s) missing")
    warnings = tuple(f"{run.id}: {n}" for n in notes)
    child_flags, child_notes = _aggregate(rows)
    run_row = {**base, "quantity": "run", "duration_s": rec.duration_s,
               "n_gaps": len(rep.gaps), "n_rejected": rep.n_rejected,
               "message": "; ".join([*child_notes, *notes]),
               "_flags": [*run_flags, *child_flags]}
    if not names or n_ok == 0:
        why = ("no accelerometer channel in the recording" if not names and not missing else
               "no channel could be analysed")
        run_row.update(status="failed", _flags=[*run_flags, "run_failed"],
                       message="; ".join([why, *notes]))
        out = (row_status(run_row), *rows)
        return RunObservations(run.id, str(run.file), out, analysed=False,
                               error=f"{run.file}: {run_row['message']}",
                               warnings=warnings, spectra=spectra)
    return RunObservations(run.id, str(run.file), (row_status(run_row), *rows), analysed=True,
                           warnings=warnings, spectra=spectra)


def _speed_varies(profile: SpeedProfile, rel_tolerance: float, z1: int, z_tracked: int
                  ) -> str | None:
    """Why the mesh line is smeared, when the speed spreads beyond the step tolerance; else None.

    The tolerance is :func:`~rigtools.analysis.speed.detect_speed_steps`' (a spread of at most
    ``2 max(2 rpm, rel_tolerance n_mid)``).
    """
    v = profile.speed_rpm[np.isfinite(profile.speed_rpm)]
    if v.size < 2:
        return None
    lo, hi = float(np.min(v)), float(np.max(v))
    tol = max(2.0, rel_tolerance * 0.5 * (lo + hi))
    if hi - lo <= 2 * tol:
        return None
    f_lo, f_hi = mesh_frequency_Hz([lo, hi], z_tracked)  # the tracked shaft's speed
    return (f"speed varies {lo:.0f}-{hi:.0f} rpm (beyond +-{100 * rel_tolerance:g} %): the mesh "
            f"line sweeps {f_lo:.0f}-{f_hi:.0f} Hz, smeared over the PSD; this peak may be "
            "the swept mesh line, not a structural mode")


def _time_base_warnings(rep: IngestReport, rec: Recording) -> tuple[list[str], bool]:
    """The ingest warnings worth a note, and whether a time base is irregular.

    The MCAP reader notes every sample rate it estimated from the stamps. When the stamps of
    every channel of that topic fit the uniform grid (:func:`_stamps_fit`) and no sample was
    moved, the rate is exact: the note is dropped. Otherwise it stays and the run is flagged
    ``time_base_irregular``. Every other warning stays.
    """
    kept: list[str] = []
    irregular = False
    for w in rep.warnings:
        m = _ESTIMATED_RATE.match(w)
        if m is None:
            kept.append(w)
            continue
        try:
            topic = str(ast.literal_eval(m.group(1)))
        except (ValueError, SyntaxError):
            kept.append(w)
            continue
        fits = m.group("moved") is None and _stamps_fit(rep, rec, topic)
        if not fits:
            kept.append(w)
            irregular = True
    return kept, irregular


def _stamps_fit(rep: IngestReport, rec: Recording, topic: str) -> bool:
    """Every channel of ``topic`` has its stamps on its grid.

    From the ingest's clock statistics (``report.timebase``): the logger clock drifts from
    the grid by at most ``_MAX_DRIFT_PPM``, every stamp lies within ``_STAMP_FIT_SAMPLES`` of
    a sample once that drift is allowed for (the residual from the median offset of a clock
    drifting by d over a record of T reaches ``d T``), and no stamp goes backwards.
    """
    chans = [c for c in rec.channels.values() if c.name.startswith(f"{topic}/")]
    if not chans:
        return False
    for c in chans:
        st = rep.timebase.get(c.name)
        if not st or not c.sample_rate_Hz > 0:
            return False
        drift = abs(float(st.get("drift_ppm", 0.0))) * 1e-6
        if not drift <= _MAX_DRIFT_PPM * 1e-6:
            return False
        worst = float(st.get("max_abs_residual_s", math.inf))
        if not worst <= _STAMP_FIT_SAMPLES / c.sample_rate_Hz + drift * len(c) / c.sample_rate_Hz:
            return False
        if float(st.get("n_stamps_backwards", 0.0)) > 0:
            return False
    return True


def _aggregate(rows: list[dict[str, Any]]) -> tuple[list[str], list[str]]:
    """The flags of a run's failed or flagged rows, and one note per channel x quantity x status."""
    flags: list[str] = []
    groups: dict[tuple[str, str, str], list[str]] = {}
    for r in rows:
        if r.get("status") not in ("failed", "flagged"):
            continue
        fl = [f for f in r.get("quality_flags", "").split(";") if f]
        flags.extend(fl)
        key = (str(r.get("channel")), str(r.get("quantity")), str(r["status"]))
        groups.setdefault(key, []).extend(fl)
    notes = []
    for (ch, q, st), fl in groups.items():
        n = sum(1 for r in rows if (str(r.get("channel")), str(r.get("quantity")),
                                    str(r.get("status"))) == (ch, q, st))
        what = q if n == 1 else f"{n} {q} rows"
        notes.append(f"{ch}: {what} {st} ({', '.join(dict.fromkeys(fl)) or 'see row'})")
    return list(dict.fromkeys(flags)), notes


def _channel_rows(base: dict[str, Any], rec: Recording, ca: ChannelAnalysis, campaign: Campaign,
                  speed_note: str | None = None) -> tuple[list[dict[str, Any]], bool]:
    """The rms, natural_frequency and line rows of a channel; and whether it was analysed."""
    a = campaign.analysis
    q = ca.quality
    flags: list[str] = []
    if q.n_invalid:
        flags.append("gaps")
    if q.clipped:
        flags.append("clipping")
    if q.n_segments_dropped:
        flags.append("windows_dropped")
    if q.constant:
        flags.append("constant")
    if q.too_short:
        flags.append("too_short")
    factor = ACCEL_TO_M_S2.get(ca.unit.strip())
    if factor is None:
        flags.append("unit_not_acceleration")
    gaps = [g for g in rec.report.gaps if g.channel == ca.name]
    common = {
        **base, "channel": ca.name, "n_samples": q.n_samples, "n_invalid": q.n_invalid,
        "n_gaps": len(gaps), "n_clipped": q.clipping.n_clipped if q.clipping else None,
    }
    msgs = list(q.messages)
    if factor is None:
        msgs.append(f"unit {ca.unit!r} is not an acceleration unit rigtools converts to m/s^2 "
                    f"({', '.join(ACCEL_TO_M_S2)}): RMS and Arms left empty")
    rms = {**common, "quantity": "rms", "_flags": list(flags)}
    if ca.spectrum is None or ca.rms is None:
        rms.update(status="failed", message=ca.error or "; ".join(msgs) or "not analysed")
        return [row_status(rms)], False
    rms.update(
        n_windows=q.n_windows, n_segments_dropped=q.n_segments_dropped,
        n_samples_dropped=q.n_samples_dropped,
        rms_m_s2=None if factor is None else float(ca.rms.rms_time) * factor,
        rms_parseval_m_s2=None if factor is None else float(ca.rms.rms_parseval) * factor)
    common.update(n_windows=q.n_windows, n_segments_dropped=q.n_segments_dropped,
                  n_samples_dropped=q.n_samples_dropped)
    rows = [rms]
    if ca.peaks is None:
        rms["_flags"].append("peaks_failed")
        msgs.append(ca.error or "peak analysis failed")
    else:
        base_flags = [f for f in flags if f != "unit_not_acceleration"]
        if getattr(ca, "response_source", "") == "guessed":
            base_flags.append("response_guessed")
        rows.extend(_peak_rows(common, ca, ca.peaks, base_flags, a.low_snr_dB, speed_note))
        if not ca.peaks.structural:
            rms["_flags"].append("no_structural_peak")
    rms["message"] = "; ".join(msgs)
    return [row_status(r) for r in rows], True


def _line_name(pk: Peak) -> str:
    """``mesh harmonic 5 (2000.0 Hz)`` and the like."""
    loc = pk.location
    what = pk.kind.replace("_", " ")
    if pk.kind == "mesh_harmonic":
        what = f"mesh harmonic {loc.harmonic}"
    elif pk.kind == "mesh_sideband":
        what = f"sideband {loc.sideband:+d} of mesh harmonic {loc.harmonic}"
    elif pk.kind == "shaft_harmonic":
        what = f"shaft harmonic {loc.harmonic}"
    return f"{what} ({pk.f_Hz:.1f} Hz)"


def _peak_rows(common: dict[str, Any], ca: ChannelAnalysis, pa: PeakAnalysis,
               base_flags: list[str], low_snr_dB: float, speed_note: str | None
               ) -> list[dict[str, Any]]:
    """The natural_frequency rows of a channel's structural peaks, and the lines on them."""
    rows: list[dict[str, Any]] = []
    response = getattr(ca, "response", None)
    for i, pk in enumerate(pa.structural):
        m = pk.mode
        if m is None:
            continue
        pflags = list(base_flags)
        pmsg = []
        mesh = [q for q in pa.lines_on(i) if q.kind in _MESH_LINES]
        if mesh:
            pflags.append("at_mesh_line")
            pmsg.append(", ".join(_line_name(q) for q in mesh) + " on the mode (within its "
                        "half-power band), masked out of its fit: f_n and zeta rest on the "
                        "rest of the peak; see the line row")
        if pk.prominence_dB < low_snr_dB:
            pflags.append("low_snr")
            pmsg.append(f"prominence {pk.prominence_dB:.1f} dB < {low_snr_dB:g} dB")
        if speed_note is not None:
            pflags.append("speed_varies")
            pmsg.append(speed_note)
        rows.append({
            **common, "quantity": "natural_frequency", "mode_index": i,
            "f_n_Hz": finite_or_none(m.f_n_Hz), "f_n_std_Hz": finite_or_none(m.f_n_std_Hz),
            "zeta": finite_or_none(m.zeta), "zeta_std": finite_or_none(m.zeta_std),
            "zeta_half_power": finite_or_none(m.zeta_half_power),
            "zeta_half_power_std": finite_or_none(m.zeta_half_power_std),
            "peak_kind": pk.kind, "response": response or m.response,
            "prominence_dB": float(pk.prominence_dB), "snr_dB": float(pk.prominence_dB),
            "message": "; ".join(pmsg), "_flags": pflags})
    for q in pa.peaks:
        if q.on_mode is None or q.kind not in LINE_KINDS:
            continue
        lflags = list(base_flags)
        lmsg = [f"{_line_name(q)} on mode {q.on_mode}"]
        if speed_note is not None:
            lflags.append("speed_varies")
            lmsg.append(speed_note)
        rows.append({
            **common, "quantity": "line", "mode_index": q.on_mode, "f_Hz": float(q.f_Hz),
            "peak_kind": q.kind, "prominence_dB": float(q.prominence_dB),
            "message": "; ".join(lmsg), "_flags": lflags})
    return rows


# --------------------------------------------------------------------------------------------
# a campaign


def observe_campaign(campaign: Campaign, *,
                     on_run: Callable[[RunObservations], None] | None = None,
                     raise_errors: bool = False) -> Observations:
    """Observations of every run of a campaign.

    Parameters
    ----------
    campaign : Campaign
    on_run : callable, optional
        Called with each run's :class:`RunObservations` as it is done (progress, reporting).
    raise_errors : bool
        Re-raise a run's error instead of recording it.

    Returns
    -------
    Observations
        Failed runs are in the table (a failed ``run`` row) and in ``failures``.
    """
    runs = []
    for run in campaign.runs:
        r = observe_run(campaign, run, raise_errors=raise_errors)
        runs.append(r)
        if on_run is not None:
            on_run(r)
    rows = [row for r in runs for row in r.rows]
    return Observations(table=to_frame(rows), runs=tuple(runs),
                        metadata=observations_metadata(campaign, [
                            {"id": r.run_id, "file": r.file, "analysed": r.analysed,
                             "error": r.error} for r in runs]))


def observations_metadata(campaign: Campaign, runs: Sequence[Mapping[str, Any]]
                          ) -> dict[str, Any]:
    """The metadata written with an observations table (JSON-ready).

    Parameters
    ----------
    campaign : Campaign
    runs : sequence of mapping
        Per run, in campaign order: ``id``, ``file``, ``analysed`` (bool), ``error`` (str or
        None).
    """
    return {
        "format": "rigtools observations",
        "schema": f"data_schemas/{SCHEMA}",
        "campaign": campaign.to_dict(),
        "gear": {"name": campaign.gear.name, "z1": campaign.pinion_teeth,
                 "z2": campaign.wheel_teeth},
        "run_gears": {r.id: {"gear_set": r.gear_set, "name": r.gear.name,
                             "z1": int(r.gear.pair.pinion.teeth),
                             "z2": int(r.gear.pair.wheel.teeth)}
                      for r in campaign.runs if r.gear is not None},
        "harmonics": list(HARMONICS),
        "max_mesh_order": campaign.analysis.max_mesh_order,
        "flags": FLAGS,
        "versions": versions(),
        "runs": [dict(r) for r in runs],
    }

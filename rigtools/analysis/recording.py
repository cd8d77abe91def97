"""Spectra, RMS, quality checks and peaks over the channels of a Recording.

:func:`analyse_recording` returns one :class:`ChannelAnalysis` per channel (see
:mod:`rigtools.analysis.peaks` for the peak method).

The single-DOF response fitted to each channel's peaks follows the channel's unit
(:func:`response_for_unit`): acceleration for an accelerometer (m/s^2, g), velocity for a
velocity pick-up (m/s, mm/s), displacement for a proximity probe (m, mm, um). The shapes
differ by :math:`(f/f_n)^{2p}`, p = 0, 1, 2, and fitting one to the other biases f_n by
about a percent at zeta = 0.03 (issue 17). A channel whose unit says nothing is fitted with
each response, and the response with the lowest weighted residual sum of squares of the log
PSD (:attr:`~rigtools.analysis.sdof_fit.SDOFFit.chi2` of :func:`fit_sdof`, summed over the
structural peaks found) is taken: the same bins and the same number of parameters for each
response, so this is the largest Gaussian likelihood and the lowest AIC. Its estimates carry
the flag ``"response_guessed"``; with no peak fitted the fallback is acceleration.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Final, Literal

import numpy as np

from rigtools.analysis.mesh_lines import MAX_MESH_ORDER
from rigtools.analysis.peak_results import LOW_DOF, ModalEstimate, PeakAnalysis
from rigtools.analysis.peaks import analyse_peaks
from rigtools.analysis.rms import mean_square_time, rms_from_psd
from rigtools.analysis.sdof_fit import fit_sdof
from rigtools.analysis.signal_checks import (
    Average,
    Detrend,
    Response,
    Window,
    check_band,
    check_detrend,
    check_fs,
    check_noverlap,
    check_response,
    resolve_nperseg,
)
from rigtools.analysis.spectra import detect_clipping
from rigtools.analysis.spectral_window import window_array, window_properties
from rigtools.analysis.spectrum_results import BandRMS, Clipping, Spectrum, WelchAccount
from rigtools.analysis.welch import welch_core
from rigtools.errors import ConstantSignalError, InsufficientDataError, SignalError
from rigtools.ingest.recording import Channel, Recording

__all__ = [
    "GUESS_FALLBACK",
    "RESPONSE_GUESSED",
    "ChannelAnalysis",
    "QualityFlags",
    "RecordingAnalysis",
    "ResponseSpec",
    "analyse_recording",
    "response_for_unit",
]

#: What :func:`analyse_recording` takes as ``response``: one response for every channel, a
#: mapping channel -> response (channels not named follow their unit), or ``"auto"`` / None:
#: every channel follows its unit.
ResponseSpec = Response | Literal["auto"] | Mapping[str, Response | Literal["auto"]] | None
#: Flag added to the fits of a channel whose response was guessed.
RESPONSE_GUESSED: Final = "response_guessed"
#: Response taken for a channel of unknown unit when no peak was fitted to tell (the sensors
#: rigtools is for are accelerometers).
GUESS_FALLBACK: Final[Response] = "acceleration"

# --------------------------------------------------------------------------------------------
# response from the unit

_UNIT_CHARS: Final = str.maketrans({"\u00b2": "2", "\u00b3": "3", "\u00b9": "1",
                                    "\u2070": "0", "\u207b": "-", "\u2212": "-",
                                    "\u00b5": "u", "\u03bc": "u", "\u00b7": " ",
                                    "\u22c5": " ", "*": " ", ".": " ", "^": "",
                                    "[": "", "]": "", "(": "", ")": ""})
_LENGTH = r"(?:m|mm|um|nm|cm|in|mil|mils|ft)"
_TIME = r"(?:s|sec)"
_UNIT_PATTERNS: Final[tuple[tuple[Response, re.Pattern[str]], ...]] = (
    ("displacement", re.compile(rf"{_LENGTH}")),
    ("velocity", re.compile(rf"{_LENGTH}/{_TIME}|{_LENGTH} ?{_TIME}-1|ips")),
    ("acceleration", re.compile(rf"{_LENGTH}/{_TIME}2|{_LENGTH}/{_TIME}/{_TIME}"
                                rf"|{_LENGTH} ?{_TIME}-2|g|gn|g0|g_n|gs|g's|mg")),
)


def response_for_unit(unit: str) -> Response | None:
    """The single-DOF response a channel's unit implies, or None when it says nothing.

    Length (m, mm, um, nm, cm, in, mil, ft): ``"displacement"``; length per time (m/s,
    mm/s, in/s, ips, m s^-1): ``"velocity"``; length per time squared (m/s^2, mm/s^2,
    m s^-2, m/s/s) or standard gravity (g, gn, g0, mg): ``"acceleration"``. Case, spaces,
    ``^``/``**``, superscripts (``m/s²``, ``m·s⁻²``), ``µ``/``μ`` and brackets are accepted.

    Parameters
    ----------
    unit : str
        A channel's unit, e.g. ``"m/s^2"``.

    Returns
    -------
    str or None
        ``"displacement"``, ``"velocity"``, ``"acceleration"``, or None (unknown unit).

    Examples
    --------
    >>> response_for_unit("m/s²"), response_for_unit("mm/s"), response_for_unit("µm")
    ('acceleration', 'velocity', 'displacement')
    >>> response_for_unit("V") is None
    True
    """
    u = str(unit).replace("**", "^").translate(_UNIT_CHARS).strip().lower()
    u = re.sub(r"\s*/\s*", "/", re.sub(r"\s+", " ", u))
    for response, pattern in _UNIT_PATTERNS:
        if pattern.fullmatch(u):
            return response
    return None



@dataclass(frozen=True)
class QualityFlags:
    """What was used of a channel, and what is wrong with it.

    Attributes
    ----------
    n_samples, n_valid, n_invalid : int
        Samples in the channel, valid and invalid (gaps, rejected).
    n_segments, n_segments_dropped, n_samples_dropped : int
        Valid segments used; segments shorter than one window and their samples, dropped.
    n_windows : int
        Welch windows averaged.
    dof : float
        Equivalent degrees of freedom of each PSD value.
    clipping : Clipping or None
    constant : bool
        Every valid sample equal.
    too_short : bool
        No valid segment long enough for the requested resolution.
    messages : tuple of str
        Human-readable notes, one per problem.
    """

    n_samples: int
    n_valid: int
    n_invalid: int
    n_segments: int = 0
    n_segments_dropped: int = 0
    n_samples_dropped: int = 0
    n_windows: int = 0
    dof: float = 0.0
    clipping: Clipping | None = None
    constant: bool = False
    too_short: bool = False
    messages: tuple[str, ...] = ()

    @property
    def clipped(self) -> bool:
        """The channel holds runs at its extreme values (see :func:`detect_clipping`)."""
        return bool(self.clipping is not None and self.clipping.clipped)

    @property
    def low_dof(self) -> bool:
        """Few Welch averages (``0 < dof < LOW_DOF``): damping less reliable.

        The same threshold as :attr:`~rigtools.analysis.peak_results.ModalEstimate.low_dof`.
        """
        return bool(0 < self.dof < LOW_DOF)

    @property
    def ok(self) -> bool:
        """Analysed, not clipped, nothing dropped."""
        return not (self.clipped or self.constant or self.too_short or self.n_samples_dropped)


@dataclass(frozen=True)
class ChannelAnalysis:
    """Spectrum, RMS, peaks and quality of one channel.

    Attributes
    ----------
    name, unit : str
    sample_rate_Hz : float
    spectrum : Spectrum or None
        None when the channel could not be analysed (see ``error``).
    rms : BandRMS or None
        Full band: time domain (detrended valid segments) and Parseval (PSD integral).
    band_rms : tuple of BandRMS
        One per requested band.
    peaks : PeakAnalysis or None
    quality : QualityFlags
    error : str or None
        Why the channel was not analysed (with ``errors="flag"``).
    response : str or None
        The single-DOF response fitted to the channel's peaks (``"displacement"``,
        ``"velocity"``, ``"acceleration"``); None when no peak was analysed and the unit
        says nothing.
    response_source : str
        Where ``response`` came from: ``"given"`` (the ``response`` argument), ``"unit"``
        (:func:`response_for_unit`), ``"guessed"`` (best fit of the three, module notes), or
        ``""`` (none).
    response_chi2 : dict of str to float
        For a guessed response: the criterion per response (weighted residual sum of squares
        over the peaks fitted under all three; lowest taken). Empty otherwise.
    """

    name: str
    unit: str
    sample_rate_Hz: float
    spectrum: Spectrum | None
    rms: BandRMS | None
    band_rms: tuple[BandRMS, ...]
    peaks: PeakAnalysis | None
    quality: QualityFlags
    error: str | None = None
    response: str | None = None
    response_source: str = ""
    response_chi2: dict[str, float] = field(default_factory=dict)

    @property
    def response_guessed(self) -> bool:
        """The response was chosen by the fit, the unit saying nothing."""
        return self.response_source == "guessed"

    @property
    def modes(self) -> tuple[ModalEstimate, ...]:
        """Modal estimates of the structural peaks (empty when none or not analysed)."""
        return () if self.peaks is None else self.peaks.modes


@dataclass(frozen=True)
class RecordingAnalysis:
    """Per-channel analysis of a recording, and the settings used.

    Attributes
    ----------
    channels : dict of str to ChannelAnalysis
    settings : dict
        The analysis parameters (JSON-ready).
    """

    channels: dict[str, ChannelAnalysis]
    settings: dict[str, Any] = field(default_factory=dict)

    def __getitem__(self, name: str) -> ChannelAnalysis:
        return self.channels[name]


def _channels_of(rec: Recording, names: Sequence[str] | None) -> dict[str, Channel]:
    chans = rec.channels
    if names is None:
        return dict(chans)
    missing = [n for n in names if n not in chans]
    if missing:
        raise SignalError("channels", f"names of channels in the recording {sorted(chans)}",
                          repr(missing))
    return {n: chans[n] for n in names}


def analyse_recording(rec: Recording, *, channels: Sequence[str] | None = None,
                      nperseg: int | None = None, resolution_Hz: float | None = None,
                      noverlap: int | None = None, window: Window = "hann",
                      detrend: Detrend = "constant", average: Average = "mean",
                      mesh_frequency_Hz: float | None = None,
                      shaft_frequencies_Hz: Sequence[float] = (),
                      bands_Hz: Sequence[Sequence[float]] = (), peaks: bool = True,
                      prominence_dB: float = 6.0, f_range_Hz: Sequence[float] | None = None,
                      max_peaks: int = 20, max_mesh_order: int = MAX_MESH_ORDER,
                      response: ResponseSpec = None, clip_min_run: int = 3,
                      full_scale: Sequence[float] | None = None,
                      errors: Literal["flag", "raise"] = "flag") -> RecordingAnalysis:
    """Spectra, RMS, natural frequencies and quality flags of a recording's channels.

    Channels that share sample rate, length and validity mask are estimated together in one
    :func:`scipy.signal.welch` call per valid segment.

    Parameters
    ----------
    rec : Recording
        The recording.
    channels : sequence of str, optional
        Channels to analyse; default all.
    nperseg, resolution_Hz, noverlap, window, detrend, average
        As for :func:`~rigtools.analysis.spectra.welch_psd`.
    mesh_frequency_Hz, shaft_frequencies_Hz, prominence_dB, f_range_Hz, max_peaks
        As for :func:`~rigtools.analysis.peaks.analyse_peaks`.
    max_mesh_order : int
        Highest mesh harmonic whose peaks (with their shaft sidebands) are mesh lines, not
        modes (:func:`~rigtools.analysis.peaks.analyse_peaks`; default 5).
    response : str, mapping or None
        Single-DOF response fitted to the peaks (:data:`ResponseSpec`): ``"displacement"``,
        ``"velocity"`` or ``"acceleration"`` for every channel; a mapping channel ->
        response (channels not in it, or mapped to ``"auto"``, follow their unit); or
        ``"auto"`` / None (default): each channel's unit decides
        (:func:`response_for_unit`), and a channel of unknown unit is fitted with each
        response and the best is taken and flagged (module notes).
    bands_Hz : sequence of (float, float)
        Bands for band-limited RMS (Hz).
    peaks : bool
        Look for peaks (False: spectra and RMS only).
    clip_min_run : int
        Run of identical extreme samples taken as clipping (:func:`detect_clipping`).
    full_scale : (float, float), optional
        Acquisition full scale (unit), e.g. ``(-491.52, 491.505)`` for the reference DBC.
    errors : {'flag', 'raise'}
        ``"flag"``: a channel that is constant or too short gets ``error`` and quality flags
        and no spectrum; ``"raise"``: the :class:`~rigtools.analysis.spectra.SignalError` is
        raised, naming the channel.

    Returns
    -------
    RecordingAnalysis
    """
    if errors not in ("flag", "raise"):
        raise SignalError("errors", "'flag' or 'raise'", repr(errors))
    if average not in ("mean", "median"):
        raise SignalError("average", "'mean' or 'median'", repr(average))
    det = check_detrend(detrend)
    chans = _channels_of(rec, channels)
    given = _responses_of(rec, response)
    resolved: dict[str, tuple[Response | None, str]] = {
        name: given.get(name) or (response_for_unit(ch.unit), "unit") for name, ch in chans.items()}
    bands = [tuple(float(v) for v in b) for b in bands_Hz]
    settings = {"nperseg": nperseg, "resolution_Hz": resolution_Hz, "noverlap": noverlap,
                "window": window if not isinstance(window, np.ndarray) else "custom",
                "detrend": det if not callable(det) else "custom", "average": average,
                "mesh_frequency_Hz": mesh_frequency_Hz,
                "shaft_frequencies_Hz": list(shaft_frequencies_Hz), "bands_Hz": bands,
                "prominence_dB": prominence_dB,
                "response": dict(response) if isinstance(response, Mapping) else response}
    results: dict[str, ChannelAnalysis] = {}
    # quality first, then group by (rate, length, mask) for batched Welch
    groups: dict[tuple[Any, ...], list[str]] = {}
    prep: dict[str, dict[str, Any]] = {}
    for name, ch in chans.items():
        fs = check_fs(ch.sample_rate_Hz)
        x = np.asarray(ch.values)
        v = np.asarray(ch.valid, bool)
        whole = bool(v.all())
        n_valid = x.size if whole else int(np.count_nonzero(v))
        clip = detect_clipping(x, v, min_run=clip_min_run, full_scale=full_scale)
        base = dict(n_samples=int(x.size), n_valid=n_valid, n_invalid=int(x.size - n_valid))
        msgs = []
        if clip.clipped:
            msgs.append(f"clipped: {clip.n_clipped} samples in {clip.n_runs} run(s) at the "
                        f"extreme values {clip.low:g} / {clip.high:g} {ch.unit}")
        prep[name] = dict(ch=ch, fs=fs, x=x, mask=None if whole else v, clip=clip, base=base,
                          msgs=msgs, response=resolved[name])
        if n_valid == 0 or clip.high == clip.low:
            err = SignalError(name, detail="holds no valid sample") if n_valid == 0 else (
                _constant_error(name, n_valid, clip.high))
            _fail(results, name, ch, prep[name], err, errors, constant=n_valid > 0)
            continue
        nps = resolve_nperseg(nperseg, resolution_Hz, fs)
        key = (fs, x.size, x.dtype.str, nps, b"all" if whole else v.tobytes())
        groups.setdefault(key, []).append(name)
    for (fs, n, _, nps, _), names in groups.items():
        nov = check_noverlap(noverlap, nps)
        w = window_array(window, nps)
        wkey = window if not isinstance(window, np.ndarray) else w
        props = window_properties(wkey, nps)
        first = prep[names[0]]
        mask = first["mask"]
        if nps > n:
            err = _short_error(nps, n, fs, n, "len(x)")
            for name in names:
                _fail(results, name, prep[name]["ch"], prep[name], err, errors, too_short=True)
            continue
        xs = first["x"][None, :] if len(names) == 1 else np.stack(
            [prep[nm]["x"] for nm in names])
        try:
            freq, P, acc, segs_list = welch_core(xs, mask, fs, w, nps, nov, det, average,
                                                  "density", props)
        except SignalError as e:
            for name in names:
                _fail(results, name, prep[name]["ch"], prep[name], e, errors, too_short=True)
            continue
        segs = segs_list[0]
        rows = np.arange(len(names))
        tot, cnt = mean_square_time(xs, segs, rows, fs, (0.0, fs / 2), det)
        band_ms = [(band, *mean_square_time(xs, segs, rows, fs, band, det))
                   for band in (check_band(b, fs) for b in bands)]
        for i, name in enumerate(names):
            pr = prep[name]
            ch = pr["ch"]
            account = WelchAccount(**{k: getattr(acc, k)[i] for k in (
                "n_windows", "dof", "n_segments", "n_segments_dropped", "n_samples_dropped",
                "n_invalid", "n_samples_used")})
            spec = Spectrum(freq_Hz=freq, unit=ch.unit, fs_Hz=fs, nperseg=nps, noverlap=nov,
                            window=window, detrend=det, account=account, psd_per_Hz=P[i],
                            average=average)
            rms = BandRMS(band_Hz=(0.0, fs / 2), rms_time=float(np.sqrt(tot[i] / cnt)),
                          rms_parseval=float(rms_from_psd(spec)), unit=ch.unit,
                          n_samples=int(cnt))
            brms = [BandRMS(band_Hz=band, rms_time=float(np.sqrt(bt[i] / bc)),
                            rms_parseval=float(rms_from_psd(spec, band)), unit=ch.unit,
                            n_samples=int(bc))
                    for band, bt, bc in band_ms]
            msgs = list(pr["msgs"])
            if account.n_segments_dropped:
                msgs.append(f"{int(account.n_segments_dropped)} valid segment(s) shorter than "
                            f"one window ({nps} samples) dropped: "
                            f"{int(account.n_samples_dropped)} samples")
            quality = QualityFlags(
                **pr["base"], n_segments=int(account.n_segments),
                n_segments_dropped=int(account.n_segments_dropped),
                n_samples_dropped=int(account.n_samples_dropped),
                n_windows=int(account.n_windows), dof=float(account.dof),
                clipping=pr["clip"], messages=tuple(msgs))
            pk = None
            error = None
            resp, source = resolved[name]
            chi2s: dict[str, float] = {}
            if peaks:
                try:
                    if resp is None:
                        pk, resp, chi2s = _guess_response(
                            spec, mesh_frequency_Hz=mesh_frequency_Hz,
                            shaft_frequencies_Hz=shaft_frequencies_Hz,
                            prominence_dB=prominence_dB, f_range_Hz=f_range_Hz,
                            max_peaks=max_peaks, max_mesh_order=max_mesh_order)
                        source = "guessed"
                    else:
                        pk = analyse_peaks(spec, mesh_frequency_Hz=mesh_frequency_Hz,
                                           shaft_frequencies_Hz=shaft_frequencies_Hz,
                                           prominence_dB=prominence_dB, f_range_Hz=f_range_Hz,
                                           max_peaks=max_peaks,
                                           max_mesh_order=max_mesh_order, response=resp)
                except SignalError as e:
                    if errors == "raise":
                        raise e.for_channel(name) from e
                    error = str(e.for_channel(name))
            results[name] = ChannelAnalysis(name=name, unit=ch.unit, sample_rate_Hz=fs,
                                            spectrum=spec, rms=rms, band_rms=tuple(brms),
                                            peaks=pk, quality=quality, error=error,
                                            response=resp,
                                            response_source=source if resp else "",
                                            response_chi2=chi2s)
    ordered = {name: results[name] for name in chans}
    return RecordingAnalysis(channels=ordered, settings=settings)


def _constant_error(name: str, n_valid: int, value: float) -> SignalError:
    return ConstantSignalError(
        "values", detail=f"is constant (all {n_valid} valid samples equal {value!r}): its "
        "spectrum is zero, no peak or damping can be estimated", channel=name)


def _short_error(nps: int, longest: int, fs: float, n: int, what: str) -> SignalError:
    return InsufficientDataError(
        "nperseg", f"<= {what}={longest}", str(nps),
        f"resolution {fs / nps:g} Hz needs {nps / fs:g} s of signal, there are {n / fs:g} s")


def _fail(results: dict[str, ChannelAnalysis], name: str, ch: Channel, pr: dict[str, Any],
          err: SignalError, errors: str, constant: bool = False, too_short: bool = False
          ) -> None:
    err = err if err.channel == name else err.for_channel(name)
    if errors == "raise":
        raise err
    quality = QualityFlags(**pr["base"], clipping=pr["clip"], constant=constant,
                           too_short=too_short, messages=(*pr["msgs"], str(err)))
    resp, source = pr["response"]
    results[name] = ChannelAnalysis(name=name, unit=ch.unit, sample_rate_Hz=pr["fs"],
                                    spectrum=None, rms=None, band_rms=(), peaks=None,
                                    quality=quality, error=str(err), response=resp,
                                    response_source=source if resp else "")


def _responses_of(rec: Recording, response: ResponseSpec
                  ) -> dict[str, tuple[Response, str]]:
    """Channel -> (response, "given") for the channels ``response`` decides; checked."""
    if response is None or (isinstance(response, str) and response == "auto"):
        return {}
    if isinstance(response, str):
        check_response(response)
        return {name: (response, "given") for name in rec.channels}
    if not isinstance(response, Mapping):
        raise SignalError("response", "a response, 'auto', a mapping channel -> response or "
                          "None", repr(response))
    missing = sorted(str(k) for k in response if k not in rec.channels)
    if missing:
        raise SignalError("response", "a mapping from names of channels in the recording "
                          f"{sorted(rec.channels)}", repr(missing))
    out: dict[str, tuple[Response, str]] = {}
    for name, value in response.items():
        if value == "auto" or value is None:
            continue
        try:
            check_response(value)
        except SignalError as e:
            raise SignalError(f"response[{name!r}]", e.expected, e.found) from None
        out[name] = (value, "given")
    return out


def _guess_response(spec: Spectrum, **kwargs: Any
                    ) -> tuple[PeakAnalysis, Response, dict[str, float]]:
    """Peaks analysed with each response; the lowest summed ``chi2`` wins (module notes).

    The responses are compared on the same bins: :func:`fit_sdof` with each response at
    every structural peak that any of the three analyses found (peaks within a fitted
    half-power half-width of each other merged), the mesh and shaft lines found masked.
    Returns the peak analysis of the response taken, with ``"response_guessed"`` added to
    the flags of its fits, the response, and the criterion per response.
    """
    candidates: tuple[Response, ...] = ("displacement", "velocity", "acceleration")
    runs = {r: analyse_peaks(spec, response=r, **kwargs) for r in candidates}
    found = sorted(((p.f_Hz, p.psd_per_Hz, p.mode.zeta * p.mode.f_n_Hz)
                    for pa in runs.values() for p in pa.peaks
                    if p.kind == "structural" and p.mode is not None
                    and np.isfinite(p.mode.zeta)), key=lambda t: t[0])
    merged: list[tuple[float, float, float]] = []
    for f, psd, hw in found:
        if merged and f - merged[-1][0] < max(hw, merged[-1][2]):
            if psd > merged[-1][1]:
                merged[-1] = (f, psd, max(hw, merged[-1][2]))
            continue
        merged.append((f, psd, hw))
    lines = sorted({p.f_Hz for pa in runs.values() for p in pa.peaks
                    if p.location.kind is not None})
    totals = dict.fromkeys(candidates, 0.0)
    n_used = 0
    for f, _, _ in merged:
        exclude = [fl for fl in lines if abs(fl - f) > spec.resolution_Hz * 4]
        fits = [fit_sdof(spec, f, response=r, exclude_Hz=exclude) for r in candidates]
        if all(ft.success and np.isfinite(ft.chi2) for ft in fits):
            n_used += 1
            for r, ft in zip(candidates, fits, strict=True):
                totals[r] += float(ft.chi2)
    if n_used == 0:
        return _with_flag(runs[GUESS_FALLBACK], RESPONSE_GUESSED), GUESS_FALLBACK, {}
    best = min(candidates, key=lambda r: totals[r])
    return _with_flag(runs[best], RESPONSE_GUESSED), best, {str(r): v for r, v in totals.items()}


def _with_flag(pa: PeakAnalysis, flag: str) -> PeakAnalysis:
    """The same peak analysis with ``flag`` added to the fit of every peak's mode."""
    peaks = []
    for p in pa.peaks:
        m = p.mode
        if m is not None and flag not in m.fit.flags:
            m = replace(m, fit=replace(m.fit, flags=(*m.fit.flags, flag)))
        peaks.append(replace(p, mode=m))
    return replace(pa, peaks=tuple(peaks))

r"""Mesh-order tracking: angular resampling, order spectra, Arms per speed step and along a ramp.

Method
------
1. **Shaft angle.** The shaft frequency ``f(t) = n(t) / 60`` (:class:`~rigtools.analysis.speed.
   SpeedProfile`) is integrated with the trapezoidal rule at the signal's sample times,
   ``theta(t) = int f dt`` (revolutions); where the speed is unknown the angle is unknown.
2. **Angular resampling.** The signal is resampled at the uniform angles
   ``theta_j = j / P`` (``P = samples_per_rev``) by band-limited interpolation with a
   **Kaiser-windowed sinc** kernel (Smith and Gossett [1]_): 32 zero crossings a side, Kaiser
   ``beta = 10``, cutoff at 0.94 of the Nyquist frequency of the slower of the input rate
   ``fs`` and the local output rate ``P f(t)``, the kernel widened as the output rate falls, and
   its taps normalised to unit sum. It is at once the interpolator and the anti-aliasing filter
   that follows the speed: flat within about 1e-5 up to ``RESAMPLER_PASSBAND`` = 0.42 of that
   rate, below -100 dB from 0.52 on, and nothing that aliases lands inside the passband.
   Orders (or input frequencies) above the passband are reported as NaN, never guessed.
3. **Order spectrum.** Blocks of ``R`` whole revolutions (``N = R P`` samples, starting at
   whole revolutions of the angle grid) are windowed (periodic Hann by default) and
   transformed; the amplitude spectrum ``2 |X_k| / sum(w)`` (the window's coherent gain
   corrected) reads ``A`` for a pure order of amplitude ``A``, because an integer order falls
   exactly on bin ``k = o R``. Blocks are power-averaged. A harmonic's amplitude is read over
   ``+-band_bins`` bins about its order,

   .. math::

       A = \sqrt{\sum_{|k - k_0| \le m} \hat A_k^2 \,/\, B_{en}},

   ``B_en = N sum(w^2) / (sum w)^2`` the window's equivalent noise bandwidth in bins (1.5 for
   Hann): exact for a pure order (its Hann main lobe is three bins wide) and insensitive to a
   little residual smearing.
4. **Mesh harmonics and Arms.** For ``z1`` teeth on the tracked shaft the mesh harmonics are
   orders ``h z1``, ``h = 1, 2, 3``, and

   .. math::

       A_{rms} = \sqrt{A_1^2 + A_2^2 + A_3^2}

   (seed 003 Sec. 4 [2]_; the extracted text prints
   ``sqrt(sum A1)``, SEED-NOTES 17). This is the seed's quantity, not the RMS of the
   three-harmonic signal (that is ``A_rms / sqrt(2)``).
5. **Acceleration to displacement** in the order domain, order ``o`` at frequency
   ``f = o n / 60`` (the block's mean speed):

   .. math::

       D(f) = -\frac{A(f)}{(2\pi f)^2}\,
              \frac{(f/f_c)^{N}}{\sqrt{1 + (f/f_c)^{2N}}},

   the second factor the magnitude of an ``N``-th order Butterworth high pass at ``f_c``
   (default 10 Hz, ``N = 4``), zero-phase, which keeps ``D`` finite (and zero at ``f = 0``).

Gaps and missing speed
----------------------
Samples with ``valid == False`` (or non-finite) and samples where the speed is unknown (or
below ``min_speed_rpm``) are never bridged: resampling works on gap-free stretches only, and an
output sample is made only where the whole kernel lies inside one stretch. A run-up window that
meets a gap is **dropped and counted** (``dropped["gap"]``, ``dropped["speed_unknown"]``); a
speed step that contains gaps is **split** into gap-free pieces whose whole-revolution blocks
are averaged, and the gaps, pieces and pieces too short for one block are counted. No speed
at all raises :class:`~rigtools.analysis.speed.MissingSpeedError`.

References
----------
.. [1] J. O. Smith, P. Gossett, "A flexible sampling-rate conversion method", Proc. IEEE
   ICASSP 1984 (band-limited interpolation with a windowed sinc).
.. [2] W. Yu, C. K. Mechefske, "Analytical modeling of spur gear corner contact effects",
   Mech. Mach. Theory 96 (2016) 146-164 (seed 003), Sec. 4: Arms of Kahraman and
   Blankenship's measured dynamic transmission error, 600-4100 rpm, mesh 500-3400 Hz (the
   seed's refs [14-17], whose list the extracted text truncates).
.. [3] K. R. Fyfe, E. D. S. Munck, "Analysis of computed order tracking", Mech. Syst. Signal
   Process. 11 (1997) 187-205 (angular resampling from a speed or tacho signal).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from scipy import signal as sps
from scipy.special import i0

from rigtools.analysis.speed import (
    MissingSpeedError,
    SpeedProfile,
    SpeedStep,
    _as_1d,
    _check_fs,
    _check_positive,
    _check_teeth,
    _check_valid,
    _runs,
    detect_speed_steps,
    speed_profile,
)
from rigtools.ingest.recording import Recording

__all__ = [
    "RESAMPLER_PASSBAND",
    "AngleSignal",
    "Campbell",
    "OrderSpectrum",
    "RunUpCurve",
    "StepLevels",
    "acceleration_to_displacement",
    "frequency_campbell",
    "harmonic_amplitudes",
    "order_campbell",
    "order_spectrum",
    "resample_to_angle",
    "run_up_curve",
    "run_up_curve_from_recording",
    "step_levels",
    "step_levels_from_recording",
]

#: Fraction of ``min(fs, P f)`` up to which the angular resampler is flat (within ~1e-5).
RESAMPLER_PASSBAND = 0.42
_ZEROS = 32  # zero crossings of the kernel on each side
_BETA = 10.0  # Kaiser shape
_CUTOFF = 0.94  # kernel cutoff, fraction of the Nyquist frequency of min(fs, P f)
_CHUNK_TAPS = 1 << 21  # outputs x taps evaluated at once (memory bound of the resampler)

Quantity = Literal["acceleration", "displacement"]
_ACCEL_UNITS = frozenset({"m/s^2", "m/s2", "m/s²", "m s-2", "m*s^-2", "m.s-2"})


# --- results ----------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class AngleSignal:
    """A signal resampled at uniform increments of shaft angle.

    Attributes
    ----------
    angle_rev : numpy.ndarray
        Shaft angle of each sample (rev), ``j / samples_per_rev`` for integers ``j``; the origin
        is arbitrary (the start of the speed record).
    values : numpy.ndarray
        Resampled values (unit of the input).
    time_s : numpy.ndarray
        Time of each sample (s, logger clock).
    speed_rpm : numpy.ndarray
        Shaft speed at each sample (rpm).
    run : numpy.ndarray
        Number of the gap-free run each sample belongs to (int); ``j`` is consecutive within
        a run.
    run_end : tuple of str
        Per run, why it ended: ``"gap"`` (invalid samples follow), ``"speed_unknown"`` (the
        speed is unknown or too low next) or ``"end"``.
    samples_per_rev : int
        Angular samples per revolution ``P``.
    input_rate_Hz : float
        Sample rate of the input (Hz), which bounds the usable orders at high speed.
    dropped : Mapping
        Input samples not resampled, by reason: ``"gap"``, ``"speed_unknown"``, ``"edge"``
        (within a kernel half-width of a gap or of the record's ends).
    """

    angle_rev: np.ndarray
    values: np.ndarray
    time_s: np.ndarray
    speed_rpm: np.ndarray
    run: np.ndarray
    run_end: tuple[str, ...]
    samples_per_rev: int
    input_rate_Hz: float
    dropped: Mapping[str, int] = field(default_factory=dict)

    @property
    def index(self) -> np.ndarray:
        """Angle sample numbers ``j`` (int)."""
        return np.rint(self.angle_rev * self.samples_per_rev).astype(np.int64)


@dataclass(frozen=True, eq=False)
class OrderSpectrum:
    """An amplitude spectrum over shaft orders.

    Attributes
    ----------
    order : numpy.ndarray
        Orders (cycles per revolution), spacing ``1 / revolutions``.
    amplitude : numpy.ndarray
        Amplitude (unit of the input, or m for displacement), power-averaged over blocks;
        a pure order of amplitude ``A`` on its bin reads ``A``.
    revolutions : int
        Revolutions per block.
    n_blocks : int
        Blocks averaged.
    speed_rpm : float
        Mean speed over the blocks, revolutions over time (rpm).
    enbw_bins : float
        Equivalent noise bandwidth of the window (bins).
    max_valid_order : float
        Orders above this lie outside the resampler's passband (at the blocks' top speed).
    window : str
        Window name.
    quantity : str
        ``"acceleration"`` (or the input's own quantity) or ``"displacement"``.
    """

    order: np.ndarray
    amplitude: np.ndarray
    revolutions: int
    n_blocks: int
    speed_rpm: float
    enbw_bins: float
    max_valid_order: float
    window: str
    quantity: str = "acceleration"

    def to_displacement(self, *, highpass_Hz: float = 10.0,
                        highpass_order: int = 4) -> OrderSpectrum:
        """The spectrum converted from acceleration (m/s^2) to displacement (m).

        Uses the mean speed for every block (see :func:`acceleration_to_displacement`).
        """
        if self.quantity != "acceleration":
            raise ValueError(f"only an acceleration spectrum converts, this is {self.quantity}")
        f = self.order * self.speed_rpm / 60.0
        amp = np.abs(acceleration_to_displacement(self.amplitude, f, highpass_Hz=highpass_Hz,
                                                  highpass_order=highpass_order))
        return OrderSpectrum(self.order, amp, self.revolutions, self.n_blocks, self.speed_rpm,
                             self.enbw_bins, self.max_valid_order, self.window, "displacement")


@dataclass(frozen=True, eq=False)
class Campbell:
    """Spectra along a run: a 2-D array with its axes (waterfall or Campbell diagram data).

    Attributes
    ----------
    time_s : numpy.ndarray
        Centre time of each spectrum (s), shape ``(rows,)``.
    speed_rpm : numpy.ndarray
        Mean shaft speed of each spectrum (rpm), ``(rows,)``; NaN where unknown.
    axis : numpy.ndarray
        Orders or frequencies (Hz) of the columns, ``(cols,)``.
    axis_name : str
        ``"order"`` or ``"frequency_Hz"``. On an order axis a shaft order is a vertical line;
        on a frequency axis order ``k`` lies on ``f = k n / 60``.
    amplitude : numpy.ndarray
        Amplitude spectra, ``(rows, cols)``; NaN beyond the valid band of a row.
    quantity : str
        ``"acceleration"`` or ``"displacement"``.
    dropped : Mapping
        Spectra not computed, by reason (``"gap"``, ``"speed_unknown"``).
    """

    time_s: np.ndarray
    speed_rpm: np.ndarray
    axis: np.ndarray
    axis_name: str
    amplitude: np.ndarray
    quantity: str = "acceleration"
    dropped: Mapping[str, int] = field(default_factory=dict)


@dataclass(frozen=True, eq=False)
class RunUpCurve:
    """Mesh-harmonic amplitudes and Arms in short windows along a run-up.

    Attributes
    ----------
    time_s : numpy.ndarray
        Centre time of each window (s), ``(w,)``.
    speed_rpm : numpy.ndarray
        Mean speed of each window, revolutions over duration (rpm).
    mesh_frequency_Hz : numpy.ndarray
        ``z1 n / 60`` (Hz).
    harmonics : tuple of int
        Mesh harmonics read (``(1, 2, 3)``).
    amplitude : numpy.ndarray
        ``(w, len(harmonics))`` amplitudes (m/s^2 or m); NaN above the passband.
    arms : numpy.ndarray
        ``sqrt(sum_h A_h^2)`` per window (seed 003's Arms).
    z1 : int
        Teeth on the tracked shaft.
    revs_per_window, hop_revs, samples_per_rev : int
        Window length and step (rev), angular sampling.
    quantity : str
        ``"acceleration"`` or ``"displacement"``.
    spectra : Campbell
        The windows' order spectra (order axis), for a waterfall.
    dropped : Mapping
        Windows dropped, by reason (``"gap"``, ``"speed_unknown"``).
    """

    time_s: np.ndarray
    speed_rpm: np.ndarray
    mesh_frequency_Hz: np.ndarray
    harmonics: tuple[int, ...]
    amplitude: np.ndarray
    arms: np.ndarray
    z1: int
    revs_per_window: int
    hop_revs: int
    samples_per_rev: int
    quantity: str
    spectra: Campbell
    dropped: Mapping[str, int] = field(default_factory=dict)

    @property
    def n_dropped(self) -> int:
        """Total windows dropped."""
        return int(sum(self.dropped.values()))


@dataclass(frozen=True, eq=False)
class StepLevels:
    """Mesh-harmonic amplitudes and Arms, one per speed step of a stepped run-up.

    Attributes
    ----------
    steps : tuple of SpeedStep
        The plateaus analysed.
    speed_rpm : numpy.ndarray
        Mean speed over the blocks used, revolutions over time (rpm), ``(s,)``.
    mesh_frequency_Hz : numpy.ndarray
        ``z1 n / 60`` (Hz).
    harmonics : tuple of int
        Mesh harmonics read.
    amplitude : numpy.ndarray
        ``(s, len(harmonics))`` amplitudes (m/s^2 or m); NaN where no block was usable or above
        the passband.
    arms : numpy.ndarray
        ``sqrt(sum_h A_h^2)`` per step.
    n_blocks : numpy.ndarray
        Whole-revolution blocks averaged per step (int).
    n_pieces : numpy.ndarray
        Gap-free pieces the step was split into that gave at least one block (int).
    n_gaps : numpy.ndarray
        Stretches of invalid samples or unknown speed inside the step (int).
    z1, revs_per_block, samples_per_rev : int
    quantity : str
    spectra : tuple of OrderSpectrum or None
        The averaged order spectrum of each step (None where no block was usable).
    dropped : Mapping
        ``"piece_shorter_than_block"``: gap-free pieces too short for one block;
        ``"step_without_block"``: steps with no usable block.
    """

    steps: tuple[SpeedStep, ...]
    speed_rpm: np.ndarray
    mesh_frequency_Hz: np.ndarray
    harmonics: tuple[int, ...]
    amplitude: np.ndarray
    arms: np.ndarray
    n_blocks: np.ndarray
    n_pieces: np.ndarray
    n_gaps: np.ndarray
    z1: int
    revs_per_block: int
    samples_per_rev: int
    quantity: str
    spectra: tuple[OrderSpectrum | None, ...]
    dropped: Mapping[str, int] = field(default_factory=dict)


# --- validation -------------------------------------------------------------------------------
def _check_int(name: str, value: Any, minimum: int = 1) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"`{name}` must be an integer >= {minimum}, was {value!r}")
    return int(value)


def _check_speed(speed: SpeedProfile | None) -> SpeedProfile:
    if speed is None:
        raise MissingSpeedError(None, detail="`speed` is None; build one with "
                                "speed_from_slow_signal, speed_from_tacho or speed_profile")
    if not isinstance(speed, SpeedProfile):
        raise TypeError(f"`speed` must be a SpeedProfile, was {type(speed).__name__}")
    return speed


def _check_harmonics(harmonics: int | Sequence[int]) -> tuple[int, ...]:
    if isinstance(harmonics, (int, np.integer)):
        n = _check_int("harmonics", harmonics)
        return tuple(range(1, n + 1))
    hs = tuple(int(h) for h in harmonics)
    if not hs or any(h < 1 or isinstance(h, bool) for h in harmonics):
        raise ValueError(f"`harmonics` must be a count or a sequence of integers >= 1, "
                         f"was {harmonics!r}")
    return hs


def _check_quantity(quantity: str) -> str:
    if quantity not in ("acceleration", "displacement"):
        raise ValueError(f"`quantity` must be 'acceleration' or 'displacement', was {quantity!r}")
    return quantity


def _auto_samples_per_rev(max_order: float) -> int:
    need = max_order / RESAMPLER_PASSBAND
    return int(2 ** max(4, int(np.ceil(np.log2(need)))))


def _check_samples_per_rev(samples_per_rev: int | None, max_order: float) -> int:
    if samples_per_rev is None:
        return _auto_samples_per_rev(max_order)
    p = _check_int("samples_per_rev", samples_per_rev, 4)
    if max_order > RESAMPLER_PASSBAND * p:
        raise ValueError(
            f"`samples_per_rev` must be >= {int(np.ceil(max_order / RESAMPLER_PASSBAND))} to "
            f"resolve order {max_order:g} inside the resampler's passband "
            f"({RESAMPLER_PASSBAND} x samples_per_rev), was {p}")
    return p


def _window(window: str, n: int) -> np.ndarray:
    try:
        return np.asarray(sps.get_window(window, n, fftbins=True), dtype=np.float64)
    except (ValueError, TypeError) as exc:
        raise ValueError(f"`window` must be a scipy.signal window name, was {window!r}: "
                         f"{exc}") from exc


# --- displacement -----------------------------------------------------------------------------
def acceleration_to_displacement(
    amplitude: np.ndarray | float,
    frequency_Hz: np.ndarray | float,
    *,
    highpass_Hz: float = 10.0,
    highpass_order: int = 4,
) -> np.ndarray:
    r"""Acceleration spectrum values to displacement, with a high pass that keeps it finite.

    Parameters
    ----------
    amplitude : array_like
        Acceleration amplitudes or complex spectrum values (m/s^2).
    frequency_Hz : array_like
        Frequency of each value (Hz), broadcastable against ``amplitude``.
    highpass_Hz : float
        Corner ``f_c`` of the Butterworth high pass (Hz).
    highpass_order : int
        Its order ``N`` (>= 2, so that the result stays finite as ``f -> 0``).

    Returns
    -------
    numpy.ndarray
        Displacement (m): :math:`-a/(2\pi f)^2 \cdot (f/f_c)^N/\sqrt{1 + (f/f_c)^{2N}}`, zero at
        ``f = 0``. For magnitudes take ``abs``: the minus sign is a phase of pi.

    Examples
    --------
    A 4 m/s^2 sine at 400 Hz (far above the high pass) is ``4 / (2 pi 400)^2`` m:

    >>> d = acceleration_to_displacement(4.0, 400.0)
    >>> bool(abs(abs(d) - 4.0 / (2 * np.pi * 400.0) ** 2) < 1e-15)
    True
    """
    fc = _check_positive("highpass_Hz", highpass_Hz)
    n = _check_int("highpass_order", highpass_order, 2)
    a = np.asarray(amplitude)
    f = np.abs(np.asarray(frequency_Hz, dtype=np.float64))
    r = f / fc
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        # (f/fc)^N / sqrt(1 + (f/fc)^2N) / (2 pi f)^2, written to stay finite at both ends
        gain = np.where(r > 1.0, 1.0 / np.sqrt(1.0 + r ** (-2 * n)),
                        r**n / np.sqrt(1.0 + r ** (2 * n)))
        h = np.where(f > 0, gain / (2.0 * np.pi * np.where(f > 0, f, 1.0)) ** 2, 0.0)
    return -a * h


# --- angular resampling -----------------------------------------------------------------------
def _kernel_apply(xr: np.ndarray, u: np.ndarray, rho: np.ndarray) -> np.ndarray:
    """Windowed-sinc values of ``xr`` at fractional positions ``u`` with cutoffs ``rho``.

    ``xr`` is one gap-free run; every kernel must lie inside it (checked by the caller).
    """
    out = np.empty(u.size)
    i = 0
    last = xr.size - 1
    while i < u.size:
        k0 = int(np.ceil(_ZEROS / rho[i]))
        rows = max(1, _CHUNK_TAPS // (2 * k0 + 2))
        sl = slice(i, min(u.size, i + rows))
        uu, rr = u[sl], rho[sl]
        kmax = int(np.ceil(_ZEROS / rr.min()))
        offs = np.arange(-kmax + 1, kmax + 1)
        base = np.floor(uu).astype(np.int64)
        idx = base[:, None] + offs[None, :]
        tau = uu[:, None] - idx
        xw = (rr[:, None] * tau) / _ZEROS
        inside = np.abs(xw) < 1.0
        w = np.where(inside, i0(_BETA * np.sqrt(np.clip(1.0 - xw * xw, 0.0, None))), 0.0)
        h = np.sinc(_CUTOFF * rr[:, None] * tau) * w
        h /= h.sum(axis=1, keepdims=True)
        out[sl] = np.einsum("ij,ij->i", h, xr[np.clip(idx, 0, last)])
        i = sl.stop
    return out


def resample_to_angle(
    x: np.ndarray,
    sample_rate_Hz: float,
    speed: SpeedProfile | None,
    *,
    samples_per_rev: int,
    start_time_s: float = 0.0,
    valid: np.ndarray | None = None,
    min_speed_rpm: float = 1.0,
) -> AngleSignal:
    """Resample a uniformly sampled signal at uniform increments of shaft angle.

    See the module docstring for the angle integration and the Kaiser-windowed-sinc kernel.

    Parameters
    ----------
    x : array_like
        Signal (any unit), uniformly sampled, NaN allowed where ``valid`` is False.
    sample_rate_Hz : float
        Its sample rate (Hz).
    speed : SpeedProfile
        Shaft speed; ``None`` raises :class:`MissingSpeedError`.
    samples_per_rev : int
        Angular samples per revolution ``P``; orders up to ``RESAMPLER_PASSBAND * P`` are kept.
    start_time_s : float
        Time of ``x[0]`` on the speed's clock (s).
    valid : array_like of bool, optional
        Per-sample validity (``Channel.valid``); default all finite samples.
    min_speed_rpm : float
        Below this speed the angle is treated as unknown (rpm).

    Returns
    -------
    AngleSignal

    Raises
    ------
    MissingSpeedError
        When ``speed`` is None or covers no sample of ``x``.
    """
    speed = _check_speed(speed)
    xs = _as_1d("x", x)
    fs = _check_fs(sample_rate_Hz)
    p = _check_int("samples_per_rev", samples_per_rev, 4)
    ok = _check_valid(valid, xs.size) & np.isfinite(xs)
    n = xs.size
    t = float(start_time_s) + np.arange(n) / fs
    f = speed.frequency_Hz_at(t)
    known = np.isfinite(f) & (f * 60.0 >= float(min_speed_rpm))
    if not np.any(known):
        raise MissingSpeedError(
            None, detail=(f"the speed ({speed.source}) is known over "
                          f"{_cover_text(speed)}, the signal spans {t[0]:.6g} to "
                          f"{t[-1] if n else t[0]:.6g} s; no sample has a known speed "
                          f">= {min_speed_rpm} rpm"))
    # 1. shaft angle, per stretch of known speed; each stretch starts on a whole revolution
    theta = np.full(n, np.nan)
    offset = 0.0
    for a, b in _runs(known):
        inc = 0.5 * (f[a + 1:b] + f[a:b - 1]) / fs
        theta[a:b] = offset + np.r_[0.0, np.cumsum(inc)]
        offset = float(np.ceil(theta[b - 1])) + 1.0
    usable = ok & known
    dropped: Counter[str] = Counter()
    dropped["gap"] = int(np.count_nonzero(~ok))
    dropped["speed_unknown"] = int(np.count_nonzero(ok & ~known))
    rho_all = np.minimum(1.0, p * np.where(known, f, 0.0) / fs)
    ang, val, tim, spd, run = [], [], [], [], []
    run_end: list[str] = []
    for a, b in _runs(usable):
        th = theta[a:b]
        j0 = int(np.ceil(th[0] * p - 1e-9))
        j1 = int(np.floor(th[-1] * p + 1e-9))
        if j1 < j0:
            dropped["edge"] += b - a
            continue
        j = np.arange(j0, j1 + 1)
        u = np.interp(j / p, th, np.arange(b - a, dtype=np.float64))
        rho = np.interp(u, np.arange(b - a, dtype=np.float64), rho_all[a:b])
        k = np.ceil(_ZEROS / rho)
        fl = np.floor(u)
        keep = (fl - k + 1 >= 0) & (fl + k <= b - a - 1)
        if not np.any(keep):
            dropped["edge"] += b - a
            continue
        reason = "end" if b == n else ("speed_unknown" if ok[b] else "gap")
        # the kept outputs are consecutive (the kernel width changes slowly); guard anyway
        pieces = _runs(keep)
        covered = 0
        for q, (ka, kb) in enumerate(pieces):
            uu = u[ka:kb]
            ang.append(j[ka:kb] / p)
            val.append(_kernel_apply(xs[a:b], uu, rho[ka:kb]))
            tim.append(t[0] + (a + uu) / fs)
            spd.append(60.0 * np.interp(uu, np.arange(b - a, dtype=np.float64), f[a:b]))
            run.append(np.full(kb - ka, len(run_end), dtype=np.int64))
            run_end.append(reason if q == len(pieces) - 1 else "edge")
            covered += int(np.ceil(uu[-1]) - np.floor(uu[0]))
        dropped["edge"] += max(0, (b - a) - covered)

    def cat(parts: list[np.ndarray], dtype: Any = np.float64) -> np.ndarray:
        return np.concatenate(parts) if parts else np.empty(0, dtype=dtype)

    return AngleSignal(
        angle_rev=cat(ang), values=cat(val), time_s=cat(tim), speed_rpm=cat(spd),
        run=cat(run, np.int64), run_end=tuple(run_end), samples_per_rev=p, input_rate_Hz=fs,
        dropped={k: v for k, v in dropped.items() if v},
    )


def _cover_text(speed: SpeedProfile) -> str:
    spans = [f"{a:.6g} to {b:.6g} s" for a, b in
             zip(speed.cover_start_s[:3], speed.cover_stop_s[:3], strict=True)]
    more = f" and {speed.n_segments - 3} more" if speed.n_segments > 3 else ""
    return ", ".join(spans) + more


# --- order spectra ----------------------------------------------------------------------------
def _block_amplitudes(blocks: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Amplitude spectra ``(b, N//2+1)`` of blocks ``(b, N)``, coherent gain corrected."""
    spec = np.abs(np.fft.rfft(blocks * w, axis=-1)) * (2.0 / w.sum())
    spec[:, 0] /= 2.0
    if blocks.shape[-1] % 2 == 0:
        spec[:, -1] /= 2.0
    return spec


def order_spectrum(
    x_angle: np.ndarray,
    samples_per_rev: int,
    *,
    revolutions: int | None = None,
    window: str = "hann",
    speed_rpm: float = float("nan"),
) -> OrderSpectrum:
    """Amplitude order spectrum of an angle-domain signal, power-averaged over blocks.

    Parameters
    ----------
    x_angle : array_like
        Signal sampled at ``samples_per_rev`` per revolution, starting at a whole revolution;
        its length must be a whole number of blocks.
    samples_per_rev : int
        Samples per revolution ``P``.
    revolutions : int, optional
        Revolutions per block ``R`` (order resolution ``1/R``). Default: the whole signal.
    window : str
        A ``scipy.signal.get_window`` name (periodic form); default Hann.
    speed_rpm : float
        Mean speed, kept in the result for frequency conversions (rpm).

    Returns
    -------
    OrderSpectrum
        A pure order ``o`` (``o R`` an integer) of amplitude ``A`` reads ``A`` at ``o``.

    Examples
    --------
    >>> th = np.arange(8 * 64) / 64                       # 8 revolutions, 64 samples/rev
    >>> s = order_spectrum(3.0 * np.cos(2 * np.pi * 5 * th), 64, revolutions=4)
    >>> float(np.round(s.amplitude[s.order == 5][0], 12))
    3.0
    """
    x = _as_1d("x_angle", x_angle)
    p = _check_int("samples_per_rev", samples_per_rev, 2)
    if x.size == 0 or x.size % p:
        raise ValueError(f"`x_angle` must hold whole revolutions of {p} samples, has {x.size}")
    r = x.size // p if revolutions is None else _check_int("revolutions", revolutions)
    nb = r * p
    if x.size % nb:
        raise ValueError(f"len(`x_angle`)={x.size} must be a multiple of revolutions x "
                         f"samples_per_rev = {nb}")
    if not np.all(np.isfinite(x)):
        raise ValueError("`x_angle` must be finite (gaps are split before the spectrum)")
    w = _window(window, nb)
    amp = np.sqrt(np.mean(_block_amplitudes(x.reshape(-1, nb), w) ** 2, axis=0))
    return OrderSpectrum(
        order=np.arange(amp.size) / r, amplitude=amp, revolutions=r, n_blocks=x.size // nb,
        speed_rpm=float(speed_rpm), enbw_bins=float(nb * np.sum(w**2) / np.sum(w) ** 2),
        max_valid_order=RESAMPLER_PASSBAND * p, window=window)


def harmonic_amplitudes(
    spectrum: OrderSpectrum,
    orders: Sequence[float] | np.ndarray,
    *,
    band_bins: int = 1,
) -> np.ndarray:
    r"""Amplitudes of given orders, read over ``+-band_bins`` bins (energy sum).

    :math:`A = \sqrt{\sum_{|k-k_0| \le m} \hat A_k^2 / B_{en}}` with the window's equivalent
    noise bandwidth ``B_en`` (bins): a pure order on its bin reads its amplitude exactly when
    ``band_bins`` covers its main lobe (1 for Hann, 0 for a rectangular window).

    Parameters
    ----------
    spectrum : OrderSpectrum
        The spectrum.
    orders : sequence of float
        Orders to read (cycles per revolution).
    band_bins : int
        Half-width of the band (bins).

    Returns
    -------
    numpy.ndarray
        Amplitudes; NaN for orders above ``spectrum.max_valid_order`` or beyond the spectrum.
    """
    m = _check_int("band_bins", band_bins, 0)
    o = np.atleast_1d(np.asarray(orders, dtype=np.float64))
    k0 = np.rint(o * spectrum.revolutions).astype(np.int64)
    out = np.full(o.shape, np.nan)
    a2 = spectrum.amplitude**2
    for i, k in enumerate(k0):
        if k - m < 0 or k + m >= a2.size or o[i] + m / spectrum.revolutions > \
                spectrum.max_valid_order:
            continue
        out[i] = np.sqrt(a2[k - m:k + m + 1].sum() / spectrum.enbw_bins)
    return out


# --- blocks and windows on the angle grid -----------------------------------------------------
@dataclass(frozen=True)
class _Block:
    start: int  # index into the AngleSignal arrays
    stop: int


def _block_spectra(sig: AngleSignal, blocks: Sequence[_Block], w: np.ndarray, revs: int
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per block: amplitude spectra, mean speed (rpm), centre time (s), top valid order."""
    data = np.stack([sig.values[b.start:b.stop] for b in blocks])
    amp = _block_amplitudes(data, w)
    t0 = np.array([sig.time_s[b.start] for b in blocks])
    # block duration: from its first sample to one angular step past its last
    t1 = np.array([sig.time_s[b.stop - 1] + 60.0 / (sig.speed_rpm[b.stop - 1]
                                                     * sig.samples_per_rev) for b in blocks])
    rpm = 60.0 * revs / (t1 - t0)
    top = np.array([sig.speed_rpm[b.start:b.stop].max() for b in blocks]) / 60.0
    max_order = RESAMPLER_PASSBAND * np.minimum(sig.samples_per_rev, sig.input_rate_Hz / top)
    return amp, rpm, 0.5 * (t0 + t1), max_order


def _to_displacement(amp: np.ndarray, orders: np.ndarray, rpm: np.ndarray, highpass_Hz: float,
                     highpass_order: int) -> np.ndarray:
    """Amplitudes ``(b, k)`` at ``orders`` ``(k,)`` of blocks at speeds ``rpm`` ``(b,)``."""
    f = np.asarray(orders)[None, :] * rpm[:, None] / 60.0
    return np.abs(acceleration_to_displacement(amp, f, highpass_Hz=highpass_Hz,
                                               highpass_order=highpass_order))


def _block_harmonics(amp: np.ndarray, revs: int, orders: Sequence[float], band: int,
                     enbw: float, max_order: np.ndarray) -> np.ndarray:
    """Band readouts ``(b, h)`` of ``orders`` from block amplitude spectra ``(b, k)``."""
    out = np.full((amp.shape[0], len(orders)), np.nan)
    a2 = amp**2
    for i, o in enumerate(orders):
        k = round(o * revs)
        if k - band < 0 or k + band >= amp.shape[1]:
            continue
        val = np.sqrt(a2[:, k - band:k + band + 1].sum(axis=1) / enbw)
        out[:, i] = np.where(o + band / revs <= max_order, val, np.nan)
    return out


def _aligned_blocks(sig: AngleSignal, sel: np.ndarray, revs: int) -> list[_Block]:
    """Blocks of ``revs`` whole revolutions inside the contiguous index range ``sel``.

    ``sel`` indexes ``sig``; blocks start at whole revolutions of the angle grid.
    """
    if sel.size == 0:
        return []
    p = sig.samples_per_rev
    jj = sig.index[sel]
    first = int(-(-jj[0] // p) * p)  # first whole revolution
    nb = revs * p
    out = []
    s = sel[0] + (first - jj[0])
    while s + nb <= sel[-1] + 1:
        out.append(_Block(int(s), int(s + nb)))
        s += nb
    return out


def _run_up_windows(sig: AngleSignal, revs: int, hop: int
                    ) -> tuple[list[_Block], Counter[str]]:
    """Windows of ``revs`` revolutions every ``hop`` revolutions on the global angle grid.

    Those not lying wholly inside one run are dropped and counted by the run's end reason.
    """
    p = sig.samples_per_rev
    dropped: Counter[str] = Counter()
    if sig.values.size == 0:
        return [], dropped
    j = sig.index
    run_starts = np.flatnonzero(np.r_[True, sig.run[1:] != sig.run[:-1]])
    run_stops = np.r_[run_starts[1:], j.size]  # exclusive, indices into sig
    j_first, j_last = j[run_starts], j[run_stops - 1]
    n = revs * p
    r0 = -(-int(j[0]) // (hop * p)) * hop  # first window start (rev), a multiple of hop
    out = []
    start_rev = r0
    while start_rev * p + n - 1 <= j[-1]:
        a = start_rev * p
        e = a + n - 1
        r = int(np.searchsorted(j_first, a, side="right")) - 1  # last run starting at <= a
        if r >= 0 and a >= j_first[r] and e <= j_last[r]:
            s = int(run_starts[r] + (a - j_first[r]))
            out.append(_Block(s, s + n))
        else:
            # the break the window meets: the end of run r (or of the run before a)
            rr = max(r, 0)
            dropped[sig.run_end[rr] if sig.run_end[rr] != "end" else "gap"] += 1
        start_rev += hop
    return out, dropped


def _order_windows(
    x: np.ndarray, sample_rate_Hz: float, speed: SpeedProfile | None, *, start_time_s: float,
    valid: np.ndarray | None, revs_per_window: int, hop_revs: int | None,
    samples_per_rev: int, window: str, quantity: str, highpass_Hz: float,
    highpass_order: int, max_order: float, min_speed_rpm: float,
) -> tuple[Campbell, np.ndarray, np.ndarray]:
    """Order spectra of the run-up windows.

    Returns the Campbell data (in ``quantity``), the spectra as given (acceleration) and each
    window's top valid order.
    """
    revs = _check_int("revs_per_window", revs_per_window)
    hop = revs // 2 if hop_revs is None else _check_int("hop_revs", hop_revs)
    hop = max(hop, 1)
    sig = resample_to_angle(x, sample_rate_Hz, speed, samples_per_rev=samples_per_rev,
                            start_time_s=start_time_s, valid=valid, min_speed_rpm=min_speed_rpm)
    blocks, dropped = _run_up_windows(sig, revs, hop)
    ncols = int(np.floor(max_order * revs)) + 1
    orders = np.arange(ncols) / revs
    if not blocks:
        empty = np.empty((0, ncols))
        return (Campbell(np.empty(0), np.empty(0), orders, "order", empty, quantity,
                         dict(dropped)), empty, np.empty(0))
    w = _window(window, revs * sig.samples_per_rev)
    amps, rpms, times, maxo = [], [], [], []
    chunk = max(1, (1 << 22) // (revs * sig.samples_per_rev))
    for i in range(0, len(blocks), chunk):
        a, r, t, m = _block_spectra(sig, blocks[i:i + chunk], w, revs)
        amps.append(a[:, :ncols])
        rpms.append(r)
        times.append(t)
        maxo.append(m)
    acc = np.concatenate(amps)
    mo = np.concatenate(maxo)
    rpm = np.concatenate(rpms)
    amp = acc if quantity == "acceleration" else _to_displacement(acc, orders, rpm, highpass_Hz,
                                                                  highpass_order)
    amp[orders[None, :] > mo[:, None]] = np.nan
    camp = Campbell(np.concatenate(times), rpm, orders, "order", amp, quantity, dict(dropped))
    return camp, acc, mo


def order_campbell(
    x: np.ndarray,
    sample_rate_Hz: float,
    speed: SpeedProfile | None,
    *,
    start_time_s: float = 0.0,
    valid: np.ndarray | None = None,
    max_order: float = 64.0,
    revs_per_window: int = 8,
    hop_revs: int | None = None,
    samples_per_rev: int | None = None,
    window: str = "hann",
    quantity: Quantity = "acceleration",
    highpass_Hz: float = 10.0,
    highpass_order: int = 4,
    min_speed_rpm: float = 1.0,
) -> Campbell:
    """Order spectra in windows of whole revolutions along a run (order-axis waterfall).

    Parameters
    ----------
    x : array_like
        Signal (m/s^2 for ``quantity="displacement"``), uniformly sampled.
    sample_rate_Hz : float
        Sample rate (Hz).
    speed : SpeedProfile
        Shaft speed (``None`` raises :class:`MissingSpeedError`).
    start_time_s : float
        Time of ``x[0]`` (s).
    valid : array_like of bool, optional
        Per-sample validity.
    max_order : float
        Highest order kept (columns).
    revs_per_window, hop_revs : int
        Window length and step (rev); default step half a window.
    samples_per_rev : int, optional
        Angular sampling; default the smallest power of two that keeps ``max_order`` inside
        the passband.
    window : str
        Window name.
    quantity : {"acceleration", "displacement"}
        Spectra as given, or converted to displacement (m) with the high pass.
    highpass_Hz, highpass_order
        High pass of the displacement conversion.
    min_speed_rpm : float
        Below this the angle is treated as unknown (rpm).

    Returns
    -------
    Campbell
        ``axis_name == "order"``; rows are windows, windows meeting a gap are dropped and
        counted in ``dropped``.
    """
    mo = _check_positive("max_order", max_order)
    p = _check_samples_per_rev(samples_per_rev, mo)
    camp, _, _ = _order_windows(
        x, sample_rate_Hz, speed, start_time_s=start_time_s, valid=valid,
        revs_per_window=revs_per_window, hop_revs=hop_revs, samples_per_rev=p, window=window,
        quantity=_check_quantity(quantity), highpass_Hz=highpass_Hz,
        highpass_order=highpass_order, max_order=mo, min_speed_rpm=min_speed_rpm)
    return camp


def run_up_curve(
    x: np.ndarray,
    sample_rate_Hz: float,
    speed: SpeedProfile | None,
    z1: int,
    *,
    start_time_s: float = 0.0,
    valid: np.ndarray | None = None,
    harmonics: int | Sequence[int] = 3,
    revs_per_window: int = 8,
    hop_revs: int | None = None,
    samples_per_rev: int | None = None,
    window: str = "hann",
    band_bins: int = 1,
    quantity: Quantity = "acceleration",
    highpass_Hz: float = 10.0,
    highpass_order: int = 4,
    min_speed_rpm: float = 1.0,
) -> RunUpCurve:
    """Mesh-harmonic amplitudes and Arms in short windows along a run-up (ramp).

    Each window is ``revs_per_window`` whole revolutions of the tracked shaft, so the mesh
    orders ``h z1`` sit on their bins however fast the speed changes within it.

    Parameters
    ----------
    x : array_like
        Signal (m/s^2 for ``quantity="displacement"``), uniformly sampled.
    sample_rate_Hz : float
        Sample rate (Hz).
    speed : SpeedProfile
        Speed of the shaft carrying the ``z1``-tooth gear (``None`` raises
        :class:`MissingSpeedError`).
    z1 : int
        Teeth of the gear on the tracked shaft.
    start_time_s : float
        Time of ``x[0]`` (s).
    valid : array_like of bool, optional
        Per-sample validity (``Channel.valid``).
    harmonics : int or sequence of int
        Mesh harmonics: a count (``3`` -> 1, 2, 3) or the list.
    revs_per_window, hop_revs : int
        Window length and step (rev); default step half a window. The order resolution is
        ``1 / revs_per_window``.
    samples_per_rev : int, optional
        Angular sampling; default the smallest power of two keeping the top harmonic inside
        the resampler's passband.
    window : str
        Window name (default Hann).
    band_bins : int
        Half-width of the harmonic readout band (bins), see :func:`harmonic_amplitudes`.
    quantity : {"acceleration", "displacement"}
        Amplitudes as given, or converted to displacement (m).
    highpass_Hz, highpass_order
        High pass of the displacement conversion (Hz, order).
    min_speed_rpm : float
        Below this the angle is treated as unknown (rpm).

    Returns
    -------
    RunUpCurve
        Windows meeting a gap are dropped and counted (``dropped``).
    """
    z = _check_teeth(z1)
    hs = _check_harmonics(harmonics)
    m = _check_int("band_bins", band_bins, 0)
    revs = _check_int("revs_per_window", revs_per_window)
    top = max(hs) * z + (m + 1) / revs
    p = _check_samples_per_rev(samples_per_rev, top)
    q = _check_quantity(quantity)
    camp, acc, maxo = _order_windows(
        x, sample_rate_Hz, speed, start_time_s=start_time_s, valid=valid,
        revs_per_window=revs, hop_revs=hop_revs, samples_per_rev=p, window=window,
        quantity=q, highpass_Hz=highpass_Hz, highpass_order=highpass_order,
        max_order=top, min_speed_rpm=min_speed_rpm)
    w = _window(window, revs * p)
    enbw = float(revs * p * np.sum(w**2) / np.sum(w) ** 2)
    orders = [h * z for h in hs]
    amp = _block_harmonics(acc, revs, orders, m, enbw, maxo)
    if q == "displacement":
        amp = _to_displacement(amp, np.asarray(orders, float), camp.speed_rpm, highpass_Hz,
                               highpass_order)
    return RunUpCurve(
        time_s=camp.time_s, speed_rpm=camp.speed_rpm,
        mesh_frequency_Hz=camp.speed_rpm * z / 60.0, harmonics=hs, amplitude=amp,
        arms=np.sqrt(np.sum(amp**2, axis=1)), z1=z, revs_per_window=revs,
        hop_revs=max(1, revs // 2) if hop_revs is None else int(hop_revs), samples_per_rev=p,
        quantity=q, spectra=camp, dropped=dict(camp.dropped))


def _count_stretches(mask: np.ndarray) -> int:
    return len(_runs(mask))


def step_levels(
    x: np.ndarray,
    sample_rate_Hz: float,
    speed: SpeedProfile | None,
    z1: int,
    *,
    steps: Sequence[SpeedStep] | None = None,
    start_time_s: float = 0.0,
    valid: np.ndarray | None = None,
    harmonics: int | Sequence[int] = 3,
    revs_per_block: int = 8,
    samples_per_rev: int | None = None,
    window: str = "hann",
    band_bins: int = 1,
    quantity: Quantity = "acceleration",
    highpass_Hz: float = 10.0,
    highpass_order: int = 4,
    min_speed_rpm: float = 1.0,
    rel_tolerance: float = 0.01,
    abs_tolerance_rpm: float = 2.0,
    min_duration_s: float = 1.0,
) -> StepLevels:
    """Mesh-harmonic amplitudes and Arms, one per speed step of a stepped run-up.

    The steps are the speed's plateaus (:func:`~rigtools.analysis.speed.detect_speed_steps`
    with ``rel_tolerance``, ``abs_tolerance_rpm`` and ``min_duration_s``) unless given. Within
    a step, each gap-free piece is cut into blocks of ``revs_per_block`` whole revolutions;
    all blocks of the step are power-averaged into one order spectrum.

    Parameters
    ----------
    x, sample_rate_Hz, speed, z1, start_time_s, valid, harmonics, samples_per_rev, window,
    band_bins, quantity, highpass_Hz, highpass_order, min_speed_rpm
        As for :func:`run_up_curve`.
    steps : sequence of SpeedStep, optional
        The steps; default detected from ``speed``.
    revs_per_block : int
        Revolutions per block (order resolution ``1 / revs_per_block``).
    rel_tolerance, abs_tolerance_rpm, min_duration_s
        Step detection (see :func:`~rigtools.analysis.speed.detect_speed_steps`).

    Returns
    -------
    StepLevels
    """
    speed = _check_speed(speed)
    z = _check_teeth(z1)
    hs = _check_harmonics(harmonics)
    m = _check_int("band_bins", band_bins, 0)
    revs = _check_int("revs_per_block", revs_per_block)
    p = _check_samples_per_rev(samples_per_rev, max(hs) * z + (m + 1) / revs)
    q = _check_quantity(quantity)
    if steps is None:
        steps = detect_speed_steps(speed, rel_tolerance=rel_tolerance,
                                   abs_tolerance_rpm=abs_tolerance_rpm,
                                   min_duration_s=min_duration_s)
    steps = tuple(steps)
    xs = _as_1d("x", x)
    fs = _check_fs(sample_rate_Hz)
    ok = _check_valid(valid, xs.size) & np.isfinite(xs)
    sig = resample_to_angle(xs, fs, speed, samples_per_rev=p, start_time_s=start_time_s,
                            valid=ok, min_speed_rpm=min_speed_rpm)
    t_in = float(start_time_s) + np.arange(xs.size) / fs
    known = np.isfinite(speed.rpm_at(t_in))
    w = _window(window, revs * p)
    enbw = float(revs * p * np.sum(w**2) / np.sum(w) ** 2)
    ns = len(steps)
    amp = np.full((ns, len(hs)), np.nan)
    rpm = np.full(ns, np.nan)
    n_blocks = np.zeros(ns, dtype=np.int64)
    n_pieces = np.zeros(ns, dtype=np.int64)
    n_gaps = np.zeros(ns, dtype=np.int64)
    spectra: list[OrderSpectrum | None] = []
    dropped: Counter[str] = Counter()
    for i, st in enumerate(steps):
        inside = (t_in >= st.start_s) & (t_in <= st.stop_s)
        n_gaps[i] = _count_stretches(inside & ~(ok & known))
        sel_all = np.flatnonzero((sig.time_s >= st.start_s) & (sig.time_s <= st.stop_s))
        blocks: list[_Block] = []
        for r in np.unique(sig.run[sel_all]):
            piece = sel_all[sig.run[sel_all] == r]
            b = _aligned_blocks(sig, piece, revs)
            if b:
                n_pieces[i] += 1
                blocks.extend(b)
            else:
                dropped["piece_shorter_than_block"] += 1
        if not blocks:
            dropped["step_without_block"] += 1
            spectra.append(None)
            continue
        a, r_b, _, mo = _block_spectra(sig, blocks, w, revs)
        orders = [h * z for h in hs]
        hb = _block_harmonics(a, revs, orders, m, enbw, mo)
        if q == "displacement":
            # each harmonic converted at its own frequency in each block, then averaged
            hb = _to_displacement(hb, np.asarray(orders, float), r_b, highpass_Hz,
                                  highpass_order)
            a = _to_displacement(a, np.arange(a.shape[1]) / revs, r_b, highpass_Hz,
                                 highpass_order)
        spec = OrderSpectrum(
            order=np.arange(a.shape[1]) / revs, amplitude=np.sqrt(np.mean(a**2, axis=0)),
            revolutions=revs, n_blocks=len(blocks),
            speed_rpm=float(len(blocks) / np.sum(1.0 / r_b)),  # total revs over total time
            enbw_bins=enbw, max_valid_order=float(mo.min()), window=window, quantity=q)
        spectra.append(spec)
        n_blocks[i] = len(blocks)
        rpm[i] = spec.speed_rpm
        amp[i] = np.sqrt(np.mean(hb**2, axis=0))
    return StepLevels(
        steps=steps, speed_rpm=rpm, mesh_frequency_Hz=rpm * z / 60.0, harmonics=hs,
        amplitude=amp, arms=np.sqrt(np.sum(amp**2, axis=1)), n_blocks=n_blocks,
        n_pieces=n_pieces, n_gaps=n_gaps, z1=z, revs_per_block=revs, samples_per_rev=p,
        quantity=q, spectra=tuple(spectra), dropped={k: v for k, v in dropped.items() if v})


# --- plain (time-frequency) waterfall ---------------------------------------------------------
def frequency_campbell(
    x: np.ndarray,
    sample_rate_Hz: float,
    speed: SpeedProfile | None = None,
    *,
    start_time_s: float = 0.0,
    valid: np.ndarray | None = None,
    nperseg: int = 4096,
    noverlap: int | None = None,
    window: str = "hann",
) -> Campbell:
    """Amplitude spectra of fixed-length time frames along a run (frequency-axis waterfall).

    No order tracking: an order whose frequency moves during a frame smears over many bins.
    Frames containing an invalid sample are dropped and counted (``dropped["gap"]``).

    Parameters
    ----------
    x : array_like
        Signal, uniformly sampled.
    sample_rate_Hz : float
        Sample rate (Hz).
    speed : SpeedProfile, optional
        When given, each row carries its frame's mean speed (rpm); otherwise NaN.
    start_time_s : float
        Time of ``x[0]`` (s).
    valid : array_like of bool, optional
        Per-sample validity.
    nperseg : int
        Frame length (samples).
    noverlap : int, optional
        Overlap (samples); default half a frame.
    window : str
        Window name; amplitudes are coherent-gain corrected (a sine of amplitude ``A`` on a
        bin reads ``A``).

    Returns
    -------
    Campbell
        ``axis_name == "frequency_Hz"``.
    """
    xs = _as_1d("x", x)
    fs = _check_fs(sample_rate_Hz)
    nps = _check_int("nperseg", nperseg, 2)
    if nps > xs.size:
        raise ValueError(f"`nperseg` must be <= len(x)={xs.size}, was {nps}")
    nov = nps // 2 if noverlap is None else _check_int("noverlap", noverlap, 0)
    if nov >= nps:
        raise ValueError(f"`noverlap` must be < nperseg={nps}, was {nov}")
    ok = _check_valid(valid, xs.size) & np.isfinite(xs)
    step = nps - nov
    starts = np.arange(0, xs.size - nps + 1, step)
    bad = np.r_[0, np.cumsum(~ok)]
    good = (bad[starts + nps] - bad[starts]) == 0
    dropped = {"gap": int(np.count_nonzero(~good))} if not np.all(good) else {}
    starts = starts[good]
    w = _window(window, nps)
    freq = np.fft.rfftfreq(nps, 1.0 / fs)
    if starts.size:
        frames = np.stack([xs[s:s + nps] for s in starts])
        amp = _block_amplitudes(frames, w)
    else:
        amp = np.empty((0, freq.size))
    t_c = float(start_time_s) + (starts + nps / 2) / fs
    if speed is not None:
        sp = _check_speed(speed)
        t_all = float(start_time_s) + np.arange(xs.size) / fs
        rpm_all = sp.rpm_at(t_all)
        rpm = np.array([np.mean(rpm_all[s:s + nps]) for s in starts])
    else:
        rpm = np.full(starts.size, np.nan)
    return Campbell(t_c, rpm, freq, "frequency_Hz", amp, "acceleration", dropped)


# --- from a Recording -------------------------------------------------------------------------
def _recording_inputs(recording: Recording, channel: str, speed: SpeedProfile | str | None,
                      pulses_per_rev: int | None, quantity: str
                      ) -> tuple[np.ndarray, float, float, np.ndarray, SpeedProfile]:
    if channel not in recording.channels:
        raise ValueError(f"`channel` must name a channel of the recording "
                         f"({', '.join(sorted(recording.channels))}), was {channel!r}")
    c = recording.channels[channel]
    if quantity == "displacement" and c.unit.strip() not in _ACCEL_UNITS:
        raise ValueError(f"displacement needs an acceleration channel (m/s^2); {channel!r} is "
                         f"in {c.unit!r}")
    sp = speed if isinstance(speed, SpeedProfile) else speed_profile(
        recording, speed, pulses_per_rev=pulses_per_rev)
    t0 = float(c.time_s[0]) if len(c) else c.start_time_s
    return c.values, c.sample_rate_Hz, t0, c.valid, sp


def run_up_curve_from_recording(
    recording: Recording,
    channel: str,
    speed: SpeedProfile | str | None,
    z1: int,
    *,
    pulses_per_rev: int | None = None,
    **kwargs: Any,
) -> RunUpCurve:
    """:func:`run_up_curve` of a Recording's channel.

    Parameters
    ----------
    recording : Recording
    channel : str
        Accelerometer channel.
    speed : SpeedProfile or str
        A profile, or the name of the slow signal or tacho channel holding the speed of the
        shaft with ``z1`` teeth (``None`` or an unknown name raises :class:`MissingSpeedError`).
    z1 : int
        Teeth on that shaft.
    pulses_per_rev : int, optional
        For a tacho channel.
    **kwargs
        Passed to :func:`run_up_curve`.
    """
    x, fs, t0, valid, sp = _recording_inputs(recording, channel, speed, pulses_per_rev,
                                             kwargs.get("quantity", "acceleration"))
    return run_up_curve(x, fs, sp, z1, start_time_s=t0, valid=valid, **kwargs)


def step_levels_from_recording(
    recording: Recording,
    channel: str,
    speed: SpeedProfile | str | None,
    z1: int,
    *,
    pulses_per_rev: int | None = None,
    **kwargs: Any,
) -> StepLevels:
    """:func:`step_levels` of a Recording's channel.

    Arguments as for :func:`run_up_curve_from_recording`; ``**kwargs`` go to
    :func:`step_levels`.
    """
    x, fs, t0, valid, sp = _recording_inputs(recording, channel, speed, pulses_per_rev,
                                             kwargs.get("quantity", "acceleration"))
    return step_levels(x, fs, sp, z1, start_time_s=t0, valid=valid, **kwargs)

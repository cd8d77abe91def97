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
   little residual smearing. The broadband response under the band (noise, the skirt of a
   resonance) adds its power to the harmonic's, the two being incoherent. The **local
   floor** is read from the order bins beside the band (up to ``FLOOR_HALF_WIDTH_ORDERS`` = 2
   orders each side; the bins within the band's half-width of an integer order, where shaft
   harmonics and sidebands lie, and the other harmonics left out): a parabola fitted to their
   log power, read across the band's bins (a resonance's skirt is curved) and corrected for
   the mean of the log of a chi-square power, gives :math:`\hat F_k^2`, and

   .. math::

       A = \sqrt{\Big(\sum_{|k - k_0| \le m} \hat A_k^2
           - \sum_{|k - k_0| \le m} \hat F_k^2\Big) \,/\, B_{en}},

   floored at 0 (:func:`~rigtools.analysis.order_spectra.harmonic_amplitudes`,
   :func:`~rigtools.analysis.order_spectra.block_floors`). Without it a harmonic under a
   resonance's skirt reads high (6-18 % in issue 17). The floor itself is returned
   (``floor``), for the harmonic's level above it (the low-SNR flag).
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
from typing import Any

import numpy as np

from models.geometry import check_teeth, mesh_frequency_Hz
from rigtools.analysis.campbell import frequency_campbell, order_campbell
from rigtools.analysis.order_spectra import (
    FLOOR_HALF_WIDTH_ORDERS,
    Block,
    Campbell,
    OrderSpectrum,
    acceleration_to_displacement,
    aligned_blocks,
    block_floors,
    block_harmonics,
    block_spectra,
    blocks_to_displacement,
    check_samples_per_rev,
    harmonic_amplitudes,
    order_spectrum,
    order_window,
    order_windows,
    subtract_floor,
)
from rigtools.analysis.resample import RESAMPLER_PASSBAND, AngleSignal, resample_to_angle
from rigtools.analysis.signal_checks import (
    Quantity,
    as_1d,
    check_harmonics,
    check_int,
    check_quantity,
    check_sample_rate,
    check_speed,
    check_valid_1d,
)
from rigtools.analysis.speed import SpeedProfile, SpeedStep, detect_speed_steps, speed_profile
from rigtools.analysis.windows import true_runs
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

_ACCEL_UNITS = frozenset({"m/s^2", "m/s2", "m/s²", "m s-2", "m*s^-2", "m.s-2"})


# --- results ----------------------------------------------------------------------------------
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
        ``(w, len(harmonics))`` amplitudes (m/s^2 or m), the local floor subtracted in power
        (module notes, 3); NaN above the passband.
    arms : numpy.ndarray
        ``sqrt(sum_h A_h^2)`` per window (seed 003's Arms).
    floor : numpy.ndarray
        ``(w, len(harmonics))``: the local floor in each harmonic's readout band, as an
        amplitude (same unit); NaN where it could not be read.
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
    floor: np.ndarray
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
        ``(s, len(harmonics))`` amplitudes (m/s^2 or m), the local floor subtracted in power
        (module notes, 3; band and floor power-averaged over the blocks first); NaN where no
        block was usable or above the passband.
    arms : numpy.ndarray
        ``sqrt(sum_h A_h^2)`` per step.
    floor : numpy.ndarray
        ``(s, len(harmonics))``: the local floor in each harmonic's readout band, as an
        amplitude (same unit, power-averaged over the blocks); NaN where it could not be read.
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
    floor: np.ndarray
    n_blocks: np.ndarray
    n_pieces: np.ndarray
    n_gaps: np.ndarray
    z1: int
    revs_per_block: int
    samples_per_rev: int
    quantity: str
    spectra: tuple[OrderSpectrum | None, ...]
    dropped: Mapping[str, int] = field(default_factory=dict)


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
    floor: bool = True,
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
    floor : bool
        Subtract the local floor under each harmonic, in power (default; module notes, 3).
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
    z = check_teeth(z1)
    hs = check_harmonics(harmonics)
    m = check_int("band_bins", band_bins, 0)
    revs = check_int("revs_per_window", revs_per_window)
    top = max(hs) * z + (m + 1) / revs
    p = check_samples_per_rev(samples_per_rev, top)
    q = check_quantity(quantity)
    # the spectra reach past the top harmonic by the floor's bins (NaN beyond the passband)
    camp, acc, maxo = order_windows(
        x, sample_rate_Hz, speed, start_time_s=start_time_s, valid=valid,
        revs_per_window=revs, hop_revs=hop_revs, samples_per_rev=p, window=window,
        quantity=q, highpass_Hz=highpass_Hz, highpass_order=highpass_order,
        max_order=top + (FLOOR_HALF_WIDTH_ORDERS if floor else 0.0),
        min_speed_rpm=min_speed_rpm)
    w = order_window(window, revs * p)
    enbw = float(revs * p * np.sum(w**2) / np.sum(w) ** 2)
    orders = [h * z for h in hs]
    amp = block_harmonics(acc, revs, orders, m, enbw, maxo)
    fl = block_floors(acc, revs, orders, m, enbw, maxo)
    if q == "displacement":
        amp, fl = (blocks_to_displacement(v, np.asarray(orders, float), camp.speed_rpm,
                                          highpass_Hz, highpass_order) for v in (amp, fl))
    if floor:
        amp = subtract_floor(amp, fl)
    return RunUpCurve(
        time_s=camp.time_s, speed_rpm=camp.speed_rpm,
        mesh_frequency_Hz=mesh_frequency_Hz(camp.speed_rpm, z), harmonics=hs, amplitude=amp,
        arms=np.sqrt(np.sum(amp**2, axis=1)), floor=fl, z1=z, revs_per_window=revs,
        hop_revs=max(1, revs // 2) if hop_revs is None else int(hop_revs), samples_per_rev=p,
        quantity=q, spectra=camp, dropped=dict(camp.dropped))


def _count_stretches(mask: np.ndarray) -> int:
    return len(true_runs(mask))


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
    floor: bool = True,
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
    band_bins, floor, quantity, highpass_Hz, highpass_order, min_speed_rpm
        As for :func:`run_up_curve`; the band and the floor are power-averaged over the
        step's blocks before the floor is subtracted.
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
    speed = check_speed(speed)
    z = check_teeth(z1)
    hs = check_harmonics(harmonics)
    m = check_int("band_bins", band_bins, 0)
    revs = check_int("revs_per_block", revs_per_block)
    p = check_samples_per_rev(samples_per_rev, max(hs) * z + (m + 1) / revs)
    q = check_quantity(quantity)
    if steps is None:
        steps = detect_speed_steps(speed, rel_tolerance=rel_tolerance,
                                   abs_tolerance_rpm=abs_tolerance_rpm,
                                   min_duration_s=min_duration_s)
    steps = tuple(steps)
    xs = as_1d("x", x)
    fs = check_sample_rate(sample_rate_Hz)
    ok = check_valid_1d(valid, xs.size) & np.isfinite(xs)
    sig = resample_to_angle(xs, fs, speed, samples_per_rev=p, start_time_s=start_time_s,
                            valid=ok, min_speed_rpm=min_speed_rpm)
    t_in = float(start_time_s) + np.arange(xs.size) / fs
    known = np.isfinite(speed.rpm_at(t_in))
    w = order_window(window, revs * p)
    enbw = float(revs * p * np.sum(w**2) / np.sum(w) ** 2)
    ns = len(steps)
    amp = np.full((ns, len(hs)), np.nan)
    fl = np.full((ns, len(hs)), np.nan)
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
        blocks: list[Block] = []
        for r in np.unique(sig.run[sel_all]):
            piece = sel_all[sig.run[sel_all] == r]
            b = aligned_blocks(sig, piece, revs)
            if b:
                n_pieces[i] += 1
                blocks.extend(b)
            else:
                dropped["piece_shorter_than_block"] += 1
        if not blocks:
            dropped["step_without_block"] += 1
            spectra.append(None)
            continue
        a, r_b, _, mo = block_spectra(sig, blocks, w, revs)
        orders = [h * z for h in hs]
        hb = block_harmonics(a, revs, orders, m, enbw, mo)
        # the floor from the step's power-averaged spectrum (a steadier fit than per block)
        fb = block_floors(np.sqrt(np.mean(a**2, axis=0))[None, :], revs, orders, m, enbw,
                          float(mo.min()), n_averaged=len(blocks))
        if q == "displacement":
            # each harmonic converted at its own frequency in each block, then averaged
            hb = blocks_to_displacement(hb, np.asarray(orders, float), r_b, highpass_Hz,
                                        highpass_order)
            fb = blocks_to_displacement(fb, np.asarray(orders, float),
                                        np.array([len(blocks) / np.sum(1.0 / r_b)]),
                                        highpass_Hz, highpass_order)
            a = blocks_to_displacement(a, np.arange(a.shape[1]) / revs, r_b, highpass_Hz,
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
        fl[i] = fb[0]
    if floor:
        amp = subtract_floor(amp, fl)
    return StepLevels(
        steps=steps, speed_rpm=rpm, mesh_frequency_Hz=mesh_frequency_Hz(rpm, z), harmonics=hs,
        amplitude=amp, arms=np.sqrt(np.sum(amp**2, axis=1)), floor=fl, n_blocks=n_blocks,
        n_pieces=n_pieces, n_gaps=n_gaps, z1=z, revs_per_block=revs, samples_per_rev=p,
        quantity=q, spectra=tuple(spectra), dropped={k: v for k, v in dropped.items() if v})


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

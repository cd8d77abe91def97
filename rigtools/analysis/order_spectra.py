"""Order spectra on the angle grid, mesh harmonic amplitudes and the shared block machinery.

See :mod:`rigtools.analysis.orders` for the method and references. The block machinery
(:class:`Block`, :func:`aligned_blocks`, :func:`block_spectra`, :func:`block_harmonics`,
:func:`order_windows`) is shared with :mod:`rigtools.analysis.orders`
and :mod:`rigtools.analysis.campbell`.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy import signal as sps
from scipy.special import digamma

from rigtools.analysis.resample import RESAMPLER_PASSBAND, AngleSignal, resample_to_angle
from rigtools.analysis.signal_checks import as_1d, check_int, check_positive
from rigtools.analysis.speed_types import SpeedProfile

__all__ = [
    "FLOOR_HALF_WIDTH_ORDERS",
    "MIN_FLOOR_BINS",
    "QUADRATIC_FLOOR_BINS",
    "Block",
    "Campbell",
    "OrderSpectrum",
    "acceleration_to_displacement",
    "aligned_blocks",
    "block_amplitudes",
    "block_floors",
    "block_harmonics",
    "block_spectra",
    "blocks_to_displacement",
    "check_samples_per_rev",
    "floor_bins",
    "harmonic_amplitudes",
    "order_spectrum",
    "order_window",
    "order_windows",
    "subtract_floor",
]


#: The local floor under a harmonic is read from the order bins up to this many orders each
#: side of its readout band.
FLOOR_HALF_WIDTH_ORDERS = 2.0
#: Fewer floor bins than half this on either side of a harmonic: no floor is subtracted (NaN
#: floor). From that many on the floor's log is fitted by a straight line across the band,
#: from half ``QUADRATIC_FLOOR_BINS`` on each side by a parabola (the curved skirt of a
#: resonance).
MIN_FLOOR_BINS = 4
QUADRATIC_FLOOR_BINS = 8


# --- results ----------------------------------------------------------------------
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


def _auto_samples_per_rev(max_order: float) -> int:
    """Smallest power of two (>= 16) of samples per revolution keeping ``max_order`` in band."""
    need = max_order / RESAMPLER_PASSBAND
    return int(2 ** max(4, int(np.ceil(np.log2(need)))))


def check_samples_per_rev(samples_per_rev: int | None, max_order: float) -> int:
    """Angular samples per revolution: ``samples_per_rev``, checked, or the automatic choice.

    ValueError when ``max_order`` lies above the resampler's passband at that sampling.
    """
    if samples_per_rev is None:
        return _auto_samples_per_rev(max_order)
    p = check_int("samples_per_rev", samples_per_rev, 4)
    if max_order > RESAMPLER_PASSBAND * p:
        raise ValueError(
            f"`samples_per_rev` must be >= {int(np.ceil(max_order / RESAMPLER_PASSBAND))} to "
            f"resolve order {max_order:g} inside the resampler's passband "
            f"({RESAMPLER_PASSBAND} x samples_per_rev), was {p}")
    return p


def order_window(window: str, n: int) -> np.ndarray:
    """The periodic ``scipy.signal`` window ``window`` of ``n`` samples (ValueError if unknown)."""
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
    fc = check_positive("highpass_Hz", highpass_Hz)
    n = check_int("highpass_order", highpass_order, 2)
    a = np.asarray(amplitude)
    f = np.abs(np.asarray(frequency_Hz, dtype=np.float64))
    r = f / fc
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        # (f/fc)^N / sqrt(1 + (f/fc)^2N) / (2 pi f)^2, written to stay finite at both ends
        gain = np.where(r > 1.0, 1.0 / np.sqrt(1.0 + r ** (-2 * n)),
                        r**n / np.sqrt(1.0 + r ** (2 * n)))
        h = np.where(f > 0, gain / (2.0 * np.pi * np.where(f > 0, f, 1.0)) ** 2, 0.0)
    return -a * h


# --- order spectra ----------------------------------------------------------------------------
def block_amplitudes(blocks: np.ndarray, w: np.ndarray) -> np.ndarray:
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
    x = as_1d("x_angle", x_angle)
    p = check_int("samples_per_rev", samples_per_rev, 2)
    if x.size == 0 or x.size % p:
        raise ValueError(f"`x_angle` must hold whole revolutions of {p} samples, has {x.size}")
    r = x.size // p if revolutions is None else check_int("revolutions", revolutions)
    nb = r * p
    if x.size % nb:
        raise ValueError(f"len(`x_angle`)={x.size} must be a multiple of revolutions x "
                         f"samples_per_rev = {nb}")
    if not np.all(np.isfinite(x)):
        raise ValueError("`x_angle` must be finite (gaps are split before the spectrum)")
    w = order_window(window, nb)
    amp = np.sqrt(np.mean(block_amplitudes(x.reshape(-1, nb), w) ** 2, axis=0))
    return OrderSpectrum(
        order=np.arange(amp.size) / r, amplitude=amp, revolutions=r, n_blocks=x.size // nb,
        speed_rpm=float(speed_rpm), enbw_bins=float(nb * np.sum(w**2) / np.sum(w) ** 2),
        max_valid_order=RESAMPLER_PASSBAND * p, window=window)


def floor_bins(k0: int, band: int, revs: int, n_bins: int,
               others: Sequence[int] = ()) -> np.ndarray:
    """Order bins the local floor under a harmonic at bin ``k0`` is read from.

    Bins from ``max(band + 2, revs / 2)`` (half an order: clear of the harmonic's own
    leakage when the speed is not quite right) to ``band + 1 + W`` away from ``k0`` on both
    sides, ``W = FLOOR_HALF_WIDTH_ORDERS x revs``, inside ``(0, n_bins)``, leaving out every
    bin within ``band`` of an integer order (shaft harmonics, mesh harmonics and their
    sidebands are lines at integer orders) and within ``band + 1`` of the bins in ``others``
    (other harmonics read).
    """
    w = max(round(FLOOR_HALF_WIDTH_ORDERS * revs), 2)
    guard = max(band + 2, -(-revs // 2))
    j = np.arange(k0 - band - 1 - w, k0 + band + 2 + w)
    keep = (np.abs(j - k0) >= guard) & (j > 0) & (j < n_bins)
    r = np.mod(j, revs)
    keep &= np.minimum(r, revs - r) > band
    for k in others:
        keep &= np.abs(j - int(k)) > band + 1
    return j[keep]


def harmonic_amplitudes(
    spectrum: OrderSpectrum,
    orders: Sequence[float] | np.ndarray,
    *,
    band_bins: int = 1,
    floor: bool = True,
) -> np.ndarray:
    r"""Amplitudes of given orders, read over ``+-band_bins`` bins (energy sum), floor removed.

    .. math::

        A = \sqrt{\Big(\sum_{|k-k_0| \le m} \hat A_k^2
            - (2m+1)\,\overline{\hat A_j^2}\Big) / B_{en}}

    with the window's equivalent noise bandwidth ``B_en`` (bins): a pure order on its bin
    reads its amplitude exactly when ``band_bins`` covers its main lobe (1 for Hann, 0 for a
    rectangular window). The broadband response under the band (the skirt of a resonance,
    noise) adds its power to the harmonic's, the two being incoherent: the local floor
    under the band, :math:`(2m+1)\,\overline{\hat A_j^2}` (:func:`block_floors`, read from
    the order bins beside the band), is subtracted in power; a band at or below the floor
    reads 0. Without floor bins on both sides (:func:`block_floors`) nothing is subtracted.

    Parameters
    ----------
    spectrum : OrderSpectrum
        The spectrum.
    orders : sequence of float
        Orders to read (cycles per revolution).
    band_bins : int
        Half-width of the band (bins).
    floor : bool
        Subtract the local floor (default); False reads the band's power as it is.

    Returns
    -------
    numpy.ndarray
        Amplitudes; NaN for orders above ``spectrum.max_valid_order`` or beyond the spectrum.
    """
    m = check_int("band_bins", band_bins, 0)
    o = np.atleast_1d(np.asarray(orders, dtype=np.float64))
    k0 = np.rint(o * spectrum.revolutions).astype(np.int64)
    amp = spectrum.amplitude[None, :]
    mo = np.array([spectrum.max_valid_order])
    ks = [float(k) / spectrum.revolutions for k in k0]  # the bins read, as orders
    readout = block_harmonics(amp, spectrum.revolutions, ks, m, spectrum.enbw_bins, mo)[0]
    if not floor:
        return readout
    fl = block_floors(amp, spectrum.revolutions, ks, m, spectrum.enbw_bins, mo,
                      n_averaged=spectrum.n_blocks)[0]
    return subtract_floor(readout, fl)


# --- blocks and windows on the angle grid -----------------------------------------------------
@dataclass(frozen=True)
class Block:
    """A block of whole revolutions: ``[start, stop)`` indices into an AngleSignal's arrays."""

    start: int
    stop: int


def block_spectra(sig: AngleSignal, blocks: Sequence[Block], w: np.ndarray, revs: int
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per block: amplitude spectra, mean speed (rpm), centre time (s), top valid order."""
    data = np.stack([sig.values[b.start:b.stop] for b in blocks])
    amp = block_amplitudes(data, w)
    t0 = np.array([sig.time_s[b.start] for b in blocks])
    # block duration: from its first sample to one angular step past its last
    t1 = np.array([sig.time_s[b.stop - 1] + 60.0 / (sig.speed_rpm[b.stop - 1]
                                                     * sig.samples_per_rev) for b in blocks])
    rpm = 60.0 * revs / (t1 - t0)
    top = np.array([sig.speed_rpm[b.start:b.stop].max() for b in blocks]) / 60.0
    max_order = RESAMPLER_PASSBAND * np.minimum(sig.samples_per_rev, sig.input_rate_Hz / top)
    return amp, rpm, 0.5 * (t0 + t1), max_order


def blocks_to_displacement(amp: np.ndarray, orders: np.ndarray, rpm: np.ndarray,
                           highpass_Hz: float, highpass_order: int) -> np.ndarray:
    """Amplitudes ``(b, k)`` at ``orders`` ``(k,)`` of blocks at speeds ``rpm`` ``(b,)``."""
    f = np.asarray(orders)[None, :] * rpm[:, None] / 60.0
    return np.abs(acceleration_to_displacement(amp, f, highpass_Hz=highpass_Hz,
                                               highpass_order=highpass_order))


def block_harmonics(amp: np.ndarray, revs: int, orders: Sequence[float], band: int,
                    enbw: float, max_order: np.ndarray) -> np.ndarray:
    """Band readouts ``(b, h)`` of ``orders`` from block amplitude spectra ``(b, k)``.

    The band's power as it is, the floor under it included (see :func:`block_floors`).
    """
    out = np.full((amp.shape[0], len(orders)), np.nan)
    a2 = amp**2
    for i, o in enumerate(orders):
        k = round(o * revs)
        if k - band < 0 or k + band >= amp.shape[1]:
            continue
        val = np.sqrt(a2[:, k - band:k + band + 1].sum(axis=1) / enbw)
        out[:, i] = np.where(o + band / revs <= max_order, val, np.nan)
    return out


def block_floors(amp: np.ndarray, revs: int, orders: Sequence[float], band: int,
                 enbw: float, max_order: np.ndarray | float, *, n_averaged: int = 1
                 ) -> np.ndarray:
    r"""The local floor in each harmonic's readout band, ``(b, h)``, as an amplitude.

    For each spectrum (row of ``amp``, a power average of ``n_averaged`` blocks) and harmonic,
    the log power of the bins of :func:`floor_bins` below the row's ``max_order`` is fitted
    by a polynomial in the bin offset from the harmonic (a parabola from
    ``QUADRATIC_FLOOR_BINS`` bins on, else a straight line: a resonance's skirt is curved),
    read across the band's ``2 band + 1`` bins (an interpolation: the floor is read on both
    sides of the harmonic), corrected for the mean of the log of a :math:`\chi^2_\nu/\nu`
    power (:math:`\psi(\nu/2) - \ln(\nu/2)`, :math:`\nu = 2\,n_\text{averaged}`: Hann
    blocks of whole revolutions, not overlapping) and divided by :math:`B_{en}`, as the
    readout is. NaN where :func:`block_harmonics` is NaN, or fewer than ``MIN_FLOOR_BINS / 2``
    floor bins lie on either side (at the top of the spectrum or of the valid band: no
    extrapolation). Subtracted in power from the readout (:func:`subtract_floor`).
    """
    out = np.full((amp.shape[0], len(orders)), np.nan)
    a2 = np.asarray(amp, np.float64) ** 2
    mo = np.broadcast_to(np.asarray(max_order, np.float64), (amp.shape[0],))
    half_nu = float(max(int(n_averaged), 1))  # nu / 2
    log_bias = float(digamma(half_nu) - np.log(half_nu))
    tiny = np.finfo(np.float64).tiny
    ks = [round(o * revs) for o in orders]
    offsets = np.arange(-band, band + 1, dtype=np.float64)
    for i, (o, k) in enumerate(zip(orders, ks, strict=True)):
        if k - band < 0 or k + band >= amp.shape[1]:
            continue
        bins = floor_bins(k, band, revs, amp.shape[1], [j for j in ks if j != k])
        for row in np.flatnonzero(o + band / revs <= mo):
            use = bins[bins / revs <= mo[row]]
            below = int(np.count_nonzero(use < k))
            if min(below, use.size - below) < MIN_FLOOR_BINS // 2:
                continue
            deg = 2 if min(below, use.size - below) >= QUADRATIC_FLOOR_BINS // 2 else 1
            coef = np.polyfit((use - k).astype(np.float64),
                              np.log(np.maximum(a2[row, use], tiny)), deg)
            power = np.exp(np.polyval(coef, offsets) - log_bias).sum() / enbw
            out[row, i] = np.sqrt(power)
    return out


def subtract_floor(readout: np.ndarray, floor: np.ndarray) -> np.ndarray:
    """Power subtraction, ``sqrt(max(readout^2 - floor^2, 0))``.

    Where the floor is NaN (too few floor bins) the readout is kept as it is; a NaN readout
    stays NaN.
    """
    readout = np.asarray(readout, np.float64)
    floor = np.asarray(floor, np.float64)
    power = readout**2 - np.where(np.isfinite(floor), floor**2, 0.0)
    power[power < 0] = 0.0
    return np.sqrt(power)


def aligned_blocks(sig: AngleSignal, sel: np.ndarray, revs: int) -> list[Block]:
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
        out.append(Block(int(s), int(s + nb)))
        s += nb
    return out


def _run_up_windows(sig: AngleSignal, revs: int, hop: int
                    ) -> tuple[list[Block], Counter[str]]:
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
            out.append(Block(s, s + n))
        else:
            # the break the window meets: the end of run r (or of the run before a)
            rr = max(r, 0)
            dropped[sig.run_end[rr] if sig.run_end[rr] != "end" else "gap"] += 1
        start_rev += hop
    return out, dropped


def order_windows(
    x: np.ndarray, sample_rate_Hz: float, speed: SpeedProfile | None, *, start_time_s: float,
    valid: np.ndarray | None, revs_per_window: int, hop_revs: int | None,
    samples_per_rev: int, window: str, quantity: str, highpass_Hz: float,
    highpass_order: int, max_order: float, min_speed_rpm: float,
) -> tuple[Campbell, np.ndarray, np.ndarray]:
    """Order spectra of the run-up windows.

    Returns the Campbell data (in ``quantity``), the spectra as given (acceleration) and each
    window's top valid order.
    """
    revs = check_int("revs_per_window", revs_per_window)
    hop = revs // 2 if hop_revs is None else check_int("hop_revs", hop_revs)
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
    w = order_window(window, revs * sig.samples_per_rev)
    amps, rpms, times, maxo = [], [], [], []
    chunk = max(1, (1 << 22) // (revs * sig.samples_per_rev))
    for i in range(0, len(blocks), chunk):
        a, r, t, m = block_spectra(sig, blocks[i:i + chunk], w, revs)
        amps.append(a[:, :ncols])
        rpms.append(r)
        times.append(t)
        maxo.append(m)
    acc = np.concatenate(amps)
    mo = np.concatenate(maxo)
    rpm = np.concatenate(rpms)
    amp = acc if quantity == "acceleration" else blocks_to_displacement(
        acc, orders, rpm, highpass_Hz, highpass_order)
    amp[orders[None, :] > mo[:, None]] = np.nan
    camp = Campbell(np.concatenate(times), rpm, orders, "order", amp, quantity, dict(dropped))
    return camp, acc, mo

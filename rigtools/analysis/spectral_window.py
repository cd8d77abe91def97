"""What a window does to a spectrum: :class:`WindowProperties` and :func:`window_properties`.

Equivalent noise bandwidth, scalloping loss, bin correlation and spectral window, cached per
window and length, and :func:`window_array`, which turns a window argument into samples.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import signal as sps

from rigtools.analysis.signal_checks import Window
from rigtools.errors import SignalError

__all__ = ["WindowProperties", "window_array", "window_properties"]

# --------------------------------------------------------------------------------------------
# window properties


@dataclass(frozen=True, eq=False)
class WindowProperties:
    r"""What a window does to a spectrum, in bins of ``fs / nperseg``.

    Attributes
    ----------
    nperseg : int
        Window length (samples).
    enbw_bins : float
        Equivalent noise bandwidth, :math:`N \sum w^2 / (\sum w)^2` (bins): 1.5 for Hann,
        3.77 for scipy's flattop.
    bandwidth_3dB_bins : float
        Full width of the spectral window :math:`|W(f)|^2` at half its peak (bins): the
        half-power bandwidth with which a pure tone appears (1.44 for Hann).
    scalloping_loss : float
        Worst-case amplitude reading of a sine halfway between two bins, as a fraction lost:
        :math:`1 - |W(1/2)| / |W(0)|` (0.151 for Hann, 0.0011 for flattop).
    amplitude_tolerance : float
        :math:`\max_{0 \le \delta \le 1/2} |1 - |W(\delta)| / |W(0)||`: the largest relative
        error of a sine's amplitude read at its nearest bin, wherever it falls (a flat top
        ripples slightly above 1 as well as below).
    mainlobe_half_width_bins : float
        Distance from the centre to the first null of :math:`|W|^2` (bins): 2 for Hann.
    bin_correlation : numpy.ndarray
        :math:`\rho_q^2`, q = 0, 1, ...: correlation of two PSD estimates q bins apart for a
        Gaussian signal, :math:`\rho_q = |\sum w_n^2 e^{-2\pi i q n/N}| / \sum w_n^2`
        (Hann: 1, 0.444, 0.028).
    kernel : numpy.ndarray
        The spectral window :math:`|W|^2` sampled at offsets ``kernel_offsets_bins``,
        normalised to sum 1: the expected Welch estimate is the true PSD convolved with it.
    kernel_offsets_bins : numpy.ndarray
        Offsets of ``kernel`` (bins), symmetric about 0 in steps of 1/8 bin.
    """

    nperseg: int
    enbw_bins: float
    bandwidth_3dB_bins: float
    scalloping_loss: float
    amplitude_tolerance: float
    mainlobe_half_width_bins: float
    bin_correlation: np.ndarray
    kernel: np.ndarray
    kernel_offsets_bins: np.ndarray
    _w: np.ndarray

    def overlap_correlation(self, noverlap: int) -> np.ndarray:
        r""":math:`\rho(mS)^2` for m = 1, 2, ... while windows S = nperseg - noverlap apart overlap.

        Percival and Walden (1993), Eq. (292b): correlation of two periodograms whose windows
        are shifted by m S samples.
        """
        w = self._w
        step = self.nperseg - noverlap
        out = []
        shift = step
        denom = float(np.dot(w, w))
        while shift < self.nperseg:
            out.append((float(np.dot(w[shift:], w[:-shift])) / denom) ** 2)
            shift += step
        return np.asarray(out)

    def averaged_bin_correlation(self, noverlap: int, n_windows: int, n_segments: int = 1
                                 ) -> np.ndarray:
        r"""Correlation of Welch-averaged PSD estimates q bins apart, q = 0, 1, ...

        :attr:`bin_correlation` is that of one window's periodogram; averaging overlapping
        windows adds the cross terms of windows shifted by :math:`mS` samples
        (S = nperseg - noverlap). For a locally white spectrum and a Gaussian signal
        (Percival and Walden 1993, Sec. 6.17 and Eq. 292b; Isserlis' theorem),

        .. math:: \rho_q^2 = \frac{K c_q(0) + 2 \sum_{m \ge 1} K_m c_q(mS)}
                  {K c_0(0) + 2 \sum_{m \ge 1} K_m c_0(mS)}, \qquad
                  c_q(s) = \frac{|\sum_n w_n w_{n+s} e^{-2\pi i q n/N}|^2}{(\sum_n w_n^2)^2},

        with :math:`K_m = \max(K - m\,n_\text{seg}, 0)` pairs of windows m steps apart when
        the K windows lie in ``n_segments`` runs. For Hann at 50 % overlap and many windows:
        1, 0.459, 0.039, 0.0015 (one window alone: 1, 0.444, 0.028, 0).

        Parameters
        ----------
        noverlap : int
            Overlap of neighbouring windows (samples).
        n_windows : int
            Windows averaged, K.
        n_segments : int
            Valid segments the windows lie in (no pair straddles a gap).

        Returns
        -------
        numpy.ndarray
            :math:`\rho_q^2` for q = 0, 1, ... until it falls below 1e-4 (at least q = 0, 1).
        """
        w = self._w
        n = self.nperseg
        step = n - int(noverlap)
        K = max(int(n_windows), 1)
        nseg = max(int(n_segments), 1)
        s2 = float(np.dot(w, w))
        idx = np.arange(n)
        shifts = [(0, float(K))]
        m = 1
        while step > 0 and m * step < n:
            pairs = max(K - m * nseg, 0)
            if pairs:
                shifts.append((m * step, 2.0 * pairs))
            m += 1
        out = []
        for q in range(n // 2):
            tot = 0.0
            for s, weight in shifts:
                prod = w[s:] * w[: n - s]
                c = abs(np.sum(prod * np.exp(-2j * np.pi * q * idx[: n - s] / n))) ** 2 / s2**2
                tot += weight * c
            out.append(tot)
            if q >= 1 and tot / out[0] < 1e-4:
                out.pop()
                break
        rho2 = np.asarray(out) / out[0]
        return rho2 if rho2.size >= 2 else np.r_[rho2, 0.0]

    def welch_covariance(self, psd_of_bin: Callable[[np.ndarray], np.ndarray],
                         bins: np.ndarray, noverlap: int, n_windows: int,
                         n_segments: int = 1) -> np.ndarray:
        r"""Relative covariance of Welch estimates at ``bins`` of a process with a given PSD.

        The DFT of one window at bin j, :math:`X_j = \sum_n w_n x_n e^{-2\pi i j n/N}`, of a
        stationary Gaussian process with PSD S has
        :math:`\mathrm{Cov}(X_j, X_k^{(s)}) = \int S(\nu) W(\nu - j) W^*(\nu - k)
        e^{-2\pi i \nu s/N} d\nu` for a window shifted by s samples (:math:`\nu` in bins,
        :math:`W(\nu) = \sum_n w_n e^{-2\pi i \nu n/N}`), and by Isserlis' theorem
        :math:`\mathrm{Cov}(|X_j|^2, |X_k^{(s)}|^2) = |\mathrm{Cov}(X_j, X_k^{(s)})|^2`.
        Averaged over K windows S = nperseg - noverlap apart,

        .. math:: \frac{\mathrm{Cov}(\hat S_j, \hat S_k)}{E\hat S_j\, E\hat S_k} =
                  \frac{K |C_{jk}(0)|^2 + \sum_{m \ge 1} K_m (|C_{jk}(mS)|^2 + |C_{kj}(mS)|^2)}
                  {K^2\, C_{jj}(0)\, C_{kk}(0)},

        :math:`K_m = \max(K - m\,n_\text{seg}, 0)`. For a white spectrum the diagonal is
        :math:`2/\nu` (Percival and Walden 1993, Eq. 292b) and the correlation
        :meth:`averaged_bin_correlation`; where the spectrum changes within the window's main
        lobe (a mode a few bins wide) neighbouring bins are correlated more, or less, than
        that. The integral is a sum over a grid of 1/8 bin, over the spectral window's extent
        (:attr:`kernel_offsets_bins`) beyond the outer bins; negative frequencies are left out
        (bins away from 0 Hz).

        Parameters
        ----------
        psd_of_bin : callable
            The PSD (any scale, >= 0) at frequencies given in bins (``f / (fs / nperseg)``).
        bins : numpy.ndarray of int
            Bins whose estimates are wanted, increasing.
        noverlap, n_windows, n_segments : int
            As for :meth:`averaged_bin_correlation`.

        Returns
        -------
        numpy.ndarray
            Shape ``(len(bins), len(bins))``: covariance of the estimates over the product of
            their expected values (about the covariance of their logs).
        """
        w = self._w
        n = self.nperseg
        ov = _KERNEL_OVERSAMPLING
        bins = np.asarray(bins, np.int64)
        ext = int(np.ceil(float(np.max(np.abs(self.kernel_offsets_bins)))))
        lo = int(bins[0])
        nf = int(bins[-1]) - lo + 1  # the contiguous run of bins holding ``bins``
        grid = np.arange((lo - ext) * ov, (lo + nf - 1 + ext) * ov + 1)  # in 1/ov bins
        S = np.maximum(np.asarray(psd_of_bin(grid / ov), np.float64), 0.0)
        W = np.fft.fft(w, n * ov)
        o = np.arange(-ext * ov, ext * ov + 1)  # offsets from a bin within the extent
        rows = np.arange(nf)
        step = n - int(noverlap)
        K = max(int(n_windows), 1)
        nseg = max(int(n_segments), 1)
        shifts = [(0, float(K))]
        m = 1
        while step > 0 and m * step < n:
            if K - m * nseg > 0:
                shifts.append((m * step, float(K - m * nseg)))
            m += 1
        tot = np.zeros((nf, nf))
        e = np.zeros(nf)
        for q in range(min(2 * ext, nf - 1) + 1):
            oq = o[o - q * ov >= -ext * ov]
            prod = W[oq % (n * ov)] * np.conj(W[(oq - q * ov) % (n * ov)])
            gi = (rows[: nf - q, None] + ext) * ov + oq[None, :]  # grid index of row j
            Sg = S[gi]
            for shift, weight in shifts:
                if shift == 0:
                    c = np.abs(np.sum(Sg * prod, axis=1)) ** 2
                    if q == 0:
                        e = np.sqrt(c)
                    val = weight * c
                else:
                    # pairs in both orders: |C_jk(s)|^2 + |C_kj(s)|^2 = |C_jk(s)|^2 + |C_jk(-s)|^2
                    ph = np.exp(-2j * np.pi * grid[gi] * shift / (n * ov))
                    val = weight * (np.abs(np.sum(Sg * ph * prod, axis=1)) ** 2
                                    + np.abs(np.sum(Sg * ph.conj() * prod, axis=1)) ** 2)
                tot[rows[: nf - q], rows[: nf - q] + q] += val
        tot = np.triu(tot) + np.triu(tot, 1).T
        sel = bins - lo
        tot = tot[np.ix_(sel, sel)]
        e = e[sel]
        return np.asarray(tot / (K * K * np.outer(e, e)), np.float64)


_WINDOW_CACHE: dict[tuple[Any, int], WindowProperties] = {}
_KERNEL_OVERSAMPLING = 8


def window_array(window: Window, nperseg: int) -> np.ndarray:
    """The samples of ``window`` (a name, tuple or the samples themselves) of ``nperseg``."""
    if isinstance(window, np.ndarray):
        w = np.asarray(window, np.float64)
        if w.shape != (nperseg,):
            raise SignalError("window", f"of shape (nperseg,)=({nperseg},)", str(w.shape))
        return w
    try:
        return np.asarray(sps.get_window(window, nperseg), np.float64)
    except (ValueError, TypeError) as e:
        raise SignalError("window", "a window scipy.signal.get_window knows", repr(window),
                          str(e)) from e


def window_properties(window: Window, nperseg: int) -> WindowProperties:
    """Equivalent noise bandwidth, scalloping loss and spectral window of a window.

    Parameters
    ----------
    window : str, tuple or numpy.ndarray
        As for :func:`scipy.signal.get_window` (periodic form), or the samples themselves.
    nperseg : int
        Window length (samples).

    Returns
    -------
    WindowProperties

    References
    ----------
    .. [1] F. J. Harris, "On the use of windows for harmonic analysis with the discrete
           Fourier transform", Proc. IEEE 66(1), 51-83, 1978 (ENBW, scalloping loss).
    .. [2] D. B. Percival and A. T. Walden, *Spectral Analysis for Physical Applications*,
           Cambridge University Press, 1993, Sec. 6.17 (correlation of spectral estimates).

    Examples
    --------
    >>> p = window_properties("hann", 4096)
    >>> round(p.enbw_bins, 3), round(p.scalloping_loss, 3)
    (1.5, 0.151)
    """
    key = (("array", window.tobytes()) if isinstance(window, np.ndarray) else repr(window),
           int(nperseg))
    props = _WINDOW_CACHE.get(key)
    if props is not None:
        return props
    w = window_array(window, nperseg)
    n = nperseg
    s1, s2 = float(w.sum()), float(np.dot(w, w))
    if s1 == 0.0 or s2 == 0.0:
        raise SignalError("window", "non-zero", "all zeros")
    enbw = n * s2 / s1**2
    idx = np.arange(n)
    offsets_half = np.linspace(0.0, 0.5, 33)[:, None]  # sine between bins: 0 .. 1/2 bin off
    gain = np.abs(np.exp(-2j * np.pi * offsets_half * idx[None, :] / n) @ w) / abs(s1)
    half = float(gain[-1])
    amp_tol = float(np.max(np.abs(1.0 - gain)))
    ov = _KERNEL_OVERSAMPLING
    spec = np.abs(np.fft.fft(w, n * ov)) ** 2
    spec /= spec.sum()
    rel = spec / spec[0]
    # 3 dB width and first null on the fine grid (positive side)
    k = int(np.argmax(rel[: n * ov // 2] < 0.5))
    x0, x1 = (k - 1) / ov, k / ov
    y0, y1 = rel[k - 1], rel[k]
    bw3 = 2 * (x0 + (y0 - 0.5) / (y0 - y1) * (x1 - x0)) if k > 0 else 1.0 / ov
    d = np.diff(rel[: n * ov // 2])
    mins = np.flatnonzero((d[:-1] < 0) & (d[1:] >= 0))
    null = (mins[0] + 1) / ov if mins.size else n / 2
    # spectral window kernel: keep offsets until 1e-4 of the energy is left out, at most 16 bins
    centred = np.fft.fftshift(spec)
    c = n * ov // 2
    L = ov
    while L < 16 * ov and 1.0 - centred[c - L: c + L + 1].sum() > 1e-4:
        L += ov
    kern = centred[c - L: c + L + 1].copy()
    kern /= kern.sum()
    offsets = np.arange(-L, L + 1) / ov
    # correlation of PSD estimates q bins apart
    w2 = w * w
    rho = [1.0]
    q = 1
    while q < n // 2:
        r = abs(np.sum(w2 * np.exp(-2j * np.pi * q * idx / n))) / s2
        if r**2 < 1e-4:
            break
        rho.append(float(r**2))
        q += 1
    props = WindowProperties(
        nperseg=int(n), enbw_bins=float(enbw), bandwidth_3dB_bins=float(bw3),
        scalloping_loss=float(1.0 - half), amplitude_tolerance=amp_tol,
        mainlobe_half_width_bins=float(null),
        bin_correlation=np.asarray(rho), kernel=kern, kernel_offsets_bins=offsets, _w=w)
    if len(_WINDOW_CACHE) > 64:
        _WINDOW_CACHE.clear()
    _WINDOW_CACHE[key] = props
    return props

r"""Mesh and shaft lines: where a frequency sits among them, and their bins masked in a PSD.

A peak within tolerance of :math:`k f_\text{mesh}`,
:math:`k f_\text{mesh} \pm j f_\text{shaft}` (:math:`1 \le k \le` ``max_harmonic``, default
:data:`MAX_MESH_ORDER`) or :math:`k f_\text{shaft}` is a mesh harmonic, a mesh sideband or a
shaft harmonic, in that order of precedence (:func:`classify_frequency`,
:class:`LocationClass`). The masks of the lines' main lobes in a PSD
(:func:`mask_main_lobe`, :func:`line_bins`, :func:`mask_standing_lines`) keep lines out of
the fits of modes in :func:`~rigtools.analysis.peaks.analyse_peaks`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.stats import chi2

from rigtools.analysis.sdof_fit import PSDContext

__all__ = [
    "LINE_STAND_OUT_FALSE_ALARM",
    "MAX_MESH_ORDER",
    "LocationClass",
    "classify_frequency",
    "line_bins",
    "mask_main_lobe",
    "mask_standing_lines",
]

#: Highest mesh harmonic order taken as a mesh line (the harmonics a rig's spectrum shows as
#: lines); a peak at a higher harmonic is classified like any other peak.
MAX_MESH_ORDER = 5
#: A mesh or shaft line of any order is masked out of a joint fit where its bin stands above
#: its surroundings by more than noise does with this probability (peaks docstring, 5a).
LINE_STAND_OUT_FALSE_ALARM = 1e-3


@dataclass(frozen=True)
class LocationClass:
    """Where a frequency sits relative to the mesh and shaft frequencies.

    Attributes
    ----------
    kind : str or None
        ``"mesh_harmonic"``, ``"mesh_sideband"``, ``"shaft_harmonic"``, or None.
    harmonic : int or None
        k, the mesh (or shaft) harmonic order.
    sideband : int or None
        j, signed sideband order (``-1`` is the lower first sideband).
    shaft_Hz : float or None
        The shaft frequency of the sideband or shaft harmonic (Hz).
    expected_Hz : float or None
        The frequency matched (Hz).
    """

    kind: str | None = None
    harmonic: int | None = None
    sideband: int | None = None
    shaft_Hz: float | None = None
    expected_Hz: float | None = None


def classify_frequency(f_Hz: float, *, mesh_frequency_Hz: float | None,
                       shaft_frequencies_Hz: Sequence[float] = (), tolerance_Hz: float = 0.0,
                       rtol: float = 0.002, max_sideband: int = 3,
                       max_shaft_harmonic: int = 10,
                       max_harmonic: int = MAX_MESH_ORDER) -> LocationClass:
    r"""Match a frequency to mesh harmonics, their sidebands and shaft harmonics.

    Parameters
    ----------
    f_Hz : float
        Frequency (Hz).
    mesh_frequency_Hz : float or None
        Mesh frequency :math:`f_m = z_1 n_1 / 60` (Hz).
    shaft_frequencies_Hz : sequence of float
        Shaft rotation frequencies (Hz), e.g. pinion and wheel.
    tolerance_Hz, rtol : float
        Matching tolerance at f: ``tolerance_Hz + rtol * f`` (Hz).
    max_sideband : int
        Largest sideband order j.
    max_shaft_harmonic : int
        Largest shaft harmonic order.
    max_harmonic : int
        Largest mesh harmonic order k taken as a mesh line (and whose sidebands are);
        default :data:`MAX_MESH_ORDER`.

    Returns
    -------
    LocationClass
        The first match in the order mesh harmonic (1 <= k <= max_harmonic), mesh sideband
        (:math:`k f_m \pm j f_s`, 1 <= k <= max_harmonic, 1 <= j <= max_sideband), shaft
        harmonic (:math:`k f_s`, 1 <= k <= max_shaft_harmonic); the nearest within a class.

    Examples
    --------
    >>> classify_frequency(1225.0, mesh_frequency_Hz=400.0, shaft_frequencies_Hz=[25.0],
    ...                    tolerance_Hz=2.0).sideband
    1
    """
    f = float(f_Hz)
    tol = float(tolerance_Hz) + float(rtol) * abs(f)
    shafts = [float(s) for s in shaft_frequencies_Hz if s is not None and s > 0]
    if mesh_frequency_Hz is not None and mesh_frequency_Hz > 0:
        fm = float(mesh_frequency_Hz)
        k = round(f / fm)
        if 1 <= k <= max_harmonic and abs(f - k * fm) <= tol:
            return LocationClass("mesh_harmonic", k, None, None, k * fm)
        best: tuple[float, LocationClass] | None = None
        for fs_ in shafts:
            for j in range(1, max_sideband + 1):
                for sign in (-1, 1):
                    kk = round((f - sign * j * fs_) / fm)
                    if not 1 <= kk <= max_harmonic:
                        continue
                    expected = kk * fm + sign * j * fs_
                    d = abs(f - expected)
                    if d <= tol and (best is None or d < best[0]):
                        best = (d, LocationClass("mesh_sideband", kk, sign * j, fs_, expected))
        if best is not None:
            return best[1]
    best = None
    for fs_ in shafts:
        k = round(f / fs_)
        if 1 <= k <= max_shaft_harmonic:
            d = abs(f - k * fs_)
            if d <= tol and (best is None or d < best[0]):
                best = (d, LocationClass("shaft_harmonic", k, None, fs_, k * fs_))
    return best[1] if best is not None else LocationClass()


def mask_main_lobe(ctx: PSDContext, k: int, mask: np.ndarray) -> None:
    """Mask the main lobe of a line at bin k and one bin more each side (not further)."""
    base = int(np.ceil(ctx.props.mainlobe_half_width_bins)) + 1
    mask[max(k - base, 0): min(k + base, mask.size - 1) + 1] = True


def line_bins(ctx: PSDContext, mesh_frequency_Hz: float | None, shafts: Sequence[float],
               max_sideband: int, max_shaft_harmonic: int) -> np.ndarray:
    """Bins of every mesh harmonic below Nyquist with its sidebands, and the shaft harmonics."""
    f_top = float(ctx.f[-1])
    out: list[float] = []
    if mesh_frequency_Hz is not None and mesh_frequency_Hz > 0:
        h = np.arange(1, int(f_top // mesh_frequency_Hz) + 1) * float(mesh_frequency_Hz)
        out += list(h)
        for fs_ in shafts:
            for j in range(1, max_sideband + 1):
                out += list(h - j * fs_) + list(h + j * fs_)
    for fs_ in shafts:
        out += [k * fs_ for k in range(1, max_shaft_harmonic + 1)]
    k = np.round(np.asarray(out, np.float64) / ctx.df).astype(np.int64)
    return np.unique(k[(k > 0) & (k < ctx.f.size - 1)])


def mask_standing_lines(ctx: PSDContext, line_bins: np.ndarray, a: int, b: int,
                         mask: np.ndarray) -> np.ndarray:
    r"""``mask`` with the main lobes of the mesh and shaft lines that stand out in ``[a, b]``.

    A line of any order stands out when the PSD at its bin (or a neighbour) exceeds the median
    of the bins 3 to 16 away (other lines' bins left out) by the one-sided
    ``LINE_STAND_OUT_FALSE_ALARM`` quantile of the Welch estimate (:math:`\chi^2_\nu/\nu`):
    the joint fit of two modes would otherwise take a cluster of weak lines with their
    sidebands for a second mode. A mode's smooth top does not stand out so; the lines are
    masked only there, for the joint fit.
    """
    out = mask.copy()
    nu = max(ctx.dof, 1.0)
    lim = float(np.log(chi2.isf(LINE_STAND_OUT_FALSE_ALARM, nu) / nu)
                - np.log(chi2.median(nu) / nu))
    near_line = np.zeros(ctx.f.size, bool)  # the ring about a line leaves the other lines out
    for k in line_bins:
        near_line[max(int(k) - 2, 0): int(k) + 3] = True
    for k in line_bins[(line_bins >= a) & (line_bins <= b)]:
        k = int(k)
        ring = np.r_[np.arange(k - 16, k - 2), np.arange(k + 3, k + 17)]
        ring = ring[(ring > 0) & (ring < ctx.f.size)]
        ring = ring[~near_line[ring]]
        if ring.size < 4:
            continue
        top = k - 1 + int(np.argmax(ctx.lnP[k - 1: k + 2]))
        if ctx.lnP[top] - float(np.median(ctx.lnP[ring])) > lim:
            mask_main_lobe(ctx, top, out)
    return out

r"""Results of the peak analysis of a PSD: peaks, their modal estimates and their kinds.

:class:`ModalEstimate` (natural frequency and damping of one peak, two ways, and whether the
peak is *broad*, a mode, or *narrow*, a line), :class:`Peak` and :class:`PeakAnalysis`, the
frozen results of :func:`~rigtools.analysis.peaks.analyse_peaks`, with the thresholds their
properties apply; the kind of a peak from its width and location (:func:`peak_kind`), and
whether a mode of a joint fit of two is resolved (:func:`joint_mode_resolved`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from rigtools.analysis.mesh_lines import MAX_MESH_ORDER, LocationClass
from rigtools.analysis.sdof_fit import LINE_FIT_FACTOR, HalfPower, SDOFFit
from rigtools.analysis.spectra import log_chi2_stats
from rigtools.analysis.two_mode_fit import TwoModeFit

__all__ = [
    "CENTRE_SIGMA",
    "FALSE_ALARM",
    "LINE_KINDS",
    "LOW_DOF",
    "MIN_RESOLVED_BINS",
    "MIN_RESOLVED_MAINLOBES",
    "ZETA_MARGIN_SIGMA",
    "ModalEstimate",
    "Peak",
    "PeakAnalysis",
    "PeakKind",
    "joint_mode_resolved",
    "peak_kind",
]

PeakKind = Literal["structural", "mesh_harmonic", "mesh_sideband", "shaft_harmonic", "tonal",
                   "unresolved"]
#: Default false-alarm probability per spectrum of the detection threshold (a noise bin
#: anywhere in the searched band exceeding it).
FALSE_ALARM = 0.01
#: A structural peak's fitted damping must exceed the resolution equivalent by this many of
#: its standard uncertainties.
ZETA_MARGIN_SIGMA = 2.0
#: ... and its half-power band (2 zeta f_n) must span at least this many bins,
MIN_RESOLVED_BINS = 4.0
#: ... and this many of the window's whole main lobes (a line a little smeared, or a line with
#: its sidebands, is about one main lobe wide).
MIN_RESOLVED_MAINLOBES = 2.0
#: Below this many equivalent degrees of freedom a modal estimate is flagged ``low_dof``.
LOW_DOF = 35.0
#: A mode's PSD maximum lies where its top stands within this many standard deviations of
#: the log estimate of the top (:attr:`ModalEstimate.centre_tolerance_Hz`).
CENTRE_SIGMA = 3.0
#: Kinds of a peak no wider than the window's main lobe.
LINE_KINDS = ("mesh_harmonic", "mesh_sideband", "shaft_harmonic", "tonal")


@dataclass(frozen=True)
class ModalEstimate:
    r"""Natural frequency and damping of one PSD peak, two ways, with uncertainties.

    Attributes
    ----------
    f_n_Hz, f_n_std_Hz : float
        Natural frequency from the SDOF fit (Hz) and its standard uncertainty.
    zeta, zeta_std : float
        Damping ratio from the SDOF fit and its standard uncertainty.
    zeta_half_power, zeta_half_power_std : float
        Damping ratio by the half-power bandwidth and its standard uncertainty.
    f_peak_Hz, f_peak_std_Hz : float
        Interpolated peak frequency (Hz, Gaussian interpolation) and its standard uncertainty.
    psd_peak_per_Hz : float
        Interpolated PSD at the peak (unit^2/Hz).
    zeta_resolution : float
        :math:`B_\text{3dB}/(2 f_\text{peak})`: the damping a pure tone appears to have.
    fit : SDOFFit
    half_power : HalfPower
    response : str
        SDOF response fitted: ``"displacement"``, ``"velocity"`` or ``"acceleration"``.
    dof : float
        Equivalent degrees of freedom of the PSD (``low_dof`` below ``LOW_DOF``).
    resolution_Hz : float
        Bin spacing of the PSD (Hz).
    mainlobe_half_width_Hz : float
        Half-width of the window's main lobe (Hz; 2 bins for Hann): how wide a line is.
    joint : TwoModeFit or None
        For a mode fitted jointly with a close neighbour (``"joint_fit"`` in the fit's flags,
        peaks docstring 5a): the joint fit, with the covariance of both modes' f_n and zeta;
        ``f_peak_Hz`` is then the fitted f_n (the merged peak has one maximum for two modes)
        and the half-power damping is not measured. Else None.
    """

    f_n_Hz: float
    f_n_std_Hz: float
    zeta: float
    zeta_std: float
    zeta_half_power: float
    zeta_half_power_std: float
    f_peak_Hz: float
    f_peak_std_Hz: float
    psd_peak_per_Hz: float
    zeta_resolution: float
    fit: SDOFFit
    half_power: HalfPower
    response: str = "displacement"

    #: Equivalent degrees of freedom of the PSD the estimate comes from.
    dof: float = float("nan")
    #: Bin spacing of the PSD (Hz).
    resolution_Hz: float = float("nan")
    #: Half-width of the window's main lobe (Hz).
    mainlobe_half_width_Hz: float = float("nan")
    #: The joint fit this mode comes from, if any.
    joint: TwoModeFit | None = None

    @property
    def broad(self) -> bool:
        r"""A mode's peak: wider than a line beyond doubt, and centred where the peak is.

        All of:

        * the fit succeeded and its damping exceeds the resolution equivalent (the half-power
          width of the window's main lobe) beyond doubt,
          :math:`\zeta - 2\sigma_\zeta > \zeta_\text{res}` (``ZETA_MARGIN_SIGMA``);
        * the half-power band :math:`2\zeta f_n` spans at least ``MIN_RESOLVED_MAINLOBES``
          whole main lobes (:math:`2 \times` ``mainlobe_half_width_Hz`` each; 8 bins for
          Hann) and ``MIN_RESOLVED_BINS`` bins: a peak hardly wider than a line may be a line
          a little smeared by the speed, or a line with its sidebands;
        * the peak lies where a mode's noisy maximum can, near :math:`f_n`
          (:attr:`centre_tolerance_Hz`: within half to one half-power half-width, by the
          scatter of the estimate): a line on the skirt of a mode, or a horn of a line swept
          by a varying speed, is not the mode its fit describes.

        A noise spike fitted with a damping just above the resolution limit is not broad. A
        line *on* a mode's maximum is told apart by
        :func:`~rigtools.analysis.peaks.analyse_peaks` (its module docstring, 6).
        """
        f = self.fit
        z, sz = self.zeta, self.zeta_std
        if not (f.success and not f.at_lower_bound and np.isfinite(z) and np.isfinite(sz)):
            return False
        if not (z - ZETA_MARGIN_SIGMA * sz > self.zeta_resolution
                and self.resolved_bins >= MIN_RESOLVED_BINS):
            return False
        if np.isfinite(self.mainlobe_half_width_Hz) and not (
                z * self.f_n_Hz >= MIN_RESOLVED_MAINLOBES * self.mainlobe_half_width_Hz):
            return False
        return bool(abs(self.f_peak_Hz - self.f_n_Hz) <= self.centre_tolerance_Hz)

    @property
    def centre_tolerance_Hz(self) -> float:  # noqa: N802 (unit in the name)
        r"""How far from :math:`f_n` the maximum of a mode's PSD may lie (Hz).

        The maximum of a noisy flat top falls anywhere the top stands within
        ``CENTRE_SIGMA`` standard deviations of the log estimate,
        :math:`s = \sqrt{\psi'(\nu/2)}`, of its top: :math:`|f - f_n| \le x\,\zeta f_n`,
        :math:`1/(1 + x^2) = e^{-3s}`, x kept within 0.5 to 1 half-power half-widths; plus
        two standard uncertainties of the interpolated maximum.
        """
        if not (np.isfinite(self.zeta) and np.isfinite(self.dof)):
            return float("nan")
        s = float(np.sqrt(log_chi2_stats(max(self.dof, 1.0))[1]))
        x = float(np.clip(np.sqrt(np.expm1(CENTRE_SIGMA * s)), 0.5, 1.0))
        return x * self.zeta * self.f_n_Hz + 2 * max(self.f_peak_std_Hz, 0.0)

    @property
    def narrow(self) -> bool:
        r"""No wider than a line: the peak's width is the window's main lobe.

        The half-power damping measured on the PSD is at most ``LINE_FIT_FACTOR`` times the
        resolution equivalent :math:`\zeta_\text{res}`, or the fitted damping is at its lower
        bound or at most :math:`\zeta_\text{res}`. Never together with :attr:`broad`.
        """
        if self.broad:
            return False
        zhp, z = self.zeta_half_power, self.fit.zeta
        if np.isfinite(zhp) and zhp <= LINE_FIT_FACTOR * self.zeta_resolution:
            return True
        return bool(np.isfinite(z) and (self.fit.at_lower_bound or z <= self.zeta_resolution))

    @property
    def resolved_bins(self) -> float:
        r"""Bins across the fitted half-power band, :math:`2\zeta f_n / \Delta f`."""
        if not (np.isfinite(self.zeta) and self.resolution_Hz > 0):
            return 0.0
        return float(2 * self.zeta * self.f_n_Hz / self.resolution_Hz)

    @property
    def low_dof(self) -> bool:
        """The PSD has few averages (dof < ``LOW_DOF``): damping less reliable."""
        return bool(self.dof < LOW_DOF)


@dataclass(frozen=True)
class Peak:
    r"""One PSD peak, its location class and (unless it is a mesh or shaft line) its mode.

    Attributes
    ----------
    index : int
        Bin of the maximum.
    f_Hz, f_std_Hz : float
        Interpolated frequency (Hz) and standard uncertainty.
    psd_per_Hz : float
        Interpolated PSD at the peak (unit^2/Hz).
    prominence_dB : float
        Prominence on the log PSD (dB); of a structural peak, the larger of that and its
        prominence on the PSD smoothed with the lines masked (a line taller than the mode's
        top on its skirt cuts the raw prominence).
    kind : str
        ``"structural"``, ``"mesh_harmonic"``, ``"mesh_sideband"``, ``"shaft_harmonic"``,
        ``"tonal"`` or ``"unresolved"``.
    location : LocationClass
        Where the peak sits relative to the mesh and shaft lines (for a structural peak, the
        line its frequency falls within tolerance of, if any: that alone says nothing).
    mode : ModalEstimate or None
        Damping estimates of the peak as measured (for a line, those of the line; None for a
        line on a mode, whose mode is its own structural peak). A structural peak found beside
        a line (its maximum hidden by the line) has ``f_Hz = f_n``, ``index`` the bin nearest
        it, and the prominence of its maximum on the PSD smoothed with the line masked.
    on_mode : int or None
        For a line (or an unresolved peak): the index, in :attr:`PeakAnalysis.structural`, of
        the structural peak whose half-power band :math:`f_n \pm \zeta f_n` holds it (masked
        out of that peak's fit); else None.
    """

    index: int
    f_Hz: float
    f_std_Hz: float
    psd_per_Hz: float
    prominence_dB: float
    kind: str
    location: LocationClass
    mode: ModalEstimate | None
    on_mode: int | None = None

    @property
    def possible_resonance(self) -> bool:
        """A line that sits on a structural mode (reported as its own structural peak)."""
        return bool(self.kind != "structural" and self.on_mode is not None)


@dataclass(frozen=True)
class PeakAnalysis:
    """The peaks of one PSD.

    Attributes
    ----------
    peaks : tuple of Peak
        In order of frequency.
    mesh_frequency_Hz : float or None
    shaft_frequencies_Hz : tuple of float
    tolerance_Hz : float
        Absolute part of the matching tolerance (Hz); the tolerance at f is
        ``tolerance_Hz + rtol * f``.
    rtol : float
    threshold_dB : float
        Prominence threshold used (dB).
    detection_threshold_dB : float
        Least height of a peak above the local background (running median, dB): the
        chi-square quantile of the Welch estimate with the equivalent dof, Sidak-corrected
        for the bins searched so that pure noise gives a peak with probability
        ``false_alarm`` per spectrum. A peak below it is still kept when its prominence
        exceeds the spread between the upper and lower such quantiles (a broad feature that
        lifts the running median).
    false_alarm : float
    max_mesh_order : int
        Highest mesh harmonic taken as a mesh line
        (:data:`~rigtools.analysis.mesh_lines.MAX_MESH_ORDER` by default).
    """

    peaks: tuple[Peak, ...]
    mesh_frequency_Hz: float | None
    shaft_frequencies_Hz: tuple[float, ...]
    tolerance_Hz: float
    rtol: float
    threshold_dB: float
    detection_threshold_dB: float = 0.0
    false_alarm: float = FALSE_ALARM
    max_mesh_order: int = MAX_MESH_ORDER

    @property
    def structural(self) -> tuple[Peak, ...]:
        """Peaks classified as structural resonances."""
        return tuple(p for p in self.peaks if p.kind == "structural")

    @property
    def modes(self) -> tuple[ModalEstimate, ...]:
        """Modal estimates of the structural peaks."""
        return tuple(p.mode for p in self.structural if p.mode is not None)

    def of_kind(self, kind: str) -> tuple[Peak, ...]:
        """Peaks of one kind."""
        return tuple(p for p in self.peaks if p.kind == kind)

    def lines_on(self, index: int) -> tuple[Peak, ...]:
        """Lines within the half-power band of structural peak ``index``, masked out of its fit.

        ``index`` is the peak's place in :attr:`structural`.
        """
        return tuple(p for p in self.peaks if p.on_mode == index)


def peak_kind(mode: ModalEstimate, loc: LocationClass) -> str:
    """Kind of a peak from its width (:attr:`ModalEstimate.broad`, ``.narrow``) and location."""
    if mode.broad:
        return "structural"
    if loc.kind is not None:
        return loc.kind
    return "tonal" if mode.narrow else "unresolved"


def joint_mode_resolved(mode: ModalEstimate, loc: LocationClass) -> bool:
    r"""A mode of a joint fit is a mode: its damping beyond the resolution limit.

    The fit succeeded, :math:`\zeta - 2\sigma_\zeta > \zeta_\text{res}`
    (``ZETA_MARGIN_SIGMA``) and the half-power band spans ``MIN_RESOLVED_BINS`` bins; at a
    mesh or shaft line (``loc``), also :attr:`ModalEstimate.broad` (a line smeared by the
    speed beside a mode would otherwise pass for a narrow second mode). Away from the lines
    the width of two main lobes is not asked: the test of the joint fit already says the
    second mode is there.
    """
    if loc.kind is not None:
        return mode.broad
    f, z, sz = mode.fit, mode.zeta, mode.zeta_std
    if not (f.success and not f.at_lower_bound and np.isfinite(z) and np.isfinite(sz)):
        return False
    return bool(z - ZETA_MARGIN_SIGMA * sz > mode.zeta_resolution
                and mode.resolved_bins >= MIN_RESOLVED_BINS)

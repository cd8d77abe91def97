r"""Two close modes in one peak: the joint fit (issue 17 leftover, issue 19 item 8).

The signals come from :mod:`modal_signals` with one white force per mode
(``forces="independent"``: two uncorrelated sources, whose PSDs add, the model
:mod:`rigtools.analysis.two_mode_fit` fits; with one common force the modes interfere and the
joint model is not the spectrum, see :func:`test_one_force_for_both_modes_is_not_split_silently`),
by the continuous FRF per FFT bin (route a) and by matched-z filters (route b), for
displacement, velocity and acceleration responses, with white noise at 20 dB SNR (defined in
:mod:`modal_signals`). The analysis is :func:`rigtools.analysis.analyse_peaks` told the
response the signal has.

Where the numbers come from:

- separations 1.0, 1.5 and 2 half-power bandwidths :math:`2\zeta f_n` of the lower mode,
  amplitude ratios 1:1 to 3:1 (the ratio of the two modes' response amplitude peaks
  :math:`|H_j(f_j)|`; the taller either side), damping 0.01-0.03: the brief of this work
  (issue 19 item 8);
- coverage of the stated 1-sigma intervals: 68.3 % for a normal estimate; over 100 seeds and
  two modes (200 intervals) the binomial standard deviation is 3.3 %, so 60-76 % is about
  +-2.4 sd (the brief's band);
- false splits of a single mode: at most 2 % of 200 seeds (the brief); the joint fit is tried
  only where the single-DOF fit is flagged ``misfit`` (false alarm
  :data:`~rigtools.analysis.sdof_fit.MISFIT_FALSE_ALARM` = 1e-3) and kept only past its own
  test (false alarm :data:`~rigtools.analysis.two_mode_fit.JOINT_FALSE_ALARM` = 1e-3);
- the demo case: the demo campaign's housing mode at 4900 Hz and the mesh mode of run LS3-55C
  at 5219 Hz (``rigtools.demo``, ``truth.json``), here both at zeta 0.02 with the housing
  mode's PSD peak twice the mesh mode's; 3 s records as the demo's ``"ci"`` size.

The default run holds one case per separation, response and route, a 24-seed coverage check,
the demo case and a few single-mode seeds (about 30 s CPU); ``-m slow`` runs the 100-seed
coverage matrix and the 200-seed false-split count.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import modal_signals as ms
import numpy as np
import pytest
from modal_signals import ModalSignal, Mode

from rigtools.analysis import FIT_FLAGS, analyse_peaks, analyse_recording, welch_psd
from rigtools.analysis.peak_results import ModalEstimate, PeakAnalysis
from rigtools.demo.campaign import generate_demo_campaign
from rigtools.ingest import read

FS = ms.FS_HZ
F1 = 2843.0  # issue 17's mode
UNIT = {"displacement": "m", "velocity": "m/s", "acceleration": "m/s^2"}
ROUTES: dict[str, Callable[..., ModalSignal]] = {
    "frequency": ms.frequency_domain_signal, "time": ms.time_domain_signal}
RESPONSES = ("displacement", "velocity", "acceleration")
COVERAGE = (0.60, 0.76)  # the brief: ~68 % (module docstring)
#: One case within this many stated sd (a single seed: 3 sd holds with 99.7 %).
ONE_CASE_SD = 3.0


# --------------------------------------------------------------------------------------------
# helpers


def pair(separation_bw: float, amplitude_ratio: float, zeta1: float, zeta2: float,
         response: str, taller_above: bool) -> tuple[Mode, Mode]:
    """Two modes: the lower at F1, the upper ``separation_bw`` bandwidths 2 zeta1 F1 above.

    ``amplitude_ratio`` (>= 1) is the taller mode's response amplitude peak over the other's.
    """
    f2 = F1 + separation_bw * 2 * zeta1 * F1
    psd_ratio = amplitude_ratio**2 if taller_above else amplitude_ratio**-2
    return ms.pair_with_psd_ratio(F1, zeta1, f2, zeta2, psd_ratio, response)


def analyse(sig: ModalSignal, **kw: Any) -> PeakAnalysis:
    sp = welch_psd(sig.x, FS, unit=UNIT[sig.truth.response])
    return analyse_peaks(sp, response=sig.truth.response, **kw)


def matched(pa: PeakAnalysis, modes: Sequence[Mode]) -> list[ModalEstimate | None]:
    """For each true mode, the structural estimate nearest it within its half-power band."""
    out: list[ModalEstimate | None] = []
    for m in modes:
        best = None
        for est in pa.modes:
            d = abs(est.f_n_Hz - m.f_n_Hz)
            if d <= m.zeta * m.f_n_Hz and (best is None or d < abs(best.f_n_Hz - m.f_n_Hz)):
                best = est
        out.append(best)
    return out


def describe(pa: PeakAnalysis) -> str:
    return "; ".join(f"{m.f_n_Hz:.1f}+-{m.f_n_std_Hz:.1f} Hz zeta {m.zeta:.4f}+-"
                     f"{m.zeta_std:.4f} {m.fit.flags}" for m in pa.modes)


def split_errors(pa: PeakAnalysis, modes: Sequence[Mode]
                 ) -> tuple[np.ndarray, np.ndarray] | None:
    """Normalised errors (error / stated sd) of (f_n, zeta) of both modes, or None: not split."""
    est = matched(pa, modes)
    if len(pa.modes) != 2 or any(e is None or "joint_fit" not in e.fit.flags for e in est):
        return None
    zf = np.array([(e.f_n_Hz - m.f_n_Hz) / e.f_n_std_Hz for e, m in zip(est, modes,
                                                                         strict=True)])
    zz = np.array([(e.zeta - m.zeta) / e.zeta_std for e, m in zip(est, modes, strict=True)])
    return zf, zz


# --------------------------------------------------------------------------------------------
# the model and the flag


def test_joint_fit_flag_is_described():
    assert FIT_FLAGS["joint_fit"] == "fitted jointly with a mode within two half-power bandwidths"


def test_independent_forces_add_the_psds():
    """The generator's own check: two modes, one force each, PSD = sum of |H_j|^2 S_F."""
    modes = ms.close_pair(F1, 0.02, 1.0)
    f = np.array([F1, 0.5 * (F1 + modes[1].f_n_Hz), modes[1].f_n_Hz])
    sig = ms.frequency_domain_signal(modes, "velocity", snr_dB=None, duration_s=1.0,
                                     forces="independent", rng=1)
    want = sum(np.abs(ms.frf(f, [m], "velocity")) ** 2 for m in modes) * sig.truth.force_psd
    np.testing.assert_allclose(ms.expected_psd(f, sig.truth), want, rtol=1e-12)
    # the realised mean square is the stated one (within the scatter of 1 s of a 2 % mode)
    assert np.mean(sig.modal**2) == pytest.approx(1.0, rel=0.15)


# --------------------------------------------------------------------------------------------
# one case each (default run)

CASES = [  # separation (bandwidths), amplitude ratio, zeta1, zeta2, taller above
    (1.0, 1.0, 0.02, 0.02, False),
    (1.5, 2.0, 0.03, 0.02, True),
    (2.0, 3.0, 0.01, 0.015, False),
]


@pytest.mark.parametrize("route", ROUTES)
@pytest.mark.parametrize("response", RESPONSES)
@pytest.mark.parametrize("case", CASES, ids=lambda c: f"{c[0]:g}bw-{c[1]:g}to1")
def test_two_close_modes_are_both_recovered(case, response, route):
    sep, ratio, z1, z2, above = case
    modes = pair(sep, ratio, z1, z2, response, above)
    sig = ROUTES[route](modes, response, snr_dB=20.0, duration_s=10.0, forces="independent",
                        rng=100 + int(10 * sep))
    pa = analyse(sig)
    errs = split_errors(pa, modes)
    assert errs is not None, f"not split: {describe(pa)}"
    zf, zz = errs
    msg = f"{describe(pa)}: f_n errors {zf} sd, zeta errors {zz} sd"
    assert np.all(np.abs(zf) < ONE_CASE_SD), msg
    assert np.all(np.abs(zz) < ONE_CASE_SD), msg
    for est in matched(pa, modes):
        assert est is not None and "misfit" not in est.fit.flags, msg
        assert est.joint is not None and est.joint.accepted, msg
        cov = est.joint.covariance
        np.testing.assert_allclose(cov, cov.T, rtol=1e-9, atol=0)
        assert est.joint.delta_chi2 > est.joint.delta_threshold


def coverage_failures(cases: Sequence[tuple[Sequence[Mode], PeakAnalysis]], what: str,
                      band: tuple[float, float] = COVERAGE) -> list[str]:
    zfs, zzs, unsplit = [], [], 0
    for modes, pa in cases:
        errs = split_errors(pa, modes)
        if errs is None:
            unsplit += 1
            continue
        zfs.append(errs[0])
        zzs.append(errs[1])
    out = []
    n = 2 * len(cases)  # intervals asked for: a mode not split does not cover
    for name, z in (("f_n", zfs), ("zeta", zzs)):
        inside = float(np.count_nonzero(np.abs(np.ravel(z)) <= 1.0)) / n if z else 0.0
        if not band[0] <= inside <= band[1]:
            out.append(f"{what}: 1-sd intervals of {name} cover the truth in {inside:.0%} "
                       f"(need {band[0]:.0%}-{band[1]:.0%}; {unsplit} of {len(cases)} not "
                       "split)")
    return out


def test_coverage_of_the_stated_intervals_over_24_seeds():
    """A small version of the slow matrix: 1.5 bandwidths, 2:1, acceleration, route (a).

    48 intervals per quantity: binomial sd 6.7 %, so 50-85 % is the 68.3 % within +-2.6 sd.
    """
    modes = pair(1.5, 2.0, 0.02, 0.02, "acceleration", True)
    cases = []
    for seed in range(200, 224):
        sig = ms.frequency_domain_signal(modes, "acceleration", snr_dB=20.0, duration_s=5.0,
                                         forces="independent", rng=seed)
        cases.append((modes, analyse(sig)))
    problems = coverage_failures(cases, "1.5 bw, 2:1", band=(0.50, 0.85))
    assert not problems, "\n".join(problems)


COMBOS = [  # (amplitude ratio, zeta1, zeta2, taller above)
    (1.0, 0.02, 0.02, False), (2.0, 0.01, 0.015, True), (3.0, 0.03, 0.02, False),
    (3.0, 0.02, 0.03, True)]
#: Each separation with each response, the other settings rotating through COMBOS and the
#: route alternating: 9 of the 3 x 4 x 3 x 2 combinations, every setting in several.
SLOW_CASES = [(sep, response, *COMBOS[(i + j) % 4], ("frequency", "time")[(i + j) % 2])
              for i, sep in enumerate((1.0, 1.5, 2.0)) for j, response in enumerate(RESPONSES)]


@pytest.mark.slow
@pytest.mark.parametrize("case", SLOW_CASES, ids=lambda c: "-".join(str(v) for v in c))
def test_coverage_of_the_stated_intervals_over_100_seeds(case):
    """Over 100 seeds of 20 s records (the length of the single-mode validation).

    In 5 s records a 3:1 pair one bandwidth apart stays unsplit in most seeds: the
    information is not there.
    """
    sep, response, ratio, z1, z2, above, route = case
    modes = pair(sep, ratio, z1, z2, response, above)
    cases = []
    for seed in range(1000, 1100):
        sig = ROUTES[route](modes, response, snr_dB=20.0, duration_s=20.0,
                            forces="independent", rng=seed)
        cases.append((modes, analyse(sig)))
    problems = coverage_failures(cases, f"{case}")
    assert not problems, "\n".join(problems)


# --------------------------------------------------------------------------------------------
# one mode is not split


def splits(pa: PeakAnalysis) -> int:
    return sum("joint_fit" in m.fit.flags for m in pa.modes)


@pytest.mark.parametrize("response", RESPONSES)
def test_one_mode_is_not_split(response):
    """The existing validation signal (2843 Hz, zeta 0.03, 20 dB), a few seeds per response."""
    for seed in range(300, 304):
        sig = ms.frequency_domain_signal([Mode(F1, 0.03)], response, snr_dB=20.0, rng=seed)
        pa = analyse(sig)
        assert len(pa.modes) == 1 and not splits(pa), f"seed {seed}: {describe(pa)}"
        assert pa.modes[0].joint is None


@pytest.mark.slow
def test_one_mode_is_split_in_at_most_2_percent_of_200_seeds():
    n_split = 0
    for seed in range(2000, 2200):
        response = RESPONSES[seed % 3]
        route = "time" if seed % 2 else "frequency"
        sig = ROUTES[route]([Mode(F1, 0.03)], response, snr_dB=20.0, rng=seed)
        n_split += splits(analyse(sig)) > 0
    assert n_split <= 4, f"{n_split} of 200 single modes split in two"


def test_one_force_for_both_modes_is_not_split_silently():
    """Two modes under one force interfere (their PSD dips between them below the sum).

    The two-mode model does not fit that spectrum either: the modes are either split with
    estimates within their stated uncertainty, or the fit stays flagged.
    """
    modes = ms.close_pair(F1, 0.02, 1.5)
    sig = ms.frequency_domain_signal(modes, "acceleration", snr_dB=20.0, rng=41)
    pa = analyse(sig)
    for est in pa.modes:
        m = min(modes, key=lambda q: abs(q.f_n_Hz - est.f_n_Hz))
        if not est.fit.flags or est.fit.flags == ("joint_fit",):
            assert abs(est.f_n_Hz - m.f_n_Hz) < 3.5 * est.f_n_std_Hz, describe(pa)


# --------------------------------------------------------------------------------------------
# the demo case


@pytest.mark.parametrize("route", ROUTES)
def test_demo_housing_and_mesh_modes_are_two_peaks(route):
    """Housing 4900 Hz (zeta 0.02, PSD peak twice the mesh mode's), mesh 5219 Hz (zeta 0.02)."""
    housing, mesh = ms.pair_with_psd_ratio(4900.0, 0.02, 5219.0, 0.02, 0.5, "acceleration")
    for seed in (0, 1):
        sig = ROUTES[route]([housing, mesh], "acceleration", snr_dB=20.0, duration_s=3.0,
                            forces="independent", rng=seed)
        pa = analyse(sig, mesh_frequency_Hz=400.0)
        assert len(pa.modes) == 2, describe(pa)
        est = matched(pa, [housing, mesh])
        assert est[1] is not None, describe(pa)
        assert abs(est[1].f_n_Hz - 5219.0) < 3 * est[1].f_n_std_Hz, describe(pa)
        assert "misfit" not in est[1].fit.flags, describe(pa)


def test_demo_campaign_run_ls3_55c_shows_the_mesh_mode(tmp_path: Path):
    """The built-in demo campaign ("ci"), run LS3-55C: the mesh mode beside the housing mode.

    Its truth (``truth.json``): the mesh mode at 5218.8 Hz, 319 Hz above the housing mode.
    """
    generate_demo_campaign(tmp_path, size="ci", runup=False)
    truth = json.loads((tmp_path / "truth.json").read_text())["runs"]["LS3-55C"]
    f_mesh = float(truth["mesh_mode_Hz"])
    ra = analyse_recording(read(tmp_path / truth["file"]),
                           mesh_frequency_Hz=truth["mesh_frequency_Hz"])
    seen = []
    for name, ca in ra.channels.items():
        near = [m for m in ca.peaks.modes if abs(m.f_n_Hz - f_mesh) < 3 * m.f_n_std_Hz]
        seen.append(f"{name}: " + "; ".join(f"{m.f_n_Hz:.1f}+-{m.f_n_std_Hz:.1f} {m.fit.flags}"
                                            for m in ca.peaks.modes))
        if name in ("accel_x", "accel_y"):
            assert near, "\n".join(seen)
            assert all("misfit" not in m.fit.flags for m in near), "\n".join(seen)

"""Sweeps of the SDOF model: period detection, parallel sweeps, dimensional view, curve tables.

Sources of the expected numbers:
* period detection: hand-built cases whose period is known -- a linear forced response
  (period 1), the principal parametric resonance of a Mathieu oscillator at Lambda = 2 limited
  by the backlash (period 2, the textbook subharmonic; Kahraman & Singh 1991), an undamped free
  oscillation at an irrational frequency ratio (quasi-periodic: no period);
* sweep_many: the serial sweep (same kernel; results must be identical bit for bit);
* dimensional helper: seed 003 Eq. 24a by hand for two discs, and the definitions of Eq. 27;
* curve tables: the periodic interpolant reproduces its samples; the sweep from the curves
  converges to the one from the Fourier series as harmonics are added.
"""

import math

import numpy as np
import pytest

from models.dynamics import (
    SDOFModel,
    periods,
    sdof_from_mesh_cycle,
    settle,
    steady_state,
    sweep,
)
from models.dynamics.dimensional import dimensional_scaling, to_dimensional
from models.dynamics.integrate import POINCARE_POINTS, settle_periodic
from models.dynamics.itms import itms_from_mesh_cycle
from models.dynamics.parallel import sweep_many
from models.dynamics.sdof import PeriodicCurve
from models.errors import ModelError
from models.geometry import equivalent_mass, gear_inertia, load_gear_set
from models.stiffness import mesh_cycle, pair_compliance, tabulate_compliance
from models.stiffness.mesh_cycle import Harmonics

PAIR = load_gear_set("kahraman-blankenship").pair
HALF_BACKLASH_M = 0.068e-3


@pytest.fixture(scope="module")
def compliance():
    return tabulate_compliance(PAIR, lambda s: pair_compliance(PAIR, s).total_m_per_N)


def mathieu(eps=0.4, zeta=0.02, force=0.1):
    """X'' + 2 zeta x' + (1 + eps cos(Lambda tau)) f(x) = F, b = 1."""
    return SDOFModel(
        zeta=zeta,
        force=force,
        backlash=1.0,
        stiffness=Harmonics(1.0, np.array([eps]), np.array([0.0])),
    )


# --- period detection --------------------------------------------------------------------------
def test_period_one_for_a_linear_forced_response():
    m = SDOFModel(
        zeta=0.05, force=0.0, backlash=0.0, error=Harmonics(0.0, np.array([0.1]), np.array([0.0]))
    )
    s = settle_periodic(m, 0.8, (0.0, 0.0), tol=1e-9, max_periods=3000)
    assert s.period == 1 and s.converged and s.periods_run < 3000
    assert s.poincare.shape == (POINCARE_POINTS, 2)
    # the Poincare point of x = Re(X exp(i Lambda tau)), X = 0.1 / (1 - L^2 + 2 i zeta L)
    X = 0.1 / (1 - 0.8**2 + 2j * 0.05 * 0.8)
    np.testing.assert_allclose(s.poincare[-3:], [[X.real, (0.8j * X).real]] * 3, atol=1e-6)


def test_period_two_at_the_principal_parametric_resonance():
    """Lambda = 2: the Mathieu instability grows until contact loss bounds it, period 2."""
    m = mathieu()
    s = settle_periodic(m, 2.0, (m.start_dte() + 0.01, 0.0), tol=1e-8, max_periods=4000)
    assert s.period == 2, "the subharmonic response repeats every two mesh periods"
    # settled well before the cap: the period-2 test ends the run
    assert s.periods_run < 1500
    pts = s.poincare[-4:]
    assert np.max(np.abs(pts[0] - pts[2])) < 1e-7 and np.max(np.abs(pts[0] - pts[1])) > 0.1
    # the sweep sees it too, with the record rounded to whole response periods
    _, fig = steady_state(
        m, 2.0, (m.start_dte() + 0.01, 0.0), tol=1e-8, max_periods=4000, record_periods=3
    )
    assert fig["period"] == 2 and fig["contact_loss"] and fig["converged"]
    # the subharmonic is not a mesh harmonic: the record of 4 (not 3) periods leaves it out
    _, xs, _ = periods(m, 2.0, tuple(pts[-1]), 4, steps_per_period=128, record=True)
    c = np.abs(np.fft.rfft(xs)) / xs.size * 2
    assert fig["amplitudes"][0] == pytest.approx(c[4], rel=1e-9)
    assert c[2] > 5 * fig["amplitudes"][0]  # the half-mesh-frequency component dominates
    # below the instability band the same oscillator settles with period 1
    assert settle_periodic(m, 1.4, (m.start_dte(), 0.0), tol=1e-8, max_periods=4000).period == 1


def test_quasi_periodic_response_has_no_period():
    """Zeta = 0, linear, free oscillation: the Poincare map turns by 2 pi / Lambda per period."""
    m = SDOFModel(zeta=0.0, force=0.0, backlash=0.0)
    lam = 2 / (1 + math.sqrt(5))  # golden ratio: no n <= 8 with n / Lambda near an integer
    s = settle_periodic(m, lam, (1.0, 0.0), tol=1e-6, max_periods=200)
    assert s.period == 0 and not s.converged and s.periods_run == 200
    state, n, ok = settle(m, lam, (1.0, 0.0), tol=1e-6, max_periods=200)
    assert not ok and n == 200 and state == s.state


def test_a_slowly_converging_period_one_is_not_taken_for_period_two():
    """A converging period-1 response is not taken for period 2.

    Lambda = 0.4: the free transient turns by 2.5 turns per mesh period, so points two
    periods apart nearly coincide while it decays; the spread test must reject n = 2.
    """
    m = SDOFModel(
        zeta=0.02, force=0.0, backlash=0.0, error=Harmonics(0.0, np.array([0.1]), np.array([0.0]))
    )
    s = settle_periodic(m, 0.4, (0.5, 0.0), tol=1e-5, min_periods=3, max_periods=2000)
    assert s.period == 1


def test_extrapolation_guard_rejects_a_slow_flip_transient():
    """Only the extrapolation guard can reject this false period 2 (zeta = 1e-4).

    Linear oscillator at Lambda = 2: the free transient turns by half a turn per mesh period
    and decays by exp(-pi zeta) = 0.99969 (hand-derived), so points two periods apart differ by
    6.3e-4 of it: with a transient of 1e-3 they repeat within tol = 1e-6 while the split
    (2e-3) is far above 100 tol and shrinks by only 0.06 % per two periods. The true response
    is period 1 (the forced one); at the cap the run is reported unresolved, -2, not period 2.
    """
    m = SDOFModel(
        zeta=1e-4, force=0.0, backlash=0.0, error=Harmonics(0.0, np.array([0.1]), np.array([0.0]))
    )
    X = 0.1 / (1 - 4 + 2j * 1e-4 * 2)
    s = settle_periodic(m, 2.0, (X.real + 1e-3, (2j * X).real), tol=1e-6, max_periods=300)
    assert s.period == -2 and s.unresolved and not s.converged and s.periods_run == 300
    pts = s.poincare[-3:]
    assert np.max(np.abs(pts[2] - pts[0])) < 1e-6 < 100e-6 < np.max(np.abs(pts[2] - pts[1]))


def test_resolution_guard_needs_the_split_above_100_tol():
    """Only the resolution guard rejects a settled period-2 orbit split by less than 100 tol.

    The Mathieu subharmonic at Lambda = 2 (split ~0.5, settled to round-off, so the
    extrapolation bound is nil): with tol = 1e-2 (100 tol = 1 > split) it is unresolved (-2),
    with tol = 1e-4 it is period 2.
    """
    m = mathieu()
    s = settle_periodic(m, 2.0, (m.start_dte() + 0.01, 0.0), tol=1e-10, max_periods=4000)
    assert s.period == 2
    split = float(np.max(np.abs(s.poincare[-1] - s.poincare[-2])))
    assert 0.1 < split < 1.0
    coarse = settle_periodic(m, 2.0, s.state, tol=1e-2, max_periods=60)
    assert coarse.period == -2 and coarse.periods_run == 60
    assert settle_periodic(m, 2.0, s.state, tol=1e-4, max_periods=60).period == 2


def test_sweep_reports_unresolved_and_aperiodic_points():
    """The sweep carries the codes: -n unresolved, 0 aperiodic, and converged only for n > 0."""
    lam = 2 / (1 + math.sqrt(5))
    free = SDOFModel(zeta=0.0, force=0.0, backlash=0.0)
    r = sweep(free, [lam], y0=(1.0, 0.0), tol=1e-6, max_periods=100)
    assert r.period[0] == 0 and not r.converged[0] and not r.unresolved[0]
    m = mathieu()
    s = settle_periodic(m, 2.0, (m.start_dte() + 0.01, 0.0), tol=1e-10, max_periods=4000)
    r = sweep(m, [2.0], y0=s.state, tol=1e-2, max_periods=60)
    assert r.period[0] == -2 and r.unresolved[0] and not r.converged[0]


# --- parallel sweeps ---------------------------------------------------------------------------
def test_sweep_many_is_identical_to_the_serial_sweeps(compliance):
    lam = np.linspace(0.45, 1.3, 18)
    models = []
    for torque in (150.0, 340.0):
        cyc = mesh_cycle(PAIR, compliance, torque, n_phases=120)
        models.append(sdof_from_mesh_cycle(cyc, "vvms", zeta=0.02, backlash_m=HALF_BACKLASH_M))
    models.append(sdof_from_mesh_cycle(cyc, "lste", zeta=0.05, backlash_m=HALF_BACKLASH_M))
    models.append(itms_from_mesh_cycle(cyc, zeta=0.02, backlash_m=HALF_BACKLASH_M))
    kw = dict(steps_per_period=48, tol=1e-5, max_periods=200)
    results, jobs = sweep_many(models, lam, **kw)
    assert [(j.model_index, j.direction) for j in jobs] == [
        (i, d) for i in range(4) for d in ("up", "down")
    ]
    for r, j in zip(results, jobs, strict=True):
        f = lam if j.direction == "up" else lam[::-1]
        s = sweep(models[j.model_index], f, **kw)
        np.testing.assert_array_equal(r.frequency, s.frequency)
        for name in (
            "amplitudes",
            "arms",
            "mean_dte",
            "contact_loss",
            "backside_impact",
            "partial_contact_loss",
            "periods",
            "period",
            "poincare",
            "entry_state",
        ):
            np.testing.assert_array_equal(getattr(r, name), getattr(s, name), err_msg=name)
    # up and down differ in the softening band of the 340 N m model (seed Sec. 4.1)
    up, down = results[2], results[3].sorted()
    assert np.max(down.arms - up.arms) > 0.1


def test_sweep_many_validates():
    m = SDOFModel(zeta=0.1, force=0.1, backlash=1.0)
    with pytest.raises(ValueError, match="directions"):
        sweep_many([m], [1.0], directions=("sideways",))  # type: ignore[list-item]
    with pytest.raises(ValueError, match="frequencies"):
        sweep_many([m, m], np.ones((3, 2)))
    with pytest.raises(ValueError, match="empty"):
        sweep_many([], [1.0])


# --- dimensional helper ------------------------------------------------------------------------
def test_dimensional_scaling_by_hand(compliance):
    cyc = mesh_cycle(PAIR, compliance, 340.0, n_phases=120)
    m = sdof_from_mesh_cycle(cyc, "vvms", zeta=0.02, backlash_m=HALF_BACKLASH_M)
    s = dimensional_scaling(m, PAIR)
    # the package's convention (models.geometry.inertia), by hand: a steel disc out to the
    # operating pitch radius r_w = r_b a / (r_b1 + r_b2) (cos alpha' = (r_b1 + r_b2) / a), bore
    # 0.3 of the reference radius (Table 3 gears state none)
    rb = PAIR.base_radius(1)
    r_w = rb * PAIR.centre_distance / (rb + PAIR.base_radius(2))
    r_i = 0.3 * PAIR.reference_radius(1)
    J = 7850.0 * PAIR.face_width_m * math.pi * (r_w**4 - r_i**4) / 2
    assert gear_inertia(PAIR, 1) == pytest.approx(J, rel=1e-12)
    assert s.mass_kg == pytest.approx(J / (2 * rb**2), rel=1e-12)  # Eq. 24a, equal gears
    assert s.omega_n_rad_s == pytest.approx(math.sqrt(m.mean_stiffness_N_m / s.mass_kg))
    assert s.damping_N_s_m == pytest.approx(2 * 0.02 * s.mass_kg * s.omega_n_rad_s)
    # Lambda <-> Hz <-> rpm round trips; 50 teeth: rpm = 60 f / 50
    lam = np.array([0.5, 1.0, 1.3])
    f = s.mesh_frequency_Hz(lam)
    np.testing.assert_allclose(f, lam * s.omega_n_rad_s / (2 * math.pi))
    np.testing.assert_allclose(s.pinion_rpm(lam), 60 * f / 50)
    np.testing.assert_allclose(s.frequency_ratio_from_rpm(s.pinion_rpm(lam)), lam)
    np.testing.assert_allclose(s.frequency_ratio_from_Hz(f), lam)
    assert PAIR.mesh_frequency(float(s.pinion_rpm(1.0))) == pytest.approx(s.natural_frequency_Hz)
    assert s.nondimensional_force(340.0) == pytest.approx(m.force, rel=1e-12)
    assert s.dte_um(1.0) == pytest.approx(68.0)
    # given inertias; unequal gears
    assert equivalent_mass(2.0, 1.0, 0.1, 0.2) == pytest.approx(2.0 / (2 * 0.04 + 0.01))
    s2 = dimensional_scaling(m, PAIR, J1_kg_m2=2 * J, J2_kg_m2=2 * J)
    assert s2.natural_frequency_Hz == pytest.approx(s.natural_frequency_Hz / math.sqrt(2))
    r = sweep(m, [0.8, 1.2], steps_per_period=48, tol=1e-5, max_periods=200)
    d = to_dimensional(r, s)
    np.testing.assert_allclose(d.arms_um, r.arms * 68.0)
    np.testing.assert_allclose(d.amplitudes_um, r.amplitudes * 68.0)
    np.testing.assert_allclose(d.mesh_frequency_Hz, s.mesh_frequency_Hz([0.8, 1.2]))
    with pytest.raises(ModelError, match="inertia_pinion_kg_m2"):
        equivalent_mass(0.0, 1.0, 0.1, 0.1)
    with pytest.raises(ModelError, match="gear"):
        gear_inertia(PAIR, 3)


def test_secant_mean_stiffness_holds_the_profile_errors(compliance):
    """VVMS / LSTE k_0 (seed Eqs. 20b, 30, 31) include the profile errors; "fvms" does not.

    A rigid error e0 on every pair shifts every gap alike, so the loaded LSTE is the error-free
    one plus e0 (hand-derived from the compatibility conditions): k_0(VVMS) = mean(F / (x_s0 +
    e0)), k_0(LSTE) = F / (mean(x_s0) + e0). For 5 um at 340 N m that is 25 % softer; the FVMS
    and the "fvms" reference stiffness do not move.
    """
    e0 = 5e-6
    c0 = mesh_cycle(PAIR, compliance, 340.0, n_phases=200)
    c5 = mesh_cycle(PAIR, compliance, 340.0, n_phases=200, error=lambda s: np.full(np.shape(s), e0))
    np.testing.assert_allclose(c5.lste_m, c0.lste_m + e0, rtol=1e-9)
    F = c0.load_N
    kw = dict(zeta=0.02, backlash_m=HALF_BACKLASH_M)
    v0, v5 = (sdof_from_mesh_cycle(c, "vvms", **kw) for c in (c0, c5))
    assert v5.mean_stiffness_N_m == pytest.approx(np.mean(F / (c0.lste_m + e0)), rel=1e-9)
    assert 0.2 < 1 - v5.mean_stiffness_N_m / v0.mean_stiffness_N_m < 0.3
    l5 = sdof_from_mesh_cycle(c5, "lste", **kw)
    assert l5.mean_stiffness_N_m == pytest.approx(F / (np.mean(c0.lste_m) + e0), rel=1e-9)
    kf0 = c0.fvms_harmonics.mean
    for c in (c0, c5):
        for kind in ("fvms", "vvms", "lste"):
            m = sdof_from_mesh_cycle(c, kind, reference_stiffness="fvms", **kw)
            assert m.mean_stiffness_N_m == pytest.approx(kf0, rel=1e-12)
            assert m.force == pytest.approx(F / (kf0 * HALF_BACKLASH_M), rel=1e-12)
    m = sdof_from_mesh_cycle(c5, "vvms", reference_stiffness="fvms", **kw)
    assert m.stiffness.mean == pytest.approx(v5.mean_stiffness_N_m / kf0, rel=1e-12)
    # one frequency axis for every model with the common reference
    hz = {
        kind: dimensional_scaling(
            sdof_from_mesh_cycle(c5, kind, reference_stiffness="fvms", **kw), PAIR
        ).natural_frequency_Hz
        for kind in ("fvms", "vvms", "lste")
    }
    assert max(hz.values()) == pytest.approx(min(hz.values()), rel=1e-12)
    with pytest.raises(ModelError, match="reference_stiffness"):
        sdof_from_mesh_cycle(c5, "vvms", reference_stiffness="tangent", **kw)  # type: ignore[arg-type]
    with pytest.raises(ModelError, match="reference_stiffness"):
        sdof_from_mesh_cycle(c5, "vvms", reference_stiffness=-1.0, **kw)


def test_reference_stiffness_is_only_a_change_of_scale(compliance):
    """The same rig (same k(t), m, c) in two scalings gives the same response in metres.

    Scaling by k_a or k_b: Lambda_b = Lambda_a sqrt(k_a / k_b), zeta_b = zeta_a sqrt(k_a / k_b)
    (c = 2 zeta sqrt(k_0 m) fixed), same length scale; the Arms in metres must agree to the
    integration error.
    """
    cyc = mesh_cycle(PAIR, compliance, 340.0, n_phases=200, n_harmonics=10)
    kw = dict(backlash_m=HALF_BACKLASH_M)
    a = sdof_from_mesh_cycle(cyc, "vvms", zeta=0.03, **kw)
    r = math.sqrt(a.mean_stiffness_N_m / cyc.fvms_harmonics.mean)
    b = sdof_from_mesh_cycle(cyc, "vvms", zeta=0.03 * r, reference_stiffness="fvms", **kw)
    for lam in (0.7, 1.2):
        _, fa = steady_state(a, lam, (a.start_dte(), 0.0), tol=1e-10, max_periods=3000)
        _, fb = steady_state(b, lam * r, (b.start_dte(), 0.0), tol=1e-10, max_periods=3000)
        assert fa["arms"] * HALF_BACKLASH_M == pytest.approx(fb["arms"] * HALF_BACKLASH_M, rel=1e-6)
        assert fa["mean_dte"] == pytest.approx(fb["mean_dte"], rel=1e-8)


# --- curve tables ------------------------------------------------------------------------------
def test_periodic_curve_interpolates_its_samples():
    v = np.array([1.0, 3.0, 2.0, 0.0])
    c = PeriodicCurve(v)
    np.testing.assert_allclose(c(np.arange(4) / 4), v)
    np.testing.assert_allclose(c([0.125, 0.875, 1.125, -0.125]), [2.0, 0.5, 2.0, 0.5])
    assert c.mean == pytest.approx(1.5)
    np.testing.assert_allclose(c.scaled(2.0, drop_mean=True).values, (v - 1.5) / 2)
    with pytest.raises(ModelError, match="values"):
        PeriodicCurve(np.array([1.0]))


def test_curve_and_fourier_models_converge(compliance):
    """Curve-based and Fourier-based models converge.

    The sweep from the cycle curves and from their Fourier series (seed Eq. 25) agree
    better as harmonics are added (VVMS and LSTE are smooth with corner contact).
    """
    cyc = mesh_cycle(PAIR, compliance, 340.0, n_phases=200, n_harmonics=40)
    lam = np.array([0.6, 0.8, 1.2])
    kw = dict(steps_per_period=100, tol=1e-8, max_periods=600)
    for kind in ("vvms", "lste"):
        ref = sweep(
            sdof_from_mesh_cycle(cyc, kind, zeta=0.05, backlash_m=HALF_BACKLASH_M, source="curve"),
            lam,
            **kw,
        ).arms
        errs = [
            np.max(
                np.abs(
                    sweep(
                        sdof_from_mesh_cycle(
                            cyc, kind, zeta=0.05, backlash_m=HALF_BACKLASH_M, n_harmonics=n
                        ),
                        lam,
                        **kw,
                    ).arms
                    / ref
                    - 1
                )
            )
            for n in (2, 5, 40)
        ]
        assert errs[2] < errs[0] and errs[2] < 2e-3, (kind, errs)


# --- linear limit through the sweep kernel -----------------------------------------------------
def test_linear_sweep_is_the_analytic_frf_both_ways():
    """Linear limit through the sweep kernel: the analytic FRF both ways.

    No backlash, constant stiffness, e = eps cos(Lambda tau): every point of the up and the
    down sweep is eps / |1 - Lambda^2 + 2 i zeta Lambda| (no jump, no hysteresis), period 1.
    """
    zeta, eps = 0.05, 0.1
    m = SDOFModel(
        zeta=zeta, force=0.0, backlash=0.0, error=Harmonics(0.0, np.array([eps]), np.array([0.0]))
    )
    lam = np.linspace(0.3, 2.0, 18)
    res, _ = sweep_many([m], lam, tol=1e-10, max_periods=6000)
    exact = eps / np.abs(1 - lam**2 + 2j * zeta * lam)
    for r in (res[0], res[1].sorted()):
        np.testing.assert_allclose(r.arms, exact, rtol=1e-3)
        np.testing.assert_allclose(r.amplitudes[:, 0], exact, rtol=1e-3)
        assert np.all(r.amplitudes[:, 1:] < 1e-7) and np.all(r.period == 1)
        np.testing.assert_allclose(r.mean_dte, 0.0, atol=1e-9)


def test_model_builder_validation(compliance):
    cyc = mesh_cycle(PAIR, compliance, 340.0, n_phases=64)
    with pytest.raises(ModelError, match="source"):
        sdof_from_mesh_cycle(cyc, "vvms", zeta=0.02, backlash_m=HALF_BACKLASH_M, source="spline")  # type: ignore[arg-type]
    with pytest.raises(ModelError, match="error"):
        sdof_from_mesh_cycle(cyc, "fvms", zeta=0.02, backlash_m=HALF_BACKLASH_M, error="measured")  # type: ignore[arg-type]
    # the FVMS error of an error-free cycle is zero; with the curve source it is a curve
    m = sdof_from_mesh_cycle(
        cyc, "fvms", zeta=0.02, backlash_m=HALF_BACKLASH_M, error="cycle", source="curve"
    )
    assert isinstance(m.error, PeriodicCurve) and np.all(m.error.values == 0.0)
    with pytest.raises(ValueError, match="steps_per_period"):
        sweep(m, [1.0], steps_per_period=2)
    with pytest.raises(ValueError, match="frequencies"):
        sweep(m, [0.0])

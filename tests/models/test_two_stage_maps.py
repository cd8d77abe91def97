"""Peak-DTE maps over mesh frequency x bulk temperature, thermal stiffness, bifurcation data.

Expected values come from: the serial driver (parallel must equal it bit for bit), the single
point steady response of :mod:`models.dynamics.two_stage` (a map point must equal it), the
analytic forced response of the linear two-DOF system (derived in ``_linear_peak``), the
similarity limit of the thermal deformation (``sigma = xi dT rho``, hand-derived), and the
eigenvalues of the mean-stiffness system (direction of the natural-frequency shift).
"""

import dataclasses
import math

import numpy as np
import pytest

from models.dynamics import two_stage_steady_response
from models.dynamics.two_stage_maps import (
    TwoStageThermalSetup,
    bifurcation_over_frequency,
    bifurcation_over_temperature,
    peak_dte_map,
    thermal_stiffness_component,
    two_stage_at_temperature,
)
from models.errors import ModelError
from models.geometry import load_gear_set
from models.stiffness import mesh_cycle, pair_compliance, tabulate_compliance
from models.thermal import ThermalReference

FAST = dict(transient_periods=20, record_periods=4, steps_per_period=32)
F_HZ = np.array([3000.0, 4500.0, 6000.0, 8000.0])
T_C = np.array([40.0, 80.0, 120.0])


def test_parallel_equals_serial():
    kw = dict(FAST, continuation=True)
    par = peak_dte_map(F_HZ, T_C, parallel=True, **kw)
    ser = peak_dte_map(F_HZ, T_C, parallel=False, **kw)
    for name in ("peak_dte_m", "amplitude_m", "contact_loss", "back_contact", "poincare_m"):
        np.testing.assert_array_equal(getattr(par, name), getattr(ser, name), err_msg=name)
    assert par.peak_dte_m.shape == (3, 4, 2) and par.poincare_m.shape == (3, 4, 4, 2)
    # the default setup is nonlinear somewhere on this grid (the flags are exercised)
    assert par.contact_loss.any()


@pytest.mark.parametrize("direction", ["up", "down"])
def test_map_point_equals_steady_response(direction):
    m = peak_dte_map(F_HZ, T_C, continuation=False, direction=direction, **FAST)
    for i, t in enumerate(T_C):
        for j, f in enumerate(F_HZ):
            model, sc, lam = two_stage_at_temperature(t, f)
            assert lam == m.frequency_ratio[j]
            r = two_stage_steady_response(model, lam, **FAST)
            np.testing.assert_array_equal(m.peak_dte_m[i, j], np.array(r.peak) * sc["L"])
            np.testing.assert_array_equal(m.contact_loss[i, j], r.contact_loss)
            np.testing.assert_array_equal(m.back_contact[i, j], r.back_contact)


def test_continuation_first_point_is_steady_response_and_carries_state():
    up = peak_dte_map(F_HZ, T_C[:1], continuation=True, **FAST)
    model, sc, lam = two_stage_at_temperature(T_C[0], F_HZ[0])
    r = two_stage_steady_response(model, lam, **FAST)
    np.testing.assert_array_equal(up.peak_dte_m[0, 0], np.array(r.peak) * sc["L"])
    # the next point starts from that final state, not from static
    model2, _, lam2 = two_stage_at_temperature(T_C[0], F_HZ[1])
    r2 = two_stage_steady_response(model2, lam2, r.state, **FAST)
    np.testing.assert_array_equal(up.peak_dte_m[0, 1], np.array(r2.peak) * sc["L"])


def _linear_setup():
    return TwoStageThermalSetup(
        stiffness_fluctuation=(0.0, 0.0),
        half_backlash_m=(0.0, 0.0),
        error_amplitude_m=(2e-6, 3e-6),
        thermal=False,
    )


def _linear_peak(model, lam, n, periods):
    """Analytic steady response of the linear model, sampled at the RK4 step starts.

    With ``kappa = 1``, ``beta = 0``: ``x1'' + 2 z1 x1' + x1 - mu1 (2 z3 W x3' + W^2 x3)
    = F1 + e1 - mu1 W^2 e3`` and ``x3'' + 2 z3 W x3' + W^2 x3 - mu3 (2 z1 x1' + x1) = F3 +
    W^2 e3 - mu3 e1`` with ``e1 = E1 cos(Lambda tau)``, ``e3 = E3 cos(p/q Lambda tau)``:
    static part plus two complex harmonic solutions.
    """
    z1, _, z3, _, f1, f3, w, mu1, mu3 = model.params()
    p, q = model.mesh_ratio
    e1 = model.stage1.error.amplitude[0]
    e3 = model.stage2.error.amplitude[0]

    def solve(s, rhs):
        a = np.array(
            [
                [s * s + 2 * z1 * s + 1, -mu1 * (2 * z3 * w * s + w * w)],
                [-mu3 * (2 * z1 * s + 1), s * s + 2 * z3 * w * s + w * w],
            ],
            dtype=complex,
        )
        return np.linalg.solve(a, np.asarray(rhs, dtype=complex))

    x0 = solve(0.0, [f1, f3]).real
    xa = solve(1j * lam, [e1, -mu3 * e1])
    lam3 = p / q * lam
    xb = solve(1j * lam3, [-mu1 * w * w * e3, w * w * e3])
    tau = np.arange(periods * q * n) * 2 * math.pi / (lam * n)
    x = (
        x0[:, None]
        + (xa[:, None] * np.exp(1j * lam * tau)).real
        + (xb[:, None] * np.exp(1j * lam3 * tau)).real
    )
    return np.max(np.abs(x), axis=1)


def test_linear_limit_matches_two_dof_forced_response():
    setup = _linear_setup()
    f = np.array([2500.0, 4800.0, 5300.0, 9000.0])  # through stage-1 resonance (~5.3 kHz)
    m = peak_dte_map(f, [60.0], setup, transient_periods=150, record_periods=2, steps_per_period=64)
    assert not m.contact_loss.any()  # no gap (back_contact only marks a tensile force here)
    for j, fj in enumerate(f):
        model, sc, lam = two_stage_at_temperature(60.0, fj, setup)
        expect = _linear_peak(model, lam, 64, 2) * sc["L"]
        np.testing.assert_allclose(m.peak_dte_m[0, j], expect, rtol=2e-4)


def test_linear_bifurcation_is_period_one():
    b = bifurcation_over_frequency(
        [3000.0, 5300.0, 8000.0], 60.0, _linear_setup(), transient_periods=150, record_periods=6
    )
    assert b.samples_m.shape == (3, 6, 2)
    np.testing.assert_array_equal(b.distinct_counts(rtol=1e-6), np.ones((3, 2), dtype=int))
    bt = bifurcation_over_temperature(
        5300.0, [40.0, 90.0], _linear_setup(), transient_periods=150, record_periods=6
    )
    np.testing.assert_array_equal(bt.distinct_counts(rtol=1e-6), np.ones((2, 2), dtype=int))
    # linear and isothermal: the temperature changes nothing
    np.testing.assert_allclose(bt.samples_m[0], bt.samples_m[1], rtol=0, atol=0)


def test_bifurcation_counts_see_a_non_periodic_response():
    """Seed-like nonlinear case (3 kN, D = 1.5, e = 0.3, k = 0.1) inside the resonance band.

    The up-sweep there loses contact and hits the back flank irregularly (bifurcation diagram
    of this setup over 1-12 kHz: period 1 outside ~3-9 kHz, clouds inside); the counter must
    report many distinct Poincare values, so the period-1 test above can fail.
    """
    s = TwoStageThermalSetup(
        half_backlash_m=(15e-6, 15e-6),
        error_amplitude_m=(3e-6, 3e-6),
        stiffness_fluctuation=(0.1, 0.1),
        normal_load_N=3e3,
    )
    b = bifurcation_over_frequency([6500.0], 60.0, s, transient_periods=300, record_periods=20)
    assert b.contact_loss[0, 0]
    assert b.distinct_counts(rtol=1e-4)[0, 0] > 4


def test_thermal_stiffness_similarity_limit():
    """No flash, uniform rise dT: sigma_1 + sigma_2 = xi dT (rho_1 + rho_2) at every point.

    In single contact (R = 1) ``k_w = F / (xi dT (rho_1 + rho_2))`` and ``rho_1 + rho_2``
    is the length T1T2 of the line of action (hand-derived from the involute).
    """
    g = load_gear_set("two-stage-45-steel").pair
    th = thermal_stiffness_component(
        g, 70.0, 1000.0, 1e4, mean_stiffness_N_m=1.9e9, flash=False, n_phases=200
    )
    xi = g.pinion.material.thermal_expansion_per_K
    expect = 1e4 / (xi * 50.0 * g.line_of_action_length)
    single = (th.phase > g.contact_ratio - 1 + 0.01) & (th.phase < 0.99)
    np.testing.assert_allclose(th.k_w_N_m[0, single], expect, rtol=1e-9)
    # the flash temperature adds deformation, more at higher speed: k_w falls with speed
    fl = thermal_stiffness_component(g, 70.0, [500.0, 3000.0], 1e4, mean_stiffness_N_m=1.9e9)
    assert fl.flash_max_K[1] > fl.flash_max_K[0] > 0
    assert fl.k_w_N_m[1].mean() < fl.k_w_N_m[0].mean() < th.k_w_N_m[0].mean()
    with pytest.raises(ModelError):
        thermal_stiffness_component(g, 20.0, 1000.0, 1e4, mean_stiffness_N_m=1.9e9)


def _natural_frequencies(model):
    """Undamped natural frequencies of the mean-stiffness linearisation (units of omega_n)."""
    _, _, _, _, _, _, w, mu1, mu3 = model.params()
    k1 = model.stage1.stiffness.mean + (model.stage1.thermal.mean if model.stage1.thermal else 0)
    k3 = model.stage2.stiffness.mean + (model.stage2.thermal.mean if model.stage2.thermal else 0)
    k = np.array([[k1, -mu1 * w * w * k3], [-mu3 * k1, w * w * k3]])
    return np.sort(np.sqrt(np.linalg.eigvals(k).real))


def test_thermal_component_raises_stiffness_and_heating_lowers_it():
    """Natural frequencies: above the isothermal ones, falling as the gears heat.

    Seed 001's ``k = k_t + k_w`` with ``k_w = F/(b sigma) > 0`` raises the stiffness; ``sigma``
    grows with the bulk temperature, so ``k_w`` and the natural frequencies fall as the gears
    heat. Seed 001 states no number or direction for the shift (its maps only report jumps
    with rising temperature); this is the direction its formula implies.
    """
    iso = _natural_frequencies(
        two_stage_at_temperature(60.0, 5000.0, TwoStageThermalSetup(thermal=False))[0]
    )
    hot = [_natural_frequencies(two_stage_at_temperature(t, 5000.0)[0]) for t in (40, 80, 120)]
    assert np.all(hot[0] > hot[1]) and np.all(hot[1] > hot[2]) and np.all(hot[2] > iso)
    # and the dynamic response shows it: the stage-1 resonance peak moves down with heating
    setup = dataclasses.replace(_linear_setup(), thermal=True)
    f = np.linspace(4000.0, 8000.0, 17)
    m = peak_dte_map(
        f, [40.0, 120.0], setup, transient_periods=80, record_periods=2, steps_per_period=32
    )
    f_res = f[np.argmax(m.amplitude_m[:, :, 0], axis=1)]
    assert f_res[0] > f_res[1]


def test_mesh_cycle_stiffness_source():
    """k_t(tau) from the potential-energy VVMS of each stage at its own normal load.

    Expected: the harmonics of an independent :func:`mesh_cycle` call, normalised; stage 2
    carries ``T_1 (r_2/r_1) / r_b3`` = 20 kN (gears 30/60 then 30/90, equal base radii of
    gears 1 and 3). The ISO-typical default ``c_gamma b`` = 1.9e9 N/m lies within 15 % of
    both VVMS means (1.72e9 and 1.79e9 N/m), which is the check on that default.
    """
    setup = TwoStageThermalSetup(stiffness_source="mesh-cycle")
    model, sc, _ = two_stage_at_temperature(60.0, 5000.0, setup)
    means = []
    for st, (name, load) in enumerate(
        (("two-stage-45-steel", 1e4), ("two-stage-45-steel-stage2", 2e4))
    ):
        pair = load_gear_set(name).pair
        comp = tabulate_compliance(pair, lambda s, p=pair: pair_compliance(p, s).total_m_per_N)
        v = mesh_cycle(pair, comp, load * pair.base_radius(1), n_phases=128).vvms_harmonics
        got = (model.stage1, model.stage2)[st].stiffness
        np.testing.assert_allclose(got.amplitude, v.amplitude / v.mean, rtol=1e-12)
        np.testing.assert_allclose(got.phase_rad, v.phase_rad, rtol=1e-12)
        means.append(v.mean)
        assert abs(1.9e9 / v.mean - 1) < 0.15
    assert sc["omega_n"] == pytest.approx(math.sqrt(means[0] / sc["m1"]), rel=1e-12)
    # the thermal part is normalised by the same mean
    th = thermal_stiffness_component(
        load_gear_set("two-stage-45-steel").pair,
        60.0,
        60.0 * 5000.0 / 30,
        1e4,
        mean_stiffness_N_m=means[0],
    )
    assert model.stage1.thermal.mean == pytest.approx(th.harmonics[0].mean, rel=1e-12)


def test_backlash_closure_option():
    """Seed 000's closure at a fixed centre distance: xi dT a' sin(alpha') over both flanks."""
    g = load_gear_set("two-stage-45-steel").pair
    ref = ThermalReference(20.0)
    setup = TwoStageThermalSetup(half_backlash_m=(40e-6, 40e-6), backlash_reference=ref)
    model, sc, _ = two_stage_at_temperature(50.0, 5000.0, setup)
    xi = g.pinion.material.thermal_expansion_per_K
    closure = xi * 30.0 * g.centre_distance * math.sin(g.operating_pressure_angle)
    assert model.stage1.backlash * sc["L"] == pytest.approx(40e-6 - closure / 2, rel=1e-9)
    with pytest.raises(ModelError, match="jammed"):
        two_stage_at_temperature(150.0, 5000.0, setup)


def test_rejects_bad_axes():
    with pytest.raises(ModelError):
        peak_dte_map([], [60.0])
    with pytest.raises(ModelError):
        peak_dte_map([-1.0], [60.0])
    with pytest.raises(ModelError):
        peak_dte_map([1000.0], [60.0], direction="sideways")  # type: ignore[arg-type]


@pytest.mark.slow
def test_up_and_down_sweeps_agree_where_the_response_is_linear():
    """Fine map: both sweeps agree wherever neither stage ever leaves the drive flank.

    There the system is linear time-periodic and its periodic response unique, so the sweep
    history must not matter (the stages are coupled, so a point is calm only if both are).
    Long transient: near 1.8 omega_n the slowest mode still carries ~1e-3 after 200 periods.
    """
    f = np.linspace(2000.0, 12000.0, 41)
    t = np.linspace(40.0, 120.0, 5)
    kw = dict(transient_periods=2000, record_periods=10)
    up = peak_dte_map(f, t, direction="up", **kw)
    down = peak_dte_map(f, t, direction="down", **kw)
    flags = up.contact_loss | up.back_contact | down.contact_loss | down.back_contact
    calm = ~flags.any(axis=2)
    assert 0.3 < calm.mean() < 1  # both regimes on the grid
    np.testing.assert_allclose(up.peak_dte_m[calm], down.peak_dte_m[calm], rtol=1e-6)
    # and where they differ, it is inside the nonlinear band around the primary resonance
    diff = ~np.isclose(up.peak_dte_m, down.peak_dte_m, rtol=1e-6).all(axis=2)
    assert np.all(flags.any(axis=2)[diff])

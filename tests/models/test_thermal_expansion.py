"""Thermal deformation of the flanks, the thermal reference state, seed 001's k_w.

Sources of the expected numbers, test by test:

* the disc: Timoshenko and Goodier (1970, ch. 13), plane-stress free annular disc,
  ``u(r) = (1 + nu) xi / r int_a^r theta r dr + xi / (b^2 - a^2) [(1 - nu) r + (1 + nu) a^2 / r]
  int_a^b theta r dr``, integrated here with ``scipy.integrate.quad`` for the logarithmic
  profile, against seed 000's printed first three terms of ``Delta r_k`` (transcribed in
  ``_seed_000_*`` below);
* similarity: a uniform rise ``dT`` scales each gear about its centre (every point moves
  radially by ``xi dT r``; a flank point moves along its normal by ``xi dT rho``; two flanks at
  a fixed centre distance close by ``xi dT a' sin(alpha')``), exact geometry;
* seed 000's printed ``Delta r_k``, ``Delta s_k = Delta t_k xi s_k / 2``,
  ``Delta phi_k = Delta s_k / r_k'`` transcribed literally, under both readings of
  ``Delta t_k``, against the same similarity;
* FZG-C (seed 000 Tables 1-2; 90 deg C oil of Table 6; 302 N m, 1500 rpm, f = 0.132): the table
  of ``Delta_1 + Delta_2`` under each reference-state reading in
  ``models/thermal/reference_state.py``, and the seed's "c* of about 10 um" with
  ``chi = 0.0285`` and "deformations of order 1e-6 m";
* seed 001: ``k_wi = F / (b sigma_i)``, springs in series, ``k = k_t + k_w``.
"""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad

from models.errors import ModelError
from models.geometry import inv, load_gear_set, shipped_gear_sets
from models.stiffness import contact_path_positions
from models.thermal import (
    DEFAULT_BORE_FRACTION,
    GearTemperature,
    ThermalReference,
    disc_mean_temperature_rise,
    disc_rim_expansion,
    flash_temperature,
    temperature_stiffness,
    thermal_deformation,
)

FZG = load_gear_set("fzg-c").pair
S = contact_path_positions(FZG)
CHI = 0.0285  # seed 000's thermoelastic correction factor
XI = 1.15e-5


# --- the disc -------------------------------------------------------------------------------
def _timoshenko_goodier(r, a, b, theta, xi, nu):
    inner = quad(lambda x: theta(x) * x, a, r, epsabs=0, epsrel=1e-13)[0]
    whole = quad(lambda x: theta(x) * x, a, b, epsabs=0, epsrel=1e-13)[0]
    return (1 + nu) * xi / r * inner + xi / (b * b - a * a) * ((1 - nu) * r
                                                               + (1 + nu) * a * a / r) * whole


def _seed_000_disc_terms(r_b, r_n, t_n, t_b, xi):
    # Seed 000's Delta r_k without its last (tooth) term, as printed.
    return (r_b * xi * t_n + xi * r_b ** 3 * (t_b - t_n) / (r_b ** 2 - r_n ** 2)
            - xi * r_b * (t_b - t_n) / (2 * (math.log(r_b) - math.log(r_n))))


@pytest.mark.parametrize("nu", [0.0, 0.2925, 0.45])
@pytest.mark.parametrize(("t_n", "t_b"), [(70.0, 70.0), (60.0, 75.0), (80.0, 40.0)])
def test_seed_disc_terms_are_the_plane_stress_disc_with_log_profile(nu, t_n, t_b):
    a, b = 0.0108, 0.0338  # FZG-C pinion: 0.3 d bore, base radius

    def theta(r):
        return t_n + (t_b - t_n) * math.log(r / a) / math.log(b / a)

    rim = _timoshenko_goodier(b, a, b, theta, XI, nu)
    assert _seed_000_disc_terms(b, a, t_n, t_b, XI) == pytest.approx(rim, rel=1e-10), \
        "Timoshenko-Goodier ch. 13: free plane-stress disc"
    assert float(disc_rim_expansion(a, b, t_n, t_b, XI)) == pytest.approx(rim, rel=1e-10)
    # ...which is xi r_b times the area-mean rise, whatever nu.
    mean = quad(lambda r: theta(r) * r, a, b)[0] * 2 / (b * b - a * a)
    assert float(disc_mean_temperature_rise(a, b, t_n, t_b)) == pytest.approx(mean, rel=1e-10)


def test_disc_refuses_bore_outside_base_circle():
    with pytest.raises(ModelError, match="0 < `bore_radius_m` < `outer_radius_m`"):
        disc_mean_temperature_rise(0.04, 0.03, 10.0, 10.0)


# --- similarity ----------------------------------------------------------------------------------
@given(name=st.sampled_from(shipped_gear_sets()), d_t=st.floats(-60.0, 200.0),
       frac=st.floats(0.0, 1.0), xi=st.sampled_from([1.15e-5, 3.43e-5]))
@settings(max_examples=80, deadline=None)
def test_uniform_rise_is_pure_similarity(name, d_t, frac, xi):
    g = load_gear_set(name).pair
    s = g.start_of_contact + frac * g.path_of_contact_length
    d = thermal_deformation(g, [s], ThermalReference(20.0), GearTemperature.uniform(20.0 + d_t),
                            expansion_per_K=xi)
    for flank in (d.pinion, d.wheel):
        # Every point moves radially by xi dT r; polar angles are unchanged.
        assert flank.radial_m[0] == pytest.approx(xi * d_t * flank.radius_m[0], rel=1e-9,
                                                  abs=1e-15)
        assert abs(flank.angle_change_rad[0]) < 1e-15
        assert abs(flank.tangential_m[0]) < 1e-15
        # The flank point moves along its normal by xi dT rho.
        assert flank.normal_m[0] == pytest.approx(xi * d_t * flank.roll_distance_m[0],
                                                  rel=1e-9, abs=1e-15)
    closure = xi * d_t * g.centre_distance * math.sin(g.operating_pressure_angle)
    assert d.total_m[0] == pytest.approx(closure, rel=1e-9, abs=1e-15)


def _seed_000_literal(pair, s, gear, xi, t_n, t_b, dt_k):
    """Seed 000's Delta r_k, Delta s_k, Delta phi_k, new coordinates and Delta_n, as printed."""
    g = pair.pinion if gear == 1 else pair.wheel
    m, a0 = pair.module_m, pair.pressure_angle_rad
    big_r = pair.reference_radius(gear)
    r_b = pair.base_radius(gear)
    r_n = DEFAULT_BORE_FRACTION * big_r
    r_k = float(pair.contact_radius(s, gear))
    alpha_k = math.acos(r_b / r_k)
    s_k = m * (math.pi / 2 + 2 * g.profile_shift * math.tan(a0))  # reference tooth thickness
    phi = s_k / (2 * big_r) - (float(inv(alpha_k)) - float(inv(a0)))
    omega = alpha_k - phi
    d_r = _seed_000_disc_terms(r_b, r_n, t_n, t_b, xi) + dt_k * xi * (r_k - r_b)
    r_new = r_k + d_r
    d_s = dt_k * xi * s_k / 2
    phi_new = phi + d_s / r_new
    dx = r_new * math.sin(phi_new) - r_k * math.sin(phi)
    dy = r_new * math.cos(phi_new) - r_k * math.cos(phi)
    return dx * math.cos(omega) + dy * math.sin(omega), r_k, alpha_k, s_k


@pytest.mark.parametrize("gear", [1, 2])
def test_seed_angular_update_breaks_similarity_under_either_reading(gear):
    # SEED-NOTES 9: a uniform rise dT must give Delta_n = xi dT rho.
    d_t, s = 70.0, FZG.pitch_point
    rho = s if gear == 1 else FZG.line_of_action_length - s
    exact = XI * d_t * rho
    # Reading A: Delta t_k is the local excess over the body, 0 here. The tooth above the base
    # circle does not grow: Delta r_k = xi dT r_b, and Delta_n falls short by xi dT (r_k - r_b)
    # sin(alpha_k).
    dn_a, r_k, alpha_k, s_k = _seed_000_literal(FZG, s, gear, XI, d_t, d_t, 0.0)
    r_b = FZG.base_radius(gear)
    assert dn_a == pytest.approx(exact - XI * d_t * (r_k - r_b) * math.sin(alpha_k), rel=1e-6)
    assert dn_a < 0.95 * exact
    # Reading B: Delta t_k is the tooth's whole rise dT. Delta r_k is right, but the angular
    # update turns the point by xi dT s / (2 r'): the circumferential growth counted twice,
    # Delta_n too large by xi dT (s / 2) cos(alpha_k).
    dn_b, *_ = _seed_000_literal(FZG, s, gear, XI, d_t, d_t, d_t)
    assert dn_b - exact == pytest.approx(XI * d_t * s_k / 2 * math.cos(alpha_k), rel=1e-3)
    assert dn_b > 1.15 * exact  # 25 % (pinion) at the FZG-C pitch point
    # The implementation keeps similarity.
    d = thermal_deformation(FZG, [s], ThermalReference(20.0), GearTemperature.uniform(90.0))
    flank = d.pinion if gear == 1 else d.wheel
    assert flank.normal_m[0] == pytest.approx(exact, rel=1e-9)


def test_radial_part_is_seed_delta_r_with_the_tooth_at_base_plus_local_rise():
    # Non-uniform field: bore 75, base circle 90, local rise along the path up to 100 K.
    rise = np.linspace(100.0, 0.0, S.size)
    temp = GearTemperature(75.0, 90.0, rise)
    d = thermal_deformation(FZG, S, ThermalReference(20.0), temp)
    for gear, flank in ((1, d.pinion), (2, d.wheel)):
        r_b = FZG.base_radius(gear)
        r_n = DEFAULT_BORE_FRACTION * FZG.reference_radius(gear)
        seed = _seed_000_disc_terms(r_b, r_n, 55.0, 70.0, XI) \
            + (70.0 + rise) * XI * (flank.radius_m - r_b)
        # They differ by xi (theta_t - theta_bar) r_b (1 - cos phi_k) (the seed measures the
        # tooth's height from the base circle along the radius, the field from the root centre
        # on the centreline) plus the second-order u_t^2 / (2 r) of the exact new radius.
        linear = XI * (flank.tooth_rise_K - flank.disc_mean_rise_K) * r_b \
            * (1 - np.cos(flank.polar_angle_rad))
        np.testing.assert_allclose(flank.radial_m - seed, linear, rtol=0, atol=1e-9)
        # At most 1.2 % of Delta r_k (0.3 um for 100 K excess low on the pinion flank).
        assert np.max(np.abs(flank.radial_m - seed) / flank.radial_m) < 0.012


def test_normal_deformation_closed_form_and_new_coordinates():
    rise = np.linspace(0.0, 150.0, S.size)
    d = thermal_deformation(FZG, S, ThermalReference(20.0), GearTemperature(60.0, 95.0, rise))
    for gear, flank in ((1, d.pinion), (2, d.wheel)):
        r_b = FZG.base_radius(gear)
        closed = XI * flank.disc_mean_rise_K * flank.roll_distance_m \
            + XI * (flank.tooth_rise_K - flank.disc_mean_rise_K) \
            * (flank.roll_distance_m - r_b * np.sin(flank.load_angle_rad))
        np.testing.assert_allclose(flank.normal_m, closed, rtol=1e-9)
        # The seed's relations between the new coordinates hold exactly.
        np.testing.assert_allclose(flank.new_radius_m, flank.radius_m + flank.radial_m)
        np.testing.assert_allclose(flank.angle_change_rad,
                                   flank.tangential_m / flank.new_radius_m, rtol=1e-12)
        np.testing.assert_allclose(
            flank.dx_m, flank.new_radius_m * np.sin(flank.new_polar_angle_rad)
            - flank.radius_m * np.sin(flank.polar_angle_rad), atol=1e-18)
        # Load angle: omega = alpha_k - phi_k, the normal (cos w, sin w) tangent to the base
        # circle: the foot of the normal from the flank point is at distance rho.
        x = flank.radius_m * np.sin(flank.polar_angle_rad)
        y = flank.radius_m * np.cos(flank.polar_angle_rad)
        foot_x = x - flank.roll_distance_m * np.cos(flank.load_angle_rad)
        foot_y = y - flank.roll_distance_m * np.sin(flank.load_angle_rad)
        np.testing.assert_allclose(np.hypot(foot_x, foot_y), r_b, rtol=1e-12)
    # A hotter tooth adds to Delta_n: the flank grows towards its mate.
    hot = thermal_deformation(FZG, S, ThermalReference(20.0), GearTemperature(60.0, 95.0, 0.0))
    assert np.all(d.total_m[1:] > hot.total_m[1:])


def test_vectorised_over_temperatures_and_linear_in_them():
    bulk = np.array([[40.0], [90.0], [140.0]])
    d = thermal_deformation(FZG, S, ThermalReference(20.0), GearTemperature.uniform(bulk))
    assert d.total_m.shape == (3, 52)
    np.testing.assert_allclose(d.total_m[2] - d.total_m[1], d.total_m[1] - d.total_m[0],
                               rtol=1e-6)


# --- the reference state ------------------------------------------------------------------------
def test_housing_that_follows_the_oil_counts_only_the_excess_over_the_oil():
    ref = ThermalReference(20.0, "follows-oil", oil_temperature_C=90.0)
    at_oil = thermal_deformation(FZG, S, ref, GearTemperature.uniform(90.0))
    np.testing.assert_allclose(at_oil.total_m, 0.0, atol=1e-15)
    np.testing.assert_allclose(at_oil.delta_pinion_m, 0.0, atol=1e-15)
    assert at_oil.centre_distance_change_m == pytest.approx(XI * 70 * FZG.centre_distance)
    # Equivalent to a fixed centre distance with the reference at the oil temperature.
    temp = GearTemperature(95.0, 100.0, np.linspace(30.0, 5.0, S.size))
    a = thermal_deformation(FZG, S, ref, temp)
    b = thermal_deformation(FZG, S, ThermalReference(90.0), temp)
    np.testing.assert_allclose(a.total_m, b.total_m, rtol=1e-6)
    np.testing.assert_allclose(a.delta_pinion_m, b.delta_pinion_m, rtol=1e-6)
    # A housing that expands less than the gears leaves part of the bulk closure.
    steel_in_alu = ThermalReference(20.0, "follows-oil", oil_temperature_C=90.0,
                                    housing_expansion_per_K=2.3e-5)
    c = thermal_deformation(FZG, S, steel_in_alu, GearTemperature.uniform(90.0))
    np.testing.assert_allclose(c.total_m, (XI - 2.3e-5) * 70 * FZG.line_of_action_length,
                               rtol=1e-9)


def _fzg_closure(reading, xi, torque=302.0):
    refs = {
        "fixed": ThermalReference(20.0),
        "fixed+flash": ThermalReference(20.0, flash_counts_as_local_rise=True),
        "oil": ThermalReference(20.0, "follows-oil", oil_temperature_C=90.0),
        "oil+flash": ThermalReference(20.0, "follows-oil", oil_temperature_C=90.0,
                                      flash_counts_as_local_rise=True),
    }
    ft = flash_temperature(FZG, S, torque, 1500.0, bulk_temperature_C=90.0)
    return thermal_deformation(FZG, S, refs[reading], GearTemperature.uniform(90.0), flash=ft,
                               expansion_per_K=xi)


# The table of models/thermal/reference_state.py: mean, min, max of Delta_1 + Delta_2 (um).
TABLE = [
    ("fixed", 1.15e-5, 28.11, 28.11, 28.11),
    ("fixed+flash", 1.15e-5, 38.69, 28.54, 48.22),
    ("oil", 1.15e-5, 0.0, 0.0, 0.0),
    ("oil+flash", 1.15e-5, 10.58, 0.42, 20.10),
    ("fixed", 3.43e-5, 83.86, 83.86, 83.86),
    ("fixed+flash", 3.43e-5, 115.40, 85.11, 143.81),
    ("oil", 3.43e-5, 0.0, 0.0, 0.0),
    ("oil+flash", 3.43e-5, 31.54, 1.26, 59.96),
]


@pytest.mark.parametrize(("reading", "xi", "mean", "low", "high"), TABLE)
def test_fzg_c_closure_under_each_reading(reading, xi, mean, low, high):
    d = _fzg_closure(reading, xi)
    um = d.total_m * 1e6
    assert (um.mean(), um.min(), um.max()) == pytest.approx((mean, low, high), abs=0.01)


def test_only_oil_reference_with_flash_and_steel_xi_reproduces_seed_000():
    # Seed 000: "c* approximately 10 um" (c* = (1 - chi)(Delta_1 + Delta_2), chi = 0.0285) and
    # thermal deformations "on the order of 1e-6 m", FZG-C at 90 deg C oil.
    hits = []
    for reading, xi, *_ in TABLE + [(r, 3.43e-7, 0, 0, 0) for r in ("fixed", "fixed+flash",
                                                                     "oil+flash")]:
        d = _fzg_closure(reading, xi)
        c_star = (1 - CHI) * float(d.total_m.mean())
        per_flank = np.concatenate([d.delta_pinion_m, d.delta_wheel_m])
        order_1e6 = 1e-7 <= np.median(np.abs(per_flank)) < 1e-5
        if 7e-6 <= c_star <= 13e-6 and order_1e6:
            hits.append((reading, xi))
    assert hits == [("oil+flash", 1.15e-5)]
    d = _fzg_closure("oil+flash", 1.15e-5)
    assert (1 - CHI) * d.total_m.mean() * 1e6 == pytest.approx(10.28, abs=0.01)
    assert d.delta_pinion_m.max() * 1e6 == pytest.approx(8.61, abs=0.01)
    assert d.delta_wheel_m.max() * 1e6 == pytest.approx(11.49, abs=0.01)
    # At the seed's other loads: 7.1 um at 183.4 N m, 12.2 um at 381.96 N m.
    for torque, c_expected in ((183.4, 7.07), (381.96, 12.25)):
        d = _fzg_closure("oil+flash", 1.15e-5, torque)
        assert (1 - CHI) * d.total_m.mean() * 1e6 == pytest.approx(c_expected, abs=0.01)


def test_reference_refuses_incomplete_or_unknown_states():
    with pytest.raises(ModelError, match="`oil_temperature_C` is required"):
        ThermalReference(20.0, "follows-oil")
    with pytest.raises(ModelError, match="`housing` must be one of"):
        ThermalReference(20.0, "floating")  # type: ignore[arg-type]
    with pytest.raises(ModelError, match="`reference_temperature_C` must be a finite"):
        ThermalReference(math.nan)
    with pytest.raises(ModelError, match="`flash_counts_as_local_rise` must be a bool"):
        ThermalReference(20.0, flash_counts_as_local_rise=1)  # type: ignore[arg-type]
    with pytest.raises(ModelError, match="`flash` is required"):
        thermal_deformation(FZG, S, ThermalReference(20.0, flash_counts_as_local_rise=True),
                            GearTemperature.uniform(90.0))
    with pytest.raises(ModelError, match="`s_m` must lie strictly between T1"):
        thermal_deformation(FZG, [FZG.line_of_action_length], ThermalReference(20.0),
                            GearTemperature.uniform(90.0))
    with pytest.raises(ModelError, match="do not broadcast"):
        thermal_deformation(FZG, S, ThermalReference(20.0), GearTemperature.uniform([1.0, 2.0]))


# --- seed 001's temperature stiffness ------------------------------------------------------------
def test_temperature_stiffness_units_series_and_sum():
    f, b, s1, s2 = 8000.0, 0.014, 4e-6, 6e-6
    kw = temperature_stiffness(f, b, s1, s2, mesh_stiffness_N_m=2.5e8)
    # k_wi = F / (b sigma_i): N / (m m) = N/m^2, a stiffness per unit face width.
    assert float(kw.tooth_pinion_N_m2) == pytest.approx(f / (b * s1))
    k1, k2 = f / (b * s1), f / (b * s2)
    assert float(kw.pair_N_m2) == pytest.approx(k1 * k2 / (k1 + k2), rel=1e-12)
    # Over the face width: b k_w = F / (sigma_1 + sigma_2) in N/m, added to k_t in N/m.
    assert float(kw.pair_N_m) == pytest.approx(f / (s1 + s2), rel=1e-12)
    assert float(kw.mesh_N_m) == pytest.approx(2.5e8 + f / (s1 + s2), rel=1e-12)


def test_temperature_stiffness_limits():
    sig = np.array([0.0, 1e-9, 1e-6, 1e-5])
    kw = temperature_stiffness(1000.0, 0.014, sig, sig)
    # sigma -> 0 diverges (the oddity: a cold pair would be infinitely stiff): never an
    # infinite stiffness, NaN flagged as undefined, no warning.
    assert np.isnan(kw.pair_N_m[0]) and np.all(np.isfinite(kw.pair_N_m[1:]))
    assert kw.undefined.tolist() == [True, False, False, False]
    assert np.all(np.diff(kw.pair_N_m[1:]) < 0)
    # One rigid thermal "spring" leaves the other one.
    one = temperature_stiffness(1000.0, 0.014, 0.0, 2e-6)
    assert np.isnan(one.tooth_pinion_N_m2) and not bool(one.undefined)
    assert float(one.pair_N_m2) == pytest.approx(float(one.tooth_wheel_N_m2))
    # Load over a thermal deformation grows with the load at a fixed temperature.
    lin = temperature_stiffness([1000.0, 2000.0], 0.014, 2e-6, 2e-6)
    assert lin.pair_N_m[1] == pytest.approx(2 * lin.pair_N_m[0])
    assert float(temperature_stiffness(0.0, 0.014, 2e-6, 2e-6).pair_N_m) == 0.0
    with pytest.raises(ModelError, match="`sigma_wheel_m` must be >= 0"):
        temperature_stiffness(1000.0, 0.014, 1e-6, -1e-6)
    with pytest.raises(ModelError, match="`face_width_m` must be a finite number > 0"):
        temperature_stiffness(1000.0, 0.0, 1e-6, 1e-6)


def test_temperature_stiffness_from_a_thermal_deformation():
    # Seed 001 usage: sigma_i from the contact temperature rise over the initial temperature
    # (bulk 90, flash on the flank, from 20 deg C at a fixed centre distance).
    ft = flash_temperature(FZG, S, 302.0, 1500.0, bulk_temperature_C=90.0)
    d = thermal_deformation(FZG, S, ThermalReference(20.0, flash_counts_as_local_rise=True),
                            GearTemperature.uniform(90.0), flash=ft)
    f = ft.load_per_width_N_m * FZG.face_width_m
    kw = temperature_stiffness(f, FZG.face_width_m, d.pinion.normal_m, d.wheel.normal_m)
    np.testing.assert_allclose(kw.pair_N_m, f / d.total_m, rtol=1e-12)
    assert np.all(kw.pair_N_m > 0)

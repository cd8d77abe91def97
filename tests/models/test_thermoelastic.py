"""Thermoelastic pair stiffness with backlash, the critical compensation gap, the jammed state.

Sources of the expected numbers and statements, test by test:

* the derivation: seed 000's own equations (thermal and coupling loads, ``delta_ti``,
  ``k'_i``, teeth in series) repeated numerically; the seed's printed "k_elastic" with
  ``c k_E`` transcribed literally in ``_printed_k_elastic`` (SEED-NOTES 7);
* analytic limits and identities of Eq. (1) (``c = c*``, ``c = 0``, ``Delta = 0``, ``chi = 1``,
  ``f_n -> inf``) and monotonic trends, as hypothesis property tests;
* the two-flank spring model of the jammed state: equilibrium and compatibility of two springs
  in parallel sharing an interference (SEED-NOTES 10);
* FZG-C statements of seed 000: Table 1 gears (``models/gear_sets/fzg-c.toml``), ``chi =
  0.0285``, the torques 381.96 and 477.45 N m, the backlashes 0, 10, 40 and 100 um of Table 4,
  the critical gap "approximately 10 um", Table 5's three regimes. The thermal closure is an
  input here: ``DELTA_SEED`` is the closure that gives the seed's ``c* = 10 um`` with its
  ``chi`` (the thermal-expansion model is another module's).
"""

import math
import pickle

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from models.errors import ModelError
from models.geometry import load_gear_set
from models.stiffness import (
    contact_path_positions,
    load_share_seed_000,
    normal_load_from_torque,
    tooth_pair_stiffness,
)
from models.thermal.natural_frequency import prepare_natural_frequency
from models.thermal.thermoelastic import (
    FALLS,
    JAMMED_STAND_IN,
    RISES,
    SEED_000_CHI,
    UNCHANGED,
    ThermalJamError,
    critical_gap,
    critical_gap_numerical,
    double_flank_contact,
    elastic_backlash_stiffness,
    stiffness_regime,
    thermoelastic_mesh_stiffness,
    thermoelastic_pair_stiffness,
    thermoelastic_stiffness,
)

FZG = load_gear_set("fzg-c").pair
CHI = 0.0285  # seed 000, "chi approximately constant ... around 0.0285"
C_STAR_SEED = 10e-6  # seed 000: "a critical compensation gap ... approximately 10 um"
DELTA_SEED = C_STAR_SEED / (1 - CHI)  # the closure that gives it (input, not computed here)
T_LOW, T_HIGH = 381.96, 477.45  # N m, seed 000 text (Table 4 paragraph)
TABLE_4_BACKLASH = (0.0, 10e-6, 40e-6, 100e-6)  # m, seed 000 Table 4
SRC = "seed 000"

loads = st.floats(1.0, 1e5)
stiffnesses = st.floats(1e7, 1e10)
closures = st.floats(-50e-6, 50e-6)
backlashes = st.floats(0.0, 200e-6)
chis = st.floats(0.0, 1.0)


def _printed_k_elastic(f_n, k_EP, k_E, delta, c, chi):
    """Seed 000's "k_elastic" exactly as printed: ``c k_E`` in the denominator."""
    return f_n * k_EP / (f_n - (1 - chi) * k_EP * delta + c * k_E)


def _seed_pair_formula(f_n, k_EP, delta, c, chi):
    """Seed 000's pair formula as printed: ``f_n / ((f_n - (1 - chi) k_EP Delta) / k_EP + c)``."""
    return f_n / ((f_n - (1 - chi) * k_EP * delta) / k_EP + c)


# --- the derivation (SEED-NOTES 7) ---------------------------------------------------------
@settings(max_examples=200, deadline=None)
@given(f=loads, k1=stiffnesses, k2=stiffnesses, delta=closures, c=backlashes, chi=chis,
       share=st.floats(0.0, 1.0))
def test_pair_stiffness_is_the_two_teeth_in_series_for_any_backlash_split(
        f, k1, k2, delta, c, chi, share):
    k_ep = k1 * k2 / (k1 + k2)
    closure_load = f - (1 - chi) * k_ep * delta
    assume(closure_load > 1e-6 * f)  # both delta_ti > 0, so both k'_i exist for any split
    r = thermoelastic_stiffness(f, k1, k2, delta, c, chi, pinion_backlash_share=share)
    # the seed's steps, one by one
    p_e, p_te = k_ep * delta, chi * k_ep * delta
    # (atol: hypothesis reaches subnormal products, where relative precision is lost)
    np.testing.assert_allclose(r.thermal_load_N, p_e, rtol=1e-14, atol=1e-300)
    np.testing.assert_allclose(r.coupling_load_N, p_te, rtol=1e-14, atol=1e-300)
    np.testing.assert_allclose(r.delta_t1_m, (f - p_e + p_te) / k1, rtol=1e-10, atol=1e-22)
    np.testing.assert_allclose(r.delta_t2_m, (f - p_e + p_te) / k2, rtol=1e-10, atol=1e-22)
    c1, c2 = share * c, (1 - share) * c
    k1p = f * k1 / (closure_load + c1 * k1)
    k2p = f * k2 / (closure_load + c2 * k2)
    np.testing.assert_allclose(r.k1_prime_N_per_m, k1p, rtol=1e-10)
    np.testing.assert_allclose(r.k2_prime_N_per_m, k2p, rtol=1e-10)
    series = k1p * k2p / (k1p + k2p)
    # series combination == the seed's pair formula == Eq. (1) with c k_EP, whatever the split
    np.testing.assert_allclose(series, _seed_pair_formula(f, k_ep, delta, c, chi), rtol=1e-9)
    np.testing.assert_allclose(r.k_N_per_m, series, rtol=1e-9)
    np.testing.assert_allclose(r.k_N_per_m, _printed_k_elastic(f, k_ep, k_ep, delta, c, chi),
                               rtol=1e-9)


def test_printed_k_elastic_with_single_tooth_stiffness_contradicts_the_derivation():
    """SEED-NOTES 7: ``c k_E`` (any single-tooth or averaged k_E) is not the series result."""
    s = FZG.pitch_point
    ks = tooth_pair_stiffness(FZG, [s])
    k1, k2, k_ep = (float(v[0]) for v in (ks.k_E1_N_per_m, ks.k_E2_N_per_m, ks.k_EP_N_per_m))
    f = float(normal_load_from_torque(FZG, T_LOW))
    c = 40e-6
    series = float(thermoelastic_stiffness(f, k1, k2, DELTA_SEED, c, CHI).k_N_per_m)
    np.testing.assert_allclose(_printed_k_elastic(f, k_ep, k_ep, DELTA_SEED, c, CHI), series,
                               rtol=1e-12, err_msg=f"{SRC}: c k_EP reproduces the series")
    for k_e in (k1, k2, 0.5 * (k1 + k2)):
        printed = _printed_k_elastic(f, k_ep, k_e, DELTA_SEED, c, CHI)
        assert abs(printed / series - 1) > 0.2, (
            f"{SRC}: printed c k_E with k_E={k_e:.4g} should differ from the series result")


def test_single_tooth_stiffness_is_nan_where_its_own_denominator_is_not_positive():
    # pair fine (net deflection > 0) but all the backlash on the wheel and delta_t < 0
    f, k1, k2 = 1000.0, 8e8, 8e8
    r = thermoelastic_stiffness(f, k1, k2, 10e-6, 9e-6, 0.0, pinion_backlash_share=0.0)
    assert not r.jammed and r.delta_t1_m < 0
    assert math.isnan(float(r.k1_prime_N_per_m)) and float(r.k2_prime_N_per_m) > 0


# --- the critical gap ---------------------------------------------------------------------
@settings(max_examples=100, deadline=None)
@given(k=stiffnesses, delta=closures, chi=chis)
def test_critical_gap_closed_form_equals_root_finding_at_several_loads(k, delta, chi):
    loads_N = [10.0, 1e3, 1e5]
    r = critical_gap_numerical(k, delta, chi, loads_N)
    c_star = float(critical_gap(delta, chi))
    atol = 1e-12 * max(loads_N) / k  # round-off of h(c) on the scale of f / k_EP
    np.testing.assert_allclose(r.gap_m, c_star, rtol=1e-9, atol=atol)
    assert r.spread_m <= 2e-9 * abs(c_star) + 2 * atol
    assert r.closed_form_m == c_star


def test_critical_gap_is_load_independent_on_the_fzg_c_path():
    """Root finding on the FZG-C mean mesh stiffness at four torques gives (1 - chi) Delta."""
    m = prepare_natural_frequency(FZG)
    torques = np.array([35.3, 183.4, T_LOW, T_HIGH])  # N m, seed 000
    r = critical_gap_numerical(m.k_EP_N_per_m, DELTA_SEED, CHI,
                               normal_load_from_torque(FZG, torques),
                               load_share=m.load_share, weights=m.weights)
    np.testing.assert_allclose(r.gap_m, C_STAR_SEED, rtol=1e-10,
                               err_msg=f"{SRC}: critical gap approximately 10 um")
    assert r.spread_m < 1e-15


def test_critical_gap_with_a_closure_varying_along_the_path_depends_on_load():
    m = prepare_natural_frequency(FZG)
    delta = DELTA_SEED * (1 + 0.5 * np.cos(np.linspace(0, np.pi, m.n_nodes)))
    r = critical_gap_numerical(m.k_EP_N_per_m, delta, CHI,
                               normal_load_from_torque(FZG, [35.3, 302.0, 3000.0]),
                               load_share=m.load_share, weights=m.weights)
    c_nodes = (1 - CHI) * delta
    assert math.isnan(r.closed_form_m)
    assert r.spread_m > 1e-8
    assert np.all((r.gap_m > c_nodes.min()) & (r.gap_m < c_nodes.max()))


def test_at_the_critical_gap_the_stiffness_is_the_elastic_one_at_every_load_and_position():
    c_star = float(critical_gap(DELTA_SEED, CHI))
    r = thermoelastic_mesh_stiffness(FZG, [3.3, 35.3, 183.4, 302.0], DELTA_SEED, c_star, CHI)
    np.testing.assert_allclose(r.k_N_per_m, r.k_EP_N_per_m, rtol=1e-12)


# --- regimes, trends and limits (hypothesis) -----------------------------------------------
@settings(max_examples=300, deadline=None)
@given(f1=loads, ratio=st.floats(1.01, 100.0), k=stiffnesses, delta=closures, c=backlashes,
       chi=chis)
def test_regime_predicts_how_stiffness_changes_with_load(f1, ratio, k, delta, c, chi):
    c_star = (1 - chi) * delta
    assume(abs(c - c_star) > 1e-9)
    assume(f1 + k * (c - c_star) > 1e-3 * f1)  # not jammed, not at the pole
    f2 = f1 * ratio
    r = thermoelastic_stiffness([f1, f2], k, k * 1e3, delta, c, chi)  # any split of k_EP
    k_ep = float(r.k_EP_N_per_m[0])
    k1_, k2_ = r.k_N_per_m
    regime = int(stiffness_regime(c, delta, chi))
    if regime == RISES:
        assert k1_ < k2_ < k_ep
    else:
        assert regime == FALLS
        assert k1_ > k2_ > k_ep


@settings(max_examples=200, deadline=None)
@given(f=loads, k=stiffnesses, delta=closures, chi=chis, c=backlashes)
def test_stiffness_saturates_at_k_EP_as_load_grows(f, k, delta, chi, c):
    r = thermoelastic_stiffness([f * 1e6, f * 1e12, f * 1e15], k, k, delta, c, chi)
    gap = np.abs(r.k_N_per_m / r.k_EP_N_per_m - 1)
    assert gap[2] <= gap[1] + 1e-15 and gap[1] <= gap[0] + 1e-15
    assert gap[1] < 1e-5


@settings(max_examples=200, deadline=None)
@given(f=loads, k=stiffnesses, delta=closures, chi=chis, c=backlashes,
       dc=st.floats(1e-8, 100e-6))
def test_stiffness_falls_as_backlash_grows(f, k, delta, chi, c, dc):
    r = thermoelastic_stiffness(f, k, k, delta, [c, c + dc], chi)
    assume(not r.any_jammed)
    assert r.k_N_per_m[1] < r.k_N_per_m[0]
    assert r.k_elastic_N_per_m[1] < r.k_elastic_N_per_m[0]


@settings(max_examples=200, deadline=None)
@given(f=loads, k1=stiffnesses, k2=stiffnesses, delta=closures, chi=chis, c=backlashes)
def test_limits_c_zero_delta_zero_chi_one(f, k1, k2, delta, chi, c):
    # c = 0 and Delta = 0: the elastic stiffness, load independent
    r = thermoelastic_stiffness(f, k1, k2, 0.0, 0.0, chi)
    np.testing.assert_allclose(r.k_N_per_m, r.k_EP_N_per_m, rtol=1e-14)
    assert int(stiffness_regime(0.0, 0.0, chi)) == UNCHANGED
    # Delta = 0: Eq. (2), rising for any c > 0
    r = thermoelastic_stiffness(f, k1, k2, 0.0, c, chi)
    np.testing.assert_allclose(r.k_N_per_m, r.k_elastic_N_per_m, rtol=1e-14)
    np.testing.assert_allclose(r.k_elastic_N_per_m,
                               elastic_backlash_stiffness(f, r.k_EP_N_per_m, c), rtol=1e-14)
    assert int(stiffness_regime(c, 0.0, chi)) == (RISES if c > 1e-12 else UNCHANGED)
    # chi = 1: the coupling gives the whole thermal growth back
    r = thermoelastic_stiffness(f, k1, k2, delta, c, 1.0)
    np.testing.assert_allclose(r.k_N_per_m, r.k_elastic_N_per_m, rtol=1e-14)
    assert float(critical_gap(delta, 1.0)) == 0.0


@settings(max_examples=200, deadline=None)
@given(f=loads, k=stiffnesses, delta=st.floats(1e-9, 50e-6), chi=st.floats(0.0, 0.99),
       c=backlashes)
def test_thermal_closure_raises_stiffness_above_the_elastic_one(f, k, delta, chi, c):
    """Seed 000: "thermoelastic coupling stiffness is generally higher than pure elastic"."""
    r = thermoelastic_stiffness(f, k, k, delta, c, chi)
    assume(not r.any_jammed)
    assert r.k_N_per_m > r.k_elastic_N_per_m


def test_regime_codes_table_5():
    c_star = float(critical_gap(DELTA_SEED, CHI))
    got = stiffness_regime([0.0, 5e-6, c_star, 20e-6], DELTA_SEED, CHI)
    assert got.tolist() == [FALLS, FALLS, UNCHANGED, RISES]
    assert got.dtype == np.int8
    assert stiffness_regime([[0.0], [1e-5]], [0.0, 2e-5], 0.0).shape == (2, 2)


# --- validity: the jammed state (SEED-NOTES 10) --------------------------------------------
def test_scalar_api_raises_a_structured_error_when_jammed():
    k, delta, c = 4e8, 10e-6, 2e-6
    c_star = (1 - CHI) * delta
    f_edge = k * (c_star - c)  # denominator exactly zero
    with pytest.raises(ThermalJamError, match=r"jammed by thermal growth.*both flanks") as info:
        thermoelastic_pair_stiffness(f_edge * 0.5, k, delta, c, CHI)
    err = info.value
    assert isinstance(err, ModelError) and isinstance(err, ValueError)
    assert err.interference_m == pytest.approx(c_star - c)
    assert err.net_deflection_m < 0
    again = pickle.loads(pickle.dumps(err))
    assert type(again) is ThermalJamError and str(again) == str(err)
    with pytest.raises(ThermalJamError, match="jammed"):
        thermoelastic_pair_stiffness(f_edge, k, delta, c, CHI)
    assert thermoelastic_pair_stiffness(f_edge * 1.5, k, delta, c, CHI) > k


def test_scalar_api_refuses_arrays():
    with pytest.raises(ModelError, match=r"`normal_load_N` must be a scalar"):
        thermoelastic_pair_stiffness(np.array([1.0, 2.0]), 4e8, 0.0, 0.0)


@settings(max_examples=300, deadline=None)
@given(f=st.floats(1e-3, 1e6), k1=stiffnesses, k2=stiffnesses, delta=closures,
       c=backlashes, chi=chis)
def test_vectorised_api_never_returns_negative_or_infinite_stiffness(f, k1, k2, delta, c, chi):
    r = thermoelastic_stiffness(f, k1, k2, delta, c, chi)
    den = f - (1 - chi) * float(r.k_EP_N_per_m) * delta + c * float(r.k_EP_N_per_m)
    if r.jammed:
        assert math.isnan(float(r.k_N_per_m))
        assert float(r.net_deflection_m) <= 0
        assert float(r.k_double_flank_N_per_m) == 2 * float(r.k_EP_N_per_m)
    else:
        assert np.isfinite(r.k_N_per_m) and r.k_N_per_m > 0
        assert den > -1e-9 * f  # agrees with the printed denominator up to round-off
    for v in (r.k1_prime_N_per_m, r.k2_prime_N_per_m, r.k_elastic_N_per_m):
        assert math.isnan(float(v)) or (math.isfinite(float(v)) and float(v) > 0)


def test_vectorised_api_marks_the_exact_pole_as_jammed_and_can_raise():
    k, delta, c = 4e8, 10e-6, 0.0
    f_edge = k * delta  # chi = 0: denominator exactly zero
    r = thermoelastic_stiffness([0.5 * f_edge, f_edge, 2 * f_edge], 2 * k, 2 * k, delta, c, 0.0)
    assert r.jammed.tolist() == [True, True, False]
    assert np.isnan(r.k_N_per_m[:2]).all() and np.isnan(JAMMED_STAND_IN)
    np.testing.assert_allclose(r.k_N_per_m[2], 2 * k * 2 * f_edge / (2 * f_edge), rtol=1e-12)
    with pytest.raises(ThermalJamError, match="jammed"):
        r.raise_if_jammed()


@settings(max_examples=200, deadline=None)
@given(f=st.floats(0.0, 1e5), k=stiffnesses, kb_ratio=st.floats(0.1, 10.0),
       i=st.floats(-50e-6, 50e-6))
def test_double_flank_model_equilibrium_compatibility_and_jam_boundary(f, k, kb_ratio, i):
    kb = k * kb_ratio
    r = double_flank_contact(f, k, i, k_back_N_per_m=kb)
    # the transmitted load, both deflections >= 0
    np.testing.assert_allclose(r.drive_load_N - r.back_load_N, f, rtol=1e-9, atol=1e-9)
    assert r.drive_deflection_m >= 0 and r.back_deflection_m >= 0
    # the back flank is loaded exactly where Eq. (1)'s denominator f + k (c - c*) <= 0
    assert bool(r.double_flank) == (f - k * i < 0)
    if r.double_flank:
        np.testing.assert_allclose(r.drive_deflection_m + r.back_deflection_m, i, rtol=1e-9)
        assert r.tangent_stiffness_N_per_m == k + kb
    else:
        np.testing.assert_allclose(r.drive_deflection_m, f / k, rtol=1e-12)
        assert r.tangent_stiffness_N_per_m == k


def test_double_flank_tangent_stiffness_by_finite_differences_and_continuity():
    k, i = 4e8, 5e-6
    f_edge = k * i
    f = np.linspace(0.0, 2 * f_edge, 2001)
    r = double_flank_contact(f, k, i)
    # rotation-like coordinate: x = drive deflection - i/2 (symmetric split at f = 0)
    x = r.drive_deflection_m - i / 2
    slope = np.diff(f) / np.diff(x)
    below = f[1:] < 0.99 * f_edge
    above = f[:-1] > 1.01 * f_edge
    np.testing.assert_allclose(slope[below], 2 * k, rtol=1e-6)
    np.testing.assert_allclose(slope[above], k, rtol=1e-6)
    assert np.all(np.abs(np.diff(r.drive_deflection_m)) < 2 * (f[1] - f[0]) / k)  # continuous
    # and Eq. (1) is jammed exactly on the double-flank side
    te = thermoelastic_stiffness(np.maximum(f, 1e-9), 2 * k, 2 * k, i, 0.0, 0.0)
    np.testing.assert_array_equal(te.jammed[f > 0], r.double_flank[f > 0] | (f[f > 0] == f_edge))


def test_invalid_inputs_are_refused_with_the_argument_named():
    with pytest.raises(ModelError, match=r"`backlash_m` must be finite and >= 0"):
        thermoelastic_stiffness(1.0, 1e8, 1e8, 0.0, -1e-6)
    with pytest.raises(ModelError, match=r"`chi` must lie in \[0, 1\], was 1.5"):
        thermoelastic_stiffness(1.0, 1e8, 1e8, 0.0, 0.0, 1.5)
    with pytest.raises(ModelError, match=r"`thermal_closure_m` must be finite"):
        critical_gap(np.inf)
    with pytest.raises(ModelError, match=r"`normal_load_N` must be finite and > 0"):
        thermoelastic_stiffness(0.0, 1e8, 1e8, 0.0, 0.0)
    with pytest.raises(ModelError, match=r"`pinion_backlash_share` must lie in \[0, 1\]"):
        thermoelastic_stiffness(1.0, 1e8, 1e8, 0.0, 0.0, pinion_backlash_share=2.0)
    with pytest.raises(ModelError, match=r"`thermal_closure_m` must have the 52 positions"):
        thermoelastic_mesh_stiffness(FZG, 100.0, np.zeros(3), 0.0, closure_along_path=True)


# --- the path, the load distribution and the FZG-C statements of seed 000 -------------------
def test_mesh_stiffness_uses_the_exact_normal_load_and_the_seed_load_share():
    s = contact_path_positions(FZG)
    r = thermoelastic_mesh_stiffness(FZG, [[T_LOW], [T_HIGH]], DELTA_SEED, [0.0, 40e-6], CHI)
    assert r.k_N_per_m.shape == (2, 2, 52)
    expected = np.array([T_LOW, T_HIGH])[:, None] / FZG.base_radius(1) * \
        load_share_seed_000(FZG, s)
    np.testing.assert_allclose(r.normal_load_N[:, 0], expected, rtol=1e-14)
    ks = tooth_pair_stiffness(FZG, s)
    np.testing.assert_allclose(r.k_EP_N_per_m[0, 0], ks.k_EP_N_per_m, rtol=1e-14)
    along = thermoelastic_mesh_stiffness(FZG, T_LOW, np.full(52, DELTA_SEED), 40e-6, CHI,
                                         closure_along_path=True)
    np.testing.assert_allclose(along.k_N_per_m, r.k_N_per_m[0, 1], rtol=1e-14)


def test_fzg_c_critical_gap_is_of_the_order_of_10_um():
    # c* from the physics chain, not from a closure chosen to give it: FZG-C flash temperature
    # at 302 N m / 1500 rpm, thermal closure under the one reference-state reading that
    # reproduces the seed (tests/models/test_thermal_expansion.py shows it is the only one).
    from models.thermal import (
        GearTemperature,
        ThermalReference,
        flash_temperature,
        thermal_deformation,
    )

    s = np.linspace(FZG.start_of_contact, FZG.end_of_contact, 52)
    flash = flash_temperature(FZG, s, 302.0, 1500.0, bulk_temperature_C=90.0)
    ref = ThermalReference(20.0, "follows-oil", oil_temperature_C=90.0,
                           flash_counts_as_local_rise=True)
    closure = thermal_deformation(FZG, s, ref, GearTemperature.uniform(90.0), flash=flash,
                                  expansion_per_K=1.15e-5)
    got = float(critical_gap(float(np.mean(closure.total_m)), SEED_000_CHI))
    assert 5e-6 < got < 20e-6, f"{SRC}: critical compensation gap approximately 10 um"


def test_fzg_c_zero_backlash_elastic_stiffness_is_the_same_at_both_loads():
    """Seed 000: "with zero backlash, the stiffness remains unchanged ... 381.96 and 477.45"."""
    r = thermoelastic_mesh_stiffness(FZG, [T_LOW, T_HIGH], 0.0, 0.0, CHI)
    np.testing.assert_allclose(r.k_N_per_m[0], r.k_N_per_m[1], rtol=1e-14, err_msg=SRC)
    np.testing.assert_allclose(r.k_elastic_N_per_m[0], r.k_elastic_N_per_m[1], rtol=1e-14)


@pytest.mark.parametrize("delta", [0.0, DELTA_SEED], ids=["elastic", "thermoelastic"])
def test_fzg_c_stiffness_falls_as_backlash_grows(delta):
    """Seed 000 Table 4 and conclusion (2): "increasing backlash reduces mesh stiffness"."""
    r = thermoelastic_mesh_stiffness(FZG, [[T_LOW], [T_HIGH]], delta,
                                     np.array(TABLE_4_BACKLASH), CHI)  # (torque, c, position)
    k = r.k_N_per_m if delta else r.k_elastic_N_per_m
    assert not r.any_jammed
    assert np.all(np.diff(k, axis=1) < 0), f"{SRC}: stiffness falls as backlash grows"


def test_fzg_c_table_4_elastic_trends():
    """Table 4: constant at c = 0, rising with load for 10, 40, 100 um, towards a limit."""
    r = thermoelastic_mesh_stiffness(FZG, [T_LOW, T_HIGH, 1e6],
                                     0.0, np.array(TABLE_4_BACKLASH)[:, None], CHI)
    k = r.k_elastic_N_per_m  # (backlash, torque, position)
    np.testing.assert_allclose(k[0, 0], k[0, 1], rtol=1e-14, err_msg=f"{SRC} Table 4, c = 0")
    rise = k[1:, 1] / k[1:, 0] - 1
    assert np.all(rise > 0), f"{SRC} Table 4: stiffness rises with load for c > 0"
    assert np.all(np.diff(rise, axis=0) > 0), f"{SRC} Table 4: more pronounced for more c"
    assert np.all(k[1:] < r.k_EP_N_per_m[1:])
    np.testing.assert_allclose(k[1:, 2], r.k_EP_N_per_m[1:, 2], rtol=0.05,
                               err_msg=f"{SRC} Table 4: approaches the limit k_EP")


def test_fzg_c_table_5_regimes_along_the_path():
    """Table 5: below c* the stiffness falls with load, at c* unchanged, above it rises."""
    c_star = float(critical_gap(DELTA_SEED, CHI))
    backlash = np.array([5e-6, c_star, 40e-6])[:, None]
    r = thermoelastic_mesh_stiffness(FZG, [T_LOW, T_HIGH], DELTA_SEED, backlash, CHI)
    assert not r.any_jammed
    k = r.k_N_per_m
    assert np.all(k[0, 1] < k[0, 0]), f"{SRC} Table 5: c < c*, stiffness decreases"
    np.testing.assert_allclose(k[1, 1], k[1, 0], rtol=1e-12,
                               err_msg=f"{SRC} Table 5: c = c*, stiffness unchanged")
    assert np.all(k[2, 1] > k[2, 0]), f"{SRC} Table 5: c > c*, stiffness increases"
    assert stiffness_regime(backlash[:, 0], DELTA_SEED, CHI).tolist() == [
        FALLS, UNCHANGED, RISES]


def test_weber_contact_term_is_evaluated_at_each_positions_load():
    r = thermoelastic_mesh_stiffness(FZG, [T_LOW, T_HIGH], 0.0, 0.0, CHI,
                                     include_hertz="weber")
    assert np.all(r.k_EP_N_per_m[1] > r.k_EP_N_per_m[0])  # Weber stiffens with load

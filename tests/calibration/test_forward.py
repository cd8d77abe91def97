"""Forward models against models.thermal's scalar reference and hand limits (seed 000)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from models.geometry import GearPair
from models.thermal import (
    SEED_000_CHI,
    ThermalReference,
    mesh_natural_frequency,
    mesh_natural_frequency_scalar,
    prepare_natural_frequency,
)
from rigtools.calibration.forward import closure_basis, predict, prepare_forward

TORQUES = np.array([3.3, 35.3, 100.0, 183.4, 302.0])
TEMPS = np.array([32.0, 42.0, 60.0, 90.0, 90.0])


@pytest.fixture(scope="module")
def nf(pair: GearPair) -> object:
    return prepare_natural_frequency(pair)


def _freq(fm: object, c_um: float, kappa: float, s: float = 1.0,
          chi: float = SEED_000_CHI) -> np.ndarray:
    return predict(fm, [c_um * 1e-6], [kappa], [s], [chi]).f_n_Hz[0]


@pytest.mark.parametrize("c_um", [5.0, 10.0, 20.0, 40.0, 100.0])
@pytest.mark.parametrize("kappa", [0.0, 0.2, 0.37])
def test_secant_path_equals_the_scalar_reference(pair: GearPair, nf: object, c_um: float,
                                                 kappa: float) -> None:
    fm = prepare_forward(pair, TORQUES, TEMPS)
    got = _freq(fm, c_um, kappa)
    closure = kappa * fm.closure.run_m
    for i, t in enumerate(TORQUES):
        try:
            ref = mesh_natural_frequency_scalar(nf, t, closure[i], c_um * 1e-6)
        except ValueError:  # ThermalJamError: jammed, censored here
            assert math.isnan(got[i])
            continue
        assert got[i] == pytest.approx(ref, rel=1e-12), \
            f"seed 000 Eq. (1) along the path: c = {c_um} um, T = {t} N m"


def test_double_flank_equals_models_thermal(pair: GearPair, nf: object) -> None:
    fm = prepare_forward(pair, TORQUES, TEMPS, jammed_model="double_flank")
    got = _freq(fm, 0.5, 1.2)
    closure = 1.2 * fm.closure.run_m
    ref = mesh_natural_frequency(nf, TORQUES, closure, 0.5e-6,
                                 jammed_model="double_flank").f_n_Hz
    np.testing.assert_allclose(got, ref, rtol=1e-12)
    assert predict(fm, [0.5e-6], [1.2], [1.0], [SEED_000_CHI]).jammed[0].any()


def test_stiffness_scale_sits_inside_eq_1(pair: GearPair) -> None:
    """``k = sum_j s w_j k_EP,j / (1 + (u / F) s k_EP,j / R_j)``, by hand."""
    fm = prepare_forward(pair, TORQUES, TEMPS)
    s, c, kappa = 0.8, 15e-6, 0.3
    u = c - (1 - SEED_000_CHI) * kappa * fm.closure.run_m
    k = np.array([np.sum(s * fm.a_N_per_m / (1 + (u[i] / fm.normal_load_N[i]) * s
                                             * fm.q_N_per_m)) for i in range(TORQUES.size)])
    ref = np.sqrt(k / fm.equivalent_mass_kg) / (2 * math.pi)
    np.testing.assert_allclose(_freq(fm, 15.0, kappa, s), ref, rtol=1e-12)


def test_secant_mesh_by_hand(pair: GearPair) -> None:
    fm = prepare_forward(pair, TORQUES, TEMPS, variant="secant_mesh")
    s, c, kappa = 1.2, 30e-6, 0.37
    km = fm.k_mesh_N_per_m
    u = c - (1 - SEED_000_CHI) * kappa * fm.closure.run_m
    k = fm.normal_load_N * s * km / (fm.normal_load_N + u * s * km)
    np.testing.assert_allclose(_freq(fm, 30.0, kappa, s),
                               np.sqrt(k / fm.equivalent_mass_kg) / (2 * math.pi), rtol=1e-12)


def test_tangent_is_backlash_free(pair: GearPair, nf: object) -> None:
    fm = prepare_forward(pair, TORQUES, TEMPS, variant="tangent")
    a = _freq(fm, 0.0, 0.0, 0.9)
    b = _freq(fm, 80.0, 1.4, 0.9)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_allclose(a, nf.elastic_natural_frequency_Hz * math.sqrt(0.9), rtol=1e-12)


@pytest.mark.parametrize("variant", ["secant_path", "secant_mesh", "tangent"])
def test_at_the_critical_gap_every_variant_is_load_independent(pair: GearPair, nf: object,
                                                              variant: str) -> None:
    """Seed 000 Table 5: c = c* gives k = k_EP at every load (here: s k_EP)."""
    fm = prepare_forward(pair, TORQUES, np.full(TORQUES.shape, 90.0), variant=variant)
    kappa, s = 0.37, 1.1
    c_star = (1 - SEED_000_CHI) * kappa * fm.closure.run_m[0]
    f = _freq(fm, c_star * 1e6, kappa, s)
    np.testing.assert_allclose(f, nf.elastic_natural_frequency_Hz * math.sqrt(s), rtol=1e-9)


@pytest.mark.parametrize("variant", ["secant_path", "secant_mesh"])
def test_high_load_limit_is_the_tangent(pair: GearPair, nf: object, variant: str) -> None:
    fm = prepare_forward(pair, [1e9], [20.0], variant=variant)
    assert _freq(fm, 40.0, 0.0)[0] == pytest.approx(nf.elastic_natural_frequency_Hz, rel=1e-6)


def test_equivalent_mass_override_scales_f_by_the_root(pair: GearPair) -> None:
    a = prepare_forward(pair, TORQUES, TEMPS)
    b = prepare_forward(pair, TORQUES, TEMPS, equivalent_mass_kg=2.0 * a.equivalent_mass_kg)
    np.testing.assert_allclose(_freq(b, 20.0, 0.3), _freq(a, 20.0, 0.3) / math.sqrt(2.0),
                               rtol=1e-13)
    assert b.equivalent_mass_basis == "given" and a.equivalent_mass_basis == "operating-disc"
    c = prepare_forward(pair, TORQUES, TEMPS, disc_radius="reference")
    assert c.equivalent_mass_kg < a.equivalent_mass_kg


@pytest.mark.parametrize("variant", ["secant_path", "secant_mesh"])
@pytest.mark.parametrize("lam", [0.7, 1.06, 1.5])
def test_mass_stiffness_backlash_symmetry(pair: GearPair, variant: str, lam: float) -> None:
    """(m_e, s, c, Delta) -> (lam m_e, lam s, c / lam, Delta / lam) leaves f_n unchanged."""
    a = prepare_forward(pair, TORQUES, TEMPS, variant=variant)
    b = prepare_forward(pair, TORQUES, TEMPS, variant=variant,
                        equivalent_mass_kg=lam * a.equivalent_mass_kg)
    np.testing.assert_allclose(_freq(b, 20.0 / lam, 0.37 / lam, 0.9 * lam),
                               _freq(a, 20.0, 0.37, 0.9), rtol=1e-12)


def test_jam_boundary_is_exact(pair: GearPair) -> None:
    """secant_path jams where (u / F) s max(k_EP / R) <= -1, censored as NaN."""
    fm = prepare_forward(pair, [10.0], [90.0])
    kappa, s = 0.37, 1.0
    c_star = (1 - SEED_000_CHI) * kappa * fm.closure.run_m[0]
    c_edge = c_star - fm.normal_load_N[0] / (s * fm.q_max_N_per_m)
    inside = predict(fm, [c_edge - 1e-12], [kappa], [s], [SEED_000_CHI])
    outside = predict(fm, [c_edge + 1e-12], [kappa], [s], [SEED_000_CHI])
    assert inside.jammed[0, 0] and math.isnan(inside.f_n_Hz[0, 0])
    assert not outside.jammed[0, 0] and outside.f_n_Hz[0, 0] > 1e5   # the secant diverges


def test_linear_closure_and_the_expansion_model_agree_at_fixed_centre_distance(
        pair: GearPair, nf: object) -> None:
    ref = ThermalReference(20.0)
    lin = closure_basis(pair, TEMPS, model="linear", reference=ref)
    exp = closure_basis(pair, TEMPS, model="expansion", reference=ref, s_m=nf.s_m,
                        weights=nf.weights)
    np.testing.assert_allclose(exp.run_m, lin.run_m, rtol=1e-9)
    assert lin.run_m[3] == pytest.approx(1.15e-5 * 70.0 * pair.line_of_action_length, rel=1e-12)
    assert exp.line_slope_m_per_K == pytest.approx(lin.line_slope_m_per_K, rel=1e-9)


def test_housing_following_the_oil_removes_the_closure_of_gears_at_oil_temperature(
        pair: GearPair) -> None:
    ref = ThermalReference(20.0, "follows-oil", oil_temperature_C=20.0)
    b = closure_basis(pair, TEMPS, model="expansion", reference=ref, oil_temperature_C=TEMPS)
    np.testing.assert_allclose(b.run_m, 0.0, atol=1e-15)
    hot = closure_basis(pair, TEMPS, model="expansion", reference=ref,
                        oil_temperature_C=TEMPS - 10.0)
    np.testing.assert_allclose(hot.run_m, 1.15e-5 * 10.0 * pair.line_of_action_length,
                               rtol=1e-9)

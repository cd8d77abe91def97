"""Mixed EHL building blocks of seed 002 (``models.ehl``).

Sources of the expected numbers:

* Moes' line-contact formula tends to its four published asymptotes (Moes 1992; Venner &
  Lubrecht 2000): Martin's rigid-isoviscous ``H = 3/M`` (the central film, 1.225 x Martin's
  minimum 4.9 U/W), Herrebrugh's elastic-isoviscous ``2.621 M^-1/5``, Blok's rigid-piezoviscous
  ``1.287 L^2/3``, Ertel-Grubin's elastic-piezoviscous ``1.311 M^-1/8 L^3/4``
  (``h/R = 2^(3/4) 1.311 (GU)^(3/4) W^(-1/8)``); at a typical gear state it agrees with the
  Dowson-Toyoda central film ``3.06 G^0.56 U^0.69 W^-0.1`` (as given on tribonet.org's "EHL
  film thickness calculator: line contact" page) within 25 %, and the Pan-Hamrock fit of
  numerical solutions within 40 %;
* Greenwood-Tripp ``F_n``: ``scipy.integrate.quad`` of the defining integral, and the closed
  form ``F_2 = (1 + t^2) F_0 - t phi``;
* Doolittle-Tait: ``mu(0, T_R) = mu_R`` by construction;
* the aerospace pair of seed 002 (aerospace-28, 2000 rpm, 71.8 N m, single-pair load
  ``T / r_b1 = 1719 N``, T_in = T_R): regression numbers printed by this module's functions
  (isothermal Moes film 7.27 um, C_t 0.495, h_c 3.60 um at the pitch point).
"""

import math

import numpy as np
import pytest
from scipy.integrate import quad

from models.ehl import (
    SEED_002_LUBRICANT,
    Roughness,
    asperity_pressure,
    central_film_thickness,
    film_parameter,
    film_stiffness,
    greenwood_tripp_integral,
    mixed_contact,
    mixed_contact_along_path,
    moes_central_film,
    moes_groups,
    thermal_reduction_factor,
)
from models.geometry import load_gear_set

E_PRIME = 207e9 / (1 - 0.3**2)


@pytest.fixture(scope="module")
def aero():
    return load_gear_set("aerospace-28").pair


# --- Moes ---------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("M", "L", "asymptote"),
    [
        (1e-3, 0.0, lambda M, L: 3 / M),  # rigid-isoviscous
        (1e6, 0.0, lambda M, L: 2.621 * M**-0.2),  # elastic-isoviscous
        (1e-2, 1e5, lambda M, L: 1.287 * L ** (2 / 3)),  # rigid-piezoviscous
        (1e8, 1e2, lambda M, L: 1.311 * M**-0.125 * L**0.75),  # elastic-piezoviscous
    ],
)
def test_moes_tends_to_published_asymptotes(M, L, asymptote):
    assert moes_central_film(M, L) == pytest.approx(asymptote(M, L), rel=0.02)


def test_moes_ertel_grubin_in_dowson_groups():
    # deep elastic-piezoviscous: M = 1e6, L = 100 (groups chosen for the regime, not a gear)
    U = 1e-14
    G, W = 100 / (2 * U) ** 0.25, 1e6 * math.sqrt(2 * U)
    M, L = moes_groups(U, G, W)
    h_R = moes_central_film(M, L) * math.sqrt(2 * U)
    grubin = 2**0.75 * 1.311 * (G * U) ** 0.75 * W**-0.125
    assert h_R == pytest.approx(grubin, rel=0.05)


def test_moes_close_to_dowson_toyoda_at_gear_conditions():
    U, G, W = 1e-11, 5000.0, 1e-4
    M, L = moes_groups(U, G, W)
    h_R = moes_central_film(M, L) * math.sqrt(2 * U)
    assert h_R == pytest.approx(3.06 * G**0.56 * U**0.69 * W**-0.1, rel=0.25)


def test_moes_vectorised_and_isothermal_switch():
    w = np.array([1e5, 2e5, 4e5])
    st = central_film_thickness(w, 8e-3, 10.0, 8.0, E_PRIME, thermal=False)
    assert st.h_c_m.shape == (3,) and np.all(np.diff(st.h_c_m) < 0)
    np.testing.assert_allclose(st.C_t, 1.0)
    assert thermal_reduction_factor(4000, 1e-4, 0.0, 0.0) == 1.0
    assert (
        thermal_reduction_factor(4000, 1e-4, 10.0, 1.0)
        < thermal_reduction_factor(4000, 1e-4, 10.0, 0.0)
        < 1
    )


def test_aerospace_pair_magnitude(aero):
    F = 71.8 / aero.base_radius(1)
    s = aero.pitch_point
    r1, r2 = aero.curvature_radii(s)
    u1, u2 = aero.surface_velocities(s, 2000.0)
    st = central_film_thickness(F / aero.face_width_m, r1 * r2 / (r1 + r2), u1, u2, E_PRIME)
    assert F == pytest.approx(1719.0, rel=1e-3)
    assert st.h_iso_m == pytest.approx(7.27e-6, rel=0.01)
    assert st.C_t == pytest.approx(0.495, rel=0.01)
    assert 0.1e-6 < st.h_c_m < 10e-6
    assert st.h_c_m == pytest.approx(3.60e-6, rel=0.01)
    lam = film_parameter(st.h_c_m, 0.4e-6, 0.4e-6)
    assert lam == pytest.approx(3.60 / (0.4 * math.sqrt(2)), rel=0.01)


def test_film_stiffness_is_minus_dF_dh(aero):
    F, B = 1719.0, aero.face_width_m
    args = (7.6e-3, 9.3, 9.3, E_PRIME)
    k = film_stiffness(F, B, *args)
    h = [central_film_thickness(f / B, *args).h_c_m for f in (0.95 * F, 1.05 * F)]
    assert k == pytest.approx(-(0.1 * F) / (h[1] - h[0]), rel=0.01)
    assert 1e8 < k < 1e11


# --- lubricant ----------------------------------------------------------------------------
def test_viscosity_reference_state():
    lub = SEED_002_LUBRICANT
    assert lub.viscosity(0.0, lub.T_ref_K) == pytest.approx(lub.mu_ref_Pas, rel=1e-12)
    mu = lub.viscosity([0.0, 0.5e9, 1e9], lub.T_ref_K)
    assert np.all(np.diff(mu) > 0)
    assert lub.viscosity(0.0, 373.15) < lub.mu_ref_Pas < lub.viscosity(0.0, 323.15)
    assert lub.temperature_viscosity_coefficient(lub.T_ref_K) == pytest.approx(0.0406, rel=0.01)


def test_carreau_limits():
    lub = SEED_002_LUBRICANT
    assert lub.effective_viscosity(1.0, 1e-3) == pytest.approx(1.0, rel=1e-9)
    mu, rate = 1.0, 1e8  # mu rate / G_cr >> 1: power law mu^n G^(1-n) rate^(n-1)
    power = mu**lub.n_power * lub.G_cr_Pa ** (1 - lub.n_power) * rate ** (lub.n_power - 1)
    assert lub.effective_viscosity(mu, rate) == pytest.approx(power, rel=1e-6)


# --- Greenwood-Tripp ----------------------------------------------------------------------
def _F_quad(n, t):
    return quad(lambda s: (s - t) ** n * math.exp(-s * s / 2), t, np.inf, epsabs=0, epsrel=1e-12)[
        0
    ] / math.sqrt(2 * math.pi)


@pytest.mark.parametrize("n", [0.0, 1.0, 1.5, 2.0, 2.5])
def test_greenwood_tripp_integrals_against_quad(n):
    t = np.array([-2.0, -0.5, 0.0, 0.7, 1.5, 3.0, 4.0])
    expected = [_F_quad(n, x) for x in t]
    np.testing.assert_allclose(greenwood_tripp_integral(n, t), expected, rtol=1e-8)


def test_greenwood_tripp_F2_closed_form():
    t = np.linspace(-3, 4, 15)
    phi = np.exp(-t * t / 2) / math.sqrt(2 * math.pi)
    F0 = 0.5 * np.array([math.erfc(x / math.sqrt(2)) for x in t])
    expected = (1 + t * t) * F0 - t * phi
    np.testing.assert_allclose(greenwood_tripp_integral(2, t), expected, rtol=1e-9)


# --- load sharing and friction ------------------------------------------------------------
def test_load_split_balances_asperity_share():
    rough = Roughness(sigma_1_m=1.5e-6, sigma_2_m=1.5e-6)
    w = np.array([1e5, 3e5])
    mc = mixed_contact(w, 8e-3, 3.0, 2.0, E_PRIME, roughness=rough)
    share = 1 / mc.gamma_2
    np.testing.assert_allclose(1 / mc.gamma_1 + share, 1.0)
    assert np.all((share > 0.01) & (share < 1))
    np.testing.assert_allclose(
        share * w,
        2 * mc.hertz_half_width_m * asperity_pressure(mc.h_c_m, E_PRIME, rough),
        rtol=1e-6,
    )
    np.testing.assert_allclose(mc.film_parameter, mc.h_c_m / rough.sigma_m)


def test_friction_changes_sign_at_pitch_point(aero):
    p = aero.pitch_point
    s = np.array([aero.start_of_contact, p - 1e-3, p, p + 1e-3, aero.end_of_contact])
    mc = mixed_contact_along_path(aero, s, 2000.0, 71.8 / aero.base_radius(1))
    f = mc.friction
    assert f[0] < 0 and f[1] < 0 and f[3] > 0 and f[4] > 0
    assert abs(f[2]) < 1e-9
    assert np.all(np.abs(f) < 0.2)


# --- additions: published magnitudes and robustness -----------------------------------------
def _moes_naive(M, L):
    """Moes' formula written out directly (no logarithms), for moderate M and L."""
    H_RI, H_EI = 3.0 / M, 2.621 * M**-0.2
    H_RP, H_EP = 1.287 * L ** (2 / 3), 1.311 * M**-0.125 * L**0.75
    s = 1.5 * (1 + math.exp(-1.2 * H_EI / H_RI))
    iso = (H_RI ** (7 / 3) + H_EI ** (7 / 3)) ** (3 * s / 7)
    piezo = (H_RP**-3.5 + H_EP**-3.5) ** (-2 * s / 7)
    return (iso + piezo) ** (1 / s)


@pytest.mark.parametrize(("M", "L"), [(0.5, 2.0), (5.0, 8.0), (22.4, 10.6), (300.0, 15.0)])
def test_moes_log_form_equals_the_direct_formula(M, L):
    assert moes_central_film(M, L) == pytest.approx(_moes_naive(M, L), rel=1e-12)


def test_moes_light_load_limit_is_finite():
    # M -> 0: rigid-isoviscous 3/M; the direct powers overflow there, the log form does not
    H = moes_central_film(np.array([1e-300, 1e-200]), np.array([10.0, 10.0]))
    np.testing.assert_allclose(H, [3e300, 3e200], rtol=1e-12)


@pytest.mark.parametrize(
    ("U", "G", "W"),
    [(1e-11, 5000.0, 1e-4), (1e-11, 4000.0, 5e-5), (5e-11, 4500.0, 2e-4), (1e-10, 5000.0, 1e-4)],
)
def test_moes_against_pan_hamrock_central_film(U, G, W):
    """Moes against the Pan-Hamrock fit of numerical line-contact solutions.

    Pan & Hamrock (1989, ASME J. Tribol. 111, 246-251): ``h_c/R = 2.922 W^-0.166 U^0.692
    G^0.470``. Moes (an asymptotic composite) lies 18-34 % above it at these gear conditions;
    the bound is 40 %.
    """
    M, L = moes_groups(U, G, W)
    h_R = moes_central_film(M, L) * math.sqrt(2 * U)
    ph = 2.922 * W**-0.166 * U**0.692 * G**0.470
    assert 1.0 < h_R / ph < 1.4


def test_greenwood_tripp_F52_at_zero_separation_closed_form():
    # F_n(0) = 2^(n/2 - 1/2) Gamma((n + 1)/2) / sqrt(2 pi); n = 5/2: 0.616634...
    expected = 2**0.75 * math.gamma(1.75) / math.sqrt(2 * math.pi)
    assert greenwood_tripp_integral(2.5, np.array([0.0]))[0] == pytest.approx(expected, rel=1e-10)

"""Potential-energy tooth-pair compliance against quadrature, hand limits, symmetry and ISO 6336.

Sources named in each test. The independent implementation below shares no code with
``models.stiffness.potential_energy``: it builds the tooth in the *radius* variable from the ISO
21771 tooth-thickness function, takes the load angle as ``alpha_k - psi_k`` and the moment arm
directly as ``cos(tau)(y_P - y) - sin(tau) x_P``, and integrates with adaptive
``scipy.integrate.quad``; the module integrates in the roll angle with a composite Gauss rule on
beam moments.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from scipy.integrate import quad

from models.errors import GeometryError, ModelError
from models.geometry import Gear, GearPair, load_gear_set
from models.stiffness import potential_energy as pe
from models.stiffness.hertz import contact_modulus, hertz_compliance, hertz_stiffness
from models.stiffness.potential_energy import (
    pair_compliance,
    pair_stiffness,
    tooth_compliance,
    tooth_stiffness,
)

DEG = math.pi / 180
#: N/m per m of face width -> N/(mm um)
PER_MM_UM = 1e-9


def _pair(name: str) -> GearPair:
    return load_gear_set(name).pair


def _shifted_pair() -> GearPair:
    """A profile-shifted pair with root circles below the base circles and unequal gears."""
    return GearPair(Gear(19, 0.35), Gear(37, -0.2), 3e-3, 20 * DEG, 16e-3)


def _independent_beam(pair: GearPair, gear: int, s: float) -> tuple[float, float, float]:
    """Bending, shear, axial compliance (m/N) by adaptive quadrature in the radius variable."""
    g = pair.pinion if gear == 1 else pair.wheel
    z, xs, a0, m = g.teeth, g.profile_shift, pair.pressure_angle_rad, pair.module_m
    r_b = z * m / 2 * math.cos(a0)
    r_f, r_a = pair.root_radius(gear), pair.tip_radius(gear)
    e, nu, b = g.material.youngs_modulus_Pa, g.material.poisson_ratio, pair.face_width_m
    gs = e / (2 * (1 + nu))

    def inv_(a: float) -> float:
        return math.tan(a) - a

    def psi(r: float) -> float:  # half tooth angle at radius r (ISO 21771 thickness s/(2r))
        return math.pi / (2 * z) + 2 * xs * math.tan(a0) / z + inv_(a0) \
            - inv_(math.acos(min(1.0, r_b / r)))

    rho = s if gear == 1 else pair.centre_distance * math.sin(pair.operating_pressure_angle) - s
    r_low = max(r_b, r_f)  # beyond T (rho < 0) the contact is held at the base circle
    r_p = min(max(math.hypot(r_b, max(rho, 0.0)), r_low), r_a)
    tau = math.acos(r_b / r_p) - psi(r_p)
    x_p, y_p = r_p * math.sin(psi(r_p)), r_p * math.cos(psi(r_p))
    c, sn = math.cos(tau), math.sin(tau)

    def parts(x: float, y: float) -> tuple[float, float, float]:
        arm = c * (y_p - y) - sn * x_p
        return (arm**2 / (e * 2 * x**3 * b / 3), 1.2 * c * c / (gs * 2 * x * b),
                sn * sn / (e * 2 * x * b))

    def involute(r: float, k: int) -> float:
        p = psi(r)
        x, y = r * math.sin(p), r * math.cos(p)
        dy_dr = math.cos(p) + math.sin(p) * math.tan(math.acos(min(1.0, r_b / r)))
        return parts(x, y)[k] * dy_dr

    kw = {"epsabs": 0.0, "epsrel": 1e-12, "limit": 400}
    out = [quad(involute, r_low, r_p, args=(k,), **kw)[0] for k in range(3)]
    if r_f < r_b:  # straight flank of the base-circle half chord, root circle to base circle
        h = r_b * math.sin(psi(r_b))
        y0, y1 = math.sqrt(r_f**2 - h**2), r_b * math.cos(psi(r_b))
        for k in range(3):
            out[k] += quad(lambda y, k=k: parts(h, y)[k], y0, y1, **kw)[0]
    return out[0], out[1], out[2]


# ------------------------------------------------------------------------------------------
# closed forms and Gauss against slow quadrature
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["fzg-c", "kahraman-blankenship", "two-stage-45-steel",
                                  "shifted"])
def test_beam_terms_match_independent_quadrature(name):
    # The brief asks 1e-6 relative against scipy.integrate.quad of the same energy integrals;
    # the composite Gauss rule reaches ~1e-13, asserted at 1e-9. Positions span the path of
    # contact and beyond both ends (clamped), on both teeth; the two-stage wheel (z = 60) has
    # its root circle above the base circle, the others below.
    pair = _shifted_pair() if name == "shifted" else _pair(name)
    lo, hi = pair.start_of_contact, pair.end_of_contact
    s = np.concatenate([np.linspace(lo, hi, 7), [lo - 0.3 * (hi - lo), hi + 0.3 * (hi - lo)]])
    for gear in (1, 2):
        c = tooth_compliance(pair, s, gear)
        for i, si in enumerate(s):
            ref = _independent_beam(pair, gear, float(si))
            got = (c.bending_m_per_N[i], c.shear_m_per_N[i], c.axial_m_per_N[i])
            np.testing.assert_allclose(
                got, ref, rtol=1e-9, atol=1e-30,
                err_msg=f"{name} gear {gear} s={si:.6g}: Gauss vs independent quad")


def test_module_quad_mode_and_node_convergence_agree_with_default():
    pair = _pair("fzg-c")
    s = np.linspace(pair.start_of_contact, pair.end_of_contact, 4)
    g = pair_compliance(pair, s)
    q = pair_compliance(pair, s, integration="quad")
    fine = pair_compliance(pair, s, n_nodes=24)
    np.testing.assert_allclose(q.total_m_per_N, g.total_m_per_N, rtol=1e-11)
    np.testing.assert_allclose(fine.total_m_per_N, g.total_m_per_N, rtol=1e-11)


def test_rectangular_beam_reduces_to_cantilever_formulas():
    # Timoshenko beam theory: a cantilever of length L, section b x 2h, tip load F normal to
    # the axis deflects F L^3 / (3 E I) (bending) + 1.2 F L / (G A) (shear), I = b (2h)^3 / 12;
    # an axial load F compresses it by F L / (E A). Checked on the closed-form straight-flank
    # moments and on the Gauss moments of a constant-width profile.
    e, nu, b, length, h = 2.06e11, 0.3, 0.02, 6e-3, 2.5e-3
    g = e / (2 * (1 + nu))
    inertia, area = b * (2 * h) ** 3 / 12, 2 * h * b
    closed = pe._flank_moments(length, h)

    def rect(t):
        return np.full_like(t, h), t, np.ones_like(t)

    lo, hi = np.zeros(1), np.full(1, length)
    np.testing.assert_allclose(pe._moment_sums(rect, lo, hi, 0.0, 8)[0], closed, rtol=1e-13)

    # load normal to the axis at the top (tau = 0): arm a = L at the root (y_ref = 0)
    perp = pe._Load(phi=np.zeros(()), cos=np.ones(()), sin=np.zeros(()),
                    clamped=np.zeros((), bool))
    cb, cs, ca = pe._beam_compliance(closed, np.asarray(length), perp, e, g, b)
    assert cb == pytest.approx(length**3 / (3 * e * inertia), rel=1e-13)
    assert cs == pytest.approx(1.2 * length / (g * area), rel=1e-13)
    assert ca == 0.0
    # load along the axis (tau = 90 deg, on the centreline): pure compression
    axial = pe._Load(phi=np.zeros(()), cos=np.zeros(()), sin=np.ones(()),
                     clamped=np.zeros((), bool))
    cb, cs, ca = pe._beam_compliance(closed, np.asarray(0.0), axial, e, g, b)
    assert (cb, cs) == (0.0, 0.0)
    assert ca == pytest.approx(length / (e * area), rel=1e-13)


def test_load_line_is_tangent_to_the_base_circle():
    # Involute geometry: the normal at any involute point is tangent to the base circle, so the
    # load line crosses the tooth centreline at r_b / cos(tau) (the fillet arm u_f + r_f) and
    # the load angle is alpha_k - psi_k (Tian 2004; ISO 6336-3 alpha_Fen at the tip).
    pair = _shifted_pair()
    for gear in (1, 2):
        g = pair.pinion if gear == 1 else pair.wheel
        r_b = pair.base_radius(gear)
        s = np.linspace(pair.start_of_contact, pair.end_of_contact, 5)
        c = tooth_compliance(pair, s, gear)
        r = pair.contact_radius(s, gear)
        alpha = np.arccos(r_b / r)
        psi = (math.pi / (2 * g.teeth) + 2 * g.profile_shift * math.tan(20 * DEG) / g.teeth
               + math.tan(20 * DEG) - 20 * DEG) - (np.tan(alpha) - alpha)
        tau = alpha - psi
        np.testing.assert_allclose(c.load_angle_rad, tau, rtol=0, atol=1e-13)
        x, y = r * np.sin(psi), r * np.cos(psi)
        np.testing.assert_allclose(y - x * np.tan(tau), r_b / np.cos(tau), rtol=1e-13)


def test_fillet_term_is_sainsot_formula_with_load_line_arm():
    # Sainsot, Velex, Duverger (2004): C_f = cos^2 a / (E b) [L (u/S)^2 + M u/S + P (1 + Q tan^2 a)]
    # with u from the root circle to the load line's crossing of the centreline and
    # S = 2 r_f theta_f; theta_f of the straight flank of half-chord r_b sin(theta_b).
    pair = _pair("kahraman-blankenship")
    s = pair.pitch_point
    c = tooth_compliance(pair, s, 1)
    r_b, r_f, z = pair.base_radius(1), pair.root_radius(1), 50
    theta_b = math.pi / (2 * z) + math.tan(20 * DEG) - 20 * DEG
    theta_f = math.asin(r_b * math.sin(theta_b) / r_f)
    h = r_f / (0.3 * 0.150 / 2)  # no bore given: 0.3 d
    lc, mc, pc, qc = pe._SAINSOT @ np.array([1 / theta_f**2, h * h, h / theta_f, 1 / theta_f,
                                             h, 1.0])
    tau = math.tan(20 * DEG) - theta_b  # at the pitch point phi = tan(alpha')
    u = r_b / math.cos(tau) - r_f
    ratio = u / (2 * r_f * theta_f)
    ref = math.cos(tau) ** 2 / (2.06e11 * 0.020) * (lc * ratio**2 + mc * ratio
                                                     + pc * (1 + qc * math.tan(tau) ** 2))
    assert float(c.fillet_m_per_N) == pytest.approx(ref, rel=1e-12)
    # Kahraman's gears lie inside the quoted fit range, FZG-C's 16-tooth pinion does not
    assert not c.fillet_extrapolated
    fzg = _pair("fzg-c")
    assert tooth_compliance(fzg, fzg.pitch_point, 1).fillet_extrapolated
    assert not tooth_compliance(fzg, fzg.pitch_point, 2).fillet_extrapolated


# ------------------------------------------------------------------------------------------
# geometry: root circle, profile shift
# ------------------------------------------------------------------------------------------
def test_root_circle_just_below_and_just_above_base_circle_agree():
    # The straight flank (root below base, Chen and Shao) and the involute-to-root beam (root
    # above base, Liang et al.) must meet continuously as r_f -> r_b: both flank length and
    # theta_f -> theta_b tend to the same limit.
    z, m = 42, 2e-3
    d_b = z * m * math.cos(20 * DEG)
    out = []
    for f in (1 - 1e-9, 1 + 1e-9):
        pair = GearPair(Gear(z, root_diameter_m=d_b * f), Gear(z, root_diameter_m=d_b * f),
                        m, 20 * DEG, 10e-3)
        s = np.linspace(pair.start_of_contact, pair.end_of_contact, 5)
        out.append(pair_compliance(pair, s))
    for part in ("bending_m_per_N", "shear_m_per_N", "axial_m_per_N", "fillet_m_per_N"):
        np.testing.assert_allclose(getattr(out[0].pinion, part), getattr(out[1].pinion, part),
                                   rtol=1e-6, err_msg=part)


def test_profile_shift_enters_the_tooth_thickness():
    # ISO 21771: transverse tooth thickness on the reference circle s = m (pi/2 + 2 x tan(alpha));
    # the involute of the beam must pass through the chord r sin(s / (2 r)) at r = z m / 2.
    for x_s in (-0.3, 0.0, 0.5):
        pair = GearPair(Gear(25, x_s), Gear(40, 0.0), 2e-3, 20 * DEG, 10e-3)
        tooth = pe._tooth(pair, 1, False)
        r = 25 * 2e-3 / 2
        phi_ref = math.tan(20 * DEG)  # roll angle at the reference circle
        x, y, _ = tooth.profile(np.asarray(phi_ref))
        s_ref = 2e-3 * (math.pi / 2 + 2 * x_s * math.tan(20 * DEG))
        assert float(x) == pytest.approx(r * math.sin(s_ref / (2 * r)), rel=1e-13)
        assert math.hypot(float(x), float(y)) == pytest.approx(r, rel=1e-13)
    # a thicker tooth (positive shift) on the same centre distance is stiffer at equal load
    # point radius: compare the pinion compliance at its reference circle
    thin = GearPair(Gear(25, -0.3), Gear(40, 0.3), 2e-3, 20 * DEG, 10e-3)
    thick = GearPair(Gear(25, 0.3), Gear(40, -0.3), 2e-3, 20 * DEG, 10e-3)
    c_thin = tooth_compliance(thin, 25e-3 * math.sin(20 * DEG), 1)
    c_thick = tooth_compliance(thick, 25e-3 * math.sin(20 * DEG), 1)
    assert float(c_thick.bending_m_per_N) < float(c_thin.bending_m_per_N)


# ------------------------------------------------------------------------------------------
# symmetry, shapes, extrapolation
# ------------------------------------------------------------------------------------------
def test_equal_gears_mirror_about_the_middle_of_the_path():
    # Equal gears (Kahraman-Blankenship, seed 003 Table 3): the wheel at T1T2 - s is the pinion
    # at s, and the pair compliance is symmetric about the pitch point, the middle of AE.
    pair = _pair("kahraman-blankenship")
    ell = pair.line_of_action_length
    assert (pair.start_of_contact + pair.end_of_contact) / 2 == pytest.approx(ell / 2, rel=1e-14)
    s = np.linspace(pair.start_of_contact - 1e-3, pair.end_of_contact + 1e-3, 41)
    p1 = tooth_compliance(pair, s, 1)
    w2 = tooth_compliance(pair, ell - s, 2)
    for part in ("bending_m_per_N", "shear_m_per_N", "axial_m_per_N", "fillet_m_per_N"):
        np.testing.assert_allclose(getattr(p1, part), getattr(w2, part), rtol=1e-12)
    c = pair_compliance(pair, s)
    np.testing.assert_allclose(c.total_m_per_N, c.total_m_per_N[::-1], rtol=1e-12)
    np.testing.assert_allclose(c.pinion.total_m_per_N, c.wheel.total_m_per_N[::-1], rtol=1e-12)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(z=st.integers(17, 90), x_s=st.floats(-0.2, 0.6), module_mm=st.floats(1.0, 8.0))
def test_equal_gears_mirror_property(z, x_s, module_mm):
    # Hypothesis: every equal pair is symmetric about the middle of its line of action.
    try:
        pair = GearPair(Gear(z, x_s), Gear(z, x_s), module_mm * 1e-3, 20 * DEG,
                        10 * module_mm * 1e-3)
    except GeometryError:
        assume(False)
        return
    ell = pair.line_of_action_length
    s = np.linspace(pair.start_of_contact, pair.end_of_contact, 9)
    c = pair_compliance(pair, s)
    np.testing.assert_allclose(c.pinion.total_m_per_N, tooth_compliance(pair, ell - s, 2)
                               .total_m_per_N, rtol=1e-11)
    np.testing.assert_allclose(c.total_m_per_N, c.total_m_per_N[::-1], rtol=1e-11)


def test_arbitrary_shapes():
    pair = _pair("fzg-c")
    s = pair.pair_positions(np.linspace(0, 1, 100, endpoint=False), n_pairs=3)
    c = pair_compliance(pair, s)
    assert s.shape == (100, 3)
    for arr in (c.total_m_per_N, c.hertz_m_per_N, c.pinion.bending_m_per_N,
                c.wheel.fillet_m_per_N, c.in_contact_path, c.pinion.clamped):
        assert arr.shape == (100, 3)
    flat = pair_compliance(pair, s.ravel())
    np.testing.assert_allclose(flat.total_m_per_N.reshape(100, 3), c.total_m_per_N, rtol=1e-14)
    cube = pair_compliance(pair, s[:24].reshape(2, 3, 4, 3))
    np.testing.assert_allclose(cube.total_m_per_N.reshape(24, 3), c.total_m_per_N[:24], rtol=1e-14)
    one = pair_compliance(pair, pair.pitch_point)
    assert np.shape(one.total_m_per_N) == ()
    assert pair_stiffness(pair, [pair.pitch_point]) == pytest.approx(1 / one.total_m_per_N)


def test_positions_outside_the_path_are_finite_and_clamped():
    # Corner-contact analysis needs C beyond A and E: finite, positive, continuous, constant on
    # the clamped tooth (its tip corner carries the load), still varying on the mating tooth.
    pair = _pair("fzg-c")
    ell, a, e = pair.line_of_action_length, pair.start_of_contact, pair.end_of_contact
    s = np.linspace(-0.5 * ell, 1.5 * ell, 401)
    c = pair_compliance(pair, s)
    assert np.all(np.isfinite(c.total_m_per_N)) and np.all(c.total_m_per_N > 0)
    np.testing.assert_array_equal(c.in_contact_path, (s >= a) & (s <= e))
    beyond = np.array([e, e + 1e-4, e + 1e-3])
    cb = pair_compliance(pair, beyond)
    assert list(cb.pinion.clamped) == [False, True, True]
    np.testing.assert_allclose(cb.pinion.total_m_per_N, cb.pinion.total_m_per_N[0], rtol=1e-13)
    assert cb.wheel.total_m_per_N[2] < cb.wheel.total_m_per_N[0]  # wheel loaded lower
    below = pair_compliance(pair, [a, a - 1e-4])
    assert list(below.wheel.clamped) == [False, True]
    assert below.wheel.total_m_per_N[1] == pytest.approx(below.wheel.total_m_per_N[0], rel=1e-13)
    # continuity across the tips
    eps = 1e-9
    near = pair_compliance(pair, [e - eps, e + eps, a - eps, a + eps]).total_m_per_N
    assert near[0] == pytest.approx(near[1], rel=1e-6)
    assert near[2] == pytest.approx(near[3], rel=1e-6)


def test_compliance_grows_as_the_load_point_rises_on_a_tooth():
    # Cantilever physics: every term of the pinion grows from A (load near its root) to E (at
    # its tip); the wheel the other way round.
    pair = _pair("kahraman-blankenship")
    s = np.linspace(pair.start_of_contact, pair.end_of_contact, 30)
    c = pair_compliance(pair, s)
    for part in ("bending_m_per_N", "shear_m_per_N", "axial_m_per_N", "fillet_m_per_N"):
        assert np.all(np.diff(getattr(c.pinion, part)) > 0), part
        assert np.all(np.diff(getattr(c.wheel, part)) < 0), part


# ------------------------------------------------------------------------------------------
# Hertz, plane strain, validation
# ------------------------------------------------------------------------------------------
def test_hertz_term_is_yang_sun_linearised_stiffness():
    # Yang and Sun (1985): k_h = pi E b / (4 (1 - nu^2)) for one material.
    e, nu, b = 2.06e11, 0.3, 0.020
    assert hertz_stiffness(b, e, nu) == pytest.approx(math.pi * e * b / (4 * (1 - nu**2)),
                                                      rel=1e-15)
    assert hertz_compliance(b, e, nu, e, nu) == pytest.approx(1 / hertz_stiffness(b, e, nu))
    # two materials through E*: steel on a softer body is softer than steel on steel
    assert contact_modulus(e, nu, 1.1e11, 0.34) < contact_modulus(e, nu)
    pair = _pair("kahraman-blankenship")
    s = np.linspace(pair.start_of_contact, pair.end_of_contact, 5)
    with_h, without = pair_compliance(pair, s), pair_compliance(pair, s, include_hertz=False)
    np.testing.assert_allclose(with_h.hertz_m_per_N, 4 * (1 - nu**2) / (math.pi * e * b))
    np.testing.assert_allclose(with_h.total_m_per_N - without.total_m_per_N,
                               with_h.hertz_m_per_N, rtol=1e-12)
    np.testing.assert_allclose(without.total_m_per_N,
                               without.pinion.total_m_per_N + without.wheel.total_m_per_N)
    with pytest.raises(ModelError, match="`face_width_m`"):
        hertz_stiffness(-1.0, e, nu)
    with pytest.raises(ModelError, match="`poisson_ratio_2`"):
        contact_modulus(e, nu, e, 0.7)


def test_plane_strain_scales_bending_axial_fillet_not_shear():
    pair = _pair("fzg-c")
    s = np.linspace(pair.start_of_contact, pair.end_of_contact, 5)
    ps = tooth_compliance(pair, s, 1, plane_strain=True)
    pl = tooth_compliance(pair, s, 1)
    f = 1 - pair.pinion.material.poisson_ratio ** 2
    for part in ("bending_m_per_N", "axial_m_per_N", "fillet_m_per_N"):
        np.testing.assert_allclose(getattr(ps, part), f * getattr(pl, part), rtol=1e-13)
    np.testing.assert_allclose(ps.shear_m_per_N, pl.shear_m_per_N, rtol=1e-13)


def test_invalid_arguments_are_refused():
    pair = _pair("fzg-c")
    with pytest.raises(ModelError, match="`integration` must be 'gauss' or 'quad'"):
        pair_compliance(pair, 0.01, integration="closed")  # type: ignore[arg-type]
    with pytest.raises(ModelError, match="`n_nodes`"):
        pair_compliance(pair, 0.01, n_nodes=1)
    with pytest.raises(ModelError, match="`gear` must be 1"):
        tooth_compliance(pair, 0.01, 3)
    with pytest.raises(ModelError, match="`s_m` must be finite"):
        pair_compliance(pair, [0.01, np.nan])
    wide_bore = GearPair(Gear(20, bore_diameter_m=0.039), Gear(40), 2e-3, 20 * DEG, 10e-3)
    with pytest.raises(GeometryError, match=r"pinion\.bore_diameter_m"):
        pair_compliance(wide_bore, 0.01)


# ------------------------------------------------------------------------------------------
# literature: ISO 6336-1 band, golden master
# ------------------------------------------------------------------------------------------
def _iso_6336_stiffness(pair: GearPair) -> tuple[float, float]:
    """ISO 6336-1 (method B, clause 9): single stiffness c' and mesh stiffness c_gamma_alpha.

    ``c'_th = 1/q'`` with ``q' = 0.04723 + 0.15551/z1 + 0.25791/z2 - 0.00635 x1
    - 0.11654 x1/z1 - 0.00193 x2 - 0.24188 x2/z2 + 0.00529 x1^2 + 0.00182 x2^2`` (mm um/N),
    ``c' = c'_th C_M C_R C_B`` with ``C_M = 0.8``, ``C_R = 1`` (solid gears) and the basic-rack
    factor ``C_B = [1 + 0.5 (1.2 - h_fP/m)] [1 - 0.02 (20 - alpha)]`` from each gear's actual
    dedendum (mean of the two), ``c_gamma_alpha = c' (0.75 eps_alpha + 0.25)``; N/(mm um).
    """
    z1, z2 = pair.pinion.teeth, pair.wheel.teeth
    x1, x2 = pair.pinion.profile_shift, pair.wheel.profile_shift
    q = (0.04723 + 0.15551 / z1 + 0.25791 / z2 - 0.00635 * x1 - 0.11654 * x1 / z1
         - 0.00193 * x2 - 0.24188 * x2 / z2 + 0.00529 * x1**2 + 0.00182 * x2**2)
    m = pair.module_m
    c_b = []
    for i, g in ((1, pair.pinion), (2, pair.wheel)):
        h_fp = (pair.reference_radius(i) - pair.root_radius(i)) / m + g.profile_shift
        c_b.append((1 + 0.5 * (1.2 - h_fp)) * (1 - 0.02 * (20 - pair.pressure_angle_rad / DEG)))
    c_single = (1 / q) * 0.8 * 1.0 * sum(c_b) / 2
    return c_single, c_single * (0.75 * pair.contact_ratio + 0.25)


def _mean_mesh_stiffness_per_width(pair: GearPair, include_hertz: bool) -> float:
    """Mean over a mesh cycle of the sum of 1/C of the pairs in theoretical contact, N/(mm um)."""
    phase = (np.arange(4000) + 0.5) / 4000
    s = pair.pair_positions(phase, n_pairs=3)
    c = pair_compliance(pair, s, include_hertz=include_hertz)
    k = np.where(c.in_contact_path, c.stiffness_N_per_m, 0.0).sum(axis=-1)
    return float(k.mean()) / pair.face_width_m * PER_MM_UM


# Tolerance: +-25 % around ISO's c_gamma_alpha. ISO 6336-1's method-B stiffness is itself an
# empirical fit (C_M = 0.8 alone is a 20 % correction between theory and measurement), and
# potential-energy methods differ among themselves by tens of percent with the fillet and
# foundation construction (SEED-NOTES 19; ross's trochoid fillet gives a single-pair stiffness
# 13 % above ours for the Kahraman gear). The band still catches factor-level errors (a missing
# 1/2 in an energy, I for A, a face width in mm). Values (N/(mm um)): FZG-C 14.8 with
# Hertz / 15.7 without vs ISO 16.3; Kahraman 14.9 / 15.7 vs ISO 18.6 (deep root, C_B = 0.82).
ISO_BAND = 0.25


@pytest.mark.parametrize("name", ["fzg-c", "kahraman-blankenship"])
@pytest.mark.parametrize("include_hertz", [True, False])
def test_mean_mesh_stiffness_lies_in_iso_6336_band(name, include_hertz):
    pair = _pair(name)
    k_mean = _mean_mesh_stiffness_per_width(pair, include_hertz)
    _, c_gamma = _iso_6336_stiffness(pair)
    assert abs(k_mean / c_gamma - 1) <= ISO_BAND, (
        f"{name} (hertz={include_hertz}): potential-energy mean mesh stiffness "
        f"{k_mean:.2f} N/(mm um) vs ISO 6336-1 c_gamma_alpha {c_gamma:.2f}, band +-{ISO_BAND:.0%}")
    # the Hertz term is in series: it lowers the mesh stiffness, by less than 10 %
    if include_hertz:
        k_no = _mean_mesh_stiffness_per_width(pair, False)
        assert 0.9 < k_mean / k_no < 1.0


def test_kahraman_pitch_point_single_pair_stiffness():
    # Golden master (this implementation, E = 206 GPa, nu = 0.3, b = 20 mm, bore 0.3 d);
    # regenerate with:
    #   python -c "from models.geometry import load_gear_set as l; from models.stiffness.\
    #   potential_energy import pair_stiffness as k; p = l('kahraman-blankenship').pair; \
    #   print(k(p, p.pitch_point), k(p, p.pitch_point, include_hertz=False))"
    pair = _pair("kahraman-blankenship")
    k = pair_stiffness(pair, pair.pitch_point)
    k_no_hertz = pair_stiffness(pair, pair.pitch_point, include_hertz=False)
    assert k == pytest.approx(GOLDEN_KAHRAMAN_PITCH_N_PER_M[0], rel=1e-9)
    assert k_no_hertz == pytest.approx(GOLDEN_KAHRAMAN_PITCH_N_PER_M[1], rel=1e-9)
    # ISO 6336-1 single stiffness c' (same band and reasons as the mean mesh stiffness)
    c_single, _ = _iso_6336_stiffness(pair)
    per_width = k / pair.face_width_m * PER_MM_UM
    assert abs(per_width / c_single - 1) <= ISO_BAND, (
        f"Kahraman pitch point {per_width:.2f} N/(mm um) vs ISO 6336-1 c' {c_single:.2f}")
    # single teeth: equal gears, equal teeth at the pitch point
    assert tooth_stiffness(pair, pair.pitch_point, 1) == pytest.approx(
        tooth_stiffness(pair, pair.pitch_point, 2), rel=1e-13)


GOLDEN_KAHRAMAN_PITCH_N_PER_M = (188910620.91428375, 199509868.90967393)

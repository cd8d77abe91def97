"""Corner contact: separation distances against rigid tooth profiles, and seed 003's case logic.

Sources: seed 003 Sec. 2.3 (separation distance, Lin et al. 1994; cases of Eqs. 9-17, Table 1);
the involute geometry of the shipped gear sets; SEED-NOTES 14.
"""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from models.errors import ModelError
from models.geometry import Gear, GearPair, load_gear_set
from models.stiffness.corner_contact import ncr_corner_contact, separation_distance
from models.stiffness.load_sharing import solve_load_sharing
from models.stiffness.mesh_cycle import mesh_cycle

KAHRAMAN = load_gear_set("kahraman-blankenship").pair
FZG = load_gear_set("fzg-c").pair
UNEQUAL = GearPair(Gear(19), Gear(47), 4e-3, math.radians(20), 20e-3)  # z1 != z2, eps ~ 1.65


# --- a brute-force rigid-body computation -----------------------------------------------------
def _involute_points(centre, rb, cusp, t):
    """Drive-flank involute of base radius rb with its cusp at polar angle ``cusp``.

    Built from the unwinding string (no involute function): tangent point at angle ``cusp - t``,
    the point a string length ``rb t`` along the tangent.
    """
    beta = cusp - t
    x = centre[0] + rb * np.cos(beta) - rb * t * np.sin(beta)
    y = centre[1] + rb * np.sin(beta) + rb * t * np.cos(beta)
    return np.stack([x, y], axis=-1)


def _rotate(p, centre, angle):
    c, s = math.cos(angle), math.sin(angle)
    d = p - centre
    return centre + np.stack([c * d[..., 0] - s * d[..., 1], s * d[..., 0] + c * d[..., 1]], -1)


def _side(poly, q):
    """Sign of the cross product of the nearest polyline segment with the point."""
    i = int(np.argmin(np.hypot(*(poly - q).T)))
    i = min(i, len(poly) - 2)
    a, b = poly[i], poly[i + 1]
    return np.sign((b[0] - a[0]) * (q[1] - a[1]) - (b[1] - a[1]) * (q[0] - a[0]))


def brute_force_separation(pair, s):
    """Rotate the wheel back (pinion held) until the tip corner meets the mating flank.

    Frame: O1 at the origin, line of action x = r_b1, O2 at (r_b1 + r_b2, L). Pair at nominal
    position ``s``: both flanks' (extended) involutes cross the line of action at ``s``. The
    corner is the end of the tooth's involute at its tip radius. Bisection on the wheel lag
    for a sign change of the corner's side of the mating flank polyline.
    """
    rb1, rb2 = pair.base_radius(1), pair.base_radius(2)
    L = pair.line_of_action_length
    o1, o2 = np.array([0.0, 0.0]), np.array([rb1 + rb2, L])
    cusp1, cusp2 = s / rb1, math.pi + (L - s) / rb2
    recess = s > pair.end_of_contact
    if recess:  # pinion tip corner, wheel flank moves
        corner = _involute_points(o1, rb1, cusp1, pair.end_of_contact / rb1)
        r = np.hypot(*(corner - o2))
        tc = math.sqrt((r / rb2) ** 2 - 1)
        t = np.linspace(tc - 0.01, tc + 0.01, 4001)

        def side(lag):
            flank = _rotate(_involute_points(o2, rb2, cusp2, t), o2, lag)
            return _side(flank, corner)
    else:  # wheel tip corner moves with the wheel, pinion flank fixed
        corner0 = _involute_points(o2, rb2, cusp2, (L - pair.start_of_contact) / rb2)
        flank = None

        def side(lag):
            nonlocal flank
            corner = _rotate(corner0, o2, lag)
            r = np.hypot(*corner)
            tc = math.sqrt((r / rb1) ** 2 - 1)
            t = np.linspace(tc - 0.01, tc + 0.01, 4001)
            flank = _involute_points(o1, rb1, cusp1, t)
            return _side(flank, corner)

    lo, hi = 0.0, 5e-3
    s_lo = side(lo)
    assert side(hi) != s_lo, "corner not reached within 5 mrad of wheel lag"
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if side(mid) == s_lo:
            lo = mid
        else:
            hi = mid
    return rb2 * 0.5 * (lo + hi)


@pytest.mark.parametrize("pair", [KAHRAMAN, FZG, UNEQUAL], ids=["kahraman", "fzg-c", "19-47"])
@pytest.mark.parametrize("distance_mm", [0.2, 0.6, 1.0, 2.0])
@pytest.mark.parametrize("where", ["approach", "recess"])
def test_exact_separation_matches_rigid_profile_rotation(pair, distance_mm, where):
    # Lin et al. 1994 (seed 003 ref. [24]): the gap along the line of action between the tip
    # corner and the mating flank; here against rotated, sampled rigid profiles.
    d = distance_mm * 1e-3
    s = pair.start_of_contact - d if where == "approach" else pair.end_of_contact + d
    exact = float(separation_distance(pair, s))
    brute = brute_force_separation(pair, s)
    assert exact == pytest.approx(brute, rel=1e-6, abs=1e-11), (
        f"{where} {distance_mm} mm: exact {exact * 1e6:.6f} um, brute force {brute * 1e6:.6f} um")


def test_separation_is_zero_on_the_path_quadratic_outside_and_infinite_far_away():
    g = KAHRAMAN
    A, E, pb = g.start_of_contact, g.end_of_contact, g.base_pitch
    s_in = np.linspace(A, E, 50)
    np.testing.assert_array_equal(separation_distance(g, s_in), 0.0)
    for end, sign in ((A, -1), (E, +1)):
        h = 20e-6
        s1, s2 = separation_distance(g, [end + sign * h, end + sign * 2 * h])
        assert s1 > 0
        # zero slope at the path ends: S ~ k d^2 (Munro's approximation), ratio 4
        assert s2 / s1 == pytest.approx(4.0, rel=5e-3)
    assert np.all(np.isinf(separation_distance(g, [A - pb - 1e-6, E + pb + 1e-6])))
    # monotone away from the path
    d = np.linspace(1e-6, pb, 200)
    assert np.all(np.diff(separation_distance(g, A - d)) > 0)
    assert np.all(np.diff(separation_distance(g, E + d)) > 0)


@pytest.mark.parametrize("d_mm", [0.1, 0.5, 1.0, 3.0])
def test_equal_gears_give_mirror_separations_shifted_by_the_lag(d_mm):
    # Kahraman gears are identical (seed 003 Table 3): approach and recess mirror each other.
    # In the lag convention the approach corner moves with the wheel, so the mirror holds at a
    # position shifted by the separation itself: S_a(A - d) = S_r(E + d + S_a).
    g, d = KAHRAMAN, d_mm * 1e-3
    sa = float(separation_distance(g, g.start_of_contact - d))
    sr = float(separation_distance(g, g.end_of_contact + d + sa))
    assert sa == pytest.approx(sr, rel=1e-9)


def test_separation_refuses_non_finite_positions():
    with pytest.raises(ModelError, match="`s_m` must be finite"):
        separation_distance(KAHRAMAN, [np.nan])


# --- seed 003's case logic (Eqs. 9-17) against the general active set ----------------------
gaps = st.one_of(st.just(np.inf), st.floats(0.0, 30e-6))


@settings(max_examples=300, deadline=None)
@given(c=st.lists(st.floats(2e-9, 2e-8), min_size=3, max_size=3),
       e1=st.floats(0.0, 20e-6), e3=st.floats(0.0, 20e-6), sr=gaps, sa=gaps,
       f=st.floats(10.0, 1e4))
def test_table_1_case_logic_equals_general_active_set(c, e1, e3, sr, sa, f):
    # seed 003's second assumption: pair #2 is never relieved out of contact (e2 = 0, the
    # others >= 0), so its case logic and the general solver must agree exactly
    e = np.array([e1, 0.0, e3])
    seed = ncr_corner_contact(c, e, sr, sa, f)
    gap = e + np.array([sr, 0.0, sa])
    gen = solve_load_sharing(c, gap, f)
    np.testing.assert_allclose(seed.loads_N, gen.loads_N, rtol=1e-9, atol=1e-6 * f,
                               err_msg="seed 003 Eqs. 9-17 vs active set")
    assert float(seed.transmission_error_m) == pytest.approx(float(gen.transmission_error_m),
                                                             rel=1e-9)
    assert seed.in_contact.tolist() == gen.in_contact.tolist()


def test_case_logic_reproduces_each_case_by_hand():
    c = [2e-9, 2e-9, 2e-9]
    f = 3000.0  # C F = 6 um on pair #2 alone
    # neither (Eq. 17): both separations exceed the deflection
    r = ncr_corner_contact(c, 0.0, 7e-6, 8e-6, f)
    assert r.loads_N.tolist() == [0.0, f, 0.0]
    # pair #3 only (Eq. 10): x = (C F + Sa) / 2 = 4 um
    r = ncr_corner_contact(c, 0.0, np.inf, 2e-6, f)
    assert float(r.transmission_error_m) == pytest.approx(4e-6)
    np.testing.assert_allclose(r.loads_N, [0.0, 2000.0, 1000.0])
    # both (Eq. 16) with equal separations: x = (C F + 2 S) / 3
    r = ncr_corner_contact(c, 0.0, 1.5e-6, 1.5e-6, f)
    assert float(r.transmission_error_m) == pytest.approx(3e-6)
    np.testing.assert_allclose(r.loads_N, [750.0, 1500.0, 750.0])


def test_seed_case_logic_matches_the_mesh_cycle_single_zone():
    # the mesh cycle (general active set over 4 slots) against Eqs. 9-17 in the single zone,
    # Kahraman pair at 340 N m with a compliance that varies along the path
    g = KAHRAMAN

    def comp(s):
        return 3e-9 * (1 + 40.0 * (np.asarray(s) - g.pitch_point) ** 2 / g.base_pitch)

    r = mesh_cycle(g, comp, 340.0, n_phases=400)
    single = (r.phase > g.contact_ratio - 1) & (r.phase < 1)
    m = r.slot_offset
    k1, k2, k3 = (int(np.flatnonzero(m == v)[0]) for v in (1, 0, -1))
    c = r.compliance_m_N[single][:, [k1, k2, k3]]
    seed = ncr_corner_contact(c, 0.0, r.separation_m[single, k1], r.separation_m[single, k3],
                              r.load_N)
    np.testing.assert_allclose(seed.transmission_error_m, r.lste_m[single], rtol=1e-10)
    np.testing.assert_allclose(seed.loads_N, r.loads_N[single][:, [k1, k2, k3]], rtol=1e-9,
                               atol=1e-6)
    assert seed.in_contact[:, 0].any() and seed.in_contact[:, 2].any()  # corner contact occurs


def test_case_logic_refuses_bad_shapes():
    with pytest.raises(ModelError, match=r"`compliance` must have shape \(\.\.\., 3\)"):
        ncr_corner_contact([1e-9, 1e-9], 0.0, 0.0, 0.0, 1.0)
    with pytest.raises(ModelError, match="`load_N` must be finite and > 0"):
        ncr_corner_contact([1e-9] * 3, 0.0, 0.0, 0.0, 0.0)


# --- the LSTE over the cycle ----------------------------------------------------------------
def _max_jump(values):
    """Largest step between neighbouring phases, the wrap from the last to the first included."""
    return float(np.max(np.abs(np.diff(np.append(values, values[0])))))


@pytest.mark.parametrize("torque", [50.0, 200.0, 340.0])
def test_lste_with_corner_contact_is_continuous_over_the_cycle(torque):
    # seed 003 Sec. 2.3.2 / Fig. 4: the incoming pair takes load gradually from zero, so the
    # LSTE has no jump: halving the phase step halves the largest step (a jump would stay).
    # At low torque the hand-over is short (extension ~ sqrt(x / k)), so the steps are steep.
    g = KAHRAMAN
    comp = lambda s: np.full(np.shape(s), 3.3e-9)  # noqa: E731
    jumps = [_max_jump(mesh_cycle(g, comp, torque, n_phases=n).lste_m) for n in (200, 400, 800)]
    assert jumps[1] == pytest.approx(jumps[0] / 2, rel=0.1)
    assert jumps[2] == pytest.approx(jumps[0] / 4, rel=0.1)
    span = np.ptp(mesh_cycle(g, comp, torque, n_phases=800).lste_m)
    assert jumps[2] < 0.05 * span
    # without corner contact, the classical LSTE jumps by C F / 2 at the zone transitions
    r = mesh_cycle(g, comp, torque, n_phases=400, corner_contact=False)
    assert _max_jump(r.lste_m) == pytest.approx(3.3e-9 * r.load_N / 2, rel=1e-9)

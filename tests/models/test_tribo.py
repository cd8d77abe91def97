"""Six-DOF tribo-dynamic model of seed 002 and its iterative decoupling loop.

Sources of the expected numbers:

* compiled RK4 against its plain-Python twin (same operations): agreement to rounding;
* ``scipy.integrate.solve_ivp`` (RK45, rtol 1e-8) on the same equations with the tables
  interpolated linearly in time: agreement to the RK4 truncation error;
* limits derived by hand: without friction, with a rigid film and rigid bearings the model is
  the SDOF model of :mod:`models.dynamics.sdof` (integrated by :mod:`models.dynamics.integrate`,
  compared sample by sample); a constant-stiffness model without backlash is linear and its
  steady response to a harmonic transmission error is the 5x5 complex solve written out in
  :func:`_linear_frf` from the equations of motion; the static DTE of a constant mesh and film
  stiffness is ``b + W_0 (1/k_m + 1/k_h)`` (series springs);
* seed 002 statements: the friction coefficient changes direction at the pitch point; the
  mixed regime ``1 < Lambda < 3``; a film stiffness about two orders of magnitude above the
  mesh stiffness, so that the comprehensive stiffness changes minimally; DTE and mesh force
  barely changed by the coupling; convergence of the loop at the relative change 1e-3. The
  regime and stiffness statements are tested on the case ``seed-002-tribo-mixed``
  (``mu_R = 0.142 Pa s``): with the printed, suspect ``mu_R = 1.42 Pa s`` (case
  ``seed-002-tribo``) they fail, which is tested too, as the evidence for the suspicion;
* mesh damping on ``s' = delta' - e'`` (seed 002's ``c_i s'``): in the linear limit the mesh
  force is ``(k + i w c)(delta - e)``, written out in :func:`_linear_frf`.
"""

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from models.dynamics import SDOFModel, periods
from models.dynamics.tribo import (
    TriboDynamics,
    build_tribo_dynamics,
    series_stiffness,
    static_state,
)
from models.dynamics.tribo_case import load_tribo_case, shipped_tribo_cases, solve_tribo_case
from models.dynamics.tribo_ehl_coupling import (
    contact_cycle,
    lubrication_tables,
    quasi_static_loads,
    relative_change,
    tribo_iteration,
)
from models.dynamics.tribo_integrate import tribo_periods, tribo_periods_reference, tribo_settle
from models.ehl import Roughness, film_stiffness
from models.ehl.asperity import mixed_film_stiffness
from models.errors import ModelError
from models.stiffness.mesh_cycle import Harmonics

CASE = load_tribo_case("seed-002-tribo")
MIXED = load_tribo_case("seed-002-tribo-mixed")


@pytest.fixture(scope="module")
def solution():
    return solve_tribo_case(CASE)


@pytest.fixture(scope="module")
def mixed():
    return solve_tribo_case(MIXED)


def hand_model(
    n=256,
    stiffness=None,
    friction=0.0,
    rigid=False,
    backlash=3e-6,
    error=None,
    kb=2e9,
    ns=2,
    arms=(0.012, 0.018),
    inertias=(6.7e-4, 6.7e-4),
    radii=(0.04177, 0.04177),
    relative=True,
):
    """A hand-made model: 2 slots, smooth stiffness, seed 002's masses and inertias."""
    phase = np.arange(2 * n) / (2 * n)
    if stiffness is None:
        k = 1e8 * (1 + 0.2 * np.cos(2 * np.pi * phase) + 0.05 * np.sin(4 * np.pi * phase))
        share = 0.5 + 0.3 * np.sin(2 * np.pi * phase)
        stiffness = np.stack([k * share, k * (1 - share)], axis=1)[:, :ns]
    shape = stiffness.shape
    mu = np.broadcast_to(np.asarray(friction, float), shape).copy()
    return TriboDynamics(
        mesh_period_s=60 / (28 * 2000),
        load_N=1719.0,
        base_radius_p_m=radii[0],
        base_radius_g_m=radii[1],
        mass_p_kg=0.4058,
        mass_g_kg=0.4058,
        inertia_p_kgm2=inertias[0],
        inertia_g_kgm2=inertias[1],
        bearing_stiffness_x_N_m=kb,
        bearing_stiffness_y_N_m=kb,
        bearing_damping_x_Ns_m=2 * 0.05 * math.sqrt(kb * 0.4058),
        bearing_damping_y_Ns_m=2 * 0.05 * math.sqrt(kb * 0.4058),
        mesh_damping_Ns_m=2 * 0.1 * math.sqrt(1e8 * 0.192),
        half_backlash_m=backlash,
        mesh_stiffness_N_m=stiffness,
        film_stiffness_N_m=np.full(shape, np.inf),
        friction=mu,
        arm_p_m=np.full(shape, arms[0]),
        arm_g_m=np.full(shape, arms[1]),
        error_m=np.zeros(shape[0]) if error is None else error,
        positions_m=np.full(shape, np.nan),
        rigid_bearings=rigid,
        damp_relative_rate=relative,
    )


# --- integrators ---------------------------------------------------------------------------
def test_compiled_matches_reference_on_the_seed_case(solution):
    m = solution.model  # film stiffness and signed friction from the converged loop
    assert np.any(m.friction != 0) and np.all(
        np.isfinite(m.film_stiffness_N_m[m.mesh_stiffness_N_m > 0])
    )
    y0 = static_state(m) * 1.1
    fast, _ = tribo_periods(m, 2, y0)
    ref = tribo_periods_reference(m, 2, y0)
    scale = np.abs(ref).max(axis=0)
    np.testing.assert_allclose(fast / scale, ref / scale, rtol=0, atol=1e-11)


def test_compiled_matches_reference_with_contact_loss():
    # 4th mesh harmonic near the mesh resonance (3.6 kHz): the teeth separate
    m = hand_model(friction=0.08, error=5e-6 * np.cos(8 * np.pi * np.arange(512) / 512))
    fast, rec = tribo_periods(m, 4, record=True)
    assert rec is not None and np.any(rec.dte_m - m.error_m[::2] < m.half_backlash_m)  # gap opens
    ref = tribo_periods_reference(m, 4)
    scale = np.abs(ref).max(axis=0)
    np.testing.assert_allclose(fast / scale, ref / scale, rtol=0, atol=1e-11)


def test_rk4_matches_solve_ivp():
    # friction of both signs (sign change at mid-cycle, as at a pitch point) and flexible bearings
    n = 512
    phase = np.arange(2 * n) / (2 * n)
    m = hand_model(n=n, friction=0.06 * np.sin(2 * np.pi * phase)[:, None], kb=5e8)
    y0 = static_state(m)
    fast, _ = tribo_periods(m, 2, y0)
    T = m.mesh_period_s
    sol = solve_ivp(
        m.ode(), (0, 2 * T), y0, method="RK45", rtol=1e-8, atol=1e-15, t_eval=[T, 2 * T]
    )
    scale = np.abs(sol.y.T).max(axis=0)
    # linear interpolation of the tables makes the RK4 O(h^2) against the interpolant
    np.testing.assert_allclose(fast / scale, sol.y.T / scale, rtol=0, atol=2e-4)


# --- limits --------------------------------------------------------------------------------
@pytest.mark.parametrize("ns", [1, 2])
def test_reduces_to_the_sdof_model(ns):
    """No friction, rigid film, rigid bearings: the SDOF model of seed 003 Sec. 3, numerically.

    With the damping on the DTE rate (``damp_relative_rate=False``), the SDOF model's form.
    """
    n = 256
    phase = np.arange(2 * n) / (2 * n)
    kt = Harmonics(1.0, np.array([0.25, 0.08]), np.array([0.4, -1.1]))
    et = Harmonics(0.0, np.array([0.6]), np.array([0.2]))
    k0 = 1.0e8
    m0 = hand_model(n=n, rigid=True, relative=False)
    me = m0.equivalent_mass_kg
    L = m0.half_backlash_m
    k = k0 * kt(phase)
    share = np.stack(
        [0.3 + 0.2 * np.cos(2 * np.pi * phase), 0.7 - 0.2 * np.cos(2 * np.pi * phase)], axis=1
    )
    table = k[:, None] * share if ns == 2 else k[:, None]
    m = dataclasses.replace(
        hand_model(n=n, stiffness=table, rigid=True, relative=False), error_m=L * et(phase)
    )
    wn = math.sqrt(k0 / me)
    zeta = m.mesh_damping_Ns_m / (2 * math.sqrt(k0 * me))
    sdof = SDOFModel(
        zeta=zeta, force=m.load_N / (k0 * L), backlash=1.0, stiffness=kt, error=et, length_scale_m=L
    )
    lam = 2 * math.pi / (m.mesh_period_s * wn)
    x0, v0 = 9.0, 0.5
    pts, _, _ = periods(sdof, lam, (x0, v0), 20, steps_per_period=n)
    y0 = np.zeros(10)
    y0[0], y0[5] = x0 * L, v0 * L * wn
    tp, _ = tribo_periods(m, 20, y0)
    np.testing.assert_allclose(tp[:, 0] / L, pts[:, 0], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(tp[:, 5] / (L * wn), pts[:, 1], rtol=1e-9, atol=1e-9)
    assert np.all(tp[:, [1, 2, 3, 4]] == 0)
    assert np.ptp(pts[:, 0]) > 0.05  # a transient, not a trivial equilibrium


def _linear_frf(m: TriboDynamics, e0: float, mu: float):
    """Complex amplitudes (q, x_p, x_g, y_p, y_g) for e = e0 exp(i w t); constant k, no gap.

    Mesh force ``F = k (delta - e) + c (delta' - e') = z delta - z e`` (seed 002, damping on
    ``s = delta - e``) or ``k (delta - e) + c delta' = z delta - k e`` (damping on the DTE).
    """
    w = 2 * math.pi / m.mesh_period_s
    k = float(m.mesh_stiffness_N_m.sum(axis=1)[0])
    c = m.mesh_damping_Ns_m
    z = k + 1j * w * c
    ke = z if m.damp_relative_rate else k
    a = (
        m.base_radius_p_m * m.arm_p_m[0, 0] / m.inertia_p_kgm2
        + m.base_radius_g_m * m.arm_g_m[0, 0] / m.inertia_g_kgm2
    )
    me = m.equivalent_mass_kg

    def bearing(mass, kb, cb):
        return -w * w * mass + 1j * w * cb + kb

    bx_p = bearing(m.mass_p_kg, m.bearing_stiffness_x_N_m, m.bearing_damping_x_Ns_m)
    bx_g = bearing(m.mass_g_kg, m.bearing_stiffness_x_N_m, m.bearing_damping_x_Ns_m)
    by_p = bearing(m.mass_p_kg, m.bearing_stiffness_y_N_m, m.bearing_damping_y_Ns_m)
    by_g = bearing(m.mass_g_kg, m.bearing_stiffness_y_N_m, m.bearing_damping_y_Ns_m)
    g = np.array([1, 1, -1, 0, 0], complex)  # d(delta)/d(state)
    A = np.zeros((5, 5), complex)
    # -w^2 Q = -(1/me + mu a) F ; bearings: B X_p = -F, B X_g = +F, B Y_p = -mu F, B Y_g = +mu F
    A[0, 0] = -w * w
    A[0] += (1 / me + mu * a) * z * g
    A[1, 1] = bx_p
    A[1] += z * g
    A[2, 2] = bx_g
    A[2] -= z * g
    A[3, 3] = by_p
    A[3] += mu * z * g
    A[4, 4] = by_g
    A[4] -= mu * z * g
    rhs = np.array([(1 / me + mu * a), 1, -1, mu, -mu], complex) * ke * e0
    return np.linalg.solve(A, rhs)


@pytest.mark.parametrize(
    ("mu", "relative", "unequal"),
    [(0.0, True, False), (0.07, True, False), (0.07, False, False), (0.07, True, True)],
)
def test_linear_limit_matches_the_analytic_frequency_response(mu, relative, unequal):
    """Unequal gears (inertias, base radii, arms): each arm goes with its own gear's inertia."""
    n = 512
    phase = np.arange(2 * n) / (2 * n)
    e0 = 1e-6
    k = np.full((2 * n, 1), 1.2e8)
    geometry = (
        {"inertias": (2.0e-4, 1.5e-3), "radii": (0.028, 0.052), "arms": (0.004, 0.030)}
        if unequal
        else {}
    )
    m = hand_model(
        n=n,
        stiffness=k,
        friction=mu,
        backlash=0.0,
        error=e0 * np.cos(2 * np.pi * phase),
        relative=relative,
        **geometry,
    )
    _, _, rec = tribo_settle(m, tol=1e-10)
    expected = _linear_frf(m, e0, mu)
    first = 2 * np.fft.rfft(rec.state[:, :5], axis=0)[1] / n  # e^{+i w t} amplitude
    np.testing.assert_allclose(first, expected, rtol=2e-4, atol=1e-6 * np.abs(expected).max())
    assert np.min(rec.pair_load_N) > 0  # stayed linear (no separation)


def test_static_dte_of_mesh_and_film_in_series():
    n = 64
    km, kh = 1.5e8, 6e8
    base = hand_model(n=n, stiffness=np.full((2 * n, 1), km), rigid=True)
    m = base.with_lubrication(np.full((2 * n, 1), kh), np.zeros((2 * n, 1)))
    _, _, rec = tribo_settle(m, tol=1e-12, min_periods=50)
    expected = m.half_backlash_m + m.load_N * (1 / km + 1 / kh)
    np.testing.assert_allclose(rec.dte_m, expected, rtol=1e-9)
    np.testing.assert_allclose(rec.mesh_force_N, m.load_N, rtol=1e-9)


def test_series_stiffness():
    assert series_stiffness(2e8, 6e8) == pytest.approx(1 / (1 / 2e8 + 1 / 6e8), rel=1e-14)
    assert series_stiffness(2e8, np.inf) == 2e8
    assert series_stiffness(0.0, 6e8) == 0.0
    np.testing.assert_allclose(
        series_stiffness([1e8, 3e8], [1e8, 1e12]), [0.5e8, 1 / (1 / 3e8 + 1e-12)], rtol=1e-14
    )


def test_stiff_bearings_barely_change_the_dte():
    """Seed 002's 1e11 N/m bearings are nearly rigid: DTE within 0.5 % of the rigid model."""
    soft = CASE.dynamics()
    rigid = dataclasses.replace(CASE, steps_per_period=soft.steps_per_period).dynamics(
        rigid_bearings=True
    )
    _, _, r1 = tribo_settle(soft)
    _, _, r2 = tribo_settle(rigid)
    d1 = np.interp(np.arange(256) / 256, r1.time_s / soft.mesh_period_s, r1.dte_m)
    d2 = np.interp(np.arange(256) / 256, r2.time_s / rigid.mesh_period_s, r2.dte_m)
    assert np.max(np.abs(d1 - d2)) < 5e-3 * np.max(np.abs(d2))


# --- seed 002 statements -------------------------------------------------------------------
def test_friction_changes_direction_at_the_pitch_point(solution):
    c = solution.contact
    pitch = CASE.pair.pitch_point
    s, f = c.along_path("friction")
    far = np.abs(s - pitch) > 1e-4
    assert np.all(np.sign(f[far]) == np.sign(s[far] - pitch))
    # the tables the dynamics used carry the same sign pattern at the half steps
    m = solution.model
    on = (m.mesh_stiffness_N_m > 0) & (np.abs(m.positions_m - pitch) > 2e-4)
    assert np.all(np.sign(m.friction[on]) == np.sign(m.positions_m[on] - pitch))
    # and the y force they produce reverses with it: friction drives the y vibration
    assert np.ptp(solution.record.friction_force_N) > 0
    assert np.ptp(solution.record.state[:, 3]) > 0


def test_film_stiffness_lowers_the_comprehensive_stiffness_slightly(solution):
    m = solution.model
    km, kc = m.mesh_stiffness_N_m, m.combined_stiffness_N_m
    on = km > 0
    assert np.all(kc[on] < km[on])
    np.testing.assert_allclose(kc[on], 1 / (1 / km[on] + 1 / m.film_stiffness_N_m[on]), rtol=1e-12)
    ratio = kc.sum(axis=1).mean() / km.sum(axis=1).mean()
    # "decreases": always; how much depends on mu_R. At the printed, suspect 1.42 Pa s the
    # ratio is 0.944 (not the seed's "minimal" change: see the mixed case's tests below)
    assert 0.85 < ratio < 1.0


def test_loop_converges_and_is_a_fixed_point(solution):
    assert 1 < solution.iterations < 30
    assert max(solution.history[-1]) < 1e-3
    assert max(solution.history[0]) > 1e-2  # the dynamic loads really change the film
    stride = solution.model.steps_per_period // 128
    m = dataclasses.replace(solution.model)
    _, _, _, again = tribo_iteration(
        CASE.pair,
        m,
        solution.contact,
        CASE.pinion_speed_rpm,
        CASE.lubrication,
        solution.state,
        1e-7,
        128,
        0.05 * m.load_N,
    )
    dk, df = relative_change(solution.contact, again)
    assert max(dk, df) < 1e-3
    assert stride * 128 == m.steps_per_period
    # film thickness and Lambda along the cycle are finite on loaded pairs (the window is a
    # plausibility bound for a gear film, not a seed 002 number: 2.0-4.0 um at mu_R = 1.42)
    c = solution.contact
    h = c.film_thickness_m[c.loaded]
    assert np.all((h > 0.5e-6) & (h < 10e-6))
    np.testing.assert_allclose(c.film_parameter[c.loaded], h / CASE.lubrication.roughness.sigma_m)


def test_distance_to_the_fixed_point_is_estimated(solution):
    """Against the loop run to 1e-6: the 1e-3 state is within 1e-3 and within 3x the estimate."""
    tight = solve_tribo_case(CASE, tol=1e-6)
    a, b = solution.contact, tight.contact
    dk = np.nanmax(np.abs(a.film_stiffness_N_m - b.film_stiffness_N_m) / b.film_stiffness_N_m)
    assert dk < 1e-3
    assert 0 < solution.contraction < 1
    assert dk < 3 * solution.distance_estimate


def test_dynamic_loads_change_the_film(solution):
    """Seed 002: dynamic loads make the film fluctuate more than the steady-state loads do."""
    steady = solution.steady_contact
    dyn = solution.contact
    assert np.nanmax(dyn.load_N) > 1.2 * np.nanmax(steady.load_N)
    assert np.nanmin(dyn.film_thickness_m) < np.nanmin(steady.film_thickness_m)


def test_non_convergence_raises_with_the_last_change():
    with pytest.raises(ModelError, match=r"did not converge in 1 iterations.*film stiffness"):
        solve_tribo_case(CASE, max_iterations=1)


def test_lubrication_tables_hold_loaded_values_and_interpolate_compliance():
    m = CASE.dynamics()
    c = contact_cycle(CASE.pair, m, quasi_static_loads(m), CASE.pinion_speed_rpm, CASE.lubrication)
    kh, mu = lubrication_tables(c, 2 * m.steps_per_period)
    stride = 2 * m.steps_per_period // 128
    on = c.loaded
    np.testing.assert_allclose(kh[::stride][on], c.film_stiffness_N_m[on], rtol=1e-12)
    np.testing.assert_array_equal(mu[::stride][on], c.friction[on])
    inside = m.mesh_stiffness_N_m > 0
    assert np.all(np.isfinite(kh[inside]))


# --- the case file -------------------------------------------------------------------------
def test_shipped_case_carries_the_seed_tables():
    assert "seed-002-tribo" in shipped_tribo_cases()
    c = CASE
    assert (c.pair.pinion.teeth, c.pair.wheel.teeth) == (28, 28)
    assert c.pair.module_m == pytest.approx(3.175e-3)
    assert c.torque_Nm == 71.8 and c.pinion_speed_rpm == 2000.0
    assert c.mass_p_kg == 0.4058 and c.inertia_p_kgm2 == pytest.approx(6.7e-4)
    assert c.bearing_stiffness_x_N_m == 1e11 and c.half_backlash_m == pytest.approx(3e-6)
    lub = c.lubrication.lubricant
    assert (lub.mu_ref_Pas, lub.T_ref_K, lub.B0, lub.R0) == (1.42, 348.15, 4.423, 0.6694)
    assert lub.K00_Pa == pytest.approx(11.5e9) and lub.G_cr_Pa == pytest.approx(31e3)
    assert lub.alpha_per_Pa == pytest.approx(19e-9)
    r = c.lubrication.roughness
    assert r.sigma_1_m == pytest.approx(0.4e-6) and r.asperity_radius_m == pytest.approx(6e-6)
    assert c.solver["tol"] == 1e-3


def _write(tmp_path, text):
    src = load_tribo_case("seed-002-tribo").path
    body = open(src, encoding="utf-8").read()
    p = tmp_path / "case.toml"
    p.write_text(text(body), encoding="utf-8")
    return p


def test_case_loader_names_unknown_and_missing_keys(tmp_path):
    p = _write(tmp_path, lambda b: b.replace("[mesh]", "[mesh]\nstifness = 1.0"))
    with pytest.raises(ModelError, match=r"case\.toml: mesh\.stifness: unknown key"):
        load_tribo_case(p)
    p = _write(tmp_path, lambda b: b.replace("torque_Nm = 71.8", ""))
    with pytest.raises(ModelError, match=r"operating\.torque_Nm: required"):
        load_tribo_case(p)
    p = _write(tmp_path, lambda b: b.replace("[friction]", "[frictions]"))
    with pytest.raises(ModelError, match="frictions: unknown section"):
        load_tribo_case(p)
    p = _write(tmp_path, lambda b: b.replace("B0 = 4.423", 'B0 = "x"'))
    with pytest.raises(ModelError, match=r"lubricant\.B0 = 'x': must be a finite number"):
        load_tribo_case(p)
    p = _write(tmp_path, lambda b: b.replace('gear_set = "aerospace-28"', 'gear_set = "nope"'))
    with pytest.raises(ModelError, match=r"case\.gear_set"):
        load_tribo_case(p)
    with pytest.raises(ModelError, match="no shipped tribo case"):
        load_tribo_case("no-such-case")


def test_case_with_a_gear_set_file_next_to_it(tmp_path):
    from models.geometry.gear_sets import gear_set_path

    (tmp_path / "pair.toml").write_text(gear_set_path("aerospace-28").read_text("utf-8"), "utf-8")
    p = _write(tmp_path, lambda b: b.replace('gear_set = "aerospace-28"', 'gear_set = "pair.toml"'))
    c = load_tribo_case(p)
    assert c.pair.contact_ratio == pytest.approx(CASE.pair.contact_ratio, rel=1e-12)
    assert c.path == str(p)


@pytest.mark.slow
def test_4000_rpm_with_contact_loss_converges_with_relaxation():
    """4000 rpm (seed 002's second speed): the pairs separate.

    The loop converges with the load floor (31 iterations plain, 66 with relaxation 0.5, about
    20 s); without the floor it does not (film stiffness ~ F^2 at vanishing load). With
    ``beta_K = 6e-3`` both runs end on the same state (mesh force 2e-6 RMS apart); with the
    printed 6e-4 (commit 3b6fc60) they ended 5.7 % apart.
    """
    plain = solve_tribo_case(CASE, 4000.0, max_iterations=60)
    relaxed = solve_tribo_case(CASE, 4000.0, relaxation=0.5, max_iterations=120)
    for sol in (plain, relaxed):
        assert max(sol.history[-1]) < 1e-3
        assert np.min(sol.record.pair_load_N[sol.model.mesh_stiffness_N_m[::2] > 0]) < 0
    assert plain.dte_m.max() == pytest.approx(relaxed.dte_m.max(), rel=1e-3)
    for sol in (plain, relaxed):  # each is a fixed point: one more pass changes < 1e-3
        _, _, _, again = tribo_iteration(
            CASE.pair,
            sol.model,
            sol.contact,
            4000.0,
            CASE.lubrication,
            sol.state,
            1e-7,
            128,
            0.05 * sol.model.load_N,
        )
        assert max(relative_change(sol.contact, again)) < 1e-3
    with pytest.raises(ModelError, match="did not converge"):
        solve_tribo_case(CASE, 4000.0, load_floor=0.0, max_iterations=40)


# --- review fixes ---------------------------------------------------------------------------
def test_error_rate_is_the_derivative_of_a_harmonic_error():
    n = 64
    phase = np.arange(2 * n) / (2 * n)
    m = hand_model(n=n, error=2e-6 * np.sin(2 * np.pi * 3 * phase + 0.4))
    w = 2 * np.pi * 3 / m.mesh_period_s
    np.testing.assert_allclose(
        m.error_rate_m_s, 2e-6 * w * np.cos(2 * np.pi * 3 * phase + 0.4), rtol=0, atol=1e-12 * w
    )
    assert np.all(m.tables()[5] == m.error_rate_m_s)
    assert np.all(dataclasses.replace(m, damp_relative_rate=False).tables()[5] == 0)


def test_friction_acts_only_on_compressive_pair_loads():
    """A tensile pair load carries no friction.

    Inside the backlash with the DTE closing the gap the damping makes the pair load tensile
    (``N = c_i s' < 0``): no friction force, so ``y`` sees its bearings only.
    """
    m = hand_model(n=64, friction=0.1)
    t = 0.3 * m.mesh_period_s
    y = np.zeros(10)
    y[0] = 0.5 * m.half_backlash_m  # inside the gap: no elastic force
    y[5] = -0.02  # closing the gap in reverse: damping force < 0
    y[3], y[8] = 1e-9, 1e-4
    dy = m.ode()(t, y)
    cb, kb = m.bearing_damping_y_Ns_m, m.bearing_stiffness_y_N_m
    assert dy[8] == pytest.approx((-cb * y[8] - kb * y[3]) / m.mass_p_kg, rel=1e-12)
    assert dy[9] == 0.0
    assert dy[5] == pytest.approx((m.load_N + m.mesh_damping_Ns_m * 0.02) / m.equivalent_mass_kg)
    # compressive: friction mu N_i on y, from the same state with the DTE opening
    y[5] = 0.02
    dy = m.ode()(t, y)
    assert dy[8] == pytest.approx(
        (-cb * y[8] - kb * y[3] - 0.1 * m.mesh_damping_Ns_m * 0.02) / m.mass_p_kg, rel=1e-9
    )


def test_recorded_friction_force_is_mu_times_compressive_loads():
    m = hand_model(friction=0.08, error=5e-6 * np.cos(8 * np.pi * np.arange(512) / 512))
    _, rec = tribo_periods(m, 4, record=True)
    assert rec is not None and np.any(rec.pair_load_N < 0)  # tensile loads occur
    expected = (m.friction[::2] * np.maximum(rec.pair_load_N, 0)).sum(axis=1)
    np.testing.assert_allclose(rec.friction_force_N, expected, rtol=1e-12, atol=1e-12)


def test_friction_arms_are_the_curvature_radii_of_each_gear():
    """Unequal gears (FZG-C, 16/24): pinion arm ``s`` (from T1), wheel arm ``T1T2 - s``."""
    from models.geometry import load_gear_set

    pair = load_gear_set("fzg-c").pair
    assert pair.pinion.teeth != pair.wheel.teeth
    m = build_tribo_dynamics(
        pair,
        torque_Nm=100.0,
        pinion_speed_rpm=1000.0,
        mass_p_kg=1.0,
        mass_g_kg=2.0,
        inertia_p_kgm2=1e-3,
        inertia_g_kgm2=4e-3,
        bearing_stiffness_x_N_m=1e9,
        bearing_stiffness_y_N_m=1e9,
        bearing_damping_ratio=0.05,
        mesh_damping_ratio=0.1,
        half_backlash_m=0.0,
        compliance=lambda s: np.full(np.shape(s), 1e-8),
        steps_per_period=64,
    )
    on = m.mesh_stiffness_N_m > 0
    rho_p, rho_g = pair.curvature_radii(m.positions_m[on])
    np.testing.assert_allclose(m.arm_p_m[on], rho_p, rtol=1e-12)
    np.testing.assert_allclose(m.arm_g_m[on], rho_g, rtol=1e-12)
    assert np.max(np.abs(rho_p - rho_g)) > 1e-3  # unequal arms: a swap would show


def test_build_rejects_unphysical_inputs():
    kwargs = {
        "torque_Nm": 71.8,
        "pinion_speed_rpm": 2000.0,
        "mass_p_kg": 0.0,
        "mass_g_kg": 0.4,
        "inertia_p_kgm2": 6.7e-4,
        "inertia_g_kgm2": 6.7e-4,
        "bearing_stiffness_x_N_m": 1e11,
        "bearing_stiffness_y_N_m": 1e11,
        "bearing_damping_ratio": 0.1,
        "mesh_damping_ratio": 0.1,
        "half_backlash_m": 3e-6,
    }
    with pytest.raises(ModelError, match="mass_p_kg"):
        build_tribo_dynamics(CASE.pair, **kwargs)
    with pytest.raises(ModelError, match="torque_Nm"):
        build_tribo_dynamics(CASE.pair, **{**kwargs, "mass_p_kg": 0.4, "torque_Nm": -1.0})


def test_relative_change_counts_the_friction():
    m = CASE.dynamics()
    c = contact_cycle(CASE.pair, m, quasi_static_loads(m), CASE.pinion_speed_rpm, CASE.lubrication)
    f2 = np.where(c.loaded, 1.01 * c.friction, np.nan)
    dk, df = relative_change(c, dataclasses.replace(c, friction=f2))
    assert dk == 0.0
    assert df == pytest.approx(0.01, rel=1e-9)


def test_loop_does_not_stop_while_the_friction_changes(monkeypatch):
    """The seed initialises and feeds back both k_h and f: a changing f blocks convergence."""
    import models.dynamics.tribo_ehl_coupling as coupling

    monkeypatch.setattr(coupling, "relative_change", lambda old, new, scale=0.0: (0.0, 0.5))
    with pytest.raises(ModelError, match="did not converge in 2 iterations"):
        solve_tribo_case(MIXED, max_iterations=2)


def test_loop_film_stiffness_is_the_mixed_contact_stiffness():
    """``k_h`` the loop feeds back is :func:`mixed_film_stiffness` at each pair's state.

    At each pair's load and kinematics; with asperity-free flanks it is the smooth film's
    :func:`film_stiffness`.
    """
    m = CASE.dynamics()
    loads = quasi_static_loads(m)
    smooth = dataclasses.replace(
        MIXED.lubrication, roughness=Roughness(sigma_1_m=1e-9, sigma_2_m=1e-9)
    )
    for lub in (MIXED.lubrication, smooth):
        c = contact_cycle(CASE.pair, m, loads, 2000.0, lub)
        on = c.loaded
        s = c.positions_m[on]
        r1, r2 = CASE.pair.curvature_radii(s)
        R = r1 * r2 / (r1 + r2)
        u1, u2 = CASE.pair.surface_velocities(s, 2000.0)
        E = 207e9 / (1 - 0.3**2)
        B = CASE.pair.face_width_m
        mc, k = mixed_film_stiffness(
            loads[on],
            B,
            R,
            u1,
            u2,
            E,
            lubricant=lub.lubricant,
            roughness=lub.roughness,
            inlet_temperature_K=lub.inlet_temperature_K,
        )
        np.testing.assert_allclose(c.film_stiffness_N_m[on], k, rtol=1e-12)
        np.testing.assert_allclose(c.asperity_share[on], 1 / mc.gamma_2, rtol=1e-12)
    np.testing.assert_allclose(
        c.film_stiffness_N_m[on],
        film_stiffness(loads[on], B, R, u1, u2, E, lub.lubricant, rel_step=1e-2),
        rtol=1e-9,
    )


# --- seed 002's qualitative statements, on the mixed case (mu_R = 0.142 Pa s) --------------
def test_mixed_case_is_in_the_mixed_regime(mixed):
    """Seed 002: spur gears operate in the mixed regime, ``1 < Lambda < 3``.

    1.47-2.19 here, with some asperity contact (1.3 % of the load at most).
    """
    c = mixed.contact
    lam = c.film_parameter[c.loaded]
    assert np.all((lam > 1) & (lam < 3))
    assert 0 < np.nanmax(c.asperity_share) < 0.1
    assert max(mixed.history[-1]) < 1e-3


def test_mixed_case_film_two_orders_stiffer_than_the_mesh(mixed):
    """Seed 002: film stiffness "two orders of magnitude higher than mesh stiffness".

    So the comprehensive stiffness decreases, but minimally (k_h/k_m 49-165, median 83;
    mean comprehensive / mesh stiffness 0.988 here).
    """
    m = mixed.model
    km, kh = m.mesh_stiffness_N_m, m.film_stiffness_N_m
    on = km > 0
    ratio = kh[on] / km[on]
    assert 30 < np.median(ratio) < 300 and ratio.min() > 20
    kc = m.combined_stiffness_N_m
    assert np.all(kc[on] < km[on])
    assert 0.97 < kc.sum(axis=1).mean() / km.sum(axis=1).mean() < 1.0


def test_mixed_case_dte_and_mesh_force_barely_change_with_the_coupling(mixed):
    """Seed 002: DTE and mesh force barely change with the coupling.

    Little variation between the coupled and the uncoupled (dry, frictionless, rigid-film)
    model (2.1 % and 2.3 % RMS here); y vibration appears only with the coupling (friction).
    """
    dry = MIXED.dynamics()
    _, _, rec = tribo_settle(dry)
    dte, dte0 = mixed.dte_m, rec.dte_m
    assert np.sqrt(np.mean((dte - dte0) ** 2)) < 0.05 * np.sqrt(np.mean(dte0**2))
    df = mixed.mesh_force_N - rec.mesh_force_N
    assert np.sqrt(np.mean(df**2)) < 0.05 * dry.load_N
    assert np.ptp(rec.state[:, 3]) == 0 and np.ptp(mixed.record.state[:, 3]) > 1e-10


def test_printed_viscosity_contradicts_the_seed_statements(solution):
    """Evidence that the printed mu_R = 1.42 Pa s is suspect.

    At it the pair runs in full film (Lambda > 3 everywhere, asperity share < 1e-4) with a film
    only 8-38x stiffer than the mesh and a 5.6 % drop of the comprehensive stiffness.
    """
    c = solution.contact
    assert np.all(c.film_parameter[c.loaded] > 3)
    assert np.nanmax(c.asperity_share) < 1e-4
    m = solution.model
    on = m.mesh_stiffness_N_m > 0
    assert np.median(m.film_stiffness_N_m[on] / m.mesh_stiffness_N_m[on]) < 30
    assert (
        m.combined_stiffness_N_m.sum(axis=1).mean() / m.mesh_stiffness_N_m.sum(axis=1).mean() < 0.97
    )


# --- case files: values, suspicion marker, range checks -------------------------------------
def test_mixed_case_differs_from_the_seed_case_only_in_mu_r():
    assert "seed-002-tribo-mixed" in shipped_tribo_cases()
    assert MIXED.lubrication.lubricant.mu_ref_Pas == 0.142
    assert CASE.lubrication.lubricant.mu_ref_Pas == 1.42
    same_lub = dataclasses.replace(MIXED.lubrication.lubricant, mu_ref_Pas=1.42)
    assert same_lub == CASE.lubrication.lubricant
    assert dataclasses.replace(MIXED.lubrication, lubricant=same_lub) == CASE.lubrication
    skip = {"name", "source", "path", "lubrication", "pair"}
    for f in dataclasses.fields(CASE):
        if f.name not in skip:
            assert getattr(MIXED, f.name) == getattr(CASE, f.name), f.name
    text = open(CASE.path, encoding="utf-8").read()
    block = text[text.index("[lubricant]") : text.index("\nmu_ref_Pas = 1.42\n")]
    assert "SUSPECT" in block and "seed-002-tribo-mixed" in block


def test_shipped_cases_carry_the_corrected_beta_k():
    for case in (CASE, MIXED):
        lub = case.lubrication.lubricant
        assert lub.beta_K_per_K == 6.0e-3
        alpha0 = float(lub.pressure_viscosity_coefficient(lub.T_ref_K))
        assert alpha0 == pytest.approx(lub.alpha_per_Pa, rel=0.02)


@pytest.mark.parametrize(
    ("old", "new", "match"),
    [
        ("mu_ref_Pas = 1.42", "mu_ref_Pas = -1.42", r"lubricant\.mu_ref_Pas = -1\.42: must be in"),
        ("R0 = 0.6694", "R0 = 1.2", r"lubricant\.R0 = 1\.2: must be in \(0, 1\)"),
        ("n_power = 0.74", "n_power = -0.5", r"lubricant\.n_power = -0\.5: must be in \(0, 1\]"),
        ("K00_GPa = 11.5", "K00_GPa = 0.0", r"lubricant\.K00_GPa"),
        ("torque_Nm = 71.8", "torque_Nm = -71.8", r"operating\.torque_Nm"),
        ("pinion_mass_kg = 0.4058", "pinion_mass_kg = 0.0", r"inertia\.pinion_mass_kg"),
        ("wheel_inertia_kgm2 = 6.7e-4", "wheel_inertia_kgm2 = -1.0", r"inertia\.wheel_inertia"),
        ("inlet_temperature_K = 348.15", "inlet_temperature_K = 0.0", r"operating\.inlet_temp"),
        ("sigma_pinion_um = 0.4", "sigma_pinion_um = 0.0", r"roughness\.sigma_pinion_um"),
        ("asperity_radius_um = 6.0", "asperity_radius_um = 0.0", r"roughness\.asperity_radius"),
        ("relaxation = 1.0", "relaxation = 2.0", r"solver\.relaxation = 2\.0: must be in \(0, 1\]"),
        ("backlash_um = 6.0", "backlash_um = -6.0", r"mesh\.backlash_um"),
        ("tolerance = 1.0e-3", "tolerance = 0.0", r"solver\.tolerance"),
    ],
)
def test_case_loader_checks_value_ranges(tmp_path, old, new, match):
    p = _write(tmp_path, lambda b: b.replace(old, new))
    with pytest.raises(ModelError, match=match):
        load_tribo_case(p)

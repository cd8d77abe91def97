"""SDOF gear dynamics with backlash (seed 003 Sec. 3, Eqs. 21-31; SEED-NOTES 16-17).

Linear limit against the analytic FRF, the dead zone (continuity, equilibrium, energy), the
compiled RK4 against its plain-Python reference and against solve_ivp, a coarse sweep of the
Kahraman-Blankenship pair at 340 N m with a seed-like parabolic compliance showing the
softening jump, and the seed-003 behaviour with the potential-energy compliance and tip relief
of models.stiffness (Secs. 4-5, Figs. 8-11): softening jump and hysteresis band, super-harmonic
near Lambda = 0.5, jump frequencies rising with load (VVMS, LSTE; not FVMS), VVMS ~ LSTE for
small fluctuation, FVMS -> VVMS as tip relief grows, FVMS far more intense at zeta = 0.02.

Not reproduced: the seed's double-sided impacts of the FVMS model at zeta = 0.02 (Sec. 4.1).
With this compliance (FVMS 1.9e8-3.4e8 N/m, 51 % of its mean peak to peak, no error) the
FVMS down-sweep peak reaches Arms ~1.5 b, period-2 and aperiodic points appear, but x - e
stays above -b.
The seed's FVMS curve is not given numerically, so no stronger check is possible.
"""

import numpy as np
import pytest

from models.dynamics import (
    SDOFModel,
    dead_zone,
    dead_zone_potential,
    periods,
    periods_reference,
    periods_solve_ivp,
    printed_contact_force,
    sdof_from_mesh_cycle,
    settle,
    settle_periodic,
    steady_state,
    sweep_up_down,
)
from models.dynamics.parallel import sweep_many
from models.errors import ModelError
from models.geometry import load_gear_set
from models.stiffness.mesh_cycle import Harmonics, mesh_cycle

KAHRAMAN = load_gear_set("kahraman-blankenship").pair
TORQUE_NM = 340.0  # seed 003 Secs. 4-5
HALF_BACKLASH_M = 0.136e-3 / 2  # seed Table 3: 2b = 0.136 mm on the line of action
ZETA = 0.02  # seed Sec. 4.2


def seed_like_compliance(pair=KAHRAMAN):
    """Parabolic compliance, 40 % higher at the tips, C(HPSTC) F(340 N m) = 16 um (Sec. 5.1)."""
    sp, E = pair.pitch_point, pair.end_of_contact
    shape = lambda s: 1 + 0.4 * ((np.asarray(s) - sp) / (E - sp)) ** 2  # noqa: E731
    F = TORQUE_NM / pair.base_radius(1)
    cp = 16e-6 / F / float(shape(pair.highest_point_single_contact))
    return lambda s: cp * shape(s)


@pytest.fixture(scope="module")
def cycle():
    return mesh_cycle(KAHRAMAN, seed_like_compliance(), TORQUE_NM, n_phases=200)


def sine_error(amplitude):
    return Harmonics(0.0, np.array([amplitude]), np.array([0.0]))


# --- dead zone (SEED-NOTES 16) -----------------------------------------------------------------
def test_dead_zone_is_continuous_and_the_printed_form_jumps_by_b():
    b, eps = 0.7, 1e-12
    for edge in (b, -b):
        assert abs(dead_zone(edge + eps, b) - dead_zone(edge - eps, b)) < 1e-11
        assert abs(dead_zone_potential(edge + eps, b) - dead_zone_potential(edge - eps, b)) < 1e-11
        jump = abs(printed_contact_force(edge + eps, b) - printed_contact_force(edge - eps, b))
        assert jump == pytest.approx(b)  # seed Eq. 22 as printed: a jump of k b
    u = np.linspace(-3, 3, 6001)
    np.testing.assert_allclose(
        np.gradient(dead_zone_potential(u, b), u), dead_zone(u, b), atol=1e-3
    )
    np.testing.assert_array_equal(dead_zone([-2.0, -0.5, 0.0, 0.5, 2.0], b), [-1.3, 0, 0, 0, 1.3])


def test_static_equilibrium_at_the_mean_load():
    """Constant stiffness, no excitation: from rest inside the gap to x = b + F."""
    m = SDOFModel(zeta=0.1, force=0.3, backlash=1.0)
    (x, v), n, ok = settle(m, 1.0, (0.0, 0.0), tol=1e-10, max_periods=2000)
    assert ok and n < 2000
    assert x == pytest.approx(m.static_dte(), abs=1e-8) and abs(v) < 1e-8
    assert dead_zone(x, 1.0) == pytest.approx(m.force)  # spring force balances the load


def test_energy_is_continuous_through_the_gap_and_impacts():
    """Zeta = 0: v^2/2 + V(x) - F x is conserved while the pair crosses the gap both ways."""
    m = SDOFModel(zeta=0.0, force=0.2, backlash=1.0)
    pts, xs, _ = periods(m, 1.0, (1.2, 2.0), 20, steps_per_period=512, record=True)
    assert xs.min() < -1.0 and xs.max() > 1.0  # drive-side and back-side contact
    energy = lambda x, v: 0.5 * v**2 + dead_zone_potential(x, 1.0) - m.force * x  # noqa: E731
    e0 = energy(1.2, 2.0)
    e = energy(pts[:, 0], pts[:, 1])
    # bounded, not drifting: RK4 is first order at the kinks; the printed h-form would jump
    # by b^2 / 2 = 0.28 e0 at every edge crossing
    assert np.max(np.abs(e - e0)) < 1e-4 * e0


# --- linear limit ------------------------------------------------------------------------------
@pytest.mark.parametrize("lam", [0.5, 0.9, 1.0, 1.3, 2.0])
def test_linear_limit_matches_the_analytic_frf(lam):
    """No backlash, k = 1, e = eps cos(Lambda tau): |X| = eps / |1 - Lambda^2 + 2 i zeta Lambda|."""
    zeta, eps = 0.05, 0.1
    m = SDOFModel(zeta=zeta, force=0.0, backlash=0.0, error=sine_error(eps))
    _, fig = steady_state(m, lam, (0.0, 0.0), tol=1e-9, max_periods=5000)
    exact = eps / abs(1 - lam**2 + 2j * zeta * lam)
    assert fig["converged"]
    assert fig["amplitudes"][0] == pytest.approx(exact, rel=1e-3)
    assert fig["amplitudes"][1] < 1e-6 and fig["amplitudes"][2] < 1e-6
    assert fig["arms"] == pytest.approx(exact, rel=1e-3)


# --- integrators -------------------------------------------------------------------------------
@pytest.mark.parametrize("kind", ["fvms", "vvms", "lste"])
def test_compiled_and_reference_rk4_agree(cycle, kind):
    m = sdof_from_mesh_cycle(cycle, kind, zeta=ZETA, backlash_m=HALF_BACKLASH_M)
    y0 = (m.static_dte() + 0.5, 0.3)  # starts with contact loss
    a, _, _ = periods(m, 0.95, y0, 15, steps_per_period=64)
    b = periods_reference(m, 0.95, y0, 15, steps_per_period=64)
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    ("kind", "lam", "y_offset", "atol"),
    [
        ("vvms", 1.3, 0.0, 1e-6),  # parametric + mesh harmonics, in contact throughout
        ("lste", 0.7, 0.0, 1e-6),
        # FVMS's gear error keeps the cycle's relief kinks, so RK4 converges at first order
        # there: 512 / 1024 / 2048 steps per period miss solve_ivp (rtol 1e-11) by 8.7e-7 /
        # 4.0e-7 / 1.8e-7 at the fourth period; scipy 1.17's RK45 at rtol 1e-9 sits 5e-8 off.
        ("fvms", 1.0, 0.0, 2e-6),
        ("vvms", 0.95, 0.6, 3e-5),  # contact loss: RK4 loses order at the kink
    ],
)
def test_rk4_matches_solve_ivp(cycle, kind, lam, y_offset, atol):
    m = sdof_from_mesh_cycle(cycle, kind, zeta=ZETA, backlash_m=HALF_BACKLASH_M, n_harmonics=5)
    y0 = (m.static_dte() + y_offset, 0.0)
    a, _, _ = periods(m, lam, y0, 4, steps_per_period=512)
    b = periods_solve_ivp(m, lam, y0, 4, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(a, b, rtol=0, atol=atol)


# --- contact flags ------------------------------------------------------------------------------
def _min_offset_margin(model, lam, y, side, steps=4096):
    """Smallest ``x - e`` (drive) or ``x - e_b`` (back) over one period, finely sampled."""
    from models.dynamics.integrate import model_tables

    _, xs, _ = periods(model, lam, y, 1, steps_per_period=steps, record=True)
    t = model_tables(model, steps)
    off = t.drive_offset if side == "drive" else t.back_offset
    return float(np.min(xs - off[::2]))


@pytest.mark.parametrize(("lam", "impact"), [(0.7, False), (0.9, True), (1.2, True), (1.5, False)])
def test_backside_impact_flag_agrees_with_the_recorded_dte(lam, impact):
    """Back-side impact flag, set and not set, against the recorded ``x - e``.

    zeta = 0.05, F = 0.1, b = 1, e = 0.3 cos: the static state is b + F = 1.1 (so x - e must
    swing by more than 2 b + F = 2.1 to reach the back flank), the linear response at
    resonance is e / (2 zeta) = 3: near resonance (Lambda 0.9-1.2, double-sided impacts, mostly
    aperiodic, so not in every period) the back flank is hit in the recorded periods at 0.9
    and 1.2; at 0.7 (period 2) and 1.5 only the drive side separates. The flags of four
    recorded periods must agree with ``x - e`` of the same four periods (same RK4 steps,
    recorded at the step starts; margins > 1e-3 so the sub-step Hermite check cannot tip
    them).
    """
    m = SDOFModel(zeta=0.05, force=0.1, backlash=1.0, error=sine_error(0.3))
    s = settle_periodic(m, lam, (m.start_dte(), 0.0), tol=1e-8, max_periods=1500)
    _, fig = steady_state(m, lam, s.state, min_periods=0, max_periods=0, record_periods=4)
    _, _, u = periods(m, lam, s.state, 4, steps_per_period=128, record=True)
    assert abs(u.min() + 1.0) > 1e-3 and abs(u.min() - 1.0) > 1e-3
    assert fig["backside_impact"] == (u.min() < -1.0) == impact
    assert fig["contact_loss"] and u.min() < 1.0  # every case loses drive-side contact


@pytest.mark.parametrize(("depth", "lost"), [(3e-4, True), (-3e-4, False)])
def test_brief_contact_loss_between_step_starts_is_flagged(depth, lost):
    """A loss shorter than an RK4 step is caught by the Hermite check of the whole step.

    Linear in contact: u = x - e = b + F + z, |z| = |X - eps| with X the FRF (hand-derived);
    F = |z| (1 - depth) makes u dip below b by depth |z| for ~0.3 % of a period only
    (depth > 0) or stay 5e-5 above (depth < 0). At 64 steps per period every step start stays
    above b in both cases; the flag must match the orbit sampled 4096 times per period.
    """
    zeta, eps, lam = 0.05, 0.1, 0.8
    X = eps / (1 - lam**2 + 2j * zeta * lam)
    m = SDOFModel(zeta=zeta, force=abs(X - eps) * (1 - depth), backlash=1.0, error=sine_error(eps))
    y0 = (1 + m.force + X.real, (1j * lam * X).real)  # on the linear orbit
    y, fig = steady_state(m, lam, y0, tol=1e-11, max_periods=3000, steps_per_period=64)
    _, _, u64 = periods(m, lam, y, 1, steps_per_period=64, record=True)
    assert u64.min() > 1.0  # step starts alone would miss the loss
    fine = _min_offset_margin(m, lam, y, "drive")
    assert (fine < 1.0) == lost and abs(fine - 1.0) > 3e-5  # clear of the threshold
    assert fig["contact_loss"] == lost


# --- models from the mesh cycle ----------------------------------------------------------------
def test_models_from_the_mesh_cycle(cycle):
    for kind in ("fvms", "vvms", "lste"):
        m = sdof_from_mesh_cycle(cycle, kind, zeta=ZETA, backlash_m=HALF_BACKLASH_M)
        assert m.stiffness.mean == pytest.approx(1.0)
        assert m.backlash == pytest.approx(1.0)
        assert m.force == pytest.approx(cycle.load_N / (m.mean_stiffness_N_m * HALF_BACKLASH_M))
    lste = sdof_from_mesh_cycle(cycle, "lste", zeta=ZETA, backlash_m=HALF_BACKLASH_M)
    assert lste.stiffness.amplitude.size == 0 and lste.error.mean == 0.0
    # quasi-static LSTE model reproduces the LSTE: (x - b) L = x_s(t)
    tau = np.linspace(0, 1, 7)
    qs = (lste.force + lste.error(tau)) * HALF_BACKLASH_M
    np.testing.assert_allclose(qs, cycle.lste_harmonics(tau), rtol=1e-12)
    assert (
        sdof_from_mesh_cycle(
            cycle, "vvms", zeta=ZETA, backlash_m=HALF_BACKLASH_M
        ).error.amplitude.size
        == 0
    )
    with pytest.raises(ModelError):
        sdof_from_mesh_cycle(cycle, "ehl", zeta=ZETA, backlash_m=HALF_BACKLASH_M)
    with pytest.raises(ModelError):
        SDOFModel(zeta=-0.1, force=0.0, backlash=0.0)


# --- Kahraman sweep (seed Secs. 4-5) -----------------------------------------------------------
def test_kahraman_sweep_shows_the_softening_jump(cycle):
    """VVMS, zeta = 0.02, 340 N m: up and down sweeps differ below Lambda = 1 (softening)."""
    m = sdof_from_mesh_cycle(cycle, "vvms", zeta=ZETA, backlash_m=HALF_BACKLASH_M)
    lam = np.linspace(0.4, 1.4, 30)
    up, down = sweep_up_down(m, lam, steps_per_period=64, tol=1e-5, max_periods=200)
    near = (lam > 0.75) & (lam < 0.94)
    # down sweep stays on the large contact-loss branch; up sweep on the small linear one
    assert np.all(down.arms[near] > 2 * up.arms[near])
    assert np.all(down.contact_loss[near]) and not np.any(up.contact_loss[near])
    # the up sweep jumps up just below Lambda = 1 and loses contact there
    i_jump = np.argmax(np.diff(up.arms) * (lam[1:] > 0.8))
    assert 0.85 < lam[i_jump + 1] < 1.0 and up.arms[i_jump + 1] > 2 * up.arms[i_jump]
    assert up.contact_loss[i_jump + 1]
    # above resonance the branches coincide; no back-side impact at this load and damping
    hi = lam > 1.1
    np.testing.assert_allclose(up.arms[hi], down.arms[hi], rtol=1e-3)
    assert not up.backside_impact.any() and not down.backside_impact.any()
    # super-harmonic resonance near Lambda = 0.5 (second mesh harmonic at the natural frequency)
    sub = (lam > 0.45) & (lam < 0.56)
    assert up.arms[sub].max() > 2 * up.arms[np.argmin(np.abs(lam - 0.65))]
    assert up.arms_m[0] == pytest.approx(up.arms[0] * HALF_BACKLASH_M)


# --- seed 003 behaviour with the potential-energy compliance and tip relief ---------------------
# The compliance of models.stiffness.potential_energy (Hertz included), tabulated on AE; tip
# relief Delta (seed Sec. 5.1, Ln = 1) from models.stiffness.tip_relief. Coarse sweeps (64 RK4
# steps per mesh period, Lambda step 0.02, tol 1e-5) keep the default run fast; the features
# asserted are several grid steps wide.
LAM = np.round(np.arange(0.4, 1.4001, 0.02), 3)
COARSE = dict(steps_per_period=64, tol=1e-5, max_periods=300)
NON_RESONANT = ((LAM > 0.58) & (LAM < 0.8)) | (LAM > 1.2)


@pytest.fixture(scope="module")
def pe_compliance():
    from models.stiffness import pair_compliance, tabulate_compliance

    return tabulate_compliance(KAHRAMAN, lambda s: pair_compliance(KAHRAMAN, s).total_m_per_N)


def pe_models(pe_compliance, kind, torques=(TORQUE_NM,), relief=0.0, zeta=ZETA):
    from models.stiffness import normalised_tip_relief, prepare_mesh_cycle

    tr = normalised_tip_relief(KAHRAMAN, pe_compliance, TORQUE_NM, amount=relief)
    geo = prepare_mesh_cycle(KAHRAMAN, pe_compliance, error=tr, n_phases=200)
    return [
        sdof_from_mesh_cycle(
            geo.solve(t), kind, zeta=zeta, backlash_m=HALF_BACKLASH_M, error="cycle"
        )
        for t in torques
    ]


def jump_up(up):
    """Index of the up sweep's jump onto the contact-loss branch.

    The first point above Lambda 0.7 where the up sweep loses contact: the jump onto the
    contact-loss branch of the primary resonance.
    """
    return int(np.argmax(up.contact_loss & (up.frequency > 0.7)))


def jump_down(down):
    """Index of the down sweep's drop off the contact-loss branch.

    The lowest Lambda above 0.6 where the (sorted) down sweep still loses contact: below it
    the down sweep has dropped off the contact-loss branch.
    """
    return int(np.argmax(down.contact_loss & (down.frequency > 0.6)))


@pytest.mark.parametrize("kind", ["vvms", "lste", "itms"])
def test_seed003_softening_jump_and_superharmonic_pe_compliance(pe_compliance, kind):
    """Softening jump and super-harmonic, potential-energy compliance (seed Sec. 4.1).

    Unmodified Kahraman pair, 340 N m, zeta = 0.02 (seed Fig. 8): primary
    resonance near Lambda = 1 with a softening jump (the up sweep jumps up at a higher
    frequency than the down sweep jumps down; between them the down sweep rides the
    contact-loss branch), and a super-harmonic resonance near Lambda = 0.5.
    """
    (m,) = pe_models(pe_compliance, kind)
    res, _ = sweep_many([m], LAM, **COARSE)
    up, down = res[0], res[1].sorted()
    iu, idn = jump_up(up), jump_down(down)
    # ITMS is scaled with k_0 = the mean FVMS, which leaves out corner contact: the loaded
    # pairs see more stiffness (corner-contact pairs join), so in its own Lambda the ITMS
    # resonance sits a little above 1
    assert 0.88 < LAM[iu] < 1.1
    assert LAM[idn] < LAM[iu] - 0.06  # a hysteresis band of several grid steps
    band = slice(idn, iu)
    assert np.all(down.contact_loss[band]) and not np.any(up.contact_loss[band])
    assert np.all(down.arms[band] > 1.2 * up.arms[band])  # the branches merge at the jump
    assert np.mean(down.arms[band] / up.arms[band]) > 3
    hi = LAM > 1.12
    np.testing.assert_allclose(up.arms[hi], down.arms[hi], rtol=2e-3)
    assert not up.backside_impact.any() and not down.backside_impact.any()
    assert np.all(up.converged) and np.all(up.period == 1)
    sup = (LAM > 0.44) & (LAM < 0.56)
    assert up.arms[sup].max() > 3 * up.arms[np.argmin(np.abs(LAM - 0.66))]


def test_seed003_jump_frequencies_move_with_load(pe_compliance):
    """Jump frequencies move with load in VVMS and LSTE, not in FVMS (seed Fig. 9).

    Seed Sec. 4.1: for 100, 200, 300 N m the resonance grows with torque and the
    jump frequencies are load dependent (they rise with load, as the measured natural
    frequency does) in the load-dependent VVMS and LSTE models, while the load-independent
    FVMS model keeps one natural frequency and jumps at the same mesh frequency.
    """
    from models.dynamics.dimensional import dimensional_scaling

    torques = (100.0, 200.0, 300.0)
    for kind in ("vvms", "lste", "fvms"):
        ms = pe_models(pe_compliance, kind, torques)
        res, _ = sweep_many(ms, LAM, directions=("up",), **COARSE)
        hz = [
            float(dimensional_scaling(m, KAHRAMAN).mesh_frequency_Hz(LAM[jump_up(r)]))
            for m, r in zip(ms, res, strict=True)
        ]
        peak_um = [r.arms.max() * HALF_BACKLASH_M * 1e6 for r in res]
        assert peak_um[0] < peak_um[1] < peak_um[2], (kind, peak_um)
        if kind == "fvms":
            assert max(hz) - min(hz) < 0.025 * hz[0], (kind, hz)
        else:
            assert hz[0] < hz[1] < hz[2] and hz[2] > 1.03 * hz[0], (kind, hz)


def test_seed003_vvms_equals_lste_for_small_fluctuation(pe_compliance):
    """VVMS ~ LSTE for small fluctuation (seed Sec. 5.1(3)).

    With Delta = 1 (small LSTE/VVMS fluctuation) the VVMS and LSTE
    responses are 'entirely the same'; without relief they differ visibly.
    """
    diffs = []
    for relief in (0.0, 1.0):
        ms = [pe_models(pe_compliance, k, relief=relief)[0] for k in ("vvms", "lste")]
        res, _ = sweep_many(ms, LAM, directions=("up",), **COARSE)
        rel = np.abs(res[1].arms / res[0].arms - 1)
        diffs.append((rel.mean(), rel[NON_RESONANT].max()))
    assert diffs[1][0] < 0.02 and diffs[1][1] < 0.02, diffs
    assert diffs[0][0] > 3 * diffs[1][0], diffs


def test_seed003_fvms_approaches_vvms_as_tip_relief_grows(pe_compliance):
    """FVMS -> VVMS as tip relief grows (seed Sec. 5.1(2), Fig. 11).

    As the relief grows, corner contact fades and the FVMS
    response approaches the VVMS one, especially away from resonance.
    """
    gaps = []
    for relief in (0.0, 0.5, 1.0):
        ms = [pe_models(pe_compliance, k, relief=relief)[0] for k in ("vvms", "fvms")]
        res, _ = sweep_many(ms, LAM, directions=("up",), **COARSE)
        gaps.append(float(np.mean(np.abs(res[1].arms / res[0].arms - 1)[NON_RESONANT])))
    assert gaps[0] > gaps[1] > gaps[2], gaps
    assert gaps[0] > 1.0 and gaps[2] < 0.25, gaps


def test_seed003_fvms_is_far_more_intense_at_low_damping(pe_compliance):
    """FVMS at zeta = 0.02 responds far more strongly than VVMS (seed Sec. 4.1).

    The seed: 'for the FVMS model, such a low damping ratio will yield such an intense
    response ...' (it reports double-sided impacts, which this model does not reach: see the
    module notes); with zeta = 0.07 (Liu and Parker) the FVMS peak comes down.
    """
    ms = [pe_models(pe_compliance, k)[0] for k in ("fvms", "vvms")]
    ms.append(pe_models(pe_compliance, "fvms", zeta=0.07)[0])
    res, _ = sweep_many(ms, LAM, directions=("down",), **COARSE)
    fvms, vvms, fvms_07 = (r.arms.max() for r in res)
    assert fvms > 2 * vvms and fvms_07 < 0.7 * fvms, (fvms, vvms, fvms_07)


@pytest.mark.slow
def test_seed003_sweeps_at_full_resolution(pe_compliance):
    """The coarse-sweep findings hold at 128 steps per period, Lambda step 0.005, tol 1e-7."""
    lam = np.round(np.arange(0.4, 1.4001, 0.005), 4)
    ms = [pe_models(pe_compliance, k)[0] for k in ("vvms", "lste", "itms")]
    res, _ = sweep_many(ms, lam, steps_per_period=128, tol=1e-7, max_periods=2000)
    for i in range(3):
        up, down = res[2 * i], res[2 * i + 1].sorted()
        iu, idn = jump_up(up), jump_down(down)
        assert 0.88 < lam[iu] < 1.1 and lam[idn] < lam[iu] - 0.05
        assert np.all(down.arms[idn:iu] > 1.2 * up.arms[idn:iu])
        sup = (lam > 0.44) & (lam < 0.56)
        assert up.arms[sup].max() > 3 * up.arms[np.argmin(np.abs(lam - 0.66))]

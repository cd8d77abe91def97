"""ITMS model (seed 003 Eq. 28): one dead-zone spring per tooth pair, from the mesh cycle.

Sources of the expected numbers:
* quasi-static solution = the LSTE of the static analysis (seed Eqs. 5-17, computed by
  ``models.stiffness.mesh_cycle``), an independent implementation of the same compatibility
  conditions;
* ITMS = FVMS (Eq. 26) when all pairs share one error and none separates: the sum of the pair
  springs is ``k_F`` (Eqs. 18-19), so the two right-hand sides are the same function;
* compiled RK4 = plain-Python RK4 (same operations), and = solve_ivp (RK45, rtol 1e-9) on the
  continuous-time right-hand side;
* ITMS ~ VVMS trends (seed Sec. 5.2): both reduce to the LSTE quasi-statically and both show
  the primary resonance with contact loss and the super-harmonic at Lambda ~ 0.5.
"""

import numpy as np
import pytest

from models.dynamics import (
    periods,
    periods_reference,
    periods_solve_ivp,
    sdof_from_mesh_cycle,
    steady_state,
    sweep,
)
from models.dynamics.itms import ITMSModel, itms_from_mesh_cycle
from models.errors import ModelError
from models.geometry import load_gear_set
from models.stiffness import (
    mesh_cycle,
    normalised_tip_relief,
    pair_compliance,
    tabulate_compliance,
)

PAIR = load_gear_set("kahraman-blankenship").pair
TORQUE_NM = 340.0  # seed 003 Secs. 4-5
HALF_BACKLASH_M = 0.136e-3 / 2  # seed Table 3
ZETA = 0.02


@pytest.fixture(scope="module")
def compliance():
    return tabulate_compliance(PAIR, lambda s: pair_compliance(PAIR, s).total_m_per_N)


@pytest.fixture(scope="module", params=[0.0, 1.0], ids=["unmodified", "relief-1"])
def cycle(request, compliance):
    relief = normalised_tip_relief(PAIR, compliance, TORQUE_NM, amount=request.param)
    return mesh_cycle(PAIR, compliance, TORQUE_NM, error=relief, n_phases=200)


def test_quasi_static_itms_is_the_lste(cycle):
    """sum_j k_j max(x - b - g_j, 0) = F at every phase gives x - b = x_s (seed Eqs. 5-17)."""
    m = itms_from_mesh_cycle(cycle, zeta=ZETA, backlash_m=HALF_BACKLASH_M)
    x = m.quasi_static_dte(cycle.phase)
    np.testing.assert_allclose((x - m.backlash) * HALF_BACKLASH_M, cycle.lste_m, rtol=1e-12)
    # and the force balance holds there
    for i in (0, 57, 140):
        assert m.contact_force(cycle.phase[i], x[i]) == pytest.approx(m.force, rel=1e-12)
    assert m.kind == "itms" and m.mean_stiffness_N_m == cycle.fvms_harmonics.mean
    assert isinstance(
        sdof_from_mesh_cycle(cycle, "itms", zeta=ZETA, backlash_m=HALF_BACKLASH_M), ITMSModel
    )


def test_partial_contact_loss_is_per_pair(cycle):
    """A pair touches only while x - b exceeds its own gap: fewer pairs as x drops."""
    m = itms_from_mesh_cycle(cycle, zeta=ZETA, backlash_m=HALF_BACKLASH_M)
    kd, ed, _, _ = m.pair_tables(100)  # 2 N = 200: exactly the cycle's phases
    i = 10  # double contact in the unmodified cycle
    x = m.quasi_static_dte(cycle.phase[[i]])[0]
    touching = (kd[i] > 0) & (x - m.backlash > ed[i])
    np.testing.assert_array_equal(touching, cycle.in_contact[i])
    # stiffness seen just below x: only the pairs with the smallest gap remain
    lo = np.sort(ed[i][kd[i] > 0])[0] + m.backlash
    assert m.contact_force(cycle.phase[i], lo) == pytest.approx(0.0, abs=1e-15)


@pytest.mark.parametrize(
    ("back_flank", "sign"), [("seed", 1.0), ("unmodified", 0.0), ("mirror", -1.0)]
)
def test_itms_equals_fvms_for_a_common_error_and_no_separation(compliance, back_flank, sign):
    """No corner contact, one constant error for every pair: ITMS == FVMS (Eq. 26 = Eq. 28).

    Drive side: ``k_F max(x - e - b, 0)``; back side ``k_F min(x - e_b + b, 0)`` with the
    back-flank offset ``e_b = sign * e`` of the chosen back flank, in both models.
    """
    e0 = 5e-6
    cyc = mesh_cycle(
        PAIR,
        compliance,
        TORQUE_NM,
        n_phases=200,
        corner_contact=False,
        error=lambda s: np.full(np.shape(s), e0),
    )
    itms = itms_from_mesh_cycle(cyc, zeta=ZETA, backlash_m=HALF_BACKLASH_M, back_flank=back_flank)
    fvms = sdof_from_mesh_cycle(
        cyc,
        "fvms",
        zeta=ZETA,
        backlash_m=HALF_BACKLASH_M,
        error="cycle",
        source="curve",
        back_flank=back_flank,
    )
    assert fvms.mean_stiffness_N_m == pytest.approx(itms.mean_stiffness_N_m, rel=1e-12)
    assert fvms.force == pytest.approx(itms.force, rel=1e-12)
    assert fvms.error.mean == pytest.approx(e0 / HALF_BACKLASH_M, rel=1e-12)
    for phase in (0.0, 0.13, 0.5, 0.77, 0.999):
        for x in (-2.0, -0.5, 0.9, 1.3, 2.5):  # back side, gap, drive side
            kf = float(fvms.stiffness(phase))
            u = x - float(fvms.error(phase))
            w = x - sign * float(fvms.error(phase))
            f = kf * (max(u - 1, 0.0) + min(w + 1, 0.0))
            assert itms.contact_force(phase, x) == pytest.approx(f, rel=1e-12, abs=1e-14)
            assert fvms.rhs(phase * 2 * np.pi, np.array([x, 0.0]), 1.0)[1] == pytest.approx(
                fvms.force - f, rel=1e-12, abs=1e-14
            )
    y0 = (fvms.start_dte() + 0.8, 0.0)  # with contact loss and a back-side excursion
    a, _, _ = periods(itms, 0.9, y0, 10, steps_per_period=100)
    b, _, _ = periods(fvms, 0.9, y0, 10, steps_per_period=100)
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-11)


BACK_SIGN = {"unmodified": 0.0, "mirror": -1.0, "seed": 1.0}


@pytest.mark.parametrize("back_flank", list(BACK_SIGN))
def test_back_side_contact_of_each_back_flank(cycle, back_flank):
    """Back-side force from the cycle's arrays, pair by pair (independent of the passage tables).

    Only pairs on the theoretical path AE (zero separation) touch on the back side, with their
    compliance and the back offset e_b = sign * e_j (0 unmodified, -e mirror, +e seed Eq. 28).
    Deep in back contact with unmodified flanks that is the FVMS: -k_F (|x| - b).
    """
    m = itms_from_mesh_cycle(cycle, zeta=ZETA, backlash_m=HALF_BACKLASH_M, back_flank=back_flank)
    k0, L = m.mean_stiffness_N_m, HALF_BACKLASH_M
    on = cycle.separation_m == 0.0
    for i in range(0, cycle.phase.size, 7):
        k = np.where(on[i], 1.0 / cycle.compliance_m_N[i], 0.0) / k0
        eb = BACK_SIGN[back_flank] * cycle.error_m[i] / L
        for x in (-3.0, -1.3, -1.1, -1.0 + 1e-9, -0.8):
            expected = float(np.sum(k * np.minimum(x + 1.0 - eb, 0.0)))
            got = m.contact_force(cycle.phase[i], x)
            assert got == pytest.approx(expected, rel=1e-9, abs=1e-12), (i, x)
        if back_flank == "unmodified":  # corner-contact pairs never touch the back flank
            deep = m.contact_force(cycle.phase[i], -3.0)
            assert deep == pytest.approx(-2.0 * cycle.fvms_N_m[i] / k0, rel=1e-9)


def test_relieved_drive_flanks_do_not_narrow_the_back_gap(compliance):
    """Delta = 1: back contact starts at x = -b unless the back flank is modelled otherwise.

    The relief reaches 25.7 um = 0.378 b at the tips; seed Eq. 28 taken literally (``"seed"``)
    lets the back flank touch from x = -0.62 b there, the unmodified back flank only at -b,
    and a mirrored relief only below -b - 0.378 b.
    """
    relief = normalised_tip_relief(PAIR, compliance, TORQUE_NM, amount=1.0)
    cyc = mesh_cycle(PAIR, compliance, TORQUE_NM, error=relief, n_phases=200)
    e_max = float(np.max(np.where(cyc.separation_m == 0.0, cyc.error_m, 0.0))) / HALF_BACKLASH_M
    assert 0.3 < e_max < 0.45
    i = int(np.argmax(np.max(np.where(cyc.separation_m == 0.0, cyc.error_m, 0.0), axis=1)))
    x_inside = -1.0 + 0.9 * e_max  # inside the true gap of unmodified back flanks
    force = {
        bf: itms_from_mesh_cycle(
            cyc, zeta=ZETA, backlash_m=HALF_BACKLASH_M, back_flank=bf
        ).contact_force(cyc.phase[i], x_inside)
        for bf in BACK_SIGN
    }
    assert force["unmodified"] == 0.0 and force["mirror"] == 0.0
    assert force["seed"] < -1e-3  # the seed convention already pushes back here
    x_deep = -1.0 - 0.5 * e_max  # past -b: unmodified touches, the mirrored relief not yet
    m = itms_from_mesh_cycle(cyc, zeta=ZETA, backlash_m=HALF_BACKLASH_M, back_flank="mirror")
    u = itms_from_mesh_cycle(cyc, zeta=ZETA, backlash_m=HALF_BACKLASH_M)
    assert u.contact_force(cyc.phase[i], x_deep) < m.contact_force(cyc.phase[i], x_deep) <= 0.0
    # the default is the unmodified back flank, also through sdof_from_mesh_cycle
    assert u.contact_force(cyc.phase[i], x_inside) == 0.0
    via = sdof_from_mesh_cycle(cyc, "itms", zeta=ZETA, backlash_m=HALF_BACKLASH_M)
    assert via.contact_force(cyc.phase[i], x_inside) == 0.0
    with pytest.raises(ModelError, match="back_flank"):
        itms_from_mesh_cycle(cyc, zeta=ZETA, backlash_m=HALF_BACKLASH_M, back_flank="inverse")  # type: ignore[arg-type]


def test_backside_impact_flag_of_the_itms_model(compliance):
    """ITMS back-side impacts: the flag agrees with the recorded ``x - e_b`` (seed 003 Sec. 3.1).

    Delta = 1 relief, 340 N m, zeta = 0.02, a small half backlash of 10 um (tilde F = 1.6):
    down the resonance the seed's back-flank convention (relief narrowing the back gap) hits
    the back flank, unmodified back flanks do not. The flags of four recorded periods are
    checked against x - e_b at the same RK4 step starts.
    """
    from models.dynamics.integrate import model_tables, settle_periodic

    relief = normalised_tip_relief(PAIR, compliance, TORQUE_NM, amount=1.0)
    cyc = mesh_cycle(PAIR, compliance, TORQUE_NM, error=relief, n_phases=200)
    lam = np.array([1.0, 0.96, 0.92, 0.9])
    seen = {}
    for bf in ("seed", "unmodified"):
        m = itms_from_mesh_cycle(cyc, zeta=ZETA, backlash_m=10e-6, back_flank=bf)
        r = sweep(m, lam, steps_per_period=128, tol=1e-6, max_periods=600)
        s = settle_periodic(m, 0.9, tuple(r.entry_state[-1]), tol=1e-6, max_periods=600)
        _, fig = steady_state(m, 0.9, s.state, min_periods=0, max_periods=0, record_periods=4)
        _, xs, _ = periods(m, 0.9, s.state, 4, steps_per_period=128, record=True)
        boff = np.tile(model_tables(m, 128).back_offset[::2], 4)
        margin = float(np.min(xs - boff)) + m.backlash
        assert abs(margin) > 1e-2
        assert fig["backside_impact"] == (margin < 0.0) == bool(r.backside_impact[-1])
        seen[bf] = fig["backside_impact"]
    assert seen == {"seed": True, "unmodified": False}


def test_fvms_takes_the_tip_relief_of_the_cycle_by_default(cycle):
    """The FVMS model's error defaults to the cycle's profile errors (seed Sec. 5.1)."""
    m = sdof_from_mesh_cycle(cycle, "fvms", zeta=ZETA, backlash_m=HALF_BACKLASH_M)
    explicit = sdof_from_mesh_cycle(
        cycle, "fvms", zeta=ZETA, backlash_m=HALF_BACKLASH_M, error="cycle"
    )
    np.testing.assert_array_equal(m.error(cycle.phase), explicit.error(cycle.phase))
    none = sdof_from_mesh_cycle(cycle, "fvms", zeta=ZETA, backlash_m=HALF_BACKLASH_M, error=None)
    assert np.all(none.error(cycle.phase) == 0.0)
    relieved = np.any(cycle.error_m != 0.0)
    assert (np.ptp(m.error(cycle.phase)) > 0.1) == relieved  # relief: e_F spans > 0.1 b
    # unmodified back flanks: the back side sees no error; mirrored: the negated one
    assert np.all(m.pair_tables(100)[3] == 0.0)
    mir = sdof_from_mesh_cycle(
        cycle, "fvms", zeta=ZETA, backlash_m=HALF_BACKLASH_M, back_flank="mirror"
    )
    np.testing.assert_allclose(mir.pair_tables(100)[3], -m.pair_tables(100)[1], atol=1e-15)


def test_static_pair_count_is_the_contact_of_the_static_analysis(cycle):
    """Pairs carrying load in the quasi-static ITMS solution = the static analysis' contacts."""
    from models.dynamics.integrate import static_pair_count

    m = itms_from_mesh_cycle(cycle, zeta=ZETA, backlash_m=HALF_BACKLASH_M)
    kd, ed, _, _ = m.pair_tables(100)  # 2 N = 200: the cycle's phases
    np.testing.assert_array_equal(
        static_pair_count(kd, ed, m.force), np.sum(cycle.in_contact, axis=1)
    )


def test_partial_contact_loss_fraction(compliance):
    """Partial contact loss of the ITMS model, recounted from the recorded DTE (seed Sec. 5.2).

    Delta = 1, 340 N m, zeta = 0.02, coarse steps (64): at resonance (Lambda = 1) pairs that
    carry load statically separate while another still touches for a large part of the
    period; well above resonance (1.3) never. The kernel's fraction must equal the count from
    x at the same RK4 step starts, the pair tables and the quasi-static DTE of the model
    (ITMSModel.quasi_static_dte). A single-spring model never has partial loss.
    """
    from models.dynamics.integrate import settle_periodic

    relief = normalised_tip_relief(PAIR, compliance, TORQUE_NM, amount=1.0)
    cyc = mesh_cycle(PAIR, compliance, TORQUE_NM, error=relief, n_phases=200)
    m = itms_from_mesh_cycle(cyc, zeta=ZETA, backlash_m=HALF_BACKLASH_M)
    n = 64
    kd, ed, _, _ = m.pair_tables(n)
    kd, ed = kd[::2], ed[::2]  # step starts
    xqs = m.quasi_static_dte(np.arange(n) / n)
    static = np.sum((kd > 0) & (xqs[:, None] - m.backlash - ed > 1e-9), axis=1)
    frac = {}
    for lam in (1.0, 1.3):
        s = settle_periodic(
            m, lam, (m.start_dte(), 0.0), steps_per_period=n, tol=1e-6, max_periods=600
        )
        _, fig = steady_state(
            m, lam, s.state, steps_per_period=n, min_periods=0, max_periods=0, record_periods=4
        )
        _, xs, _ = periods(m, lam, s.state, 4, steps_per_period=n, record=True)
        touching = np.sum(
            (np.tile(kd, (4, 1)) > 0) & (xs[:, None] - np.tile(ed, (4, 1)) > m.backlash), axis=1
        )
        expected = np.mean((touching > 0) & (touching < np.tile(static, 4)))
        assert fig["partial_contact_loss"] == pytest.approx(expected, abs=1e-12)
        frac[lam] = fig["partial_contact_loss"]
    assert frac[1.0] > 0.1 and frac[1.3] == 0.0
    v = sdof_from_mesh_cycle(cyc, "vvms", zeta=ZETA, backlash_m=HALF_BACKLASH_M)
    r = sweep(v, [1.1, 1.05, 1.0, 0.95], steps_per_period=n, tol=1e-5, max_periods=300)
    assert np.all(r.partial_contact_loss == 0.0) and r.arms.max() > 0.2  # through resonance


def test_compiled_reference_and_solve_ivp_agree(cycle):
    m = itms_from_mesh_cycle(cycle, zeta=ZETA, backlash_m=HALF_BACKLASH_M)
    y0 = (m.start_dte() + 0.4, 0.0)
    a, _, _ = periods(m, 0.95, y0, 6, steps_per_period=64)
    b = periods_reference(m, 0.95, y0, 6, steps_per_period=64)
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)
    # RK4 at 1000 steps per period against the adaptive integrator on the interpolated curves
    # (the tables sample the same piecewise-linear curves; kinks limit RK4 to ~1e-5)
    c, _, _ = periods(m, 1.3, (m.start_dte(), 0.0), 3, steps_per_period=1000)
    d = periods_solve_ivp(m, 1.3, (m.start_dte(), 0.0), 3, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(c, d, rtol=0, atol=2e-5)


def test_itms_and_vvms_trends(compliance):
    """ITMS ~ VVMS trends (seed Secs. 4.1, 5.2).

    Unmodified pair at 340 N m: same quasi-static Arms, resonance with contact loss near
    Lambda = 1 and super-harmonic near 0.5 in both (seed Secs. 4.1, 5.2).
    """
    cyc = mesh_cycle(PAIR, compliance, TORQUE_NM, n_phases=200)
    itms = itms_from_mesh_cycle(cyc, zeta=ZETA, backlash_m=HALF_BACKLASH_M)
    vvms = sdof_from_mesh_cycle(cyc, "vvms", zeta=ZETA, backlash_m=HALF_BACKLASH_M)
    # quasi-static: both are the LSTE (its harmonics 1-3, in units of b)
    lste = np.sqrt(np.sum(cyc.lste_harmonics.amplitude[:3] ** 2)) / HALF_BACKLASH_M
    for m in (itms, vvms):
        _, fig = steady_state(
            m, 0.05, (m.start_dte(), 0.0), tol=1e-8, max_periods=400, steps_per_period=128
        )
        assert fig["arms"] == pytest.approx(lste, rel=0.03)
    lam = np.round(np.arange(0.4, 1.4001, 0.02), 3)
    for m in (itms, vvms):
        r = sweep(m, lam, steps_per_period=64, tol=1e-5, max_periods=300)
        i = int(np.argmax(r.arms))
        assert 0.9 < lam[i] < 1.1 and r.contact_loss[i]
        sup = r.arms[(lam > 0.44) & (lam < 0.56)].max()
        assert sup > 3 * r.arms[np.argmin(np.abs(lam - 0.66))]


def test_validation(cycle):
    with pytest.raises(ModelError, match="length scale"):
        itms_from_mesh_cycle(cycle, zeta=ZETA, backlash_m=0.0)
    with pytest.raises(ModelError, match="zeta"):
        itms_from_mesh_cycle(cycle, zeta=-1.0, backlash_m=HALF_BACKLASH_M)

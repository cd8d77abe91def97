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


def test_itms_equals_fvms_for_a_common_error_and_no_separation(compliance):
    """No corner contact, one constant error for every pair: ITMS == FVMS (Eq. 26 = Eq. 28)."""
    e0 = 5e-6
    cyc = mesh_cycle(
        PAIR,
        compliance,
        TORQUE_NM,
        n_phases=200,
        corner_contact=False,
        error=lambda s: np.full(np.shape(s), e0),
    )
    itms = itms_from_mesh_cycle(cyc, zeta=ZETA, backlash_m=HALF_BACKLASH_M)
    fvms = sdof_from_mesh_cycle(
        cyc, "fvms", zeta=ZETA, backlash_m=HALF_BACKLASH_M, error="cycle", source="curve"
    )
    assert fvms.mean_stiffness_N_m == pytest.approx(itms.mean_stiffness_N_m, rel=1e-12)
    assert fvms.force == pytest.approx(itms.force, rel=1e-12)
    assert fvms.error.mean == pytest.approx(e0 / HALF_BACKLASH_M, rel=1e-12)
    for phase in (0.0, 0.13, 0.5, 0.77, 0.999):
        for x in (-2.0, -0.5, 0.9, 1.3, 2.5):  # back side, gap, drive side
            kf = float(fvms.stiffness(phase))
            u = x - float(fvms.error(phase))
            f = kf * (u - 1 if u > 1 else (u + 1 if u < -1 else 0.0))
            assert itms.contact_force(phase, x) == pytest.approx(f, rel=1e-12, abs=1e-14)
    y0 = (fvms.start_dte() + 0.8, 0.0)  # with contact loss and a back-side excursion
    a, _, _ = periods(itms, 0.9, y0, 10, steps_per_period=100)
    b, _, _ = periods(fvms, 0.9, y0, 10, steps_per_period=100)
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-11)


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

"""Walker-vectorised SDOF sweeps (models.dynamics.walkers) against the plain per-walker loop."""

from __future__ import annotations

import math

import numpy as np
import pytest

from models.dynamics import sdof_from_mesh_cycle
from models.dynamics.walkers import (
    CycleBank,
    WalkerSweep,
    cycle_bank,
    sweep_agreement,
    sweep_walkers,
    sweep_walkers_reference,
)
from models.geometry import load_gear_set
from models.geometry.inertia import pair_equivalent_mass
from models.stiffness import mesh_cycle, pair_compliance, tabulate_compliance

TORQUE = 340.0


@pytest.fixture(scope="module")
def pair():
    return load_gear_set("kahraman-blankenship").pair


@pytest.fixture(scope="module")
def banks(pair) -> dict[str, CycleBank]:
    return {kind: cycle_bank(pair, TORQUE, kind) for kind in ("fvms", "vvms", "lste")}


def _path(bank: CycleBank, points: int = 60) -> np.ndarray:
    f = np.linspace(0.5, 1.3, points) * float(bank.natural_frequency_Hz(1.0))
    return np.concatenate([f, f[::-1]])  # run-up then run-down, in time order


def _assert_contract(fast, ref, w, n):
    """The error contract of the module notes, for ``fast`` against the plain loop ``ref``."""
    a = sweep_agreement(fast, ref)
    assert fast.amplitude_m.shape == (w, n, 3)
    assert a.compared >= 0.97 * a.points
    assert a.off_jump_over + a.unmatched_jumps <= 0.005 * a.points, a
    assert a.p99_off_jump < 0.005, a
    # contact flags agree wherever the amplitudes do (off jumps)
    ok = np.isfinite(a.relative_error) & (a.relative_error < 0.005)
    assert np.mean(fast.contact_loss[ok] == ref.contact_loss[ok]) > 0.99
    assert fast.newton_fraction > 0.7  # shooting did the work


@pytest.mark.parametrize("kind", ["vvms", "lste"])
def test_walkers_match_the_plain_per_walker_sweep(banks, kind):
    """6 random walkers, 60 points up and down: the error contract of the module notes.

    Off-jump points within 0.5 %, jumps matched within 2 grid points, and at most 0.5 % of
    the points off (an off-jump point above 0.5 % or an unmatched jump counts as one point on
    another attractor). Walkers: zeta ~ U(0.015, 0.035), s, eps ~ logN(0, 0.1) (between the
    bank's nodes), 2b ~ U(0, 300 um).
    """
    bank = banks[kind]
    path = _path(bank)
    rng = np.random.default_rng({"vvms": 2, "lste": 3}[kind])
    w = 6
    kw = dict(zeta=rng.uniform(0.015, 0.035, w), stiffness_scale=np.exp(rng.normal(0, 0.1, w)),
              fluctuation_scale=np.exp(rng.normal(0, 0.1, w)),
              backlash_m=rng.uniform(0.0, 300e-6, w))
    ref = sweep_walkers_reference(bank, path, **kw)
    _assert_contract(sweep_walkers(bank, path, **kw), ref, w, path.size)


def test_fvms_walkers_match_the_plain_per_walker_sweep(pair, banks):
    """FVMS under the default method: 12 random walkers over a wide parameter box.

    4 walkers at each of 100, 220 and 340 N m, zeta ~ U(0.01, 0.05), s ~ U(0.6, 1.6),
    eps ~ U(0.5, 1.5), 2b ~ U(0, 300 um); 60 points up and down. FVMS has coexisting orbits
    (back-side impacts, period doubling): the first point is settled, then Newton continues
    the branch under the continuation guard and the basin check (module notes). The contract
    is checked on all 12 walkers together (1440 points; measured 3 off, the bound is 7).

    The bound is statistical: near a basin boundary the reference's attractor depends on the
    round-off of the entry state (a long chaotic transient), so one such walker can put a whole
    stretch of a coexistence region on the other branch, for time integration as for
    shooting (seed 2020: a walker with zeta 0.013, eps 1.49 gives 25 points with
    ``method="integrate"``, 26 with shooting). Over 11 such sets plus the benchmark's
    (16880 points) shooting had 40 points off, 0.24 %.
    """
    rng = np.random.default_rng(101)
    w = 4
    fast, ref = [], []
    for torque in (100.0, 220.0, TORQUE):
        bank = banks["fvms"] if torque == TORQUE else cycle_bank(pair, torque, "fvms")
        path = _path(bank)
        kw = dict(zeta=rng.uniform(0.01, 0.05, w), stiffness_scale=rng.uniform(0.6, 1.6, w),
                  fluctuation_scale=rng.uniform(0.5, 1.5, w),
                  backlash_m=rng.uniform(0.0, 300e-6, w))
        ref.append(sweep_walkers_reference(bank, path, **kw))
        fast.append(sweep_walkers(bank, path, **kw))
    n = fast[0].amplitude_m.shape[1]
    _assert_contract(_stack(fast), _stack(ref), 3 * w, n)


@pytest.mark.parametrize(("zeta", "scale"), [(0.028894765, 1.0487676478),
                                             (0.0369773430, 1.8809742067)])
def test_large_path_steps_do_not_leave_the_reference_attractor(pair, zeta, scale):
    """A sparse VVMS path (16 points a way over 0.6-1.45 f_n, steps of 5.5 %) at 300 N m.

    The two parameter sets are the true values of the reduced SBC's simulations 205 and 201
    (``tests/calibration/sbc_runup.py``, drawn from the default priors). With the basin check
    accepting one period's Lyapunov decrease, shooting kept one down-sweep point of each on
    the resonant branch (5.7 and 8.2 times the reference's Arms) where the reference's
    transient from the entry state falls to the other one; the check now also asks the
    transient to contract (module notes, item 4). Every point must match the reference.
    """
    bank = cycle_bank(pair, 300.0, "vvms")
    fn = float(bank.natural_frequency_Hz(scale))
    up = fn * np.exp(np.linspace(math.log(0.6), math.log(1.45), 16))
    path = np.concatenate([up, up[::-1]])
    kw = dict(zeta=[zeta], stiffness_scale=[scale], fluctuation_scale=[1.0],
              backlash_m=[136e-6])
    fast = sweep_walkers(bank, path, **kw)
    ref = sweep_walkers_reference(bank, path, **kw)
    a = np.sqrt(np.sum((np.arange(1, 4) ** 2 * fast.amplitude_m[0]) ** 2, axis=-1))
    b = np.sqrt(np.sum((np.arange(1, 4) ** 2 * ref.amplitude_m[0]) ** 2, axis=-1))
    np.testing.assert_allclose(a, b, rtol=0.01)


def _stack(sweeps: list[WalkerSweep]) -> WalkerSweep:
    return WalkerSweep(
        np.concatenate([r.amplitude_m for r in sweeps]),
        np.concatenate([r.contact_loss for r in sweeps]),
        np.concatenate([r.backside_impact for r in sweeps]),
        np.concatenate([r.converged for r in sweeps]),
        float(np.mean([r.newton_fraction for r in sweeps])),
        np.concatenate([r.periods_run for r in sweeps]),
    )


def test_stiffness_scale_is_the_cycle_at_t_over_s(pair, banks):
    """Compliance C / s at T == the cycle at T / s with k_ref = s kbar_F0 (PLAN section 2).

    Independent route: the mesh cycle of the scaled compliance at the nominal torque, scaled
    by its own reference stiffness s kbar_F0; the bank's walker model must give the same
    non-dimensional stiffness, error and force.
    """
    s = 1.37
    bank = banks["vvms"]
    comp = tabulate_compliance(pair, lambda x: pair_compliance(pair, x).total_m_per_N)
    soft = mesh_cycle(pair, lambda x: comp(x) / s, TORQUE)
    direct = sdof_from_mesh_cycle(soft, "vvms", zeta=0.02, backlash_m=50e-6,
                                  length_scale_m=bank.length_scale_m,
                                  reference_stiffness=s * bank.reference_stiffness_N_m)
    walker = bank.walker_model(0.02, s, 1.0, 100e-6)
    phase = np.linspace(0, 1, 37)
    np.testing.assert_allclose(walker.stiffness(phase), direct.stiffness(phase), rtol=1e-9)
    assert walker.force == pytest.approx(direct.force, rel=1e-12)
    assert walker.backlash == pytest.approx(direct.backlash, rel=1e-12)
    # kbar_F0: the mean error-free FVMS at the torque; m_e from the package convention
    cyc = mesh_cycle(pair, comp, TORQUE)
    assert bank.reference_stiffness_N_m == pytest.approx(cyc.fvms_harmonics.mean, rel=1e-12)
    m_e = pair_equivalent_mass(pair)
    assert bank.equivalent_mass_kg == m_e
    np.testing.assert_allclose(
        bank.natural_frequency_Hz([0.5, 1.0, 2.0]),
        np.sqrt(np.array([0.5, 1.0, 2.0]) * cyc.fvms_harmonics.mean / m_e) / (2 * math.pi),
        rtol=1e-14,
    )
    # the model's own mean stiffness (VVMS at T / s) for the load-dependent f_n
    k_model = mesh_cycle(pair, comp, TORQUE / s).vvms_harmonics.mean
    assert float(bank.model_natural_frequency_Hz(s)) == pytest.approx(
        math.sqrt(s * k_model / m_e) / (2 * math.pi), rel=2e-4)


def test_no_fluctuation_no_error_gives_the_static_state(banks):
    """No fluctuation (eps = 0), FVMS of an error-free pair: k = kbar_F0 constant, no excitation.

    The start state b + F is the exact equilibrium (mean k~ = 1 exactly since the FVMS does not
    depend on the load), so every harmonic amplitude is zero to round-off, for both methods.
    """
    bank = banks["fvms"]
    path = _path(bank, 20)
    for method in ("shooting", "integrate"):
        r = sweep_walkers(bank, path, zeta=0.02, stiffness_scale=[0.8, 1.2],
                          fluctuation_scale=0.0, backlash_m=100e-6, method=method)
        assert np.max(r.amplitude_m) < 1e-12 * bank.length_scale_m
        assert r.converged.all() and not r.contact_loss.any()


def test_linear_lste_matches_the_analytic_frf(banks):
    """LSTE with a small fluctuation scale stays in contact, so it is linear.

    ``x'' + 2 zeta x' + k (x - b - e(tau)) = F`` with constant ``k`` (the bank's LSTE
    stiffness over ``s kbar_F0``), whose harmonic ``h`` of ``e`` (amplitude ``E_h``) gives
    ``X_h = k E_h / |k - (h Lambda)^2 + 2 i zeta h Lambda|`` exactly (continuous time). The
    kernel's RK4 at 64 steps and the DFT of one period agree to 1e-4 relative; ``s`` at a
    bank node, so the tables are the exact cycle's.
    """
    bank = banks["lste"]
    s = float(bank.scales[40])
    zeta, eps = 0.05, 0.3
    model = bank.walker_model(zeta, s, eps, 100e-6)
    k = model.stiffness.mean
    lam = np.array([0.3, 0.45, 0.6, 0.8, 1.1, 1.5])
    f = lam * float(bank.natural_frequency_Hz(s))
    r = sweep_walkers(bank, f, zeta=zeta, stiffness_scale=s, fluctuation_scale=eps,
                      backlash_m=100e-6)
    assert not r.contact_loss.any()
    e_h = model.error.amplitude[:3] * bank.length_scale_m  # already times eps
    for i, lm in enumerate(lam):
        for h in range(1, 4):
            hl = h * lm
            expected = k * e_h[h - 1] / abs(k - hl**2 + 2j * zeta * hl)
            assert r.amplitude_m[0, i, h - 1] == pytest.approx(expected, rel=2e-3), (lm, h)


def test_error_contract_refusals_and_flags(banks):
    """Out-of-bank scales raise; a point that does not settle is flagged, not hidden."""
    bank = banks["vvms"]
    path = _path(bank, 10)
    with pytest.raises(ValueError, match="bank's range"):
        sweep_walkers(bank, path, zeta=0.02, stiffness_scale=3.5, fluctuation_scale=1.0,
                      backlash_m=0.0)
    with pytest.raises(ValueError, match="method"):
        sweep_walkers(bank, path, zeta=0.02, stiffness_scale=1.0, fluctuation_scale=1.0,
                      backlash_m=0.0, method="hb")
    with pytest.raises(ValueError, match="zeta"):
        sweep_walkers(bank, path, zeta=-0.1, stiffness_scale=1.0, fluctuation_scale=1.0,
                      backlash_m=0.0)
    # time integration capped at 4 periods at zeta = 0.005: cannot settle to 1e-6
    r = sweep_walkers(bank, path, zeta=0.005, stiffness_scale=1.0, fluctuation_scale=1.0,
                      backlash_m=100e-6, method="integrate", max_periods=4)
    assert not r.converged.all()
    assert r.newton_fraction == 0.0


def _dense(bank: CycleBank, scale: float, step: float = 0.003,
           span: tuple[float, float] = (0.75, 1.3), every: int = 6
           ) -> tuple[np.ndarray, np.ndarray]:
    """A dense run-up and run-down through the resonance: ``(path, record)``.

    Log-spaced nodes ``step`` apart in ``ln f_m`` (the run-up calibration's continuation step)
    over ``span`` times the walker's natural frequency; every ``every``-th node is a "window"
    node (``record`` True), the others continuation nodes.
    """
    fn = float(bank.natural_frequency_Hz(scale))
    m = math.ceil(math.log(span[1] / span[0]) / step)
    up = fn * span[0] * np.exp(step * np.arange(m + 1))
    path = np.concatenate([up, up[::-1]])
    record = np.zeros(path.size, dtype=bool)
    record[::every] = True
    record[-1] = True
    return path, record


def _log_weighted(sw: WalkerSweep) -> np.ndarray:
    return np.log(np.sqrt(np.sum((np.arange(1, 4) ** 2 * sw.amplitude_m) ** 2, axis=-1)))


def _jumps(log_a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per walker, the node index of the largest step up the path and down it."""
    half = log_a.shape[1] // 2
    d = np.abs(np.diff(log_a, axis=1))
    return np.argmax(d[:, :half - 1], axis=1), half + np.argmax(d[:, half:], axis=1)


WALKERS = dict(zeta=np.array([0.02, 0.025, 0.03, 0.04]),
               stiffness_scale=np.array([0.9, 0.95, 1.0, 1.1]),
               fluctuation_scale=np.ones(4), backlash_m=np.full(4, 136e-6))


@pytest.mark.parametrize("kind", ["vvms", "lste"])
def test_record_verification_matches_the_variational_one(banks, kind):
    """Newton iterates verified by the recorded period match a second variational period.

    The default against ``verify_record=False``, every node solved, on a dense path with a
    fold: same jump nodes, amplitudes within the module notes' bound (1e-4 in log; the
    accepted orbits are the same iterates, so they agree to round-off), at about 3 instead
    of 5 period-equivalents per Newton point.
    """
    bank = banks[kind]
    path, _ = _dense(bank, 1.0)
    old = sweep_walkers(bank, path, **WALKERS, verify_record=False)
    new = sweep_walkers(bank, path, **WALKERS)
    la, lb = _log_weighted(old), _log_weighted(new)
    assert np.max(np.abs(np.diff(la, axis=1))) > 0.3  # the path crosses a fold
    for a, b in zip(_jumps(la), _jumps(lb), strict=True):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_allclose(lb, la, atol=1e-4)
    assert new.solved.all() and old.solved.all()
    both = old.newton & new.newton
    assert both.mean() > 0.8
    assert new.periods_run[both].mean() < 0.75 * old.periods_run[both].mean()


@pytest.mark.parametrize("kind", ["vvms", "lste"])
def test_skipped_continuation_nodes_keep_the_window_nodes(banks, kind):
    """Skipping continuation nodes far from folds keeps the window nodes' results.

    Window nodes are always solved, no node is skipped right after a settled (non-Newton)
    node, the jumps stay at the same window nodes and the window nodes' amplitudes agree with
    every node solved within 1e-4 in log away from the jumps; fewer periods in all.
    """
    bank = banks[kind]
    path, record = _dense(bank, 1.0)
    dense = sweep_walkers(bank, path, **WALKERS)
    skip = sweep_walkers(bank, path, **WALKERS, record=record)
    assert skip.solved[:, record].all()
    assert not skip.solved.all()  # something was skipped
    assert (skip.periods_run[~skip.solved] == 0).all()
    assert skip.solved[:, 0].all() and skip.solved[:, 1].all()  # the first node is settled
    for w in range(skip.solved.shape[0]):
        solved = np.flatnonzero(skip.solved[w])
        for i in np.flatnonzero(~skip.solved[w]):
            last = solved[solved < i][-1]
            assert skip.newton[w, last], (w, i)
    la, lb = _log_weighted(dense)[:, record], _log_weighted(skip)[:, record]
    for a, b in zip(_jumps(la), _jumps(lb), strict=True):
        np.testing.assert_array_equal(a, b)
    near = np.zeros(la.shape, dtype=bool)
    for w, i in zip(*np.nonzero(np.abs(np.diff(la, axis=1)) > 0.3), strict=True):
        near[w, max(0, i - 1): i + 3] = True
    assert np.max(np.abs(la - lb)[~near]) < 1e-4
    assert skip.periods_run.sum() < dense.periods_run.sum()


def test_no_skipping_without_newton(banks):
    """``method="integrate"`` settles every node: nothing is skipped whatever the mask."""
    bank = banks["vvms"]
    path, record = _dense(bank, 1.0, span=(0.8, 0.9))
    r = sweep_walkers(bank, path, **WALKERS, record=record, method="integrate")
    assert r.solved.all() and not r.newton.any()
    with pytest.raises(ValueError, match="record"):
        sweep_walkers(bank, path, **WALKERS, record=record[:-1])

"""Time a 200-point SDOF frequency sweep, compiled RK4 against ``scipy.integrate.solve_ivp``.

Model: VVMS SDOF of the Kahraman-Blankenship pair at 340 N m (seed-like parabolic compliance,
C(HPSTC) F = 16 um), zeta = 0.02, 2b = 0.136 mm, 10 stiffness harmonics. Sweep: 200 values of
Lambda in [0.4, 1.4] upwards, 400 mesh periods per point (396 to settle, fixed, and 4 recorded),
128 RK4 steps per period, state carried from point to point. Baseline: solve_ivp (RK45,
rtol 1e-9, atol 1e-12, the same right-hand side evaluated from the Fourier series) for 400
periods from the same entry state at a few points, timed and extrapolated to 200 points; its
Arms (harmonics 1-3 over the last 4 periods) is compared with the compiled one. The script
prints the times, the ratio (target >= 300) and the Arms differences (target < 1 %).

Run: ``python tests/benchmarks/bench_sdof_sweep.py [--points 200] [--check 3]``, or
``python -m pytest tests/benchmarks/bench_sdof_sweep.py -m benchmark -s``. Timings depend on
the machine and its load; the script reports ratios, it does not assert them.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np
import pytest

from models.dynamics import periods_solve_ivp, sdof_from_mesh_cycle, steady_state
from models.geometry import load_gear_set
from models.stiffness.mesh_cycle import mesh_cycle

TORQUE_NM = 340.0
PERIODS = 400
RECORD = 4
STEPS = 128


def kahraman_vvms():
    pair = load_gear_set("kahraman-blankenship").pair
    sp, E = pair.pitch_point, pair.end_of_contact
    shape = lambda s: 1 + 0.4 * ((np.asarray(s) - sp) / (E - sp)) ** 2  # noqa: E731
    F = TORQUE_NM / pair.base_radius(1)
    cp = 16e-6 / F / float(shape(pair.highest_point_single_contact))
    cyc = mesh_cycle(pair, lambda s: cp * shape(s), TORQUE_NM, n_phases=200)
    return sdof_from_mesh_cycle(cyc, "vvms", zeta=0.02, backlash_m=0.068e-3)


def compiled_sweep(model, lam):
    """Fixed 400 periods per point; returns Arms and the entry state of every point."""
    y = (model.static_dte(), 0.0)
    entries, arms = [], []
    n_settle = PERIODS - RECORD
    for f in lam:
        entries.append(y)
        y, fig = steady_state(
            model,
            float(f),
            y,
            steps_per_period=STEPS,
            tol=0.0,
            min_periods=n_settle,
            max_periods=n_settle,
            record_periods=RECORD,
        )
        arms.append(fig["arms"])
    return np.array(arms), entries


def ivp_arms(model, f, y0):
    _, x = periods_solve_ivp(model, f, y0, PERIODS, record_points=STEPS)
    xs = x[-RECORD * STEPS :]
    c = np.fft.rfft(xs) / xs.size
    return float(np.sqrt(np.sum((2 * np.abs(c[[RECORD, 2 * RECORD, 3 * RECORD]])) ** 2)))


def run(n_points: int = 200, n_check: int = 3) -> dict:
    model = kahraman_vvms()
    lam = np.linspace(0.4, 1.4, n_points)
    compiled_sweep(model, lam[:2])  # compile / load the cache
    t0 = time.perf_counter()
    arms, entries = compiled_sweep(model, lam)
    t_compiled = time.perf_counter() - t0
    picks = [int(np.argmin(np.abs(lam - f))) for f in (0.6, 1.0, 1.3, 0.5, 1.2)[:n_check]]
    t_ivp, rows = 0.0, []
    for i in picks:
        t0 = time.perf_counter()
        a = ivp_arms(model, lam[i], entries[i])
        t_ivp += time.perf_counter() - t0
        rows.append((lam[i], arms[i], a, abs(arms[i] - a) / a))
    t_ivp_total = t_ivp / len(picks) * n_points
    print(
        f"compiled sweep: {n_points} points x {PERIODS} periods x {STEPS} steps: {t_compiled:.3f} s"
    )
    print(
        f"solve_ivp RK45 rtol 1e-9: {t_ivp / len(picks):.2f} s per point, "
        f"{t_ivp_total:.0f} s extrapolated to {n_points} points"
    )
    print(f"ratio solve_ivp / compiled: {t_ivp_total / t_compiled:.0f}x (target >= 300)")
    for f, a, b, r in rows:
        print(f"  Lambda {f:.3f}: Arms compiled {a:.5f}, solve_ivp {b:.5f}, diff {100 * r:.3f} %")
    return dict(t_compiled=t_compiled, t_ivp_total=t_ivp_total, rows=rows)


@pytest.mark.benchmark
def test_bench_sdof_sweep():
    """The benchmark (excluded from the default run by the ``benchmark`` marker)."""
    run(n_points=200, n_check=2)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--points", type=int, default=200)
    p.add_argument("--check", type=int, default=3)
    a = p.parse_args(argv)
    run(a.points, a.check)
    return 0


if __name__ == "__main__":
    sys.exit(main())

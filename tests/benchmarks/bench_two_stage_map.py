"""Time a peak-DTE map of the two-stage thermal model (seed 001): parallel against serial.

Grid: ``--temps`` bulk temperatures in [40, 120] deg C x ``--freqs`` stage-1 mesh frequencies
in [2, 12] kHz, default setup of :class:`~models.dynamics.two_stage_thermal.TwoStageThermalSetup`
(seed 001's gear sets, 10 kN, 10 um half backlash, flash temperature per column), 200
transient + 20 recorded system periods per point, 64 RK4 steps per stage-1 mesh period, state
carried along frequency (up-sweep); a column gets more steps where the stiffest mode needs
them (``h omega_max <= 1``, none on this grid). Timed in the same run: the model assembly (thermal
stiffness and tables at every point), the serial kernel (the same row function, one thread),
the parallel kernel (numba ``prange`` over temperature rows), and a Python loop of
``two_stage_steady_response`` over the first row (the single-point API), extrapolated. The
script checks that the parallel and serial results are identical and prints the ratios; it
asserts nothing about time.

Run: ``python tests/benchmarks/bench_two_stage_map.py [--temps 8] [--freqs 60]``, or
``python -m pytest tests/benchmarks/bench_two_stage_map.py -m benchmark -s``. Timings depend
on the machine and its load (the parallel gain is bounded by the number of cores numba uses,
printed).
"""

from __future__ import annotations

import argparse
import sys
import time

import numba
import numpy as np
import pytest

from models.dynamics import two_stage_steady_response
from models.dynamics.two_stage_kernels import (
    allocate_map_outputs,
    map_rows_parallel,
    map_rows_serial,
)
from models.dynamics.two_stage_maps import prepare_map_grid
from models.dynamics.two_stage_thermal import TwoStageThermalSetup, two_stage_at_temperature

TRANSIENT = 200
RECORD = 20
STEPS = 64


def _kernel(kernel, grid):
    out = allocate_map_outputs(grid.Y0.shape[0], grid.Y0.shape[1], RECORD)
    t0 = time.perf_counter()
    kernel(*grid.kernel_args(), True, TRANSIENT, RECORD, *out)
    return time.perf_counter() - t0, out


def run(n_temps: int = 8, n_freqs: int = 60) -> dict:
    setup = TwoStageThermalSetup()
    f = np.linspace(2000.0, 12000.0, n_freqs)
    t = np.linspace(40.0, 120.0, n_temps)
    small = prepare_map_grid(setup, f[:2], t[:2], STEPS, "up")
    _kernel(map_rows_parallel, small)  # compile / load the caches
    _kernel(map_rows_serial, small)
    t0 = time.perf_counter()
    grid = prepare_map_grid(setup, f, t, STEPS, "up")
    t_prep = time.perf_counter() - t0
    t_ser, out_s = _kernel(map_rows_serial, grid)
    t_par, out_p = _kernel(map_rows_parallel, grid)
    same = all(
        np.array_equal(a, b, equal_nan=a.dtype.kind == "f")
        for a, b in zip(out_s, out_p, strict=True)
    )
    n_loop = min(6, n_freqs)
    t0 = time.perf_counter()
    for j, fj in enumerate(f[:n_loop]):
        model, _, lam = two_stage_at_temperature(t[0], fj, setup)
        two_stage_steady_response(
            model,
            lam,
            transient_periods=TRANSIENT,
            record_periods=RECORD,
            steps_per_period=int(grid.steps[j]),
        )
    t_loop = (time.perf_counter() - t0) / n_loop * f.size * t.size
    pts = f.size * t.size
    print(
        f"grid {n_temps} temperatures x {n_freqs} frequencies = {pts} points, "
        f"{TRANSIENT}+{RECORD} system periods x {STEPS} steps; numba threads: "
        f"{numba.get_num_threads()}"
    )
    print(
        f"RK4 steps per mesh period over the columns: {int(grid.steps.min())}-"
        f"{int(grid.steps.max())} (at least {STEPS}; more where h omega_max would exceed 1); "
        f"diverged points: {int(out_p[5].sum())}"
    )
    print(f"assembly (thermal stiffness + tables): {t_prep:.3f} s")
    print(f"serial kernel:   {t_ser:.3f} s ({1e3 * t_ser / pts:.2f} ms/point)")
    print(f"parallel kernel: {t_par:.3f} s ({1e3 * t_par / pts:.2f} ms/point)")
    print(f"ratio serial / parallel kernel: {t_ser / t_par:.2f}x; parallel == serial: {same}")
    print(
        f"map total (assembly + parallel): {t_prep + t_par:.3f} s; python loop of "
        f"two_stage_steady_response (extrapolated from {n_loop} points): {t_loop:.3f} s, "
        f"ratio {t_loop / (t_prep + t_par):.2f}x"
    )
    return dict(t_prep=t_prep, t_serial=t_ser, t_parallel=t_par, same=same, t_loop=t_loop)


@pytest.mark.benchmark
def test_bench_two_stage_map():
    """The benchmark (excluded from the default run by the ``benchmark`` marker)."""
    r = run(n_temps=4, n_freqs=30)
    assert r["same"]  # correctness, not time


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--temps", type=int, default=8)
    p.add_argument("--freqs", type=int, default=60)
    a = p.parse_args(argv)
    run(a.temps, a.freqs)
    return 0


if __name__ == "__main__":
    sys.exit(main())

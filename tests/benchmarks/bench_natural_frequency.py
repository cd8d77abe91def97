"""Time the vectorised mesh natural frequency against a scalar Python loop (seed 000, FZG-C).

A *model evaluation* is one parameter set (backlash ``c``, correction factor ``chi``) taken
through a whole 10-run campaign: 10 natural frequencies, each the mean over 24 quadrature
nodes on the path of Eq. (1) of :mod:`models.thermal.thermoelastic`. This prints

* :func:`~models.thermal.natural_frequency.mesh_natural_frequency` on a batch of parameter sets
  (``params (n_samples, 1)`` x ``runs (10,)``), for several batch sizes (1 is a plain
  one-at-a-time sampler, 32-256 an ensemble sampler's walkers, 10^4 a vectorised sweep):
  model evaluations per second and run evaluations per second;
* the same evaluations by a scalar Python loop over samples and runs
  (:func:`~models.thermal.natural_frequency.mesh_natural_frequency_scalar`, which calls the
  scalar stiffness API node by node), its rate, and the ratio of the rates;
* the largest relative difference between the two (they must agree to 1e-12).

The target is >= 1e5 model evaluations per second on one core. BLAS threads are limited to one
when the script is run directly (the environment is set before numpy is imported); under
pytest numpy is already imported and the setting of the session applies.

Run: ``python tests/benchmarks/bench_natural_frequency.py [--samples 20000] [--repeat 7]``, or
``python -m pytest tests/benchmarks/bench_natural_frequency.py -m benchmark -s``. Timings
depend on the machine and its load; the script reports rates and ratios, it does not assert
them.
"""

from __future__ import annotations

import os
import sys

_NUMPY_ALREADY_IMPORTED = "numpy" in sys.modules
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core, as the target says (before numpy loads)

import argparse  # noqa: E402
import gc  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from typing import TypeVar  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from models.geometry import load_gear_set  # noqa: E402
from models.thermal.natural_frequency import (  # noqa: E402
    mesh_natural_frequency,
    mesh_natural_frequency_scalar,
    prepare_natural_frequency,
)

T = TypeVar("T")
CHI_SEED = 0.0285
#: The campaign: seed 000 Table 6's five conditions and five more torques (N m), and the
#: thermal closure Delta_1 + Delta_2 of each run (m, illustrative: growing with temperature up
#: to the closure that gives the seed's c* = 10 um at 90 degC).
TORQUES_NM = np.array([3.3, 3.3, 35.3, 183.4, 302.0, 100.0, 150.0, 200.0, 250.0, 381.96])
CLOSURES_M = np.array([1.0, 2.5, 2.3, 10.29, 10.29, 6.0, 8.0, 9.0, 10.0, 10.29]) * 1e-6


def _best(fn: Callable[[], T], repeat: int, min_time_s: float = 0.02) -> tuple[float, T]:
    """Best of ``repeat`` timings of one call (s).

    Each timing averages over enough calls to last ``min_time_s``, so that short calls are not
    timed one by one.
    """
    out = fn()
    t0 = time.perf_counter()
    out = fn()
    once = time.perf_counter() - t0
    number = max(1, int(min_time_s / max(once, 1e-9)))
    best = float("inf")
    for _ in range(max(1, repeat)):
        gc.collect()
        t0 = time.perf_counter()
        for _ in range(number):
            out = fn()
        best = min(best, (time.perf_counter() - t0) / number)
    return best, out


def _parameters(n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Backlash above the largest closure (no jammed run) and chi, shape (n, 1) each."""
    backlash = rng.uniform(12e-6, 100e-6, size=(n, 1))
    chi = rng.uniform(0.0, 0.1, size=(n, 1))
    return backlash, chi


def run(n_samples: int = 20000, repeat: int = 7, n_scalar: int = 100,
        out: Callable[[str], object] = print) -> dict[str, float]:
    """Time the vectorised and the scalar evaluation; print and return the figures."""
    pair = load_gear_set("fzg-c").pair
    t_prep, model = _best(lambda: prepare_natural_frequency(pair), 3, min_time_s=0.0)
    n_runs = TORQUES_NM.size
    rng = np.random.default_rng(7)
    threads = os.environ.get("OPENBLAS_NUM_THREADS")
    note = " (numpy imported before: session setting)" if _NUMPY_ALREADY_IMPORTED else ""
    out(f"FZG-C, {n_runs}-run campaign, {model.n_nodes} nodes on the path; prepare "
        f"{t_prep * 1e3:.2f} ms; OPENBLAS_NUM_THREADS={threads}{note}")

    # the scalar loop: same evaluations, one (sample, run) at a time
    c_s, chi_s = _parameters(n_scalar, rng)

    def scalar() -> np.ndarray:
        res = np.empty((n_scalar, n_runs))
        for i in range(n_scalar):
            for j in range(n_runs):
                res[i, j] = mesh_natural_frequency_scalar(
                    model, float(TORQUES_NM[j]), float(CLOSURES_M[j]), float(c_s[i, 0]),
                    float(chi_s[i, 0]))
        return res

    t_scalar, ref = _best(scalar, max(1, repeat // 3), min_time_s=0.0)
    vec = mesh_natural_frequency(model, TORQUES_NM, CLOSURES_M, c_s, chi_s).f_n_Hz
    dev = float(np.max(np.abs(vec / ref - 1)))
    if dev > 1e-12:
        raise AssertionError(f"vectorised and scalar f_n differ by {dev:.3g} (relative)")
    scalar_rate = n_scalar / t_scalar
    out(f"scalar Python loop: {scalar_rate:,.0f} model evaluations/s "
        f"({scalar_rate * n_runs:,.0f} run evaluations/s); max |rel. diff| {dev:.1e}")

    figures: dict[str, float] = {"scalar_evals_per_s": scalar_rate}
    out(f"{'batch':>8}{'time ms':>10}{'model evals/s':>16}{'run evals/s':>16}{'ratio':>9}")
    for batch in sorted({1, 32, 256, 4096, n_samples}):
        c, chi = _parameters(batch, rng)
        t_vec, res = _best(lambda c=c, chi=chi: mesh_natural_frequency(
            model, TORQUES_NM, CLOSURES_M, c, chi), repeat)
        if res.jammed.any() or res.f_n_Hz.shape != (batch, n_runs):
            raise AssertionError("unexpected jammed run or shape in the benchmark campaign")
        rate = batch / t_vec
        figures[f"batch {batch}: evals_per_s"] = rate
        out(f"{batch:>8}{t_vec * 1e3:>10.3f}{rate:>16,.0f}{rate * n_runs:>16,.0f}"
            f"{rate / scalar_rate:>8,.0f}x")
    best = figures[f"batch {n_samples}: evals_per_s"]
    out(f"target >= 1e5 model evaluations/s: {best:,.0f}/s at batch {n_samples} "
        f"({'met' if best >= 1e5 else 'NOT met'})")
    return figures


@pytest.mark.benchmark
def test_bench_natural_frequency(capsys):
    """The benchmark (excluded from the default run by the ``benchmark`` marker)."""
    with capsys.disabled():
        figures = run(n_samples=20000, repeat=5)
    assert all(v > 0 for v in figures.values())


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point."""
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--samples", type=int, default=20000)
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--scalar", type=int, default=100, help="parameter sets in the scalar loop")
    args = ap.parse_args(argv)
    run(args.samples, args.repeat, args.scalar)
    return 0


if __name__ == "__main__":
    sys.exit(main())

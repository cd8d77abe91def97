"""Time the walker-vectorised run-up sweep against the plain per-walker loop (issue 20, item 4).

Case: Kahraman-Blankenship pair (potential-energy compliance with Hertz, corner contact, no
relief) at 340 N m, 2b = 136 um. Path: ``--points`` mesh frequencies from 0.4 to 1.4 times
the nominal natural frequency ``sqrt(kbar_F0 / m_e) / 2 pi`` (3117 Hz) and back down, in time
order (one run-up and run-down, the state carried). ``--walkers`` walkers: zeta ~ U(0.015,
0.035), stiffness scale s and fluctuation scale eps ~ logN(0, 0.1) (seed ``--seed``).

Per model, measured in the same run:

1. **plain**: :func:`models.dynamics.walkers.sweep_walkers_reference`, the per-walker loop
   (exact cycle at T / s, ``SDOFModel``, :func:`models.dynamics.sweep.sweep` with its
   defaults: 128 steps, tol 1e-6, >= 10 periods, 4 recorded) -- the "full sweep";
2. **kernel**: :func:`models.dynamics.walkers.sweep_walkers` (one compiled call, 64 steps),
   with shooting (what ``method="auto"`` does for every model) and, for FVMS, also pure
   integration; best of ``--repeat`` after a warm-up.

3. **dense path** (issue 20, item 4): the same points with continuation nodes inserted so
   that no step exceeds 0.3 % in ``ln f_m`` (as the run-up calibration sweeps them), swept by
   the *old* method (``verify_record=False``, every node solved) and the *new* one (the
   default record verification, continuation nodes skippable: ``record`` True at the points
   only), and by the plain loop; compared at the points.

Printed: times, speed-up (plain / kernel), Newton fraction, period equivalents per point, and
the error of the kernel against the full sweep (:func:`~models.dynamics.walkers.sweep_agreement`,
acceleration-weighted amplitude): p99 and worst off jumps, points above 10 % near and away
from jumps (within 2 grid points of a jump), off-jump points above 0.5 %, unmatched jumps.

Run: ``python tests/benchmarks/bench_runup_sweep.py [--walkers 32] [--points 100]
[--kinds fvms,vvms,lste] [--repeat 2]`` or ``python -m pytest
tests/benchmarks/bench_runup_sweep.py -m benchmark -s``. Timings depend on the machine's load
(numba threads: the default, the number of cores); ratios are reported, not asserted.
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time
from typing import Any

import numba
import numpy as np
import pytest

from models.dynamics.walkers import (
    CycleBank,
    WalkerSweep,
    cycle_bank,
    sweep_agreement,
    sweep_walkers,
    sweep_walkers_reference,
)
from models.geometry import load_gear_set

TORQUE_NM = 340.0
BACKLASH_M = 136e-6


def run(walkers: int = 32, points: int = 100, kinds: tuple[str, ...] = ("fvms", "vvms", "lste"),
        repeat: int = 2, seed: int = 20) -> dict[str, dict[str, object]]:
    """Run the benchmark; returns the figures per model and method."""
    pair = load_gear_set("kahraman-blankenship").pair
    rng = np.random.default_rng(seed)
    kw: dict[str, Any] = dict(zeta=rng.uniform(0.015, 0.035, walkers),
              stiffness_scale=np.exp(rng.normal(0.0, 0.1, walkers)),
              fluctuation_scale=np.exp(rng.normal(0.0, 0.1, walkers)),
              backlash_m=np.full(walkers, BACKLASH_M))
    print(f"numba threads: {numba.get_num_threads()}; {walkers} walkers x {points} points up "
          f"and down ({2 * points} in time order), {TORQUE_NM:g} N m, 2b = "
          f"{1e6 * BACKLASH_M:g} um")
    out: dict[str, dict[str, object]] = {}
    for kind in kinds:
        t0 = time.perf_counter()
        bank = cycle_bank(pair, TORQUE_NM, kind)
        t_bank = time.perf_counter() - t0
        f = np.linspace(0.4, 1.4, points) * float(bank.natural_frequency_Hz(1.0))
        path = np.concatenate([f, f[::-1]])
        t0 = time.perf_counter()
        ref = sweep_walkers_reference(bank, path, **kw)
        t_plain = time.perf_counter() - t0
        print(f"\n=== {kind}: bank ({bank.scales.size} nodes) {t_bank:.2f} s; plain per-walker "
              f"loop {t_plain:.2f} s ({1e3 * t_plain / walkers:.0f} ms per walker, "
              f"{ref.periods_run.mean():.0f} periods per point)")
        for method in (("shooting", "integrate") if kind == "fvms" else ("shooting",)):
            sweep_walkers(bank, path[:3], **{k: v[:2] for k, v in kw.items()}, method=method)
            best = np.inf
            for _ in range(repeat):
                t0 = time.perf_counter()
                res = sweep_walkers(bank, path, **kw, method=method)
                best = min(best, time.perf_counter() - t0)
            a = sweep_agreement(res, ref)
            print(f"  {method}: {1e3 * best:.0f} ms = {t_plain / best:.1f}x the plain loop "
                  f"({1e3 * best / walkers:.1f} ms per walker); Newton "
                  f"{100 * res.newton_fraction:.0f} %"
                  f"; {res.periods_run.mean():.1f} period-equivalents per point\n"
                  f"    vs full sweep ({a.compared}/{a.points} points both converged, "
                  f"{a.near_jump} near jumps): p99 off jumps {100 * a.p99_off_jump:.3g} %, worst "
                  f"off jumps {100 * a.worst_off_jump:.3g} %; > 10 %: {a.over_10pct_near_jump} "
                  f"near jumps, {a.over_10pct_off_jump} away; off-jump > 0.5 %: "
                  f"{a.off_jump_over}; unmatched jumps: {a.unmatched_jumps}")
            out[f"{kind}/{method}"] = dict(t_plain=t_plain, t_kernel=best,
                                           speedup=t_plain / best, agreement=a,
                                           newton=res.newton_fraction)
        dense_path(bank, path, kw, repeat, out, kind)
    return out


def _dense(path: np.ndarray, max_step: float = 0.003) -> tuple[np.ndarray, np.ndarray]:
    """``path`` with continuation nodes at most ``max_step`` apart in ``ln f``; ``record``."""
    nodes, record = [path[:1]], [np.ones(1, dtype=bool)]
    for a, b in itertools.pairwise(path):
        k = max(int(np.ceil(abs(np.log(b / a)) / max_step)), 1)
        nodes.append(a * (b / a) ** (np.arange(1, k + 1) / k))
        rec = np.zeros(k, dtype=bool)
        rec[-1] = True
        record.append(rec)
    return np.concatenate(nodes), np.concatenate(record)


def _at(sw: WalkerSweep, keep: np.ndarray) -> WalkerSweep:
    return WalkerSweep(sw.amplitude_m[:, keep], sw.contact_loss[:, keep],
                       sw.backside_impact[:, keep], sw.converged[:, keep], sw.newton_fraction,
                       sw.periods_run[:, keep])


def dense_path(bank: CycleBank, path: np.ndarray, kw: dict[str, Any], repeat: int,
               out: dict[str, dict[str, object]], kind: str) -> None:
    """Item 3 of the module notes: old and new method on the dense path, and the plain loop."""
    f, record = _dense(path)
    t0 = time.perf_counter()
    ref = _at(sweep_walkers_reference(bank, f, **kw), record)
    t_plain = time.perf_counter() - t0
    runs = {}
    for name, opts in (("old", dict(verify_record=False)), ("new", dict(record=record))):
        best = np.inf
        for _ in range(repeat):
            t0 = time.perf_counter()
            res = sweep_walkers(bank, f, **kw, **opts)  # type: ignore[arg-type]
            best = min(best, time.perf_counter() - t0)
        runs[name] = (res, best)
    (old, t_old), (new, t_new) = runs["old"], runs["new"]
    c_old = old.periods_run.sum() / record.sum() / old.periods_run.shape[0]
    c_new = new.periods_run.sum() / record.sum() / new.periods_run.shape[0]
    vs_old = sweep_agreement(_at(new, record), _at(old, record))
    print(f"  dense path ({f.size} nodes, {record.sum()} points): old {1e3 * t_old:.0f} ms, "
          f"{c_old:.1f} period-equivalents per point; new {1e3 * t_new:.0f} ms, {c_new:.1f} "
          f"per point ({100 * new.solved.mean():.0f} % of the nodes solved): "
          f"{c_old / c_new:.2f}x fewer periods, {t_old / t_new:.2f}x faster; plain loop "
          f"{t_plain:.1f} s = {t_plain / t_new:.0f}x the new\n"
          f"    new vs old at the points: p99 {vs_old.p99_off_jump:.2g}, worst "
          f"{vs_old.worst_off_jump:.2g} off jumps; unmatched jumps {vs_old.unmatched_jumps}")
    for name, res in (("old", old), ("new", new)):
        a = sweep_agreement(_at(res, record), ref)
        print(f"    {name} vs full sweep: p99 off jumps {100 * a.p99_off_jump:.3g} %, worst "
              f"{100 * a.worst_off_jump:.3g} %; off-jump > 0.5 %: {a.off_jump_over}; "
              f"unmatched jumps: {a.unmatched_jumps}")
    out[f"{kind}/dense"] = dict(t_old=t_old, t_new=t_new, periods_old=c_old,
                                periods_new=c_new, agreement_old=vs_old)


@pytest.mark.benchmark
def test_bench_runup_sweep():
    """The benchmark (excluded from the default run by the ``benchmark`` marker)."""
    run(walkers=16, points=100, repeat=1)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--walkers", type=int, default=32)
    p.add_argument("--points", type=int, default=100, help="per direction")
    p.add_argument("--kinds", default="fvms,vvms,lste")
    p.add_argument("--repeat", type=int, default=2)
    p.add_argument("--seed", type=int, default=20)
    a = p.parse_args(argv)
    run(a.walkers, a.points, tuple(a.kinds.split(",")), a.repeat, a.seed)
    return 0


if __name__ == "__main__":
    sys.exit(main())

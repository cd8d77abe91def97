"""Time one VVMS/LSTE mesh-cycle curve against a naive per-position Python loop.

For the Kahraman-Blankenship pair at 340 N m without relief (corner contact on both sides, up to
three loaded pairs) and with Delta = 0.5 linear tip relief, this prints

* ``mesh_cycle(...)``: one whole curve (positions, exact separation distances, compliance
  lookup, active-set load sharing, FVMS, VVMS, LSTE, contact ratio, harmonics), best of
  ``--repeat`` runs; target well under 10 ms for 200 phases;
* ``MeshCycleGeometry.solve``: the load-dependent part alone (torque sweeps reuse the rest);
* the naive baseline: a Python loop over phases and pairs with scalar geometry, a scalar
  compliance call per pair, and the seed's drop-and-resolve active set by
  ``numpy.linalg.solve`` of the compatibility system at each position; and the ratio of the two.

The baseline's LSTE is compared with the vectorised one (they must agree to 1e-9). The
compliance is the potential-energy model of ``models.stiffness.potential_energy`` tabulated
on 401 points (``tabulate_compliance``); the direct (untabulated) potential-energy call is
timed once for reference.

Run: ``python tests/benchmarks/bench_mesh_cycle.py [--phases 200] [--repeat 20]``, or
``python -m pytest tests/benchmarks/bench_mesh_cycle.py -m benchmark -s``. Timings depend on
the machine and its load; the script reports times and ratios, it does not assert them.
"""

from __future__ import annotations

import argparse
import gc
import math
import sys
import time
from collections.abc import Callable
from functools import partial
from typing import TypeVar

import numpy as np
import pytest

from models.geometry import GearPair, load_gear_set
from models.stiffness.corner_contact import separation_distance
from models.stiffness.mesh_cycle import mesh_cycle, prepare_mesh_cycle, tabulate_compliance
from models.stiffness.potential_energy import pair_compliance
from models.stiffness.tip_relief import normalised_tip_relief

TORQUE_NM = 340.0
T = TypeVar("T")


def _best(fn: Callable[[], T], repeat: int) -> tuple[float, T]:
    best = float("inf")
    for _ in range(max(1, repeat)):
        gc.collect()
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def compliance_for(pair: GearPair) -> tuple[Callable[[np.ndarray], np.ndarray], str]:
    """The potential-energy compliance of ``pair`` and its name."""

    def pe(s: np.ndarray) -> np.ndarray:
        return np.asarray(pair_compliance(pair, s).total_m_per_N)

    return pe, "potential_energy.pair_compliance"


def naive_lste(pair: GearPair, compliance: Callable[[np.ndarray], np.ndarray],
               torque_Nm: float, error: Callable[[np.ndarray], np.ndarray] | None,
               n_phases: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The baseline: per phase and pair, scalar calls and a dense solve with drop-and-resolve."""
    A, E, pb = pair.start_of_contact, pair.end_of_contact, pair.base_pitch
    F = torque_Nm / pair.base_radius(1)
    n_slots = math.ceil(pair.contact_ratio) + 2
    lste = np.empty(n_phases)
    fvms = np.empty(n_phases)
    vvms = np.empty(n_phases)
    for j in range(n_phases):
        tau = j / n_phases
        cs, gs, in_path = [], [], []
        for k in range(n_slots):
            s = A + (tau + n_slots - 2 - k) * pb
            sc = min(max(s, A), E)
            c = float(compliance(np.array([sc]))[0])
            e = 0.0 if error is None else float(error(np.array([sc]))[0])
            sep = float(separation_distance(pair, s))
            cs.append(c)
            gs.append(e + sep)
            in_path.append(A <= s <= E)
        active = [k for k in range(n_slots) if math.isfinite(gs[k])]
        while True:
            n = len(active)
            a = np.zeros((n + 1, n + 1))
            b = np.zeros(n + 1)
            for i, k in enumerate(active):
                a[i, i] = cs[k]
                a[i, n] = -1.0
                b[i] = -gs[k]
                a[n, i] = 1.0
            b[n] = F
            sol = np.linalg.solve(a, b)
            keep = [k for i, k in enumerate(active) if sol[i] > 0]
            if len(keep) == n:
                break
            active = keep
        lste[j] = sol[-1]
        fvms[j] = sum(1.0 / cs[k] for k in range(n_slots) if in_path[k])
        vvms[j] = F / sol[-1]
    return lste, fvms, vvms


def run(n_phases: int = 200, repeat: int = 20,
        out: Callable[[str], object] = print) -> dict[str, float]:
    """Time the vectorised and the naive curve; print and return the figures (s)."""
    pair = load_gear_set("kahraman-blankenship").pair
    comp, label = compliance_for(pair)
    t_tab, tab = _best(lambda: tabulate_compliance(pair, comp), 1)
    t_direct, _ = _best(lambda: mesh_cycle(pair, comp, TORQUE_NM, n_phases=n_phases), 3)
    out(f"Kahraman-Blankenship, {TORQUE_NM:g} N m, {n_phases} phases, compliance: {label} "
        f"(tabulated on 401 points in {t_tab * 1e3:.1f} ms; one curve with the direct call "
        f"{t_direct * 1e3:.2f} ms)")
    relief = normalised_tip_relief(pair, comp, TORQUE_NM, 0.5)
    figures: dict[str, float] = {}
    out(f"{'case':<22}{'mesh_cycle ms':>14}{'solve ms':>10}{'naive ms':>10}{'ratio':>8}"
        f"{'max |dLSTE| m':>15}{'corner':>8}")
    for name, err in (("no relief", None), ("Delta 0.5, Ln 1", relief)):
        t_curve, r = _best(partial(mesh_cycle, pair, tab, TORQUE_NM, error=err,
                                   n_phases=n_phases), repeat)
        geo = prepare_mesh_cycle(pair, tab, error=err, n_phases=n_phases)
        t_solve, _ = _best(partial(geo.solve, TORQUE_NM), repeat)
        t_naive, ref = _best(partial(naive_lste, pair, tab, TORQUE_NM, err, n_phases),
                             max(1, repeat // 10))
        lste_ref, fvms_ref, vvms_ref = ref
        dev = float(np.max(np.abs(r.lste_m - lste_ref)))
        if dev > 1e-9 * float(np.max(lste_ref)):
            raise AssertionError(f"vectorised and naive LSTE differ by {dev:.3g} m")
        np.testing.assert_allclose(r.fvms_N_m, fvms_ref, rtol=1e-12)
        np.testing.assert_allclose(r.vvms_N_m, vvms_ref, rtol=1e-9)
        ratio = t_naive / t_curve
        corner = "yes" if r.has_corner_contact else "no"
        out(f"{name:<22}{t_curve * 1e3:>14.3f}{t_solve * 1e3:>10.3f}{t_naive * 1e3:>10.1f}"
            f"{ratio:>7.0f}x{dev:>15.2e}{corner:>8}")
        figures[f"{name}: mesh_cycle_s"] = t_curve
        figures[f"{name}: solve_s"] = t_solve
        figures[f"{name}: naive_s"] = t_naive
    target = max(v for k, v in figures.items() if k.endswith("mesh_cycle_s"))
    out(f"one curve: {target * 1e3:.2f} ms ({'well under' if target < 2e-3 else 'vs'} the "
        f"10 ms target)")
    return figures


@pytest.mark.benchmark
def test_bench_mesh_cycle(capsys):
    """The benchmark (excluded from the default run by the ``benchmark`` marker)."""
    with capsys.disabled():
        figures = run()
    assert all(v > 0 for v in figures.values())


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point."""
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--phases", type=int, default=200)
    ap.add_argument("--repeat", type=int, default=20)
    args = ap.parse_args(argv)
    run(args.phases, args.repeat)
    return 0


if __name__ == "__main__":
    sys.exit(main())

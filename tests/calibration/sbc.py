"""Simulation-based calibration of ``rigtools.calibration`` (Talts et al. 2018).

Each simulation draws the parameters from the default priors, draws an FZG-C campaign of ten
runs (five torques at 40 and 90 degC, two channels) through the forward model with the model
error, the fit scatter, a load-independent housing mode at a random frequency on every
channel and Poisson spurious peaks, fits it with :func:`rigtools.calibration.calibrate` and
records, for the backlash ``c``, the critical gap at the highest temperature ``c*(90 degC)``
and the margin ``c - c*(90 degC)``: whether the central 90 % interval covers the truth, the
rank of the truth among ``L = 99`` evenly spaced posterior draws (uniform on 0..L when the
posterior is calibrated), and the error of the posterior median.

Checks (``check``): every quantity's 90 % coverage in [0.85, 0.95]; the rank histogram (10
bins) passes a chi-square test of uniformity at 1 %. Simulations the calibration refuses
(a :class:`~rigtools.calibration.errors.CalibrationError`) are counted and reported.

Usage::

    python tests/calibration/sbc.py --n 100 --seed 0 --jobs 2 --out sbc.json

(``tests/calibration/test_sbc.py`` runs 100 as a slow test and a small subset in the
default suite.)

References
----------
.. [1] S. Talts, M. Betancourt, D. Simpson, A. Vehtari, A. Gelman, "Validating Bayesian
   inference algorithms with simulation-based calibration", arXiv:1804.06788 (2018).
"""

from __future__ import annotations

import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from sbc_common import N_RANK_DRAWS, emit_report, parse_cli, rank_coverage

from models.geometry import load_gear_set
from rigtools.calibration import CalibrationError, calibrate_observations, default_config
from rigtools.calibration.simulate import simulate_observations

TORQUES_NM = (20.0, 50.0, 100.0, 183.4, 302.0) * 2
TEMPERATURES_C = (40.0,) * 5 + (90.0,) * 5
QUANTITIES = ("backlash", "critical_gap@90C", "margin@90C")
BAND_HZ = (50.0, 16000.0)


@dataclass(frozen=True)
class Settings:
    """Sampler settings of the fits (reduced ones for the fast subset)."""

    walkers: int = 24
    max_steps: int = 8000
    check_every: int = 100
    map_starts: int = 4


def one(args: tuple[int, int, Settings]) -> dict[str, Any]:
    """Simulate and fit campaign ``i`` of the run seeded ``seed``."""
    i, seed, st = args
    rng = np.random.default_rng([seed, i])
    cfg = replace(default_config(), compare_variants=(), band_Hz=BAND_HZ, walkers=st.walkers,
                  max_steps=st.max_steps, check_every=st.check_every,
                  map_starts=st.map_starts, seed=int(rng.integers(2**31)))
    truth = {p.name: (float(p.prior.sample(rng, 1)[0]) if p.prior is not None and p.free
                      else float(p.fixed)) for p in cfg.parameters}  # type: ignore[arg-type]
    pair = load_gear_set("fzg-c").pair
    housing = float(rng.uniform(2000.0, 9000.0))
    obs = simulate_observations(
        pair, [f"R{k}" for k in range(10)], TORQUES_NM, TEMPERATURES_C, truth, rng=rng,
        band_Hz=BAND_HZ, housing_modes_Hz=(housing,), spurious_per_run=0.3)
    kappa = truth["closure_coefficient"] * (1.0 - truth["chi"])
    slope = pair.pinion.material.thermal_expansion_per_K * pair.line_of_action_length
    c_star = kappa * slope * (90.0 - 20.0) * 1e6
    true = {"backlash": truth["backlash"], "critical_gap@90C": c_star,
            "margin@90C": truth["backlash"] - c_star}
    t0 = time.perf_counter()
    try:
        res = calibrate_observations(obs, pair, cfg)
    except CalibrationError as exc:
        return {"i": i, "refused": str(exc), "truth": truth}
    out: dict[str, Any] = {"i": i, "truth": truth, "seconds": time.perf_counter() - t0,
                           "converged": res.converged, "housing_Hz": housing}
    fit = res.headline
    for q in QUANTITIES:
        d = fit.draws(q).ravel()
        pick = d[np.linspace(0, d.size - 1, N_RANK_DRAWS).astype(int)]
        lo, hi = np.quantile(d, [0.05, 0.95])
        out[q] = {"truth": true[q], "rank": int(np.sum(pick < true[q])),
                  "covered": bool(lo <= true[q] <= hi), "median": float(np.median(d)),
                  "sd": float(np.std(d))}
    return out


def run(n: int, seed: int, settings: Settings, jobs: int = 1,
        verbose: bool = False) -> list[dict[str, Any]]:
    """``n`` simulations (in ``jobs`` processes; progress on stderr when ``verbose``)."""
    tasks = [(i, seed, settings) for i in range(n)]
    if jobs <= 1:
        done = []
        for t in tasks:
            done.append(one(t))
            if verbose:
                print(f"sbc {t[0] + 1}/{n}", file=sys.stderr, flush=True)
        return done
    with ProcessPoolExecutor(jobs) as pool:
        out = []
        for r in pool.map(one, tasks):
            if verbose:
                print(f"sbc {r['i'] + 1}/{n}" + (" refused" if "refused" in r else ""),
                      file=sys.stderr, flush=True)
            out.append(r)
        return out


def check(results: list[dict[str, Any]]) -> dict[str, Any]:
    """Coverage, rank-histogram chi-square p-value and bias of each quantity."""
    fitted = [r for r in results if "refused" not in r]
    report: dict[str, Any] = {"n": len(results), "fitted": len(fitted),
                              "refused": [r["refused"] for r in results if "refused" in r],
                              "not_converged": sum(not r["converged"] for r in fitted)}
    for q in QUANTITIES:
        summary = rank_coverage(fitted, q)
        err = np.array([r[q]["median"] - r[q]["truth"] for r in fitted])
        report[q] = {
            "coverage_90": summary.coverage_90,
            "rank_counts": summary.rank_counts.tolist(),
            "chi2_p": summary.chi2_p,
            "bias": float(np.mean(err)),
            "bias_se": float(np.std(err, ddof=1) / np.sqrt(err.size)) if err.size > 1 else None,
            "mean_posterior_sd": float(np.mean([r[q]["sd"] for r in fitted])),
        }
    return report


def main(argv: list[str] | None = None) -> int:
    """Run the SBC from the command line; exit 1 when a check fails."""
    a = parse_cli(__doc__.splitlines()[0], argv)
    t0 = time.perf_counter()
    results = run(a.n, a.seed, Settings(), a.jobs, verbose=True)
    report = check(results)
    report["seconds"] = time.perf_counter() - t0
    return emit_report(report, results, a.out, QUANTITIES, indent=1)


if __name__ == "__main__":
    sys.exit(main())

"""Time a calibration: a 10-run campaign from its observations table to a converged posterior.

Prints

* the wall time of :func:`rigtools.calibration.calibrate` (headline variant only, default
  sampler settings: 32 walkers, convergence at 50 autocorrelation times) on a synthetic
  FZG-C campaign of ten runs (five torques at 40 and 90 degC, two channels, a housing mode),
  and whether it converged (target: under 10 s on 2 cores);
* how that time splits: preparation (table, forward model, MAP), sampling (of which the log
  posterior itself, the rest emcee and the convergence checks), summaries (derived
  quantities, diagnostics, PSIS-LOO) and writing the files;
* log-posterior evaluations per second of the compiled kernel at the batch emcee uses
  (half the walkers), and of a plain per-walker Python log posterior (the same mathematics
  in loops, checked equal to 1e-9) measured in the same run, with their ratio.

Run: ``python tests/benchmarks/bench_calibration.py``, or
``python -m pytest tests/benchmarks/bench_calibration.py -m benchmark -s``. Timings depend
on the machine and its load (the numba kernel is compiled once and cached; the first run
on a machine compiles it); the script reports, it does not assert.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from models.geometry import load_gear_set
from models.thermal import ThermalReference
from rigtools.calibration import (
    calibrate_observations,
    default_config,
    simulate_observations,
    write_outputs,
)
from rigtools.calibration.data import prepare_data
from rigtools.calibration.model import CalibrationModel, build_model
from rigtools.calibration.sampler import SamplerSettings, find_map, run_sampler

TORQUES_NM = (20.0, 50.0, 100.0, 183.4, 302.0) * 2
TEMPERATURES_C = (40.0,) * 5 + (90.0,) * 5
TRUTH = {"backlash": 20.0, "closure_coefficient": 0.37, "stiffness_scale": 0.9,
         "chi": 0.0285, "model_error": 0.02}
CODES = {"uniform": 0, "normal": 1, "lognormal": 2, "halfnormal": 3}


def plain_log_posterior(model: CalibrationModel, theta: list[float]) -> float:
    """The log posterior of one parameter vector in plain Python loops (secant_path, normal)."""
    lp = 0.0
    for x, p in zip(theta, model.priors, strict=True):
        if not p.lower <= x <= p.upper:
            return -math.inf
        if p.dist == "uniform":
            lp += p.log_density_constant
        elif p.dist == "lognormal":
            z = (math.log(x) - p.loc) / p.scale
            lp += p.log_density_constant - 0.5 * z * z - math.log(x)
        else:
            z = (x - p.loc) / p.scale
            lp += p.log_density_constant - 0.5 * z * z
    par = dict(zip(model.names, theta, strict=True)) | model.fixed
    fm, cand, st = model.forward, model.data.candidates, model.settings
    lo, hi = st.band_Hz
    c = par["backlash"] * 1e-6
    kc = (1.0 - par["chi"]) * par["closure_coefficient"]
    s, me = par["stiffness_scale"], par["model_error"]
    q, a = fm.q_N_per_m.tolist(), fm.a_N_per_m.tolist()
    n_z = cand.log_background.shape[0]
    per = [[0.0] * fm.n_runs for _ in range(n_z)]
    for r in range(fm.n_runs):
        ratio = (c - kc * float(fm.closure.run_m[r])) * s / float(fm.normal_load_N[r])
        jammed = ratio * fm.q_max_N_per_m <= -1.0
        if jammed:
            p_d, fp = 0.0, 10.0 * hi
        else:
            k = s * sum(aj / (1.0 + ratio * qj) for aj, qj in zip(a, q, strict=True))
            fp = math.sqrt(k) * fm.frequency_factor
            p_d = st.detection_probability * 0.5 * math.erfc(-(fp - lo) / (0.03 * lo)
                                                             / math.sqrt(2.0)) \
                * 0.5 * math.erfc(-(hi - fp) / (0.03 * hi) / math.sqrt(2.0))
            fp = min(max(fp, 0.1 * lo), 10.0 * hi)
        n_j = int(cand.count[r])
        terms = []
        for j in range(n_j):
            var = float(cand.sd_Hz[r, j]) ** 2 + (me * me + 1e-8) * fp * fp
            d = float(cand.f_Hz[r, j]) - fp
            terms.append(-0.5 * (d * d / var + math.log(var)) - 0.5 * math.log(2 * math.pi)
                         + math.log(max(p_d, 1e-300)) - math.log(n_j))
        for z in range(n_z):
            lb = [float(cand.log_background[z, r, j]) for j in range(n_j)]
            total = (1.0 - p_d) + sum(math.exp(t - b) for t, b in zip(terms, lb, strict=True))
            per[z][r] = math.log(total) + sum(lb)
    tz = [sum(row) - math.log(n_z) for row in per]
    m = max(tz)
    return lp + m + math.log(sum(math.exp(t - m) for t in tz))


def run(verbose: bool = True) -> dict[str, float]:
    """Time the calibration and the log posterior; print and return the figures."""
    pair = load_gear_set("fzg-c").pair
    obs = simulate_observations(pair, [f"R{i}" for i in range(10)], TORQUES_NM,
                                TEMPERATURES_C, TRUTH, rng=np.random.default_rng(3),
                                housing_modes_Hz=(4500.0,))
    cfg = replace(default_config(), compare_variants=())
    calibrate_observations(obs, pair, replace(cfg, max_steps=400))   # compile (or load) kernel
    t0, c0 = time.perf_counter(), time.process_time()
    res = calibrate_observations(obs, pair, cfg)
    total, cpu = time.perf_counter() - t0, time.process_time() - c0
    with tempfile.TemporaryDirectory() as tmp:
        t1 = time.perf_counter()
        write_outputs(res, Path(tmp))
        t_io = time.perf_counter() - t1
    # the split, by the same steps as calibrate_observations()
    t1 = time.perf_counter()
    data = prepare_data(obs, cfg)
    model = build_model(data, pair, cfg, reference=ThermalReference(20.0))
    map_est = find_map(model, model.priors, starts=cfg.map_starts, seed=cfg.seed)
    t_prep = time.perf_counter() - t1
    spent = [0.0]

    def timed(theta: np.ndarray) -> np.ndarray:
        t = time.perf_counter()
        out = model(theta)
        spent[0] += time.perf_counter() - t
        return out

    st = SamplerSettings(walkers=None, max_steps=cfg.max_steps, check_every=cfg.check_every,
                         seed=cfg.seed, map_starts=cfg.map_starts)
    t1 = time.perf_counter()
    sr = run_sampler(timed, model.priors, st, map_estimate=map_est)
    t_sampling = time.perf_counter() - t1
    # log-posterior rates at emcee's batch (half the walkers)
    batch = sr.chain[-1][: st.n_walkers(model.ndim) // 2]
    n_loop = 2000
    t1 = time.perf_counter()
    for _ in range(n_loop):
        model(batch)
    kernel_rate = n_loop * batch.shape[0] / (time.perf_counter() - t1)
    rows = [list(map(float, b)) for b in batch]
    n_plain = 20
    t1 = time.perf_counter()
    plain = [plain_log_posterior(model, r) for _ in range(n_plain) for r in rows]
    plain_rate = len(plain) / (time.perf_counter() - t1)
    diff = float(np.max(np.abs(np.array(plain[: len(rows)]) - model(batch))))
    share = total / (t_prep + t_sampling)      # scale the replicated split to the real run
    out = {"total_s": total, "cpu_s": cpu, "converged": float(res.converged),
           "steps": res.headline.run.n_steps, "prepare_s": t_prep, "sampling_s": t_sampling,
           "log_prob_s": spent[0], "emcee_and_checks_s": t_sampling - spent[0], "io_s": t_io,
           "kernel_evals_per_s": kernel_rate, "plain_evals_per_s": plain_rate,
           "ratio": kernel_rate / plain_rate, "max_abs_diff": diff}
    if verbose:
        print(f"10-run campaign to a {'converged' if res.converged else 'NOT converged'} "
              f"posterior: {total:.2f} s wall, {cpu:.2f} s CPU ({res.headline.run.n_steps} "
              f"steps x {res.headline.samples.shape[0]} walkers; target < 10 s: "
              f"{'met' if total < 10 and res.converged else 'NOT met'})")
        print(f"  split (a replicated run, wall; x{share:.2f} to the run above): prepare "
              f"(table, model, MAP) {t_prep:.2f} s | sampling {t_sampling:.2f} s (log "
              f"posterior {spent[0]:.2f} s, emcee + convergence checks "
              f"{t_sampling - spent[0]:.2f} s) | write outputs {t_io:.2f} s")
        print(f"  log posterior: kernel {kernel_rate:,.0f} evals/s at batch {batch.shape[0]}; "
              f"plain Python {plain_rate:,.0f} evals/s; ratio {kernel_rate / plain_rate:.0f}x "
              f"(max |difference| {diff:.2e})")
    return out


@pytest.mark.benchmark
def test_bench_calibration(capsys: pytest.CaptureFixture[str]) -> None:
    out = run()
    assert out["max_abs_diff"] < 1e-6
    with capsys.disabled():
        print()


def main(argv: list[str] | None = None) -> int:
    """Command-line entry."""
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args(argv)
    run()
    return 0


if __name__ == "__main__":
    sys.exit(main())

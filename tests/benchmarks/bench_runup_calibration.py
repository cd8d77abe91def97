"""Time the SDOF run-up calibration to convergence on the demo's run-up (issue 20, item 4).

Issue 20's goal: one run-up curve (about 100 speed points, up and down) calibrated to
convergence (the autocorrelation rule of :mod:`rigtools.calibration.sampler`) in under 10
minutes on 2 cores, all three models under 30 minutes. On the run-up of a ``rigtools demo``
output folder, with ``max_speed_points`` windows per direction and the campaign's other
``[calibration]`` settings, this script runs :func:`rigtools.calibration.calibrate_runups`
for the chosen models with the default sampler (``screened``: delayed acceptance, a
quadratic surrogate screening the proposals so that only those passing cost a sweep, and the
mixture move, a fifth of the steps independence proposals from a mixture fitted to the chain;
``[calibration.runup] delayed_acceptance`` and ``mixture_move``) and, in the same run, with
both off (``plain``: every proposal of the stretch and DE moves swept), and prints per
model and variant the wall time from its start to the next model's (MAP, sampling and
summaries), the steps, whether the rule was met, the final ``tau``, the largest split-walker
R-hat and the sweeps per step; then per model the speed-up of the screened run, its
surrogate's fit and screen figures, and what the choice costs in accuracy: both moves are
exact (the second stage accepts by the full sweep; the independence step by the
Metropolis-Hastings ratio), so the two posteriors differ by Monte Carlo error only, printed as
the largest difference of a parameter's mean between them in units of its posterior sd; the
total against the goals closes the table.

It needs a demo output (``rigtools demo -o DIR``, 7-20 minutes by the machine; its
observations table is read from ``DIR/results/observations.parquet``): the calibrations take
minutes a model, so it is a script, not a pytest benchmark. Run:
``python tests/benchmarks/bench_runup_calibration.py DIR [--models vvms,lste,fvms]
[--points 50] [--walkers 16] [--max-steps 8000] [--seed 1] [--variants screened,plain]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

#: Issue 20's goals (s): one model, and all three.
GOAL_ONE_S = 600.0
GOAL_ALL_S = 1800.0


def calibrate(demo_out: Path, models: tuple[str, ...], args: argparse.Namespace,
              screened: bool) -> tuple[object, dict[str, float], float]:
    """Calibrate ``models``; the result, each model's wall time (s) and the total (s)."""
    import pandas as pd

    from rigtools.calibration import calibrate_runups, campaign_config
    from rigtools.campaign.manifest import load_campaign

    camp = load_campaign(demo_out / "campaign" / "campaign.toml")
    cfg = campaign_config(camp)
    cfg = dataclasses.replace(cfg, models=models, runup=dataclasses.replace(
        cfg.runup, max_steps=args.max_steps, max_speed_points=args.points,
        walkers=args.walkers, delayed_acceptance=screened, mixture_move=screened))
    obs = pd.read_parquet(demo_out / "results" / "observations.parquet")
    t0 = time.perf_counter()
    last: dict[int, float] = {}  # model index -> its last progress report (its chain's end)

    def progress(step: int, max_steps: int, tau: float | None) -> None:
        last[(step - 1) // args.max_steps] = time.perf_counter()

    res = calibrate_runups(camp, obs, config=cfg, outdir=None, progress=progress,
                           seed=args.seed)
    total = time.perf_counter() - t0
    # A model's time runs from the end of the previous model's chain to the end of its own
    # (its bank, its MAP and its sampling; the previous model's summary too); the summaries
    # after the last chain and the comparison count in the total only.
    times, prev = {}, t0
    for k, m in enumerate(m for m in models if m in res.fits):
        end = last.get(k, prev)
        times[m], prev = end - prev, end
    return res, times, total


def _mean_shift(a: dict, b: dict) -> float:
    """Largest |mean_a - mean_b| / sd_b over the sampled parameters and f_n."""
    pairs = [(a["parameters"][n], b["parameters"][n]) for n in b["parameters"]]
    pairs.append((a["derived"]["mesh_natural_frequency_Hz"],
                  b["derived"]["mesh_natural_frequency_Hz"]))
    return max((abs(x["mean"] - y["mean"]) / y["sd"] for x, y in pairs
                if x.get("mean") is not None and y.get("mean") is not None and y.get("sd")),
               default=float("nan"))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    ap.add_argument("demo_out", type=Path, help="output folder of `rigtools demo`")
    ap.add_argument("--models", default="vvms,lste,fvms")
    ap.add_argument("--points", type=int, default=50, help="max_speed_points per direction")
    ap.add_argument("--walkers", type=int, default=16)
    ap.add_argument("--max-steps", type=int, default=8000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--variants", default="screened,plain",
                    help="screened (the default sampler), plain (stretch and DE, every "
                    "proposal swept), or both")
    args = ap.parse_args(argv)
    for p in (args.demo_out / "campaign" / "campaign.toml",
              args.demo_out / "results" / "observations.parquet"):
        if not p.is_file():
            print(f"{p}: not found; run `rigtools demo -o {args.demo_out}` first",
                  file=sys.stderr)
            return 2
    models = tuple(args.models.split(","))
    variants = tuple(args.variants.split(","))
    if not set(variants) <= {"screened", "plain"}:
        ap.error("--variants: screened, plain or both")
    runs = {v: calibrate(args.demo_out, models, args, v == "screened") for v in variants}

    print(f"run-up calibration, {args.points} windows per direction, {args.walkers} walkers, "
          f"max {args.max_steps} steps; goal {GOAL_ONE_S:g} s a model, {GOAL_ALL_S:g} s for all")
    for v, (res, times, total) in runs.items():
        for m, dt in times.items():
            fit = res.fits[m]  # type: ignore[attr-defined]
            run = fit.run
            rhat = max((p.get("r_hat") or 0.0) for p in fit.summary["parameters"].values())
            ok = fit.converged and dt < GOAL_ONE_S
            print(f"  {v:8s} {m:5s} {dt:7.0f} s  {run.n_steps:6d} steps  converged "
                  f"{fit.converged!s:5s}  tau {min(run.tau):.0f}-{max(run.tau):.0f}  "
                  f"max R-hat {rhat:.3f}  sweeps/step "
                  f"{run.log_prob_evaluations / max(run.n_steps, 1):5.2f}  "
                  f"goal {'met' if ok else 'NOT met'}")
        ok = all(f.converged for f in res.fits.values()) and total < GOAL_ALL_S  # type: ignore[attr-defined]
        print(f"  {v:8s} all   {total:7.0f} s  goal {'met' if ok else 'NOT met'}")
    if len(runs) == 2:
        (res_s, t_s, _), (res_p, t_p, _) = runs["screened"], runs["plain"]
        for m in t_s:
            if m not in t_p:
                continue
            fs, fp = res_s.fits[m], res_p.fits[m]  # type: ignore[attr-defined]
            n, passed, acc = fs.run.screen_counts
            fit_note = next((x for x in fs.run.notes if x.startswith("delayed acceptance")),
                            "no surrogate fitted")
            print(f"  {m}: screened {t_p[m] / t_s[m]:.2f}x faster than plain; "
                  f"{100 * passed / max(n, 1):.0f} % of proposals swept, "
                  f"{100 * acc / max(passed, 1):.0f} % of those accepted; posterior means "
                  f"differ by at most {_mean_shift(fs.summary, fp.summary):.2f} sd "
                  f"(Monte Carlo error; exact by construction)\n    {fit_note}")
    print(next(iter(runs.values()))[0].statement)  # type: ignore[attr-defined]
    return 0


if __name__ == "__main__":
    sys.exit(main())

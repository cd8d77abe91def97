"""Time the SDOF run-up calibration to convergence on the demo's run-up (issue 20, item 4).

Issue 20's goal: one run-up curve (about 100 speed points, up and down) calibrated to
convergence (the autocorrelation rule of :mod:`rigtools.calibration.sampler`) in under 10
minutes on 2 cores, all three models under 30 minutes. On the run-up of a ``rigtools demo``
output folder, with ``max_speed_points`` windows per direction and the campaign's other
``[calibration]`` settings, this script runs :func:`rigtools.calibration.calibrate_runups`
for the chosen models and prints, per model, the wall time from its start to the next model's
(MAP, sampling and summaries), the steps, whether the rule was met, the final ``tau`` and the
largest split-walker R-hat, then the total against the goals and the comparison statement.

It needs a demo output (``rigtools demo -o DIR``, about 20 minutes; its observations table is
read from ``DIR/results/observations.parquet``): the calibration itself takes 10-30 minutes a
model, so it is a script, not a pytest benchmark. Run:
``python tests/benchmarks/bench_runup_calibration.py DIR [--models vvms,lste,fvms]
[--points 50] [--walkers 16] [--max-steps 8000] [--seed 1]``.
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


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    ap.add_argument("demo_out", type=Path, help="output folder of `rigtools demo`")
    ap.add_argument("--models", default="vvms,lste,fvms")
    ap.add_argument("--points", type=int, default=50, help="max_speed_points per direction")
    ap.add_argument("--walkers", type=int, default=16)
    ap.add_argument("--max-steps", type=int, default=8000)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)

    import pandas as pd

    from rigtools.calibration import calibrate_runups, campaign_config
    from rigtools.campaign.manifest import load_campaign

    manifest = args.demo_out / "campaign" / "campaign.toml"
    table = args.demo_out / "results" / "observations.parquet"
    for p in (manifest, table):
        if not p.is_file():
            print(f"{p}: not found; run `rigtools demo -o {args.demo_out}` first",
                  file=sys.stderr)
            return 2
    camp = load_campaign(manifest)
    cfg = campaign_config(camp)
    models = tuple(args.models.split(","))
    cfg = dataclasses.replace(cfg, models=models, runup=dataclasses.replace(
        cfg.runup, max_steps=args.max_steps, max_speed_points=args.points,
        walkers=args.walkers))
    obs = pd.read_parquet(table)

    t0 = time.perf_counter()
    last: dict[int, float] = {}  # model index -> its last progress report (its chain's end)

    def progress(step: int, max_steps: int, tau: float | None) -> None:
        last[(step - 1) // args.max_steps] = time.perf_counter()

    res = calibrate_runups(camp, obs, config=cfg, outdir=None, progress=progress,
                           seed=args.seed)
    total = time.perf_counter() - t0
    print(f"run-up calibration, {args.points} windows per direction, {args.walkers} walkers, "
          f"max {args.max_steps} steps; goal {GOAL_ONE_S:g} s a model, {GOAL_ALL_S:g} s for all")
    fitted = [m for m in models if m in res.fits]
    # A model's time runs from the end of the previous model's chain to the end of its own
    # (its bank, its MAP and its sampling; the previous model's summary too); the summaries
    # after the last chain and the comparison count in the total only.
    prev = t0
    for k, m in enumerate(fitted):
        fit = res.fits[m]
        end = last.get(k, prev)
        dt, prev = end - prev, end
        rhat = max((p.get("r_hat") or 0.0) for p in fit.summary["parameters"].values())
        ok = fit.converged and dt < GOAL_ONE_S
        print(f"  {m:5s} {dt:7.0f} s  {fit.run.n_steps:6d} steps  converged "
              f"{fit.converged!s:5s}  tau {min(fit.run.tau):.0f}-{max(fit.run.tau):.0f}  "
              f"max R-hat {rhat:.3f}  goal {'met' if ok else 'NOT met'}")
    ok = all(f.converged for f in res.fits.values()) and total < GOAL_ALL_S
    print(f"  all   {total:7.0f} s  goal {'met' if ok else 'NOT met'}")
    print(res.statement)
    return 0


if __name__ == "__main__":
    sys.exit(main())

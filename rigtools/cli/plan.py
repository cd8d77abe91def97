"""``rigtools plan``: which runs to add next to pin down the margin at the operating temperature.

Calibrates the campaign as ``rigtools calibrate`` does (resuming from OUTDIR's checkpoint when
that calibration already ran there), then ranks candidate runs (torque x bulk temperature,
within the ``[calibration]`` block's ``plan_torque_range_Nm`` / ``plan_temperature_range_C``)
by the predicted posterior sd of the margin c - c*(theta) at the operating temperature
(:func:`rigtools.calibration.plan_next_runs`), and prints the best.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from rigtools.campaign import load_campaign
from rigtools.cli.arguments import int_in_range
from rigtools.cli.common import fail, output_problem

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> None:
    """Register the subcommand."""
    p = subparsers.add_parser(
        "plan",
        help="propose the next runs (torque, temperature) that most narrow the margin",
        description="Propose the runs that would most reduce the posterior sd of the margin "
        "c - c*(theta) at the operating temperature, within the ranges the campaign states.",
    )
    p.add_argument("campaign", help="campaign manifest (TOML)")
    p.add_argument("--observations", metavar="OBS.parquet",
                   help="observations table (default: observe the campaign first)")
    p.add_argument("-o", "--output", required=True, metavar="OUTDIR",
                   help="calibration folder (reused when `rigtools calibrate` ran there)")
    p.add_argument("-n", "--number", type=lambda t: int_in_range(t, 1, 100), default=3,
                   help="how many runs to propose (1..100, default 3)")
    p.add_argument("--json", action="store_true", help="print the proposals as JSON")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the subcommand."""
    from rigtools.calibration import calibrate, campaign_config, plan_next_runs

    outdir = Path(args.output)
    problem = output_problem(outdir, folder=True)
    if problem:
        return fail(problem)
    campaign = load_campaign(args.campaign)
    config = campaign_config(campaign)
    outdir.mkdir(parents=True, exist_ok=True)
    result = calibrate(campaign, args.observations, config=config, outdir=outdir)
    plan = plan_next_runs(result)  # the ranges come from the [calibration] block
    best = plan.best(args.number)
    if args.json:
        print(json.dumps({"operating_temperature_C": plan.operating_temperature_C,
                          "current_margin_sd_um": plan.current_sd_um, "proposals": best},
                         indent=2))
        return 0
    print(f"margin sd at {plan.operating_temperature_C:g} degC now: {plan.current_sd_um:.3g} um")
    for i, b in enumerate(best, 1):
        print(f"{i}. torque {b['torque_Nm']:.4g} N m at {b['temperature_C']:.4g} degC: "
              f"margin sd -> {b['predicted_sd_um']:.3g} um (mesh mode near "
              f"{b['predicted_f_n_Hz']:.0f} Hz, detected with p = "
              f"{b['detection_probability']:.2f})")
    return 0

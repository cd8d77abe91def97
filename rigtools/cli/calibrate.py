"""``rigtools calibrate``: backlash, thermal closure and the critical gap from a campaign.

Reads the campaign file (its optional ``[calibration]`` block), the observations table
(``--observations``; without it the campaign is observed first, as ``rigtools observe`` does,
and the table is written into OUTDIR), runs :func:`rigtools.calibration.calibrate` and writes
``posterior.nc``, ``summary.json``, ``summary.csv`` and the figures into OUTDIR. A run that
did not converge within the step cap still writes its outputs, flagged, and exits 0 with a
warning; a killed run started again with the same arguments resumes from OUTDIR's checkpoint.
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path
from typing import Any

from rigtools.campaign import load_campaign
from rigtools.cli.common import fail, one_line, output_problem

__all__ = ["add_parser", "format_verdict", "run"]


def add_parser(subparsers: Any) -> None:
    """Register the subcommand."""
    p = subparsers.add_parser(
        "calibrate",
        help="calibrate backlash, thermal closure and the critical gap (emcee)",
        description="Calibrate the thermoelastic-backlash model of seed 000 to a campaign's "
        "natural frequencies: posterior of the backlash, the thermal closure and the stiffness "
        "scale, the critical compensation gap at every campaign temperature, the margin and "
        "regime of every run, and which model reading the data favour.",
    )
    p.add_argument("campaign", help="campaign manifest (TOML), with an optional [calibration]")
    p.add_argument("--observations", metavar="OBS.parquet",
                   help="observations table from `rigtools observe` (default: observe the "
                   "campaign first and write OUTDIR/observations.parquet)")
    p.add_argument("-o", "--output", required=True, metavar="OUTDIR",
                   help="output folder (created; a checkpoint in it lets a killed run resume)")
    p.add_argument("--seed", type=int, default=None,
                   help="random seed (default: the [calibration] block's, else 0)")
    p.set_defaults(func=run)


def format_verdict(summary: dict[str, Any]) -> str:
    """A few plain lines: backlash, c* at each temperature, regime of every run."""

    def interval(entry: dict[str, Any], scale: float, unit: str) -> str:
        return (f"{entry['q50'] * scale:.3g} {unit} (90 % {entry['q05'] * scale:.3g} .. "
                f"{entry['q95'] * scale:.3g})")

    def um(entry: dict[str, Any]) -> float:  # lengths are reported in um; m is converted
        return 1e6 if entry.get("unit") == "m" else 1.0

    lines = []
    b = summary["parameters"]["backlash"]
    lines.append(f"backlash c: {interval(b, um(b), 'um')}")
    for name, entry in summary["derived"].items():
        if name.startswith("critical_gap@"):
            lines.append(f"c* at {name.split('@', 1)[1]}: {interval(entry, um(entry), 'um')}")
    flip = summary["derived"].get("flip_temperature_C")
    if flip is not None:
        lines.append(f"flip temperature: {interval(flip, 1.0, 'degC')}")
    for run_id, r in summary["runs"].items():
        if r.get("left_out"):
            lines.append(f"run {run_id}: left out ({r['left_out']})")
        else:
            if r.get("mesh_mode_Hz") is None:
                mode = "no peak identified as the mesh mode"
            else:
                mode = (f"mesh mode {r['mesh_mode_Hz']:.0f} Hz on {r['mesh_mode_channel']} "
                        f"(p = {r['mesh_mode_probability']:.2f})")
            lines.append(f"run {run_id}: {r['regime']} (p = {r['regime_probability']:.2f}), "
                         f"{mode}")
    favoured = summary.get("model_comparison", {}).get("favoured")
    if favoured:
        lines.append(f"model reading favoured: {favoured}")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Run the subcommand."""
    from rigtools.calibration import calibrate, campaign_config, write_outputs
    from rigtools.plots.calibration import calibration_figures

    outdir = Path(args.output)
    problem = output_problem(outdir, folder=True)
    if problem:
        return fail(problem)
    campaign = load_campaign(args.campaign)
    config = campaign_config(campaign)          # a wrong block fails before any observing
    outdir.mkdir(parents=True, exist_ok=True)
    result = calibrate(campaign, args.observations, config=config, outdir=outdir,
                       seed=args.seed)
    written = write_outputs(result, outdir)
    logging.disable(logging.WARNING)  # corner logs "too few points" for every narrow panel
    try:
        figures = calibration_figures(result, outdir)
    finally:
        logging.disable(logging.NOTSET)
    for w in result.warnings:
        print(f"rigtools: warning: {one_line(w)}", file=sys.stderr)
    if not result.converged:
        print("rigtools: warning: the sampler did not converge within the step cap; the "
              "result is flagged (summary.json) and its intervals are not to be trusted",
              file=sys.stderr)
    print(format_verdict(result.summary))
    print()
    print(f"wrote {len(written) + len(figures)} files to {outdir} "
          f"(summary: {written.get('summary.json', outdir / 'summary.json')})")
    return 0

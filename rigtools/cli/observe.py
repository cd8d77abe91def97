"""``rigtools observe CAMPAIGN.toml -o OBS.parquet``: the observations table of a campaign.

Reads and analyses every run of the campaign (ingest, spectra, natural frequencies with damping,
RMS, Arms per speed step or along a ramp) with a progress bar over runs on stderr (when stderr
is a terminal, or with ``--progress``), and writes the tidy table
(``data_schemas/observations.schema.json``) as Parquet. A run that fails is reported on stderr
with its file and the reason, recorded in the table, and the others go on; a run whose speed
signal is missing gets a warning naming the run. Exit 0 when at least one run was analysed, 3
when none could be (or the campaign file itself is malformed).
"""

from __future__ import annotations

import argparse
import math
import sys
from typing import TYPE_CHECKING, Any

from rigtools.campaign import load_campaign, write_observations
from rigtools.cli.arguments import output_path
from rigtools.cli.common import fail, one_line, output_problem

if TYPE_CHECKING:
    from rigtools.campaign import Observations, RunObservations

__all__ = ["add_parser", "format_summary", "run"]


def add_parser(subparsers: Any) -> None:
    """Register the subcommand."""
    p = subparsers.add_parser(
        "observe",
        help="analyse every run of a campaign into one observations table (Parquet)",
        description="Read and analyse every run of a campaign manifest (TOML) and write one "
        "tidy table: conditions, natural frequencies with damping, RMS, Arms per speed step, "
        "quality flags and provenance per run and channel.",
    )
    p.add_argument("campaign", help="campaign manifest (TOML)")
    p.add_argument("-o", "--output", required=True, metavar="OUT.parquet",
                   type=output_path(".parquet"),
                   help="output file; its suffix must be .parquet (checked, with its folder, "
                   "before any run is read)")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="show (--progress) or hide (--no-progress) the progress bar over runs "
                   "on stderr; default: shown when stderr is a terminal")
    p.set_defaults(func=run)


class _Progress:
    """A tqdm bar over runs on stderr; by default only when stderr is a terminal.

    ``force`` True shows it anyway, False never (``--progress`` / ``--no-progress``).
    """

    def __init__(self, total: int, force: bool | None = None) -> None:
        self.bar: Any = None
        isatty = getattr(sys.stderr, "isatty", None)
        show = force if force is not None else bool(isatty is not None and isatty())
        if show:
            try:
                from tqdm import tqdm
            except ImportError:  # progress is a nicety; the table is the job
                tqdm = None
            if tqdm is not None:
                self.bar = tqdm(total=total, unit="run", desc="observe", file=sys.stderr,
                                leave=False, dynamic_ncols=True)

    def write(self, line: str) -> None:
        if self.bar is not None:
            self.bar.write(line, file=sys.stderr)
        else:
            print(line, file=sys.stderr)

    def update(self, run_id: str) -> None:
        if self.bar is not None:
            self.bar.set_postfix_str(run_id, refresh=False)
            self.bar.update(1)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _fmt(v: Any, spec: str) -> str:
    try:
        f = float(v)
    except (TypeError, ValueError):
        return "-"
    return format(f, spec) if math.isfinite(f) else "-"


def format_summary(obs: Observations) -> str:
    """One line per run: status, channels analysed, clean modes, lowest f_n, Arms (max).

    ``modes`` counts clean modes (status ``ok``) over all found: a flagged mode (clipped
    channel, low SNR, at a mesh line, swept mesh line) is not clean. ``f_n`` and ``zeta`` are
    the medians over the channels of the lowest clean mode; a run without a clean mode shows
    those of its lowest flagged modes, marked ``*`` (the table holds them, with their flags).
    ``steps`` counts speed steps, or says ``ramp`` when Arms was read along a ramp.
    """
    df = obs.table
    w = max([16, *(len(r.run_id) + 2 for r in obs.runs)])
    lines = [f"{'run':<{w}}{'status':<9}{'channels':>9}{'modes':>7}{'f_n Hz':>10}{'zeta':>8}"
             f"{'steps':>7}{'Arms m/s^2':>12}"]
    marked = False
    for r in obs.runs:
        rows = df[df["run_id"] == r.run_id]
        run_row = rows[rows["quantity"] == "run"]
        status = str(run_row["status"].iloc[0]) if len(run_row) else "-"
        rms = rows[rows["quantity"] == "rms"]
        n_ok = int((rms["status"] != "failed").sum())
        found = rows[(rows["quantity"] == "natural_frequency") & (rows["status"] != "failed")]
        modes = found[found["status"] == "ok"]
        shown, mark = (modes, "") if len(modes) else (found, "*" if len(found) else "")
        shown = shown[shown["f_n_Hz"].notna()]  # a row without a fitted f_n says nothing here
        lowest = shown.sort_values("mode_index").groupby("channel", sort=False).head(1)
        f_n = _fmt(lowest["f_n_Hz"].median() if len(lowest) else None, ".1f")
        zeta = _fmt(lowest["zeta"].median() if len(lowest) else None, ".4f")
        if f_n != "-" and mark:
            f_n, zeta, marked = f_n + mark, zeta + mark, True
        arms = rows[(rows["quantity"] == "arms") & (rows["status"] != "failed")]
        steps = arms[arms["segment"] != "ramp"]
        n_steps = "ramp" if len(arms) and not len(steps) else str(steps["step_index"].nunique())
        lines.append(
            f"{r.run_id:<{w}}{status:<9}{f'{n_ok}/{len(rms)}':>9}"
            f"{f'{len(modes)}/{len(found)}':>7}{f_n:>10}{zeta:>8}{n_steps:>7}"
            f"{_fmt(arms['arms_m_s2'].max() if len(arms) else None, '.3g'):>12}")
    if marked:
        lines.append("* no clean mode in the run: its lowest flagged modes (see quality_flags "
                     "and message in the table)")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Run the subcommand."""
    # Observing loads the signal analysis (scipy.signal): when this subcommand runs, not when
    # the command line starts.
    from rigtools.campaign.observe import observe_campaign

    problem = output_problem(args.output)
    if problem:
        return fail(problem)
    campaign = load_campaign(args.campaign)
    progress = _Progress(len(campaign.runs), getattr(args, "progress", None))

    def on_run(r: RunObservations) -> None:
        for w in r.warnings:
            progress.write(f"rigtools: warning: {one_line(w)}")
        if not r.analysed:
            progress.write(f"rigtools: error: run {r.run_id!r} failed: {one_line(str(r.error))}")
        progress.update(r.run_id)

    try:
        obs = observe_campaign(campaign, on_run=on_run, raise_errors=bool(args.debug))
    finally:
        progress.close()
    out = write_observations(obs, args.output)
    n, total = obs.n_analysed, len(obs.runs)
    print(format_summary(obs))
    print()
    failed = f", {total - n} failed" if n < total else ""
    print(f"wrote {out}: {len(obs.table)} rows, {n} of {total} run(s) analysed{failed}")
    if n == 0:
        return fail(f"{args.campaign}: no run could be analysed")
    return 0

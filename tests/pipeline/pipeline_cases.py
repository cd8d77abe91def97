"""Small campaigns for the pipeline tests: a few short runs of the demo campaign.

:func:`small_campaign` copies a demo campaign (``rigtools.demo.campaign``, size ``ci``,
runs of 1 s) keeping only the runs asked for, and appends a ``[calibration]`` block that
keeps the sampler short (one variant, 16 walkers, a few hundred steps), so a whole pipeline
run takes seconds.
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest

from rigtools.demo.campaign import generate_demo_campaign
from rigtools.pipeline import PipelineResult, run_campaign

__all__ = ["ACCEL", "CALIBRATION", "RUNS", "demo_source", "small_campaign", "whole_run"]

#: A short calibration: one variant, few walkers and steps.
CALIBRATION = """
[calibration]
compare_variants = ["secant_path"]
walkers = 16
max_steps = 300
check_every = 50
map_starts = 2
seed = 3
"""
#: Four runs over two temperatures, MCAP and BLF.
RUNS = ("LS3-30C", "LS9-30C", "LS7-105C", "LS9-105C")
#: Two of the three axes of the demo's accelerometer.
ACCEL = ("accel_x", "accel_y")


@pytest.fixture(scope="session")
def demo_source(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A demo campaign of 1-s runs, without the run-up, made once per session (do not modify)."""
    out = tmp_path_factory.mktemp("demo")
    generate_demo_campaign(out, size="ci", seed=3, duration_s=1.0, runup=False)
    return out


def small_campaign(source: Path, dest: Path, runs: tuple[str, ...] = RUNS, *,
                   calibration: str = CALIBRATION, extra_runs: str = "",
                   accel: tuple[str, ...] = ACCEL) -> Path:
    """Copy ``source`` to ``dest`` keeping ``runs``; returns the campaign file.

    Parameters
    ----------
    source : pathlib.Path
        A generated demo campaign.
    dest : pathlib.Path
    runs : tuple of str
        Run ids to keep, in this order.
    calibration : str
        Appended to the campaign file.
    extra_runs : str
        More ``[[run]]`` tables, appended as written.
    accel : tuple of str
        The accelerometer channels analysed (fewer channels, faster tests).
    """
    shutil.copytree(source, dest)
    text = (dest / "campaign.toml").read_text(encoding="utf-8")
    head, *blocks = text.split("\n[[run]]\n")
    head = re.sub(r"^accel = \[.*\]$", "accel = " + json.dumps(list(accel)), head,
                  flags=re.M)
    by_id = {re.search(r'^id = "([^"]+)"', b, re.M).group(1): b for b in blocks}
    kept = [f"[[run]]\n{by_id[r].rstrip()}\n" for r in runs]
    (dest / "campaign.toml").write_text(
        head.rstrip() + "\n\n" + "\n".join(kept) + extra_runs + calibration, encoding="utf-8")
    return dest / "campaign.toml"


@pytest.fixture(scope="session")
def whole_run(demo_source: Path, tmp_path_factory: pytest.TempPathFactory) -> PipelineResult:
    """:func:`small_campaign` run once through every stage, uninterrupted (do not modify)."""
    base = tmp_path_factory.mktemp("whole")
    camp = small_campaign(demo_source, base / "c")
    return run_campaign(camp, base / "whole", progress=False)

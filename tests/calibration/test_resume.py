"""A calibration killed and started again ends with the numbers of an uninterrupted run."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from calibration_cases import campaign, fast_config

from models.geometry import GearPair
from rigtools.calibration import calibrate_observations

HERE = Path(__file__).resolve().parent
SETTINGS = {"walkers": 16, "max_steps": 900, "check_every": 50, "map_starts": 2}


class InterruptError(Exception):
    pass


def _same(a: object, b: object) -> None:
    fa, fb = a.headline, b.headline
    assert np.array_equal(fa.run.chain, fb.run.chain)
    assert np.array_equal(fa.samples, fb.samples)
    assert (fa.run.burn_in, fa.run.thin, fa.run.n_steps) == (fb.run.burn_in, fb.run.thin,
                                                             fb.run.n_steps)
    assert a.summary["parameters"] == b.summary["parameters"]
    assert a.summary["derived"] == b.summary["derived"]


def test_interrupted_in_process_resumes_bit_for_bit(pair: GearPair, tmp_path: Path) -> None:
    obs = campaign(pair, seed=5)
    cfg = fast_config(**SETTINGS)
    whole = calibrate_observations(obs, pair, cfg, outdir=tmp_path / "whole")

    def stop(step: int, max_steps: int, tau: float | None) -> None:
        if step >= 400:
            raise InterruptError

    with pytest.raises(InterruptError):
        calibrate_observations(obs, pair, cfg, outdir=tmp_path / "cut", progress=stop)
    again = calibrate_observations(obs, pair, cfg, outdir=tmp_path / "cut")
    assert again.headline.run.resumed_from == 400
    assert whole.headline.run.resumed_from == 0
    _same(whole, again)


def test_a_changed_configuration_does_not_resume(pair: GearPair, tmp_path: Path) -> None:
    obs = campaign(pair, seed=5)
    short = SETTINGS | {"max_steps": 100}
    calibrate_observations(obs, pair, fast_config(**short), outdir=tmp_path)
    other = calibrate_observations(obs, pair, fast_config(**(short | {"seed": 2})),
                                   outdir=tmp_path)
    assert other.headline.run.resumed_from == 0
    assert any("belongs to another configuration" in w for w in other.headline.run.notes)


SCRIPT = textwrap.dedent("""
    import sys
    sys.path.insert(0, {here!r})
    from calibration_cases import campaign, fast_config
    from models.geometry import load_gear_set
    from rigtools.calibration import calibrate_observations
    pair = load_gear_set("fzg-c").pair

    def progress(step, max_steps, tau):
        print(step, flush=True)

    calibrate_observations(campaign(pair, seed=5), pair, fast_config(**{settings!r}),
                           outdir={out!r}, progress=progress)
    print("done", flush=True)
""")


@pytest.mark.slow
def test_sigkill_mid_run_then_restart_gives_the_same_numbers(pair: GearPair,
                                                             tmp_path: Path) -> None:
    out = tmp_path / "killed"
    code = SCRIPT.format(here=str(HERE), settings=SETTINGS, out=str(out))
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True,
                            cwd=HERE.parents[1])
    assert proc.stdout is not None
    killed_at = None
    for line in proc.stdout:
        if line.strip().isdigit() and int(line) >= 350:
            os.kill(proc.pid, signal.SIGKILL)
            killed_at = int(line)
            break
    proc.wait(timeout=60)
    assert killed_at is not None and proc.returncode == -signal.SIGKILL, "not killed mid-run"
    assert not (out / "summary.json").exists()
    obs = campaign(pair, seed=5)
    cfg = fast_config(**SETTINGS)
    resumed = calibrate_observations(obs, pair, cfg, outdir=out)
    assert resumed.headline.run.resumed_from >= 350
    whole = calibrate_observations(obs, pair, cfg, outdir=tmp_path / "whole")
    _same(whole, resumed)
    a = json.loads((out / "summary.json").read_text())
    b = json.loads((tmp_path / "whole" / "summary.json").read_text())
    assert a["sampler"].pop("resumed_from") >= 350 and b["sampler"].pop("resumed_from") == 0
    assert a == b

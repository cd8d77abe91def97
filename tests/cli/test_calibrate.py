"""``rigtools calibrate`` and ``rigtools plan`` from a campaign file and an observations table.

The table is simulated from known parameters (:func:`rigtools.calibration.simulate_observations`,
the secant-along-the-path model of seed 000 with a 4.9 kHz housing mode), so the test checks the
wiring end to end: the campaign's ``[calibration]`` block reaches the sampler (its errors name
the line), the outputs land in OUTDIR, the verdict names the regimes, and a bad block exits 3.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from models.geometry import load_gear_set
from rigtools.calibration import simulate_observations
from rigtools.campaign.observation_files import write_observations
from rigtools.cli import main

TRUTH = {"backlash": 7.5, "closure_coefficient": 0.376, "stiffness_scale": 0.8,
         "chi": 0.0285, "model_error": 0.002}
RUNS = [("LS3-30C", 35.3, 30.0), ("LS9-30C", 183.4, 30.0), ("LS12-30C", 302.0, 30.0),
        ("LS3-55C", 35.3, 55.0), ("LS9-55C", 183.4, 55.0), ("LS9-105C", 183.4, 105.0),
        ("LS12-105C", 302.0, 105.0)]

CAMPAIGN = """\
[campaign]
name = "wiring test"
gear_set = "fzg-c"

[thermal]
reference_temperature_C = 20.0

[calibration]
compare_variants = []
walkers = 16
max_steps = 3000
check_every = 100
map_starts = 3
{extra}
{runs}
"""


def _campaign(tmp: Path, extra: str = "") -> Path:
    runs = "\n".join(
        f'[[run]]\nid = "{r}"\nfile = "runs/{r}.mcap"\ntorque_Nm = {t}\n'
        f"bulk_temperature_C = {T}\nspeed_rpm = 1500.0\n" for r, t, T in RUNS)
    p = tmp / "campaign.toml"
    p.write_text(CAMPAIGN.format(extra=extra, runs=runs))
    return p


@pytest.fixture(scope="module")
def observations(tmp_path_factory: pytest.TempPathFactory) -> Path:
    pair = load_gear_set("fzg-c").pair
    table = simulate_observations(
        pair, [r for r, _, _ in RUNS], [t for _, t, _ in RUNS], [T for _, _, T in RUNS],
        TRUTH, rng=np.random.default_rng(3), housing_modes_Hz=[4900.0], campaign="wiring test")
    out = tmp_path_factory.mktemp("obs") / "obs.parquet"
    write_observations(table, out)
    return out


def test_calibrate_writes_the_outputs_and_names_the_regimes(tmp_path, observations, capsys):
    out = tmp_path / "cal"
    code = main(["calibrate", str(_campaign(tmp_path)), "--observations", str(observations),
                 "-o", str(out)])
    text = capsys.readouterr().out
    assert code == 0
    for name in ("summary.json", "summary.csv", "posterior.nc"):
        assert (out / name).is_file(), name
    summary = json.loads((out / "summary.json").read_text())
    b = summary["parameters"]["backlash"]
    assert b["unit"] == "um" and b["q05"] < TRUTH["backlash"] < b["q95"]
    assert summary["runs"]["LS3-30C"]["regime"] == "rises"  # c > c*(30 C) = 1.5 um
    assert summary["runs"]["LS9-105C"]["regime"] == "falls"  # c < c*(105 C) = 12.5 um
    assert "backlash c:" in text and "run LS9-105C: falls" in text


def test_plan_proposes_runs(tmp_path, observations, capsys):
    out = tmp_path / "cal"
    code = main(["plan", str(_campaign(tmp_path)), "--observations", str(observations),
                 "-o", str(out), "-n", "2", "--json"])
    assert code == 0
    plan = json.loads(capsys.readouterr().out)
    assert len(plan["proposals"]) == 2
    assert all(p["predicted_sd_um"] <= plan["current_margin_sd_um"] * 1.0001
               for p in plan["proposals"])


def test_a_bad_calibration_block_names_its_line_and_exits_3(tmp_path, observations, capsys):
    campaign = _campaign(tmp_path, extra='[calibration.priors]\n'
                         'backlash = {dist = "uniform", lower = 50.0, upper = 10.0}\n')
    code = main(["calibrate", str(campaign), "--observations", str(observations),
                 "-o", str(tmp_path / "cal")])
    err = capsys.readouterr().err
    assert code == 3
    line = next(i for i, s in enumerate(campaign.read_text().splitlines(), 1)
                if s.startswith("backlash ="))
    assert f"line {line}" in err and "backlash" in err
    assert "Traceback" not in err


def test_python_entry_takes_the_campaign_and_its_observations(tmp_path, observations):
    """``calibrate(campaign, observations)``: the path, the loaded campaign and a table agree.

    The ``[calibration]`` block (16 walkers) and the ``[thermal]`` reference reach the sampler:
    the same seed gives the same draws whichever way the inputs are passed.
    """
    from rigtools.calibration import calibrate
    from rigtools.campaign import load_campaign
    from rigtools.campaign.observation_files import read_observations

    path = _campaign(tmp_path)
    by_path = calibrate(path, observations, seed=4)
    by_objects = calibrate(load_campaign(path), read_observations(observations), seed=4)
    assert by_path.config.walkers == 16
    assert by_path.summary["conventions"]["reference_temperature_C"] == 20.0
    np.testing.assert_array_equal(by_path.headline.samples, by_objects.headline.samples)
    b = by_path.summary["parameters"]["backlash"]
    assert b["q05"] < TRUTH["backlash"] < b["q95"]

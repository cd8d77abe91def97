"""Shared cases of the calibration tests: the FZG-C pair, synthetic campaigns, fast settings.

The fixtures are registered by ``tests/calibration/conftest.py``; the test modules import the
plain helpers from here (a module of its own name: ``from conftest import`` would be ambiguous
between the conftest files of the test tree).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from models.geometry import GearPair, load_gear_set
from rigtools.calibration import (
    CalibrationConfig,
    calibrate_observations,
    default_config,
    simulate_observations,
)

#: A 10-run FZG-C campaign: five torques at two bulk temperatures.
TORQUES_NM = (20.0, 50.0, 100.0, 183.4, 302.0) * 2
TEMPERATURES_C = (40.0,) * 5 + (90.0,) * 5
RUN_IDS = tuple(f"R{i}" for i in range(10))
#: The truth the synthetic campaigns are drawn from (backlash in um).
TRUTH = {"backlash": 20.0, "closure_coefficient": 0.37, "stiffness_scale": 0.9,
         "chi": 0.0285, "model_error": 0.02}
#: A load-independent housing mode, close to the mesh mode at some runs and taller than it.
HOUSING_HZ = 4500.0


@pytest.fixture(scope="session")
def pair() -> GearPair:
    return load_gear_set("fzg-c").pair


@pytest.fixture(scope="session")
def secant_fit(pair: GearPair, tmp_path_factory: pytest.TempPathFactory) -> tuple[object, Path]:
    """One calibration shared by several test modules, outputs written (folder returned).

    Campaign seed 6, the headline variant compared with the tangent reading.
    """
    out = tmp_path_factory.mktemp("cal")
    res = calibrate_observations(campaign(pair, seed=6), pair,
                    fast_config(compare_variants=("secant_path", "tangent")), outdir=out)
    return res, out


def campaign(pair: GearPair, seed: int = 3, **kw: object) -> pd.DataFrame:
    """The synthetic 10-run campaign (with the housing mode unless overridden)."""
    args: dict[str, object] = {"housing_modes_Hz": (HOUSING_HZ,)}
    args.update(kw)
    truth = dict(TRUTH)
    truth.update(args.pop("truth", {}))  # type: ignore[arg-type]
    return simulate_observations(
        pair, list(args.pop("run_ids", RUN_IDS)), args.pop("torques", TORQUES_NM),
        args.pop("temperatures", TEMPERATURES_C), truth, rng=np.random.default_rng(seed),
        **args)


def fast_config(**kw: object) -> CalibrationConfig:
    """Reduced sampler settings for the default test suite (one variant unless asked)."""
    base = replace(default_config(), compare_variants=(), walkers=24, max_steps=6000,
                   check_every=100, map_starts=4)
    return replace(base, **kw)


def toml_lines(text: str) -> Callable[[str], int | None]:
    """``line_of`` for a TOML text: dotted key -> line of that key (or of its table)."""
    lines: dict[str, int] = {}
    table = ""
    for i, line in enumerate(text.splitlines(), 1):
        m = re.match(r"\s*\[([^\]]+)\]", line)
        if m:
            table = m.group(1).strip()
            lines.setdefault(table, i)
            continue
        m = re.match(r"\s*([A-Za-z0-9_]+)\s*=", line)
        if m:
            key = f"{table}.{m.group(1)}" if table else m.group(1)
            lines.setdefault(key, i)
            for inner in re.findall(r"([A-Za-z0-9_]+)\s*=", line.split("=", 1)[1]):
                lines.setdefault(f"{key}.{inner}", i)

    def line_of(key: str) -> int | None:
        k = key
        while k:
            if k in lines:
                return lines[k]
            k = k.rpartition(".")[0]
        return None

    return line_of

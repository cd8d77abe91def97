"""Simulation-based calibration of the run-up calibration (tests/calibration/sbc_runup.py).

Thresholds, stated: the full run (100 simulated VVMS run-ups, 100 points per direction,
default sampler to convergence) needs the 90 % interval of ``zeta``, the mesh natural
frequency and the two errors to cover the truth in 85-95 % of them and each rank histogram
(10 bins) to pass a chi-square test of uniformity at 1 %. The reduced subset in the default
suite (6 run-ups, 16 points per direction, 10 walkers, 120 steps: short chains) needs at
least 4 of 6 covered per quantity: a calibrated posterior fails that with probability
P(Binomial(6, 0.9) <= 3) = 0.016 per quantity.
"""

from __future__ import annotations

import pytest
from sbc_runup import QUANTITIES, Settings, check, run


def test_sbc_runup_reduced() -> None:
    report = check(run(6, seed=201, settings=Settings(walkers=10, max_steps=120,
                                                      map_starts=1, points_per_direction=16)))
    assert report["fitted"] == 6, report["refused"]
    for q in QUANTITIES:
        covered = round(report[q]["coverage_90"] * report["fitted"])
        assert covered >= 4, (q, report[q])


@pytest.mark.slow
def test_sbc_runup_100() -> None:
    report = check(run(100, seed=0, settings=Settings(), jobs=2))
    assert report["fitted"] >= 95, report["refused"]
    for q in QUANTITIES:
        assert 0.85 <= report[q]["coverage_90"] <= 0.95, (q, report[q])
        assert report[q]["chi2_p"] > 0.01, (q, report[q])

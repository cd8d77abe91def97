"""Simulation-based calibration (tests/calibration/sbc.py): a fast subset and the full run.

Thresholds, stated: the full run (100 simulated campaigns) needs every quantity's 90 %
interval to cover the truth in 85-95 % of them and its rank histogram (10 bins) to pass a
chi-square test of uniformity at 1 %. The fast subset (8 campaigns, reduced sampler
settings: 16 walkers, at most 1200 steps) needs at least 5 of 8 covered per quantity: a
calibrated posterior fails that with probability P(Binomial(8, 0.9) <= 4) = 0.005 per
quantity.
"""

from __future__ import annotations

import pytest
from sbc import QUANTITIES, Settings, check, run


def test_sbc_fast_subset() -> None:
    report = check(run(8, seed=101, settings=Settings(walkers=16, max_steps=1200,
                                                      check_every=100, map_starts=2)))
    assert report["fitted"] >= 7, report["refused"]
    for q in QUANTITIES:
        covered = report[q]["coverage_90"] * report["fitted"]
        assert covered >= 5 - (8 - report["fitted"]), (q, report[q])


@pytest.mark.slow
def test_sbc_100_campaigns() -> None:
    report = check(run(100, seed=0, settings=Settings()))
    assert report["fitted"] >= 95, report["refused"]
    for q in QUANTITIES:
        assert 0.85 <= report[q]["coverage_90"] <= 0.95, (q, report[q])
        assert report[q]["chi2_p"] > 0.01, (q, report[q])

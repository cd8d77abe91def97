"""What the simulation-based calibration scripts share (``sbc.py``, ``sbc_runup.py``).

Each simulation records, per quantity, whether the central 90 % interval covers the truth
and the rank of the truth among ``L = N_RANK_DRAWS`` posterior draws (uniform on ``0..L``
when the posterior is calibrated, Talts et al. 2018). This module holds the summary over
the simulations (90 % coverage and the chi-square test of the rank histogram), the checks
on it and the command line both scripts take.

References
----------
.. [1] S. Talts, M. Betancourt, D. Simpson, A. Vehtari, A. Gelman, "Validating Bayesian
   inference algorithms with simulation-based calibration", arXiv:1804.06788 (2018).
"""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import stats

__all__ = [
    "COVERAGE_BAND",
    "MIN_CHI2_P",
    "N_BINS",
    "N_RANK_DRAWS",
    "RankCoverage",
    "emit_report",
    "parse_cli",
    "passes_checks",
    "rank_coverage",
]

#: Posterior draws the truth is ranked among (ranks run over ``0..N_RANK_DRAWS``).
N_RANK_DRAWS = 99
#: Bins of the rank histogram.
N_BINS = 10
#: The 90 % interval must cover the truth in this share of the simulations.
COVERAGE_BAND = (0.85, 0.95)
#: The rank histogram must pass the chi-square test of uniformity at this level.
MIN_CHI2_P = 0.01


@dataclass(frozen=True)
class RankCoverage:
    """Coverage and rank uniformity of one quantity over the fitted simulations.

    Attributes
    ----------
    coverage_90 : float
        Share of the simulations whose central 90 % interval covers the truth (NaN when
        none was fitted).
    chi2_p : float
        p-value of the chi-square test of uniformity of ``rank_counts`` (NaN when none was
        fitted).
    rank_counts : numpy.ndarray
        Ranks per bin, ``N_BINS`` integers.
    """

    coverage_90: float
    chi2_p: float
    rank_counts: np.ndarray


def rank_coverage(fitted: Sequence[dict[str, Any]], quantity: str) -> RankCoverage:
    """Coverage and rank histogram of ``quantity`` over the fitted simulations.

    Parameters
    ----------
    fitted : sequence of dict
        One record per fitted simulation; ``record[quantity]`` holds ``"covered"`` (bool)
        and ``"rank"`` (int in ``0..N_RANK_DRAWS``).
    quantity : str
        The quantity to summarise.

    Returns
    -------
    RankCoverage
        The 90 % coverage, the chi-square p-value and the rank histogram.
    """
    ranks = np.array([r[quantity]["rank"] for r in fitted])
    counts = np.histogram(ranks, bins=N_BINS, range=(0, N_RANK_DRAWS + 1))[0]
    if not fitted:
        return RankCoverage(math.nan, math.nan, counts)
    return RankCoverage(coverage_90=float(np.mean([r[quantity]["covered"] for r in fitted])),
                        chi2_p=float(stats.chisquare(counts).pvalue), rank_counts=counts)


def passes_checks(report: dict[str, Any], quantities: Sequence[str]) -> bool:
    """Whether every quantity's coverage lies in ``COVERAGE_BAND`` and its p > ``MIN_CHI2_P``."""
    lo, hi = COVERAGE_BAND
    return all(lo <= report[q]["coverage_90"] <= hi and report[q]["chi2_p"] > MIN_CHI2_P
               for q in quantities)


def parse_cli(description: str, argv: list[str] | None = None) -> argparse.Namespace:
    """The options of an SBC script: ``--n``, ``--seed``, ``--jobs`` and ``--out``."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--n", type=int, default=100)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--out", default=None)
    return ap.parse_args(argv)


def emit_report(report: dict[str, Any], results: list[dict[str, Any]], out: str | None,
                quantities: Sequence[str], *, indent: int) -> int:
    """Write report and results as JSON to ``out`` (if given), print the report.

    Returns
    -------
    int
        The exit code: 0 when :func:`passes_checks`, else 1.
    """
    text = json.dumps({"report": report, "results": results}, indent=indent)
    if out:
        with open(out, "w", encoding="utf-8") as fh:
            fh.write(text)
    print(json.dumps(report, indent=indent))
    return 0 if passes_checks(report, quantities) else 1

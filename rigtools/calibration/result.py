"""What a calibration returns: one fit per model variant and the campaign-level result.

:class:`VariantFit` holds one variant's posterior (draws, per-run log-likelihood and
predictions, summaries, warnings); :class:`CalibrationResult` holds the fits, the comparison
of the variants, the headline variant and the ``summary.json`` content. Both are frozen;
their arrays are the caller's to read, not to change.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from rigtools.calibration.comparison import ModelComparison
from rigtools.calibration.config import CalibrationConfig
from rigtools.calibration.data import CalibrationData
from rigtools.calibration.derived import Quantity
from rigtools.calibration.model import CalibrationModel
from rigtools.calibration.sampler import SamplerRun

__all__ = ["CalibrationResult", "VariantFit"]


@dataclass(frozen=True, eq=False)
class VariantFit:
    """The posterior of one model variant.

    Attributes
    ----------
    variant : str
    model : CalibrationModel
    run : SamplerRun
    samples : numpy.ndarray
        Kept draws ``(W, N, D)``.
    log_prob : numpy.ndarray
        Log posterior of the kept draws ``(W, N)``.
    log_likelihood : numpy.ndarray
        Per-run log-likelihood ``(W, N, R)``.
    f_pred_Hz : numpy.ndarray
        Predicted mesh-mode frequency ``(W, N, R)`` (NaN where jammed and censored).
    jammed : numpy.ndarray
        Bool ``(W, N, R)``.
    quantities : tuple of Quantity
        Parameters and derived quantities.
    summaries : dict
        Name -> summary (:func:`rigtools.calibration.diagnostics.summarize`).
    runs : dict
        Run id -> regime, probabilities and mesh mode
        (:func:`rigtools.calibration.derived.run_summaries`).
    warnings : tuple of str
    """

    variant: str
    model: CalibrationModel
    run: SamplerRun
    samples: np.ndarray
    log_prob: np.ndarray
    log_likelihood: np.ndarray
    f_pred_Hz: np.ndarray
    jammed: np.ndarray
    quantities: tuple[Quantity, ...]
    summaries: dict[str, dict[str, Any]]
    runs: dict[str, dict[str, Any]]
    warnings: tuple[str, ...]

    def draws(self, name: str) -> np.ndarray:
        """Draws ``(W, N)`` of a parameter or derived quantity."""
        for q in self.quantities:
            if q.name == name:
                return q.draws
        raise KeyError(name)

    @property
    def converged(self) -> bool:
        """The sampler's convergence rule was met."""
        return self.run.converged


@dataclass(frozen=True, eq=False)
class CalibrationResult:
    """A campaign's calibration.

    Attributes
    ----------
    config : CalibrationConfig
        As resolved (seed included).
    data : CalibrationData
    variant : str
        The headline variant.
    fits : dict
        Variant -> VariantFit (the headline one always present).
    comparison : ModelComparison or None
        None when only one variant was fitted.
    summary : dict
        The content of ``summary.json``.
    warnings : tuple of str
        Everything a reader must know before trusting the headline numbers.
    """

    config: CalibrationConfig
    data: CalibrationData
    variant: str
    fits: dict[str, VariantFit]
    comparison: ModelComparison | None
    summary: dict[str, Any]
    warnings: tuple[str, ...]

    @property
    def headline(self) -> VariantFit:
        """The fit of the headline variant."""
        return self.fits[self.variant]

    @property
    def converged(self) -> bool:
        """Every fitted variant met the convergence rule."""
        return all(f.converged for f in self.fits.values())

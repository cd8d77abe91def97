r"""The likelihood of a run's peaks: a mixture over which peak, if any, is the mesh mode.

A rig housing has structural modes that do not move with load or temperature, and one of them
may be taller than the mesh mode and close to it. So no peak is chosen before the fit: every
natural-frequency row of a run (all channels), ``f_1 .. f_J``, is a candidate, and the
assignment ``z`` (which row is the mesh mode, or none) is marginalised.

The mixture
-----------
Each candidate that is not the mesh mode is a *background* peak with density ``b(f)``: uniform
on the band the peaks were searched in, or, for a peak of a recurring group taken as a
structural mode, narrow about the group's frequency (:mod:`rigtools.calibration.data`). The
mesh mode, predicted at
``f_p``, is among the candidates with probability ``p_d(f_p)`` (``detection_probability``
``p_0`` inside the band, falling smoothly to 0 outside it: ``p_d = p_0 Phi((f_p - f_lo) / (e
f_lo)) Phi((f_hi - f_p) / (e f_hi))``, ``e = 0.03``), each candidate equally likely. The
measured ``f_j`` of the mesh-mode row scatters about ``f_p`` with

.. math:: \sigma_j^2 = \mathrm{sd}_j^2 + (\sigma_{rel} f_p)^2 ,

``sd_j`` the SDOF fit's ``f_n_std_Hz`` and ``sigma_rel`` the relative model error (normal, or
Student-t with ``nu`` degrees of freedom and scale ``sigma_j`` with
``likelihood = "student_t"``). Marginalising ``z``:

.. math::

    L_r = \prod_j b(f_j) \left[ (1 - p_d) + \frac{p_d}{J}
          \sum_{j=1}^{J} \frac{\varphi(f_j \mid f_p, \sigma_j)}{b(f_j)} \right] .

``L_r >= (1 - p_0) prod_j b(f_j) > 0``: one run can never veto a parameter set, however far the
prediction is from every peak (an outlier peak costs a bounded amount). The posterior
probability that row ``j`` is the mesh mode is its share of the bracket, averaged over the
posterior draws (:func:`assignment_probabilities`). A mode that appears on several channels
appears as several candidates; their probabilities add up (the summary reports the sum over
rows within three combined standard deviations of the chosen one).

Recurring groups: whether each of the ``K`` recurring groups is a structural mode is one
campaign-level choice ``z`` (``Z = 2^K`` configurations, equal prior weight), marginalised:

.. math::

    L = \frac{1}{Z} \sum_z \prod_r L_r(z), \qquad
    \pi_z = \frac{\prod_r L_r(z)}{\sum_{z'} \prod_r L_r(z')} .

The sampler uses ``ln L``. The pointwise log-likelihood of run ``r`` (for PSIS-LOO and the
posterior summaries) is ``ln sum_z pi_z L_r(z)``: the configuration is weighed by all the
data (as a campaign-level latent is), the run by itself. With one recurring group or none,
and ``pi_z`` near 0 or 1 as soon as a few runs speak, this is the run's term of ``ln L``.

The jammed state (SEED-NOTES 10), ``jammed_model = "censored"``
--------------------------------------------------------------
Eq. (1) has no meaning for a jammed run, and as a run approaches the jam from outside, the
secant stiffness, and with it ``f_p``, grows without bound. Under the secant reading the mesh
mode therefore leaves the band upward before the jam is reached: ``p_d -> 0`` and
``L_r -> prod b``. The censored treatment gives a jammed run exactly that limit:
"the model predicts no mesh mode in the band; every peak is background". The likelihood is
then finite everywhere and continuous across the jam boundary (a test evaluates it on both
sides of the boundary); a jammed run is penalised exactly as much as its peaks are better
explained by a prediction than by the background. ``jammed_model = "double_flank"`` instead
predicts the double-flank tangent stiffness at the jammed nodes (a separate physical state,
:mod:`rigtools.calibration.forward`); it is finite everywhere but, as the physics it encodes,
jumps at the boundary, where the secant diverges and the double-flank tangent does not.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import gammaln, ndtr

from rigtools.calibration.config import LikelihoodKind
from rigtools.calibration.data import Candidates

__all__ = [
    "EDGE_WIDTH",
    "SD_FLOOR",
    "LikelihoodSettings",
    "MixtureLikelihood",
    "assignment_probabilities",
    "detection_probability",
    "run_log_likelihood",
]

#: Relative width ``e`` of the smooth edges of the detection probability at the band edges.
EDGE_WIDTH: Final = 0.03
#: Relative floor of the per-row sd (keeps a zero fit sd and zero model error finite).
SD_FLOOR: Final = 1e-4
_LOG_SQRT_2PI: Final = 0.5 * math.log(2.0 * math.pi)


@dataclass(frozen=True)
class LikelihoodSettings:
    """How the candidates of a run are scored (module notes).

    Attributes
    ----------
    band_Hz : (float, float)
        Band of the background density and of detection.
    detection_probability : float
        ``p_0``.
    kind : {"normal", "student_t"}
    dof : float
        ``nu`` of the Student-t.
    """

    band_Hz: tuple[float, float]
    detection_probability: float = 0.9
    kind: LikelihoodKind = "normal"
    dof: float = 4.0

    @property
    def log_uniform(self) -> float:
        """``ln U = -ln(f_hi - f_lo)`` (ln 1/Hz)."""
        return -math.log(self.band_Hz[1] - self.band_Hz[0])


def detection_probability(f_pred_Hz: ArrayLike, settings: LikelihoodSettings) -> np.ndarray:
    """``p_d(f_p)``: probability that the mesh mode is among the candidates (0 if NaN).

    Parameters
    ----------
    f_pred_Hz : array_like
        Predicted mesh-mode frequency (Hz); NaN for a censored (jammed) run.
    settings : LikelihoodSettings

    Returns
    -------
    numpy.ndarray

    Examples
    --------
    >>> s = LikelihoodSettings((1000.0, 10000.0), 0.9)
    >>> [round(float(p), 3) for p in detection_probability([5000.0, 20000.0, np.nan], s)]
    [0.9, 0.0, 0.0]
    """
    f = np.asarray(f_pred_Hz, dtype=float)
    lo, hi = settings.band_Hz
    ok = np.isfinite(f)
    fs = np.where(ok, f, hi * 10.0)
    p = settings.detection_probability * ndtr((fs - lo) / (EDGE_WIDTH * lo)) * ndtr(
        (hi - fs) / (EDGE_WIDTH * hi))
    return np.where(ok, p, 0.0)


class MixtureLikelihood:
    """The mixture likelihood of one campaign's candidates, with its constants precomputed.

    Parameters
    ----------
    candidates : Candidates
    settings : LikelihoodSettings
    """

    def __init__(self, candidates: Candidates, settings: LikelihoodSettings) -> None:
        self.candidates = candidates
        self.settings = settings
        self.candidate_f = np.where(candidates.mask, candidates.f_Hz, 0.0)
        self.candidate_sd2 = np.where(candidates.mask, candidates.sd_Hz, 0.0) ** 2
        self._pad = np.where(candidates.mask, 0.0, -np.inf)
        self.log_count = np.log(candidates.count)
        self.log_background = np.where(candidates.mask[None], candidates.log_background, 0.0)
        self.background_constant = self.log_background.sum(axis=-1)          # (Z, R)
        self.log_configuration_prior = -math.log(self.log_background.shape[0])
        lo, hi = settings.band_Hz
        self._edge = (lo, 1.0 / (EDGE_WIDTH * lo), hi, 1.0 / (EDGE_WIDTH * hi))
        nu = settings.dof
        self.student_t_constant = (gammaln(0.5 * (nu + 1.0)) - gammaln(0.5 * nu)
                                   - 0.5 * math.log(nu * math.pi))

    def _terms(self, f_pred: np.ndarray,
               model_error: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``ln(1 - p_d)`` ``(W, R)`` and ``ln(p_d / J) + ln phi_j`` ``(W, R, J)``."""
        ok = np.isfinite(f_pred)
        lo, ilo, hi, ihi = self._edge
        fp = np.where(ok, f_pred, 10.0 * hi)
        p = (self.settings.detection_probability * ndtr((fp - lo) * ilo)
             * ndtr((hi - fp) * ihi))
        p = np.where(ok, p, 0.0)
        # far outside the band p_d is 0 to machine precision; clipping keeps the (then
        # irrelevant) candidate densities finite for any prediction
        fp = np.clip(fp, 0.1 * lo, 10.0 * hi)
        me2 = (model_error * model_error + SD_FLOOR * SD_FLOOR)[:, None]
        var = self.candidate_sd2 + (me2 * fp * fp)[..., None]
        d = self.candidate_f - fp[..., None]
        z2 = d * d / var
        if self.settings.kind == "normal":
            log_phi = -0.5 * (z2 + np.log(var)) - _LOG_SQRT_2PI
        else:
            nu = self.settings.dof
            log_phi = self.student_t_constant - 0.5 * np.log(var) - 0.5 * (nu + 1.0) * \
                np.log1p(z2 / nu)
        log_p = np.log(np.maximum(p, 1e-300)) - self.log_count
        return np.log1p(-p), log_phi + log_p[..., None] + self._pad

    def per_configuration(self, f_pred_Hz: np.ndarray, model_error: np.ndarray) -> np.ndarray:
        """``ln L_r(z)`` for every configuration of the recurring groups, ``(W, Z, R)``."""
        log_q, base = self._terms(f_pred_Hz, model_error)
        out = []
        for z in range(self.log_background.shape[0]):
            terms = base - self.log_background[z]
            m = np.maximum(log_q, terms.max(axis=-1))
            total = np.exp(log_q - m) + np.exp(terms - m[..., None]).sum(axis=-1)
            out.append(m + np.log(total) + self.background_constant[z])
        return np.stack(out, axis=1)

    def _combine(self, per: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        t = per.sum(axis=-1) + self.log_configuration_prior                # (W, Z)
        tmax = t.max(axis=-1, keepdims=True)
        total = (tmax + np.log(np.exp(t - tmax).sum(axis=-1, keepdims=True)))[:, 0]
        log_w = t - total[:, None]                                          # ln pi_z
        a = log_w[..., None] + per                                          # (W, Z, R)
        amax = a.max(axis=1)
        pointwise = amax + np.log(np.exp(a - amax[:, None]).sum(axis=1))
        return total, pointwise, np.exp(log_w)

    def total_log_likelihood(self, f_pred_Hz: np.ndarray, model_error: np.ndarray) -> np.ndarray:
        """``ln L`` of the campaign, the recurring groups' configuration marginalised, ``(W,)``."""
        return self._combine(self.per_configuration(f_pred_Hz, model_error))[0]

    def run_log_likelihood(self, f_pred_Hz: np.ndarray, model_error: np.ndarray) -> np.ndarray:
        """Pointwise ``ln L_r`` ``(W, R)`` (module notes).

        The runs' terms of :meth:`total_log_likelihood` when there is no recurring group.
        """
        return self._combine(self.per_configuration(f_pred_Hz, model_error))[1]

    def configuration_probabilities(self, f_pred_Hz: np.ndarray,
                                    model_error: np.ndarray) -> np.ndarray:
        """``pi_z``: probability of each configuration given the parameters, ``(W, Z)``."""
        return self._combine(self.per_configuration(f_pred_Hz, model_error))[2]

    def assignment_probabilities(self, f_pred_Hz: np.ndarray,
                                 model_error: np.ndarray) -> np.ndarray:
        """``(W, R, J + 1)``: each candidate (0 in padding), then "none of them"."""
        log_q, base = self._terms(f_pred_Hz, model_error)
        pi = self.configuration_probabilities(f_pred_Hz, model_error)
        out = np.zeros((*log_q.shape, base.shape[-1] + 1))
        for z in range(self.log_background.shape[0]):
            allt = np.concatenate([base - self.log_background[z], log_q[..., None]], axis=-1)
            w = np.exp(allt - allt.max(axis=-1, keepdims=True))
            out += pi[:, z, None, None] * w / w.sum(axis=-1, keepdims=True)
        return out


def run_log_likelihood(
    f_pred_Hz: ArrayLike,
    model_error: ArrayLike,
    candidates: Candidates,
    settings: LikelihoodSettings,
) -> np.ndarray:
    """Log-likelihood of each run's candidate peaks, the assignment marginalised (module notes).

    Parameters
    ----------
    f_pred_Hz : array_like
        Predicted mesh-mode frequency (Hz), ``(W, R)``; NaN for a censored (jammed) run.
    model_error : array_like
        ``sigma_rel`` per parameter set, ``(W,)``.
    candidates : Candidates
    settings : LikelihoodSettings

    Returns
    -------
    numpy.ndarray
        ``ln L_r``, ``(W, R)``, finite everywhere.
    """
    f = np.atleast_2d(np.asarray(f_pred_Hz, dtype=float))
    return MixtureLikelihood(candidates, settings).run_log_likelihood(
        f, np.atleast_1d(np.asarray(model_error, dtype=float)))


def assignment_probabilities(
    f_pred_Hz: ArrayLike,
    model_error: ArrayLike,
    candidates: Candidates,
    settings: LikelihoodSettings,
) -> np.ndarray:
    """Posterior probability, per parameter set, of each assignment of the mesh mode.

    Parameters
    ----------
    f_pred_Hz, model_error, candidates, settings
        As :func:`run_log_likelihood`.

    Returns
    -------
    numpy.ndarray
        ``(W, R, J + 1)``: candidates ``0 .. J-1`` (0 in padding), then "none of them".
    """
    f = np.atleast_2d(np.asarray(f_pred_Hz, dtype=float))
    return MixtureLikelihood(candidates, settings).assignment_probabilities(
        f, np.atleast_1d(np.asarray(model_error, dtype=float)))

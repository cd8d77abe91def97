"""The log posterior of a campaign: parameter vector, priors, forward model and likelihood.

:func:`build_model` ties the pieces together for one model variant; the resulting
:class:`CalibrationModel` is the vectorised log-probability emcee calls
(``model(theta)`` with ``theta`` of shape ``(W, D)``, one row per walker) and unpacks sample
arrays into named parameters for everything downstream.

Sampled vector, in order: the free global parameters of
:data:`rigtools.calibration.config.PARAMETERS` (``backlash`` in um, the others as their units
say), then, with ``temperature_sd_K``, one ``temperature_offset@<run>`` (K) per run. Fixed
parameters enter as constants. Parameter sets outside a prior's support get ``-inf`` without
evaluating the model.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import ArrayLike

from models.geometry import GearPair
from models.thermal import ThermalReference
from rigtools.calibration.config import CalibrationConfig, Variant
from rigtools.calibration.data import CalibrationData
from rigtools.calibration.forward import (
    ForwardModel,
    Prediction,
    mesh_frequency,
    predict,
    prepare_forward,
)
from rigtools.calibration.kernel import (
    DIST_CODES,
    JAMMED_CODES,
    KIND_CODES,
    VARIANT_CODES,
    log_posterior_kernel,
)
from rigtools.calibration.likelihood import (
    EDGE_WIDTH,
    SD_FLOOR,
    LikelihoodSettings,
    MixtureLikelihood,
)
from rigtools.calibration.priors import Prior, prior_from_mapping

__all__ = ["TEMPERATURE_OFFSET", "UM", "CalibrationModel", "build_model"]

#: Metres per micrometre (backlash is sampled and reported in um).
UM: Final = 1e-6
#: Name prefix of the per-run temperature offsets.
TEMPERATURE_OFFSET: Final = "temperature_offset@"


@dataclass(frozen=True, eq=False)
class CalibrationModel:
    """Vectorised log posterior of one model variant (module notes).

    Attributes
    ----------
    names : tuple of str
        Sampled parameters, in vector order.
    units : tuple of str
        Their units.
    priors : tuple of Prior
    fixed : dict
        Fixed global parameters (name -> value in its unit).
    forward : ForwardModel
    data : CalibrationData
    settings : LikelihoodSettings
    """

    names: tuple[str, ...]
    units: tuple[str, ...]
    priors: tuple[Prior, ...]
    fixed: dict[str, float]
    forward: ForwardModel
    data: CalibrationData
    settings: LikelihoodSettings

    @property
    def ndim(self) -> int:
        """``D``."""
        return len(self.names)

    @property
    def variant(self) -> Variant:
        """The forward model's variant."""
        return self.forward.variant

    def with_variant(self, variant: Variant) -> CalibrationModel:
        """The same posterior with another forward-model variant."""
        return CalibrationModel(self.names, self.units, self.priors, dict(self.fixed),
                                self.forward.with_variant(variant), self.data, self.settings)

    def unpack(self, theta: ArrayLike) -> dict[str, np.ndarray]:
        """Named parameters of parameter vectors ``(..., D)``.

        Returns
        -------
        dict
            Global parameters (free and fixed) as arrays of the leading shape, and
            ``temperature_offset_K`` of shape ``(..., R)`` (zeros when not sampled).
        """
        t = np.asarray(theta, dtype=float)
        lead = t.shape[:-1]
        out: dict[str, np.ndarray] = {}
        offsets = []
        for i, n in enumerate(self.names):
            if n.startswith(TEMPERATURE_OFFSET):
                offsets.append(t[..., i])
            else:
                out[n] = t[..., i]
        for n, v in self.fixed.items():
            out[n] = np.full(lead, v)
        out["temperature_offset_K"] = (np.stack(offsets, axis=-1) if offsets
                                       else np.zeros((*lead, self.forward.n_runs)))
        return out

    def log_prior(self, theta: ArrayLike) -> np.ndarray:
        """Sum of the log prior densities, ``(W,)`` (``-inf`` outside a support)."""
        t = np.atleast_2d(np.asarray(theta, dtype=float))
        lp = np.zeros(t.shape[0])
        for i, p in enumerate(self.priors):
            lp += p.logpdf(t[:, i])
        return lp

    def predict(self, theta: ArrayLike) -> Prediction:
        """Forward-model predictions for parameter vectors ``(W, D)``."""
        p = self.unpack(np.atleast_2d(theta))
        offsets = p["temperature_offset_K"] if self.has_temperature_offsets else None
        return predict(self.forward, p["backlash"] * UM, p["closure_coefficient"],
                       p["stiffness_scale"], p["chi"], temperature_offset_K=offsets)

    @property
    def has_temperature_offsets(self) -> bool:
        """The per-run temperatures are sampled."""
        return any(n.startswith(TEMPERATURE_OFFSET) for n in self.names)

    @functools.cached_property
    def likelihood(self) -> MixtureLikelihood:
        """The mixture likelihood of the campaign's candidates."""
        return MixtureLikelihood(self.data.candidates, self.settings)

    def frequencies(self, theta: ArrayLike) -> np.ndarray:
        """Predicted mesh-mode frequency (Hz), ``(W, R)`` (NaN where jammed and censored)."""
        p = self.unpack(np.atleast_2d(np.asarray(theta, dtype=float)))
        offsets = p["temperature_offset_K"] if self.has_temperature_offsets else None
        return mesh_frequency(self.forward, p["backlash"] * UM, p["closure_coefficient"],
                              p["stiffness_scale"], p["chi"], offsets)

    def log_likelihood_runs(self, theta: ArrayLike) -> np.ndarray:
        """Per-run log-likelihood, ``(W, R)`` (NaN rows outside the prior support)."""
        return self.evaluate(theta)[1]

    def evaluate(self, theta: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Log posterior ``(W,)``, per-run log-likelihood ``(W, R)`` and ``f_n`` ``(W, R)``.

        The compiled kernel (:mod:`rigtools.calibration.kernel`); rows outside the prior
        support get ``-inf`` and NaN.
        """
        t = np.ascontiguousarray(np.atleast_2d(np.asarray(theta, dtype=float)))
        n_w, n_r = t.shape[0], self.forward.n_runs
        out = np.empty(n_w)
        runs = np.empty((n_w, n_r))
        freq = np.empty((n_w, n_r))
        _KERNEL(t, *self._kernel_args, out, runs, freq)
        return out, runs, freq

    @functools.cached_property
    def _kernel_args(self) -> tuple[object, ...]:
        pri = self.priors
        index = np.full(5, -1, dtype=np.int64)
        fixed = np.zeros(5)
        for k, n in enumerate(_KERNEL_ORDER):
            if n in self.names:
                index[k] = self.names.index(n)
            else:
                fixed[k] = self.fixed[n]
        offsets = [i for i, n in enumerate(self.names) if n.startswith(TEMPERATURE_OFFSET)]
        fm, lk, st = self.forward, self.likelihood, self.settings
        lo, hi = st.band_Hz
        return (
            np.array([DIST_CODES[p.dist] for p in pri], dtype=np.int64),
            np.array([p.loc for p in pri]), np.array([p.scale for p in pri]),
            np.array([p.lower for p in pri]), np.array([p.upper for p in pri]),
            np.array([p.log_density_constant for p in pri]),
            index, fixed, offsets[0] if offsets else -1,
            np.ascontiguousarray(fm.closure.run_m), np.ascontiguousarray(fm.closure.slope_m_per_K),
            np.ascontiguousarray(fm.normal_load_N), np.ascontiguousarray(fm.q_N_per_m),
            np.ascontiguousarray(fm.a_N_per_m), fm.q_max_N_per_m, fm.k_mesh_N_per_m,
            fm.frequency_factor, VARIANT_CODES[fm.variant], JAMMED_CODES[fm.jammed_model],
            np.ascontiguousarray(lk.candidate_f), np.ascontiguousarray(lk.candidate_sd2),
            np.ascontiguousarray(self.data.candidates.mask),
            np.ascontiguousarray(lk.log_background), lk.log_count,
            np.ascontiguousarray(lk.background_constant), st.detection_probability, lo, hi,
            EDGE_WIDTH,
            KIND_CODES[st.kind], float(st.dof), lk.student_t_constant, SD_FLOOR,
        )

    def log_prob_numpy(self, theta: ArrayLike) -> np.ndarray:
        """The log posterior by the NumPy path (the kernel's reference), ``(W,)``."""
        t = np.atleast_2d(np.asarray(theta, dtype=float))
        lp = self.log_prior(t)
        ok = np.isfinite(lp)
        out = np.full(lp.shape, -np.inf)
        if ok.any():
            tt = t[ok]
            ll = self.likelihood.total_log_likelihood(self.frequencies(tt),
                                                      self.unpack(tt)["model_error"])
            out[ok] = lp[ok] + ll
        return out

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        """Log posterior (up to a constant) of parameter vectors ``(W, D)``, ``(W,)``."""
        return self.evaluate(theta)[0]


#: The compiled kernel, typed loosely for the type checker (numba checks the arguments).
_KERNEL: Final[Callable[..., None]] = log_posterior_kernel
#: Kernel order of the global parameters.
_KERNEL_ORDER: Final = ("backlash", "closure_coefficient", "stiffness_scale", "model_error",
                        "chi")


def build_model(
    data: CalibrationData,
    pair: GearPair,
    config: CalibrationConfig,
    *,
    reference: ThermalReference,
    variant: Variant | None = None,
) -> CalibrationModel:
    """The log posterior of a campaign for one variant.

    Parameters
    ----------
    data : CalibrationData
    pair : GearPair
    config : CalibrationConfig
    reference : ThermalReference
        Reference temperature and housing of the thermal closure.
    variant : str, optional
        Default ``config.model_variant``.

    Returns
    -------
    CalibrationModel
    """
    runs = data.runs
    fwd: ForwardModel = prepare_forward(
        pair, runs.torque_Nm, runs.bulk_temperature_C,
        variant=config.model_variant if variant is None else variant,
        thermal_model=config.thermal_model, jammed_model=config.jammed_model,
        reference=reference, oil_temperature_C=runs.oil_temperature_C,
        equivalent_mass_kg=config.equivalent_mass_kg, inertia_kg_m2=config.inertia_kg_m2,
        disc_radius=config.disc_radius)
    names, units, priors = [], [], []
    fixed: dict[str, float] = {}
    for spec in config.parameters:
        if spec.fixed is None and spec.prior is not None:
            names.append(spec.name)
            units.append(spec.unit)
            priors.append(spec.prior)
        elif spec.fixed is not None:
            fixed[spec.name] = float(spec.fixed)
    if config.temperature_sd_K is not None:
        prior = prior_from_mapping({"dist": "normal", "mu": 0.0, "sd": config.temperature_sd_K})
        for r in runs.run_id:
            names.append(f"{TEMPERATURE_OFFSET}{r}")
            units.append("K")
            priors.append(prior)
    settings = LikelihoodSettings(band_Hz=data.candidates.band_Hz,
                                  detection_probability=config.detection_probability,
                                  kind=config.likelihood, dof=config.student_t_dof)
    if not math.isfinite(settings.log_uniform):
        raise ValueError("band_Hz must have a positive width")
    return CalibrationModel(tuple(names), tuple(units), tuple(priors), fixed, fwd, data,
                            settings)

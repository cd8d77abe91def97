r"""The log posterior of one SDOF model against every run-up curve, vectorised over walkers.

Free parameters (``[calibration.runup.priors]``, in this order, those not fixed by
``[calibration.runup.fixed]``): ``zeta`` (1), ``mesh_stiffness_scale`` (1),
``fluctuation_scale`` (1), ``backlash`` (um, total ``2b``), ``model_error`` (1: the error
shared by the channels at a point), ``model_error_length`` (1: its correlation length along a
sweep, in ``ln f_m``) and ``channel_error`` (1: each channel's own). The channel
gains are marginalised (:mod:`rigtools.calibration.runup_likelihood`), one per channel and
run, all with the ``gain`` prior.

``log p(theta | data) = sum_k log prior_k(theta_k) + sum_runs log p(curve | theta)`` up to a
constant; ``-inf`` outside a prior's support or outside the stiffness scales the cycle banks
cover (:attr:`~rigtools.calibration.runup_forward.RunUpForward.scale_range`, 0.3-3 by
default: a note when the prior reaches beyond), and ``-inf`` where a sweep fails at an
observed point. A :class:`RunUpPosterior` is the ``(W, D) -> (W,)`` callable that
:func:`rigtools.calibration.sampler.run_sampler` takes; walkers outside the support are not
swept.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigtools.calibration.priors import Prior
from rigtools.calibration.runup_config import RunUpSettings
from rigtools.calibration.runup_forward import RunSweep, RunUpForward
from rigtools.calibration.runup_likelihood import (
    GainPrior,
    error_gaps,
    marginal_log_likelihood,
)

__all__ = ["MICROMETRE", "RunUpPosterior", "build_posterior"]

#: Metres per micrometre (backlash in the configuration and summaries is in um).
MICROMETRE = 1e-6
_SWEPT = ("zeta", "mesh_stiffness_scale", "fluctuation_scale", "backlash", "model_error",
          "model_error_length", "channel_error")


@dataclass(frozen=True, eq=False)
class RunUpPosterior:
    """Vectorised log posterior of one SDOF model.

    Attributes
    ----------
    forward : RunUpForward
    names : tuple of str
        Free parameters, sampling order.
    priors : tuple of Prior
        One per free parameter.
    fixed : dict
        Fixed parameters (name -> value in the parameter's unit).
    gain_prior : GainPrior
        Prior of ``log G_c``.
    log_observed : tuple of numpy.ndarray
        ``log Arms`` per curve, ``(C, N)``, NaN where not observed.
    gaps : tuple of numpy.ndarray
        Per curve, ``(N - 1,)`` ``ln f_m`` steps between neighbouring points over which the
        model error is correlated (:func:`~rigtools.calibration.runup_likelihood.error_gaps`).
    notes : tuple of str
    """

    forward: RunUpForward
    names: tuple[str, ...]
    priors: tuple[Prior, ...]
    fixed: dict[str, float]
    gain_prior: GainPrior
    log_observed: tuple[np.ndarray, ...]
    gaps: tuple[np.ndarray, ...]
    notes: tuple[str, ...] = ()

    @property
    def kind(self) -> str:
        """The SDOF model."""
        return self.forward.kind

    @property
    def log_scale(self) -> tuple[bool, ...]:
        """Per free parameter: sampled as ``ln x`` (every prior whose support is ``x >= 0``).

        The damping ratio, the stiffness scales and the three error parameters are positive
        and scale-like. So is the backlash: a misspecified model's posterior can put its mass
        at a backlash of a few um or less (an FVMS fitted to a VVMS-made run-up: below ~2 um
        the back flank closes the gap and the model turns linear, damping 0.058, where with a
        wide gap it needs 0.09 to match the jumps). Moved in um, that region is a sliver of
        1 % of a 0-300 um prior against which the stretch and DE moves of walkers on the
        plateau hardly ever land: a 3000-step chain from the MAP found 8 % of its draws
        there, where in ``ln x`` the chain puts 95 %, its log density ~7 above the plateau's
        (README, performance). See :func:`rigtools.calibration.sampler.run_sampler`.
        """
        return tuple(p.lower >= 0.0 for p in self.priors)

    @property
    def ndim(self) -> int:
        """Free parameters."""
        return len(self.names)

    def unpack(self, theta: np.ndarray) -> dict[str, np.ndarray]:
        """Every parameter (free and fixed) as ``(...)`` arrays, in its unit."""
        t = np.asarray(theta, dtype=float)
        out = {n: t[..., i] for i, n in enumerate(self.names)}
        for n, v in self.fixed.items():
            out[n] = np.full(t.shape[:-1], float(v))
        return out

    def log_prior(self, theta: np.ndarray) -> np.ndarray:
        """Sum of the priors' log densities, ``(W,)``; ``-inf`` outside the bank's scales."""
        t = np.atleast_2d(np.asarray(theta, dtype=float))
        lp = np.zeros(t.shape[0])
        for i, p in enumerate(self.priors):
            lp = lp + p.logpdf(t[:, i])
        s = self.unpack(t)["mesh_stiffness_scale"]
        lo, hi = self.forward.scale_range
        return np.where((s >= lo) & (s <= hi), lp, -np.inf)

    def sweeps(self, theta: np.ndarray) -> tuple[RunSweep, ...]:
        """The model sweeps of every run for ``theta`` ``(W, D)``."""
        p = self.unpack(np.atleast_2d(theta))
        return self.forward.sweeps(p["zeta"], p["mesh_stiffness_scale"],
                                   p["fluctuation_scale"], p["backlash"] * MICROMETRE)

    def log_likelihood(self, theta: np.ndarray,
                       sweeps: tuple[RunSweep, ...] | None = None) -> np.ndarray:
        """Marginal log-likelihood (gains integrated out), ``(W,)``."""
        t = np.atleast_2d(np.asarray(theta, dtype=float))
        sw = self.sweeps(t) if sweeps is None else sweeps
        p = self.unpack(t)
        ll = np.zeros(t.shape[0])
        for y, gaps, s in zip(self.log_observed, self.gaps, sw, strict=True):
            ll = ll + marginal_log_likelihood(y, s.log_mu, p["model_error"],
                                              p["channel_error"], self.gain_prior,
                                              error_length=p["model_error_length"], gaps=gaps)
        return np.where(np.isnan(ll), -np.inf, ll)

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        """Log posterior, ``(W, D) -> (W,)``."""
        t = np.atleast_2d(np.asarray(theta, dtype=float))
        lp = self.log_prior(t)
        ok = np.isfinite(lp)
        out = np.full(t.shape[0], -np.inf)
        if ok.any():
            out[ok] = lp[ok] + self.log_likelihood(t[ok])
        return out


def build_posterior(forward: RunUpForward, settings: RunUpSettings) -> RunUpPosterior:
    """The log posterior of ``forward`` under the ``[calibration.runup]`` priors.

    Parameters
    ----------
    forward : RunUpForward
    settings : RunUpSettings

    Returns
    -------
    RunUpPosterior
    """
    names, priors, fixed, notes = [], [], {}, []
    for n in _SWEPT:
        spec = settings.parameter(n)
        if spec.free:
            assert spec.prior is not None
            names.append(n)
            priors.append(spec.prior)
        else:
            assert spec.fixed is not None
            fixed[n] = float(spec.fixed)
    gp = settings.parameter("gain").prior
    assert gp is not None and gp.dist == "lognormal"
    gain = GainPrior(gp.loc, gp.scale)
    lo, hi = forward.scale_range
    s = settings.parameter("mesh_stiffness_scale")
    if s.prior is not None and s.free and (s.prior.ppf(0.001) < lo or s.prior.ppf(0.999) > hi):
        notes.append(f"the mesh_stiffness_scale prior {s.prior.describe()} reaches beyond the "
                     f"scales the cycle banks cover [{lo:g}, {hi:g}]; it is cut there")
    elif not s.free and s.fixed is not None and not lo <= s.fixed <= hi:
        notes.append(f"the fixed mesh_stiffness_scale {s.fixed:g} lies outside the banks' "
                     f"[{lo:g}, {hi:g}]")
    with np.errstate(divide="ignore"):
        logs = tuple(np.where(np.asarray(c.observed, dtype=float) > 0,
                              np.log(np.where(np.asarray(c.observed) > 0, c.observed, 1.0)),
                              np.nan) for c in forward.curves)
    gaps = tuple(error_gaps(c.mesh_frequency_Hz, c.direction) for c in forward.curves)
    return RunUpPosterior(forward=forward, names=tuple(names), priors=tuple(priors),
                          fixed=fixed, gain_prior=gain, log_observed=logs, gaps=gaps,
                          notes=tuple(notes))

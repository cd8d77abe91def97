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

from dataclasses import dataclass, replace
from typing import Final

import numpy as np

from rigtools.calibration.priors import Prior
from rigtools.calibration.runup_config import RunUpSettings
from rigtools.calibration.runup_forward import RunSweep, RunUpForward
from rigtools.calibration.runup_likelihood import (
    GainPrior,
    error_gaps,
    marginal_log_likelihood,
)

__all__ = ["ERROR_PARAMETERS", "MICROMETRE", "PROFILE_GRIDS", "PROFILE_JOINT_GRIDS",
           "RunUpPosterior", "build_posterior"]

#: Metres per micrometre (backlash in the configuration and summaries is in um).
MICROMETRE = 1e-6
_SWEPT = ("zeta", "mesh_stiffness_scale", "fluctuation_scale", "backlash", "model_error",
          "model_error_length", "channel_error")
#: The error parameters: the log posterior depends on them through the likelihood of fixed
#: sweeps, so moving them costs no sweep.
ERROR_PARAMETERS: Final = ("model_error", "model_error_length", "channel_error")
#: :meth:`RunUpPosterior.profile_errors`' passes: ``(half-width in ln x, points)`` of the grid
#: each error parameter is searched on, in turn, around its current value ...
PROFILE_GRIDS: Final = ((3.0, 13), (0.8, 9))
#: ... then of the grids searched jointly (``points ** 3``: the errors trade off).
PROFILE_JOINT_GRIDS: Final = ((0.4, 5), (0.15, 5), (0.05, 5), (0.02, 5))


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

    def smoothed_start(self) -> dict[int, float]:
        """Columns held fixed in the smoothed MAP search, and their values (module notes).

        The free error parameters at a wide, short-correlated error: ``model_error`` at its
        prior's 95 % quantile, ``model_error_length`` at its 5 % quantile, ``channel_error``
        at its median (:func:`rigtools.calibration.runup_map.find_runup_map`). Empty when
        none is free.
        """
        at = {"model_error": 0.95, "model_error_length": 0.05, "channel_error": 0.5}
        return {self.names.index(n): float(self.priors[self.names.index(n)].ppf(at[n]))
                for n in ERROR_PARAMETERS if n in self.names}

    def profile_errors(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``theta`` with its free error parameters moved up the log posterior, sweeps fixed.

        One sweep per row; then each free error parameter in turn is searched on a grid in
        ``ln x`` around its current value (:data:`PROFILE_GRIDS`: +-3, +-0.8) and moved to
        the grid's best point if that raises the log posterior, then all of them together on
        shrinking joint grids (:data:`PROFILE_JOINT_GRIDS`, +-0.4 to +-0.02: the model and
        channel errors trade off, which one at a time follows slowly). It costs likelihoods
        of the fixed sweeps (~1 % of a sweep each; ~560 a row), not sweeps. A value that is
        not positive starts from the prior's median.

        Returns
        -------
        theta : numpy.ndarray
            ``(W, D)``, a copy.
        log_prob : numpy.ndarray
            ``(W,)`` log posterior at the returned rows.
        """
        t = np.array(np.atleast_2d(theta), dtype=float)
        w = t.shape[0]
        cols = [self.names.index(n) for n in ERROR_PARAMETERS if n in self.names]
        for j in cols:
            bad = ~(t[:, j] > 0)
            t[bad, j] = float(self.priors[j].ppf(0.5))
        ok = np.isfinite(self.log_prior(t))
        if not cols or not ok.any():
            return t, self(t)
        sub = t[ok]
        sw = self.sweeps(sub)
        best = self.log_prior(sub) + self.log_likelihood(sub, sw)
        rows = np.arange(sub.shape[0])
        passes = [(half, k, [j]) for half, k in PROFILE_GRIDS for j in cols]
        passes += [(half, k, cols) for half, k in PROFILE_JOINT_GRIDS]
        for half, k, move in passes:
            steps = np.exp(np.linspace(-half, half, k))
            grid = np.stack(np.meshgrid(*([steps] * len(move)), indexing="ij"),
                            axis=-1).reshape(-1, len(move))
            g = grid.shape[0]
            rep = tuple(replace(s, log_mu=np.repeat(s.log_mu, g, axis=0)) for s in sw)
            cand = np.repeat(sub, g, axis=0)
            cand[:, move] *= np.tile(grid, (sub.shape[0], 1))
            lp = self.log_prior(cand)
            inside = np.isfinite(lp)
            lp[inside] += self.log_likelihood(cand, rep)[inside]
            lp = np.where(np.isnan(lp), -np.inf, lp).reshape(-1, g)
            i = np.argmax(lp, axis=1)
            up = lp[rows, i] > best
            sub[up] = cand.reshape(-1, g, t.shape[1])[rows, i][up]
            best[up] = lp[rows, i][up]
        t[ok] = sub
        out = np.full(w, -np.inf)
        out[ok] = best
        return t, out

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

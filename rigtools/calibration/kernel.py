r"""The log posterior compiled (numba): priors, forward model and mixture likelihood in one loop.

An ensemble step evaluates ``W/2`` parameter vectors at once. In NumPy that is some 60 array
operations on arrays of a few hundred elements, each costing more in dispatch than in
arithmetic; :func:`log_posterior_kernel` does the same arithmetic in one compiled loop over
walkers, runs, quadrature nodes and candidates. It is the same mathematics as the NumPy path
(:class:`rigtools.calibration.priors.Prior`, :func:`rigtools.calibration.forward.mesh_frequency`
and :class:`rigtools.calibration.likelihood.MixtureLikelihood`), which stays as its reference:
``tests/calibration/test_kernel.py`` compares the two on random parameter sets of every
variant, jammed treatment and likelihood to 1e-10 relative.

Codes (plain integers, so one compiled function serves every configuration): variants
``0 secant_path, 1 secant_mesh, 2 tangent``; jammed ``0 censored, 1 double_flank``;
likelihood ``0 normal, 1 student_t``; priors ``0 uniform, 1 normal, 2 lognormal,
3 halfnormal``. ``ndtr(x) = erfc(-x / sqrt 2) / 2``.
"""

from __future__ import annotations

import math
from typing import Final

import numpy as np
from numba import njit

__all__ = [
    "DIST_CODES",
    "JAMMED_CODES",
    "KIND_CODES",
    "VARIANT_CODES",
    "log_posterior_kernel",
]

VARIANT_CODES: Final = {"secant_path": 0, "secant_mesh": 1, "tangent": 2}
JAMMED_CODES: Final = {"censored": 0, "double_flank": 1}
KIND_CODES: Final = {"normal": 0, "student_t": 1}
DIST_CODES: Final = {"uniform": 0, "normal": 1, "lognormal": 2, "halfnormal": 3}
_LOG_SQRT_2PI: Final = 0.5 * math.log(2.0 * math.pi)
_SQRT_HALF: Final = math.sqrt(0.5)


@njit(cache=True)
def _ndtr(x: float) -> float:  # pragma: no cover (compiled)
    return 0.5 * math.erfc(-x * _SQRT_HALF)


@njit(cache=True)
def log_posterior_kernel(
    theta: np.ndarray,
    prior_code: np.ndarray, prior_loc: np.ndarray, prior_scale: np.ndarray,
    prior_lower: np.ndarray, prior_upper: np.ndarray, prior_const: np.ndarray,
    index: np.ndarray, fixed: np.ndarray, offset_start: int,
    basis: np.ndarray, slope: np.ndarray, normal_load: np.ndarray,
    q: np.ndarray, a: np.ndarray, q_max: float, k_mesh: float, factor: float,
    variant: int, jammed_model: int,
    cand_f: np.ndarray, cand_sd2: np.ndarray, cand_mask: np.ndarray, cand_logb: np.ndarray,
    log_count: np.ndarray,
    const_background: np.ndarray, p0: float, lo: float, hi: float, edge: float,
    kind: int, nu: float, t_const: float, sd_floor: float,
    out: np.ndarray, out_runs: np.ndarray, out_f: np.ndarray,
) -> None:  # pragma: no cover (compiled; checked against the NumPy path)
    """Log posterior of every row of ``theta`` into ``out``, per-run terms into ``out_runs``.

    ``index[k]`` is the column of parameter ``k`` (backlash um, closure coefficient,
    stiffness scale, model error, chi) or -1 for ``fixed[k]``; ``offset_start`` the column of
    the first per-run temperature offset or -1. Rows outside the prior support get ``-inf``
    (their ``out_runs`` and ``out_f`` rows are NaN). ``out_f`` receives ``f_n`` (Hz; NaN
    where jammed and censored).
    """
    n_w, n_d = theta.shape
    n_r = basis.shape[0]
    n_n = q.shape[0]
    n_j = cand_f.shape[1]
    terms = np.empty(max(n_j, 1))
    par = np.empty(5)
    n_z = cand_logb.shape[0]
    per = np.empty((n_z, n_r))
    tz = np.empty(n_z)
    log_prior_z = -math.log(n_z)
    for w in range(n_w):
        lp = 0.0
        for d in range(n_d):
            x = theta[w, d]
            if not (x >= prior_lower[d] and x <= prior_upper[d]):
                lp = -np.inf
                break
            code = prior_code[d]
            if code == 0:
                lp += prior_const[d]
            elif code == 2:
                lx = math.log(x) if x > 0.0 else math.log(1e-300)
                z = (lx - prior_loc[d]) / prior_scale[d]
                lp += prior_const[d] - 0.5 * z * z - lx
            else:
                z = (x - prior_loc[d]) / prior_scale[d]
                lp += prior_const[d] - 0.5 * z * z
        if lp == -np.inf:
            out[w] = -np.inf
            for r in range(n_r):
                out_runs[w, r] = np.nan
                out_f[w, r] = np.nan
            continue
        for k in range(5):
            par[k] = theta[w, index[k]] if index[k] >= 0 else fixed[k]
        c = par[0] * 1e-6
        kc = (1.0 - par[4]) * par[1]
        s = par[2]
        me2 = par[3] * par[3] + sd_floor * sd_floor
        for r in range(n_r):
            b = basis[r]
            if offset_start >= 0:
                b += slope[r] * theta[w, offset_start + r]
            u = c - kc * b
            jam = False
            if variant == 2:
                k_mean = s * k_mesh
            else:
                ratio = u * s / normal_load[r]
                if variant == 0:
                    jam = ratio * q_max <= -1.0
                    k_mean = 0.0
                    if not jam:
                        for j in range(n_n):
                            k_mean += a[j] / (1.0 + ratio * q[j])
                    elif jammed_model == 1:
                        for j in range(n_n):
                            den = 1.0 + ratio * q[j]
                            k_mean += a[j] / den if den > 0.0 else 2.0 * a[j]
                    k_mean *= s
                else:
                    den = 1.0 + ratio * k_mesh
                    jam = den <= 0.0
                    if not jam:
                        k_mean = s * k_mesh / den
                    else:
                        k_mean = 2.0 * s * k_mesh
            censored = jam and jammed_model == 0
            if censored:
                out_f[w, r] = np.nan
                p = 0.0
                fp = 10.0 * hi
            else:
                fp = math.sqrt(k_mean) * factor
                out_f[w, r] = fp
                p = p0 * _ndtr((fp - lo) / (edge * lo)) * _ndtr((hi - fp) / (edge * hi))
                fp = min(max(fp, 0.1 * lo), 10.0 * hi)
            log_q = math.log1p(-p)
            log_p = math.log(max(p, 1e-300)) - log_count[r]
            for j in range(n_j):
                if cand_mask[r, j]:
                    var = cand_sd2[r, j] + me2 * fp * fp
                    dd = cand_f[r, j] - fp
                    z2 = dd * dd / var
                    if kind == 0:
                        t = -0.5 * (z2 + math.log(var)) - _LOG_SQRT_2PI
                    else:
                        t = (t_const - 0.5 * math.log(var)
                             - 0.5 * (nu + 1.0) * math.log1p(z2 / nu))
                    terms[j] = t + log_p
            # log-sum-exp over the candidates and "none", per configuration
            for z in range(n_z):
                m = log_q
                for j in range(n_j):
                    if cand_mask[r, j]:
                        t = terms[j] - cand_logb[z, r, j]
                        if t > m:
                            m = t
                total = math.exp(log_q - m)
                for j in range(n_j):
                    if cand_mask[r, j]:
                        total += math.exp(terms[j] - cand_logb[z, r, j] - m)
                per[z, r] = m + math.log(total) + const_background[z, r]
        # the recurring groups' configuration, marginalised over the campaign
        tmax = -np.inf
        for z in range(n_z):
            tz[z] = log_prior_z
            for r in range(n_r):
                tz[z] += per[z, r]
            if tz[z] > tmax:
                tmax = tz[z]
        acc = 0.0
        for z in range(n_z):
            acc += math.exp(tz[z] - tmax)
        total_ll = tmax + math.log(acc)
        for r in range(n_r):
            amax = -np.inf
            for z in range(n_z):
                v = tz[z] - total_ll + per[z, r]
                if v > amax:
                    amax = v
            acc = 0.0
            for z in range(n_z):
                acc += math.exp(tz[z] - total_ll + per[z, r] - amax)
            out_runs[w, r] = amax + math.log(acc)
        lp += total_ll
        out[w] = lp

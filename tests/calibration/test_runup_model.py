"""The run-up log posterior's error profile (rigtools.calibration.runup_model).

:meth:`RunUpPosterior.profile_errors` moves the error parameters up the log posterior with the
sweeps fixed (coordinate, then joint grids in ``ln x``); checked against scipy's Nelder-Mead
over the same three parameters in ``ln x``, each row's sweep computed once.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from sbc_runup import Settings, config_for, simulate_curve
from scipy.optimize import minimize

from models.geometry import load_gear_set
from rigtools.calibration.runup_api import build_forward
from rigtools.calibration.runup_model import ERROR_PARAMETERS, build_posterior


def _posterior():
    curve = simulate_curve("vvms", 300.0, zeta=0.025, stiffness_scale=0.9,
                           gains=(1e-2, 4e-3, 7e-3), model_error=0.1, channel_error=0.03,
                           model_error_length=0.05, seed=4, points_per_direction=12,
                           run_id="KB-300")
    cfg = config_for(Settings(), models=("vvms",), fix_backlash=False)
    pair = load_gear_set("kahraman-blankenship").pair
    fwd = build_forward("vvms", (curve,), {"KB-300": pair}, {},
                        steps_per_period=cfg.runup.steps_per_period)
    return build_posterior(fwd, cfg.runup)


def test_the_error_profile_reaches_the_conditional_maximum_and_keeps_the_rest() -> None:
    post = _posterior()
    names = post.names
    cols = [names.index(n) for n in ERROR_PARAMETERS]
    theta = np.array([[0.025, 0.9, 136.0, 0.5, 0.3, 0.2],    # near the truth, errors wide
                      [0.04, 0.85, 50.0, 0.05, 0.001, 0.01],  # elsewhere, errors narrow
                      [0.02, 1.1, 200.0, 0.0, 0.05, 0.3],     # a zero error: starts at median
                      [0.02, 9.0, 200.0, 0.1, 0.05, 0.3]])    # outside the banks: -inf
    got, lp = post.profile_errors(theta)
    np.testing.assert_array_equal(got[:, :3], theta[:, :3])
    assert lp[3] == -np.inf
    np.testing.assert_allclose(lp[:3], post(got[:3]), rtol=0, atol=1e-9)
    for i in range(3):
        sweeps = post.sweeps(got[i : i + 1])

        def neg(u: np.ndarray, i: int = i, sweeps: tuple = sweeps) -> float:
            t = got[i : i + 1].copy()
            t[0, cols] = np.exp(u)
            v = post.log_prior(t) + post.log_likelihood(t, sweeps)
            return float(-v[0]) if np.isfinite(v[0]) else 1e300

        best = minimize(neg, np.log(got[i, cols]), method="Nelder-Mead",
                        options={"xatol": 1e-6, "fatol": 1e-9, "maxiter": 4000})
        # the last joint grid steps 0.01 in ln x: within a hundredth of a nat of scipy
        print(f"row {i}: profile {lp[i]:.3f}, Nelder-Mead from it {-best.fun:.3f}")
        assert lp[i] >= -best.fun - 0.01
        start = theta[i : i + 1].copy()     # where the profile starts: a zero at the median
        start[0, cols] = np.where(start[0, cols] > 0, start[0, cols],
                                  [post.priors[j].ppf(0.5) for j in cols])
        assert lp[i] > post(start)[0]


def test_the_smoothed_start_holds_the_free_errors_wide_and_short() -> None:
    post = _posterior()
    held = post.smoothed_start()
    by_name = {post.names[j]: v for j, v in held.items()}
    assert set(by_name) == set(ERROR_PARAMETERS)
    assert by_name["model_error"] == float(post.priors[post.names.index("model_error")]
                                           .ppf(0.95))
    assert by_name["model_error_length"] < 0.05 * 0.1    # the 5 % quantile of its prior
    fixed = replace(post, names=post.names[:3], priors=post.priors[:3],
                    fixed={**post.fixed, "model_error": 0.1, "model_error_length": 0.05,
                           "channel_error": 0.03})
    assert fixed.smoothed_start() == {}

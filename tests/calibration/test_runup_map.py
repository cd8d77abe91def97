"""The run-up MAP by vectorised differential evolution (rigtools.calibration.runup_map)."""

from __future__ import annotations

import numpy as np

from rigtools.calibration.priors import prior_from_mapping
from rigtools.calibration.runup_map import find_runup_map

# a correlated Gaussian in a positive parameter and a free one; its mode is its mean
MODE = np.array([2.0, -1.0])
PREC = np.linalg.inv(np.array([[0.04, 0.03], [0.03, 0.09]]))
PRIORS = (prior_from_mapping({"dist": "lognormal", "median": 1.0, "sigma": 1.0}),
          prior_from_mapping({"dist": "normal", "mu": 0.0, "sd": 3.0}))


def gaussian(theta: np.ndarray) -> np.ndarray:
    d = np.atleast_2d(theta) - MODE
    return -0.5 * np.einsum("ij,jk,ik->i", d, PREC, d)


def test_the_mode_of_a_correlated_gaussian() -> None:
    est = find_runup_map(gaussian, PRIORS, population=16, seed=3, generations=200)
    # stops when the population's log posterior spreads < 0.05: within ~0.3 sd of the mode
    assert gaussian(est.theta)[0] > -0.05
    np.testing.assert_allclose(est.theta, MODE, atol=0.1)
    assert est.optima_log_prob[0] == est.log_prob

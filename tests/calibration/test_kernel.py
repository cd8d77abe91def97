"""The compiled log posterior against the NumPy path (its reference implementation)."""

from __future__ import annotations

from dataclasses import replace
from itertools import product

import numpy as np
import pytest
from calibration_cases import campaign, fast_config

from models.geometry import GearPair
from models.thermal import ThermalReference
from rigtools.calibration.data import prepare_data
from rigtools.calibration.model import build_model


@pytest.mark.parametrize(("variant", "jammed", "kind", "offsets"), list(product(
    ["secant_path", "secant_mesh", "tangent"], ["censored", "double_flank"],
    ["normal", "student_t"], [False, True])))
def test_kernel_equals_numpy(pair: GearPair, variant: str, jammed: str, kind: str,
                             offsets: bool) -> None:
    obs = campaign(pair, seed=11)
    cfg = fast_config(model_variant=variant, jammed_model=jammed, likelihood=kind,
                      temperature_sd_K=3.0 if offsets else None)
    data = prepare_data(obs, cfg)
    m = build_model(data, pair, cfg, reference=ThermalReference(20.0))
    rng = np.random.default_rng(5)
    theta = np.column_stack([p.sample(rng, 400) for p in m.priors])
    theta[:50, 0] = rng.uniform(0.0, 6.0, 50)       # many jammed runs
    theta[50:60, 1] = -0.1                          # outside the closure prior
    a, runs, freq = m.evaluate(theta)
    b = m.log_prob_numpy(theta)
    assert np.array_equal(np.isfinite(a), np.isfinite(b))
    ok = np.isfinite(b)
    assert ok.sum() > 300
    np.testing.assert_allclose(a[ok], b[ok], rtol=1e-10, atol=1e-8)
    np.testing.assert_allclose(freq[ok], m.frequencies(theta[ok]), rtol=1e-12)
    ll = m.likelihood.run_log_likelihood(m.frequencies(theta[ok]),
                                         m.unpack(theta[ok])["model_error"])
    np.testing.assert_allclose(runs[ok], ll, rtol=1e-10, atol=1e-8)
    if jammed == "censored" and variant != "tangent":
        assert np.isnan(freq[ok]).any(), "the test set should hold jammed runs"


def test_uniform_background_variant(pair: GearPair) -> None:
    obs = campaign(pair, seed=2)
    cfg = replace(fast_config(), structural_modes="none")
    m = build_model(prepare_data(obs, cfg), pair, cfg, reference=ThermalReference(20.0))
    theta = np.column_stack([p.sample(np.random.default_rng(1), 100) for p in m.priors])
    np.testing.assert_allclose(m(theta), m.log_prob_numpy(theta), rtol=1e-10)

"""posterior.nc, summary.json (against its schema) and summary.csv of a calibration."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import arviz as az
import numpy as np
import pytest
from calibration_cases import RUN_IDS

from rigtools.schemas import iter_errors


@pytest.fixture(scope="module")
def done(secant_fit: tuple[object, Path]) -> tuple[object, Path]:
    return secant_fit


def test_summary_json_follows_its_schema(done: tuple[object, Path]) -> None:
    res, out = done
    doc = json.loads((out / "summary.json").read_text())
    assert iter_errors(doc, "calibration_summary.schema.json") == []
    assert doc == json.loads(json.dumps(res.summary))


def test_summary_json_holds_what_issue_18_lists(done: tuple[object, Path]) -> None:
    res, _ = done
    s = res.summary
    assert s["parameters"]["backlash"]["unit"] == "um"
    for k in ("mean", "sd", "q05", "q50", "q95", "ess_bulk", "r_hat", "unit"):
        assert k in s["parameters"]["backlash"]
    for name in ("critical_gap@40C", "critical_gap@90C", "flip_temperature_C",
                 *(f"margin@{r}" for r in RUN_IDS)):
        assert name in s["derived"], name
    for r in RUN_IDS:
        run = s["runs"][r]
        assert run["regime"] in ("rises", "falls", "unchanged")
        assert 0.0 <= run["regime_probability"] <= 1.0 and run["left_out"] is None
        for k in ("p_c_lt_cstar", "mesh_mode_Hz", "mesh_mode_channel", "mesh_mode_probability"):
            assert k in run
    conv = s["conventions"]
    assert conv["model_variant"] == "secant_path" and conv["thermal_model"] == "linear"
    assert conv["equivalent_mass_kg"] == pytest.approx(0.1857, rel=1e-3)
    assert conv["reference_temperature_C"] == 20.0 and conv["chi"] == 0.0285
    mc = s["model_comparison"]
    assert mc["criterion"] == "psis-loo" and set(mc["variants"]) == {"secant_path", "tangent"}
    for v in mc["variants"].values():
        assert {"elpd_loo", "se", "pareto_k_max"} <= set(v)
    # the data come from the secant model with a load-dependent mesh mode
    assert mc["favoured"] == "secant_path", mc["statement"]
    assert "flip_temperature_C" in s["robustness"]


def test_the_margin_is_the_backlash_minus_the_critical_gap(done: tuple[object, Path]) -> None:
    res, _ = done
    fit = res.headline
    c = fit.draws("backlash")
    m90 = fit.draws("margin@R5")
    np.testing.assert_allclose(m90, c - fit.draws("critical_gap@90C"), rtol=1e-9, atol=1e-9)
    flip = fit.draws("flip_temperature_C")
    kappa = fit.draws("closure_coefficient")
    rate_um_per_K = (1 - 0.0285) * kappa * fit.model.forward.closure.line_slope_m_per_K * 1e6
    np.testing.assert_allclose(c, rate_um_per_K * (flip - 20.0), rtol=1e-9)


def test_posterior_nc_is_arviz_inference_data(done: tuple[object, Path]) -> None:
    res, out = done
    idata = az.from_netcdf(out / "posterior.nc")
    for g in ("posterior", "posterior_predictive", "observed_data", "sample_stats",
              "log_likelihood", "constant_data"):
        assert g in idata.groups(), g
    post = idata.posterior
    assert post["backlash"].shape == res.headline.samples.shape[:2]
    assert list(post["margin"].coords["run"].values) == list(RUN_IDS)
    assert idata.log_likelihood["f_n"].shape[-1] == len(RUN_IDS)
    cfg = json.loads(idata.attrs["calibration_config"])
    assert cfg["model_variant"] == "secant_path" and cfg["seed"] == 1
    np.testing.assert_array_equal(post["backlash"].values, res.headline.draws("backlash"))


def test_summary_csv(done: tuple[object, Path]) -> None:
    res, out = done
    with open(out / "summary.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0]) == ["name", "kind", "unit", "mean", "sd", "q05", "q50", "q95",
                             "ess_bulk", "r_hat"]
    names = [r["name"] for r in rows]
    assert names[:4] == ["backlash", "closure_coefficient", "stiffness_scale", "model_error"]
    assert "critical_gap@90C" in names
    row = rows[0]
    assert float(row["mean"]) == pytest.approx(res.summary["parameters"]["backlash"]["mean"])

"""Issue 18 item 8: what moves with the equivalent mass and the reference temperature."""

from __future__ import annotations

import numpy as np
import pytest
from calibration_cases import RUN_IDS, campaign, fast_config

from models.geometry import GearPair
from rigtools.calibration import calibrate_observations
from rigtools.calibration.derived import ROBUSTNESS, derived_quantities
from rigtools.calibration.forward import predict

LAM = 1.06          # the 6 % between the two disc conventions of the package
SHIFT_K = 5.0


@pytest.fixture(scope="module")
def fits(pair: GearPair) -> dict[str, object]:
    obs = campaign(pair, seed=7)
    base = calibrate_observations(obs, pair, fast_config(max_steps=3000))
    m_e = base.summary["conventions"]["equivalent_mass_kg"]
    heavy = calibrate_observations(obs, pair,
                                   fast_config(max_steps=3000, equivalent_mass_kg=LAM * m_e))
    warm = calibrate_observations(obs, pair, fast_config(
        max_steps=3000, reference_temperature_C=20.0 + SHIFT_K))
    return {"base": base, "heavy": heavy, "warm": warm}


def _q(res: object, name: str) -> dict:
    s = res.summary
    return s["parameters"].get(name) or s["derived"][name]


def test_invariants_do_not_move(fits: dict[str, object]) -> None:
    base = fits["base"]
    for other in (fits["heavy"], fits["warm"]):
        f0, f1 = _q(base, "flip_temperature_C"), _q(other, "flip_temperature_C")
        assert abs(f1["q50"] - f0["q50"]) < 0.25 * f0["sd"], (f0, f1)
        for r in RUN_IDS:
            a, b = base.summary["runs"][r], other.summary["runs"][r]
            assert a["regime"] == b["regime"], r
            assert abs(a["p_c_lt_cstar"] - b["p_c_lt_cstar"]) < 0.05, r
            # the margin over the elastic deflection: invariant to both (derived module notes)
            m0, m1 = _q(base, f"relative_margin@{r}"), _q(other, f"relative_margin@{r}")
            assert abs(m1["q50"] - m0["q50"]) < 0.25 * m0["sd"], (r, m0, m1)
            assert m1["sd"] == pytest.approx(m0["sd"], rel=0.25), r


def test_backlash_and_critical_gap_scale_with_the_equivalent_mass(
        fits: dict[str, object]) -> None:
    base, heavy = fits["base"], fits["heavy"]
    for name in ("backlash", "critical_gap@90C", "margin@R9"):
        ratio = _q(base, name)["q50"] / _q(heavy, name)["q50"]
        assert ratio == pytest.approx(LAM, rel=0.02), name
    s_ratio = _q(heavy, "stiffness_scale")["q50"] / _q(base, "stiffness_scale")["q50"]
    assert s_ratio == pytest.approx(LAM, rel=0.02)
    assert ROBUSTNESS["backlash"]["equivalent_mass"] == "scales as 1/m_e"


def test_backlash_shifts_with_the_reference_temperature_and_margins_do_not(
        fits: dict[str, object]) -> None:
    base, warm = fits["base"], fits["warm"]
    b0 = base.headline
    rate = float(np.median((1 - 0.0285) * b0.draws("closure_coefficient")
                           * b0.model.forward.closure.line_slope_m_per_K * 1e6))   # um/K
    shift = _q(warm, "backlash")["q50"] - _q(base, "backlash")["q50"]
    assert shift == pytest.approx(-rate * SHIFT_K, rel=0.15, abs=0.1)
    for r in RUN_IDS:
        m0, m1 = _q(base, f"margin@{r}"), _q(warm, f"margin@{r}")
        assert abs(m1["q50"] - m0["q50"]) < 0.25 * m0["sd"], r
    c0, c1 = _q(base, "critical_gap@90C"), _q(warm, "critical_gap@90C")
    assert c1["q50"] - c0["q50"] == pytest.approx(-rate * SHIFT_K, rel=0.15, abs=0.1)


def test_relative_margin_is_the_margin_over_the_elastic_deflection_and_minus_one_jams(
        secant_fit: tuple[object, object]) -> None:
    """relative_margin = (c - c*) / (F / (s k_m)); at -1 the whole-mesh reading jams.

    The jam of ``secant_mesh`` by hand (rigtools.calibration.forward notes): Eq. (1) for the
    mesh as a whole has the denominator ``1 + (u / F) s k_m``, zero where ``u = -F / (s k_m)``.
    """
    res, _ = secant_fit
    model = res.headline.model.with_variant("secant_mesh")
    fwd = model.forward
    kappa, s, chi = 0.37, 0.9, 0.0285
    run = 0
    c_star = (1 - chi) * kappa * fwd.closure.run_m[run]
    deflection = fwd.normal_load_N[run] / (s * fwd.k_mesh_N_per_m)
    values = {"closure_coefficient": kappa, "stiffness_scale": s, "chi": chi,
              "model_error": 0.02}
    for rel in (-1.0, -0.3, 0.0, 2.5):
        c_m = c_star + rel * deflection
        theta = np.array([[[c_m * 1e6 if n == "backlash" else values.get(n, 0.0)
                            for n in model.names]]])
        q = {d.name: d for d in derived_quantities(model, theta, operating_temperature_C=90.0)}
        run_id = model.data.runs.run_id[run]
        assert q[f"relative_margin@{run_id}"].draws[0, 0] == pytest.approx(rel, abs=1e-9)
        assert q[f"margin@{run_id}"].draws[0, 0] == pytest.approx(rel * deflection * 1e6,
                                                                  abs=1e-9)
    edge = c_star - deflection
    inside = predict(fwd, [edge - 1e-9 * abs(edge)], [kappa], [s], [chi])
    outside = predict(fwd, [edge + 1e-9 * abs(edge)], [kappa], [s], [chi])
    assert inside.jammed[0, run] and not outside.jammed[0, run]

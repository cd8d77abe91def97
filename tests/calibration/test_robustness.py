"""Issue 18 item 8: what moves with the equivalent mass and the reference temperature."""

from __future__ import annotations

import numpy as np
import pytest
from calibration_cases import RUN_IDS, campaign, fast_config

from models.geometry import GearPair
from rigtools.calibration import calibrate
from rigtools.calibration.derived import ROBUSTNESS

LAM = 1.06          # the 6 % between the two disc conventions of the package
SHIFT_K = 5.0


@pytest.fixture(scope="module")
def fits(pair: GearPair) -> dict[str, object]:
    obs = campaign(pair, seed=7)
    base = calibrate(obs, pair, fast_config(max_steps=3000))
    m_e = base.summary["conventions"]["equivalent_mass_kg"]
    heavy = calibrate(obs, pair, fast_config(max_steps=3000, equivalent_mass_kg=LAM * m_e))
    warm = calibrate(obs, pair, fast_config(max_steps=3000,
                                            reference_temperature_C=20.0 + SHIFT_K))
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

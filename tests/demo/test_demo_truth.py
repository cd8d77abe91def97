"""The demo's truth against independent computations with models.thermal's scalar API.

Sources: seed 000 (FZG-C, Eq. (1), ``c* ~ 10 um`` at its 90 degC hot state), the stiffness-scale
convention of rigtools.calibration.forward (``s k_EP`` inside Eq. (1)).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from models.geometry import load_gear_set
from models.thermal import (
    SEED_000_CHI,
    GearTemperature,
    ThermalReference,
    prepare_natural_frequency,
    thermal_deformation,
    thermoelastic_pair_stiffness,
)
from rigtools.demo.truth import (
    RunCondition,
    campaign_truth,
    closure_slope_from_seed,
    housing_temperature_C,
    mesh_mode,
    regime_name,
    temperature_label,
    true_physics,
)


@pytest.fixture(scope="module")
def fzg():
    gs = load_gear_set("fzg-c")
    model = prepare_natural_frequency(gs.pair)
    return gs, model, true_physics(model, gs)


def _f_n_by_loop(model, torque_Nm: float, closure_m: float, backlash_m: float, s: float) -> float:
    """Cycle-mean stiffness with ``s k_EP`` in Eq. (1), one node at a time (slow reference)."""
    big_f = torque_Nm / model.base_radius_pinion_m
    k = sum(w * thermoelastic_pair_stiffness(big_f * r, s * kep, closure_m, backlash_m,
                                             SEED_000_CHI)
            for w, r, kep in zip(model.weights, model.load_share, model.k_EP_N_per_m,
                                 strict=True))
    return math.sqrt(k / model.equivalent_mass_kg) / (2 * math.pi)


@pytest.mark.parametrize(("torque_Nm", "temperature_C"),
                         [(3.3, 30.0), (35.3, 55.0), (183.4, 90.0), (302.0, 105.0)])
def test_mesh_mode_equals_eq1_with_scaled_stiffness_node_by_node(fzg, torque_Nm,
                                                                 temperature_C) -> None:
    _gs, model, p = fzg
    got = mesh_mode(model, p, torque_Nm, temperature_C).f_n_Hz
    want = _f_n_by_loop(model, torque_Nm, p.closure_m(temperature_C), p.backlash_m,
                        p.stiffness_scale)
    assert got == pytest.approx(want, rel=1e-10), "sqrt(s) f_model(s Delta, s c) identity"


def test_closure_slope_is_seed_000s_hot_state_over_its_temperature_rise(fzg) -> None:
    gs, _model, p = fzg
    beta = closure_slope_from_seed(gs, 20.0)
    assert beta * 1e6 == pytest.approx(10.58 / 70, rel=2e-3), "seed 000 hot state 10.58 um"
    assert p.closure_slope_m_per_K == beta
    assert p.closure_coefficient == pytest.approx(0.376, abs=0.002)
    assert p.critical_gap_m(90.0) * 1e6 == pytest.approx(10.27, abs=0.02), "seed 000: ~10 um"
    with pytest.raises(ValueError, match="`reference_temperature_C` must be < 90"):
        closure_slope_from_seed(gs, 95.0)


@pytest.mark.parametrize("temperature_C", [30.0, 55.0, 105.0])
def test_logged_oil_temperature_gives_the_same_closure_by_the_expansion_model(
        fzg, temperature_C) -> None:
    gs, _model, p = fzg
    pair = gs.pair
    oil = housing_temperature_C(pair, temperature_C, p.closure_slope_m_per_K, 20.0)
    ref = ThermalReference(20.0, "follows-oil", oil_temperature_C=oil)
    s = np.linspace(0.2, 0.8, 5) * pair.line_of_action_length
    d = thermal_deformation(pair, s, ref, GearTemperature.uniform(temperature_C)).total_m
    assert np.allclose(d, p.closure_m(temperature_C), rtol=1e-9, atol=1e-12)


def test_jammed_runs_are_refused(fzg) -> None:
    gs, model, p = fzg
    with pytest.raises(ValueError, match="is jammed"):
        campaign_truth(model, gs, [RunCondition("LS1-105C", 3.3, 105.0)], p)
    with pytest.raises(ValueError, match="unique run ids"):
        campaign_truth(model, gs, [RunCondition("a", 302.0, 30.0)] * 2, p)


def test_names() -> None:
    assert temperature_label(90.0) == "90C" and temperature_label(32.5) == "32.5C"
    assert [regime_name(k) for k in (1, 0, -1)] == ["rises", "unchanged", "falls"]

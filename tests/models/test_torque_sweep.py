"""The thermal closure and the torque x backlash sweep of seed 000 (models.thermal.torque_sweep).

The closure is seed 000's hot state under the one reference-state reading that reproduces
``c* ~ 10 um`` (``tests/models/test_thermal_expansion.py``: 10.58 um, ``c*`` 10.28 um). The
sweep is checked against the independent route (:func:`models.thermal.mesh_natural_frequency`
at the same torques and backlash), the jam boundaries against the closed form
``T = r_b1 (c* - c) max_j(k_EP,j / R_j)`` (SEED-NOTES 10). The figures drawn from the sweep are
tested in ``tests/plots/test_thermal_plots.py``.
"""

import numpy as np
import pytest

from models.geometry import load_gear_set
from models.thermal import (
    SEED_000_CHI,
    TABLE_6_TORQUES_NM,
    JamSpan,
    ThermalClosure,
    ThermalSweep,
    critical_gap,
    default_backlash,
    jammed_torque_spans,
    mesh_natural_frequency,
    seed_000_hot_state_closure,
    thermal_sweep,
    torque_grid,
)

GEAR_SET = load_gear_set("fzg-c")
SRC = "seed 000"


@pytest.fixture(scope="module")
def closure():
    return seed_000_hot_state_closure(GEAR_SET)


@pytest.fixture(scope="module")
def c_star(closure):
    return float(critical_gap(closure.total_m, SEED_000_CHI))


@pytest.fixture(scope="module")
def sweep():
    return thermal_sweep(GEAR_SET, n_torques=60)


def test_closure_is_the_hot_state_of_the_reference_reading(closure, c_star):
    # tests/models/test_thermal_expansion.py: "oil+flash", xi = 1.15e-5 /K, 302 N m
    assert isinstance(closure, ThermalClosure)
    assert closure.total_m * 1e6 == pytest.approx(10.58, abs=0.01)
    lo, hi = closure.range_m
    assert (lo * 1e6, hi * 1e6) == pytest.approx((0.42, 20.10), abs=0.01)
    assert c_star * 1e6 == pytest.approx(10.28, abs=0.01), f"{SRC}: c* approximately 10 um"
    for words in ("SEED-NOTES 8", "housing at the oil temperature", "flash temperature",
                  "302 N·m", "1500 min⁻¹", "90 °C oil", "held fixed at every torque"):
        assert words in closure.description


def test_sweep_is_the_natural_frequency_at_its_grid(sweep, closure, c_star):
    assert isinstance(sweep, ThermalSweep)
    assert sweep.closure == closure
    assert sweep.c_star == c_star
    np.testing.assert_array_equal(sweep.backlash, default_backlash(c_star))
    assert set(TABLE_6_TORQUES_NM) <= set(sweep.torque.tolist())
    assert np.all(np.diff(sweep.torque) > 0) and sweep.torque[-1] == 500.0
    ref = mesh_natural_frequency(sweep.model, sweep.torque, closure.total_m,
                                 sweep.backlash[:, None], SEED_000_CHI)
    np.testing.assert_array_equal(sweep.result.f_n_Hz, ref.f_n_Hz)
    np.testing.assert_array_equal(sweep.result.jammed, ref.jammed)


def test_jam_spans_end_at_the_closed_form_boundary(sweep, c_star):
    """SEED-NOTES 10: jammed below ``T = r_b1 (c* - c) max(k_EP / R)``, from the first torque."""
    m = sweep.model
    q_max = np.max(m.k_EP_N_per_m / m.load_share)
    for i, c in enumerate(sweep.backlash.tolist()):
        spans = jammed_torque_spans(sweep.torque, sweep.result.jammed[i],
                                    sweep.result.min_net_deflection_m[i])
        if c < c_star:
            edge = m.base_radius_pinion_m * (c_star - c) * q_max
            assert spans == [JamSpan(0.0, pytest.approx(edge, rel=1e-9), True, False)], c
        else:
            assert spans == [], c


def test_jam_spans_of_a_run_inside_and_at_the_end_of_the_grid():
    t = np.arange(1.0, 7.0)
    jammed = np.array([False, True, True, False, False, True])
    net = np.array([1.0, -1.0, -1.0, 1.0, 3.0, -2.0])
    assert jammed_torque_spans(t, jammed, net) == [JamSpan(1.5, 3.5, False, False),
                                                   JamSpan(5.6, 6.0, False, True)]


def test_torque_grid_merges_the_extra_torques_inside_its_range():
    np.testing.assert_array_equal(torque_grid(10.0, 5, (3.0, 0.0, -1.0, 11.0, 4.0)),
                                  [2.0, 3.0, 4.0, 6.0, 8.0, 10.0])


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"torque_max_Nm": 0.0}, r"`torque_max_Nm` must be finite and > 0, was 0.0"),
    ({"torque_max_Nm": float("inf")}, r"`torque_max_Nm` must be finite and > 0, was inf"),
    ({"n": 1}, r"`n` must be an integer >= 2, was 1"),
    ({"n": True}, r"`n` must be an integer >= 2, was True"),
])
def test_torque_grid_refuses_bad_arguments(kwargs, match):
    with pytest.raises(ValueError, match=match):
        torque_grid(**kwargs)


def test_sweep_refuses_a_closure_that_is_not_one():
    with pytest.raises(ValueError, match="`thermal_closure` must be a ThermalClosure, was float"):
        thermal_sweep(GEAR_SET, thermal_closure=10e-6)  # type: ignore[arg-type]


def test_no_closure_no_jam():
    s = thermal_sweep("fzg-c", [0.0, 40e-6], n_torques=10,
                      thermal_closure=ThermalClosure(0.0, "cold"))
    assert s.c_star == 0.0 and not s.result.jammed.any()

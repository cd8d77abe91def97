"""The run-up forward model's path: window nodes and continuation nodes (runup_forward)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rigtools.calibration.runup_data import WINDOW_WEIGHTS, RunUpCurve
from rigtools.calibration.runup_forward import MAX_PATH_STEP, window_path


def _curve(f: list[float], nodes: np.ndarray | None = None) -> RunUpCurve:
    n = len(f)
    return RunUpCurve(run_id="r", gear_set="kb", torque_Nm=100.0, channels=("x",),
                      mesh_frequency_Hz=np.array(f), time_s=np.arange(n, dtype=float),
                      direction=np.array(["up"] * n, dtype=object),
                      observed=np.ones((1, n)), harmonics=np.full((1, n, 3), np.nan),
                      window_mesh_frequency_Hz=nodes)


def test_continuation_nodes_keep_every_step_small_and_weigh_nothing():
    c = _curve([1000.0, 1100.0, 1050.0])
    p = window_path(c)
    steps = np.abs(np.diff(np.log(p.mesh_frequency_Hz)))
    assert steps.max() <= MAX_PATH_STEP * (1 + 1e-12)
    # by hand: ln(1.1) / 0.003 = 31.8 -> 31 continuation nodes, then the point itself
    assert p.starts.tolist() == [0, 1, 1 + 31 + 1]
    assert p.mesh_frequency_Hz[p.starts[1] + 31] == 1100.0
    assert p.weights[0] == 1.0 and p.weights[1:32].sum() == 0.0 and p.weights[32] == 1.0
    # the point's value is its own node's, whatever the continuation nodes hold
    arms = np.arange(1.0, p.mesh_frequency_Hz.size + 1.0)
    out = p.power_mean(arms[None, :])[0]
    np.testing.assert_allclose(out, arms[p.starts + np.r_[0, 31, 15]])
    flags = np.zeros((1, arms.size), dtype=bool)
    flags[0, 5] = True                                  # a continuation node only
    assert not p.any(flags).any() and p.all(~flags).all()


def test_window_nodes_give_the_weighted_power_mean():
    nodes = np.array([[990.0, 1000.0, 1010.0], [1210.0, 1220.0, 1230.0]])
    p = window_path(_curve([1000.0, 1220.0], nodes))
    own = np.flatnonzero(p.weights > 0)
    np.testing.assert_array_equal(p.mesh_frequency_Hz[own], nodes.ravel())
    a = np.ones(p.mesh_frequency_Hz.size)
    a[own] = [1.0, 2.0, 3.0, 4.0, 4.0, 4.0]
    out = p.power_mean(a)
    w = np.asarray(WINDOW_WEIGHTS)
    assert out[0] == pytest.approx(math.sqrt(np.dot(w, [1.0, 4.0, 9.0])), rel=1e-14)
    assert out[1] == pytest.approx(4.0, rel=1e-14)
    # a window straddling a jump by a factor 10 in Arms: the mean lies between the branches
    a[own[:3]] = [1.0, 10.0, 10.0]
    mixed = p.power_mean(a)[0]
    assert 1.0 < mixed < 10.0
    assert mixed == pytest.approx(math.sqrt(w[0] + 100.0 * (w[1] + w[2])), rel=1e-14)

"""Counter unwrapping and clock checks (rigtools.ingest.timebase)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rigtools.ingest.timebase import indices_from_stamps, timebase_check, unwrap_counter


def test_plain_wrap_of_a_16_bit_counter():
    ticks = np.arange(60_000, 140_000)
    un = unwrap_counter(ticks % 65536, 65536)
    assert np.array_equal(un.ticks - un.ticks[0], ticks - ticks[0])
    assert un.keep.all() and un.n_duplicate == 0 and un.n_reordered == 0


def test_gap_duplicate_and_late_frame():
    c = np.array([10, 11, 11, 12, 15, 9, 16, 17])
    un = unwrap_counter(c, 256)
    # The late frame is kept and placed by its counter; only the repeated 11 is dropped.
    assert un.ticks[un.keep].tolist() == [10, 11, 12, 15, 9, 16, 17]
    assert un.n_duplicate == 1
    assert un.n_reordered == 1


def test_swapped_neighbours_are_all_kept():
    ticks = np.arange(3000)
    swapped = ticks.reshape(-1, 2)[:, ::-1].ravel()  # 1, 0, 3, 2, ...
    un = unwrap_counter(swapped % 65536, 65536, swapped / 8533.0, 8533.0)
    assert un.keep.all() and sorted(un.ticks.tolist()) == ticks.tolist()
    assert un.n_duplicate == 0 and un.n_reordered == 1500


def test_gap_longer_than_one_wrap_needs_the_clock():
    # 8-bit counter at 100 ticks/s; 3.0 s of silence = 300 ticks = one wrap + 44.
    t = np.r_[np.arange(10) / 100, 3.09 + np.arange(10) / 100]
    true_ticks = np.round(t * 100).astype(int)
    c = true_ticks % 256
    blind = unwrap_counter(c, 256)
    assert blind.ticks[10] - blind.ticks[9] == 300 - 256  # without a clock, the wrap is invisible
    seen = unwrap_counter(c, 256, t, 100.0)
    assert np.array_equal(seen.ticks - seen.ticks[0], true_ticks - true_ticks[0])


def test_restart_resynchronises_instead_of_dropping_everything_after():
    c = np.r_[np.arange(1000, 1100), np.arange(0, 100)]
    t = np.arange(200) / 100.0
    un = unwrap_counter(c % 65536, 65536, t, 100.0)
    assert un.keep.sum() == 200
    assert un.restarts.tolist() == [100]
    assert un.ticks[100] == un.ticks[99] + 1
    assert np.all(np.diff(un.ticks) > 0)


@settings(max_examples=200, deadline=None)
@given(
    steps=st.lists(st.integers(min_value=0, max_value=40), min_size=1, max_size=300),
    start=st.integers(min_value=0, max_value=65535),
)
def test_unwrap_recovers_any_forward_sequence_with_small_steps(steps, start):
    # Property: steps below half the modulus are recovered exactly; zeros are duplicates.
    ticks = start + np.cumsum([0, *steps])
    un = unwrap_counter(ticks % 65536, 65536)
    assert np.array_equal(un.ticks, ticks)
    assert un.n_duplicate == steps.count(0)


def test_indices_from_stamps_on_a_jittered_clock():
    rng = np.random.default_rng(1)
    t = 5.0 + np.arange(1000) / 1000.0 + rng.normal(0, 1e-5, 1000)
    idx = indices_from_stamps(t, 1000.0)
    assert np.array_equal(idx, np.arange(1000))


def test_timebase_check_measures_latency_and_drift():
    idx = np.arange(0, 100_000, 100)
    fs = 10_000.0
    t = 100.0 + 0.002 + idx / fs * (1 + 50e-6)  # 2 ms latency, 50 ppm fast logger clock
    t0, stats = timebase_check(idx, t, fs)
    assert t0 == pytest.approx(100.002 + 5 * 50e-6, abs=1e-4)
    assert stats["drift_ppm"] == pytest.approx(50.0, rel=1e-6)
    assert stats["n_stamps_backwards"] == 0


def test_clock_step_with_an_intact_counter_keeps_the_counter():
    # A logger clock adjusted by +3600 s while the sensor counter runs on at its usual step.
    n = 20_000
    t = np.arange(n) / 8533.0
    t[n // 2 :] += 3600.0
    un = unwrap_counter(np.arange(n) % 65536, 65536, t, 8533.0)
    assert np.array_equal(un.ticks, np.arange(n))
    assert un.clock_jumps == 1


@pytest.mark.parametrize("bad", [1e6, np.nan, np.inf, -np.inf, 1.7e16])
def test_one_outlying_or_non_finite_stamp_is_ignored(bad):
    n = 5000
    t = 1.7e9 + np.arange(n) / 8533.0
    t[2500] = bad
    un = unwrap_counter(np.arange(n) % 65536, 65536, t, 8533.0)
    assert np.array_equal(un.ticks, np.arange(n))
    t0, _ = timebase_check(np.arange(n), t, 8533.0)
    assert t0 == pytest.approx(1.7e9, abs=1e-6)


def test_long_gap_with_lost_frames_uses_the_clock_to_count_wraps():
    # 20 s of silence (170,660 ticks = 2 wraps + 39,588) with a 16-bit counter.
    rate = 8533.0
    ticks = np.r_[np.arange(1000), 1000 + 170_660 + np.arange(1000)]
    un = unwrap_counter(ticks % 65536, 65536, ticks / rate, rate)
    assert np.array_equal(un.ticks, ticks)


def test_indices_from_stamps_do_not_hinge_on_a_jittered_first_stamp():
    # A first stamp 0.45 period late: anchoring on it would put every other stamp with
    # jitter below -0.05 period into the slot before its own (fake duplicates and gaps).
    rng = np.random.default_rng(2)
    t = np.arange(2000) / 1000.0 + rng.uniform(-0.3e-3, 0.3e-3, 2000)
    t[0] = 0.45e-3
    idx = indices_from_stamps(t, 1000.0)
    assert np.array_equal(idx, np.arange(2000))

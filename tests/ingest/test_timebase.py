"""Counter unwrapping and clock checks (rigtools.ingest.timebase)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rigtools.ingest.timebase import (
    indices_from_stamps,
    median_elements,
    timebase_check,
    unwrap_counter,
)


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


# Regressions from the review of the fuzz suite (r5, defects 3-5); reproducers as given there.
RATE = 8533.0  # reference frame rate (ticks/s), data_schemas/rig_reference.dbc


def test_block_replayed_from_more_than_half_a_wrap_back_lands_on_its_own_ticks():
    # 16-bit counter: ticks 0..49999, then 0..999 logged again with their original stamps,
    # then 50000..50099. The step 49999 -> 0 is 15537 forward modulo 65536, but the clock went
    # back 49999 ticks: the replay must fall on ticks 0..999 (duplicates), not at 65536...
    ticks = np.r_[np.arange(50_000), np.arange(1000), np.arange(50_000, 50_100)]
    un = unwrap_counter(ticks % 65536, 65536, ticks / RATE, RATE)
    assert un.n_duplicate == 1000 and un.restarts.size == 0
    assert np.array_equal(un.ticks, ticks)  # true tick 50000 at 50000, not 115536
    assert np.array_equal(un.ticks[un.keep], np.arange(50_100))


def test_restart_with_a_simultaneous_clock_step_back_is_a_restart_when_payloads_differ():
    # 60 frames, counter restarts to 0 at frame 30 while the logger clock steps back 1 ms
    # (NTP/PTP step). Different payloads: a restart, every frame kept. Same payloads as at
    # those ticks: a replay, 30 duplicates (the earlier rule, kept when payloads agree).
    c = np.r_[np.arange(30), np.arange(30)]
    t = np.arange(60) / RATE
    t[30:] -= 1e-3
    payload = np.arange(60) * 7
    un = unwrap_counter(c, 65536, t, RATE, payload=payload)
    assert un.keep.all() and un.n_duplicate == 0
    assert un.restarts.tolist() == [30]
    assert np.array_equal(un.ticks, np.arange(60))
    replay = unwrap_counter(c, 65536, t, RATE, payload=np.r_[payload[:30], payload[:30]])
    assert replay.n_duplicate == 30 and replay.restarts.size == 0
    assert np.array_equal(replay.ticks[replay.keep], np.arange(30))


@pytest.mark.parametrize("where", ["first", "last"])
@pytest.mark.parametrize("clock", ["quantised_1ms", "jitter_0.35_tick"])
def test_endpoint_next_to_a_lost_frame_is_not_an_outlier(where, clock):
    # Ticks [0, 2, 3, ..., 39] (frame 1 lost) or [0..37, 39] (frame 38 lost): the clock moves
    # with the counter, only blurred by 1 ms stamp quantisation (USB batching) or by
    # +-0.35 tick jitter; the endpoint frame is intact and must be kept at its tick.
    ticks = np.r_[0, np.arange(2, 40)] if where == "first" else np.r_[np.arange(38), 39]
    if clock == "quantised_1ms":
        t = np.floor(ticks / RATE * 1000) / 1000
    else:
        # Alternating jitter, arranged so that the clock over the endpoint's step reads
        # 2 - 0.7 = 1.3 ticks: nearer the usual step (1) than the counter's (2).
        jitter = np.where(np.arange(ticks.size) % 2 == 0, 0.35, -0.35)
        if where == "last":
            jitter = -jitter if ticks.size % 2 else jitter
        t = (ticks + jitter) / RATE
    un = unwrap_counter(ticks, 65536, t, RATE)
    assert un.n_outlier == 0 and un.keep.all()
    assert np.array_equal(un.ticks, ticks)


def test_flipped_high_bit_on_an_endpoint_is_still_an_outlier():
    # The stricter endpoint rule must not give up a flip the clock clearly contradicts.
    ticks = np.arange(40)
    c = ticks.copy()
    c[0] ^= 1 << 12
    t = ticks / RATE
    un = unwrap_counter(c, 65536, t, RATE)
    assert un.n_outlier == 1 and not un.keep[0]
    assert np.array_equal(un.ticks[1:], ticks[1:])


def _same_unwrap(a, b) -> None:
    assert np.array_equal(a.ticks, b.ticks) and a.ticks.dtype == b.ticks.dtype
    assert np.array_equal(a.keep, b.keep)
    assert (a.n_duplicate, a.n_reordered, a.clock_jumps, a.n_outlier) == (
        b.n_duplicate, b.n_reordered, b.clock_jumps, b.n_outlier)
    assert np.array_equal(a.restarts, b.restarts)
    assert (a.outlier is None) == (b.outlier is None)


@given(bits=st.integers(2, 20), step=st.integers(1, 1 << 19), start=st.integers(0, 1 << 20),
       n=st.integers(0, 300), clock=st.sampled_from(["none", "even", "jumps", "nan", "back"]),
       spoil=st.integers(-1, 299), seed=st.integers(0, 2**32 - 1))
@settings(max_examples=400, deadline=None)
def test_the_steady_path_gives_what_the_general_path_gives(bits, step, start, n, clock, spoil,
                                                           seed):
    """A counter with one and the same step (the steady case, one pass) or one step spoilt.

    Any modulus (powers of two and others), any step, clocks with jumps, NaN, steps back.
    """
    rng = np.random.default_rng(seed)
    m = (1 << bits) - (seed % 3 == 0)          # a third of the moduli are not powers of two
    step = step % m or 1
    c = (start + step * np.arange(n, dtype=np.int64)) % m
    if 0 <= spoil < n:
        c[spoil] = rng.integers(0, m)
    rate = 100.0
    t = None if clock == "none" else np.arange(n) / rate * step
    if t is not None and n and clock == "jumps":
        t[rng.integers(0, n, 3)] += rng.choice([-1.0, 1.0], 3) * m / rate * rng.uniform(0.2, 3, 3)
    if t is not None and n and clock == "nan":
        t[rng.integers(0, n, 3)] = rng.choice([np.nan, np.inf, -np.inf], 3)
    if t is not None and n > 10 and clock == "back":
        t[n // 2:] -= m / rate * rng.uniform(0.1, 2.0)
    fast = unwrap_counter(c, m, t, None if t is None else rate)
    slow = unwrap_counter(c, m, t, None if t is None else rate, steady_first=False)
    _same_unwrap(fast, slow)


def test_a_counter_whose_every_value_looks_corrupted_is_unwrapped_not_crashed():
    """Found by the test above: a step beyond half the modulus that the clock confirms.

    Every value then reads as an outlier (the usual step is > M/2, taken as a step back);
    with nothing left to unwrap the reader raised IndexError. Now none is set aside.
    """
    c = (2 * np.arange(10)) % 3
    un = unwrap_counter(c, 3, np.arange(10) * 0.02, 100.0)
    assert un.ticks.shape == (10,) and un.n_outlier == 0


@given(n=st.integers(1, 400), seed=st.integers(0, 2**32 - 1), ties=st.booleans())
@settings(max_examples=300, deadline=None)
def test_timebase_check_gives_the_numpy_median_figures_bit_for_bit(n, seed, ties):
    """Start time and jitter against np.median written out (odd and even sizes, ties)."""
    rng = np.random.default_rng(seed)
    idx = np.sort(rng.choice(10 * n, n, replace=False)).astype(np.float64)
    jitter = rng.normal(0, 1e-5, n)
    if ties:
        jitter = np.round(jitter, 5)
    t = 1.7e9 + idx / 2560.0 + jitter
    t0, stats = timebase_check(idx, t, 2560.0)
    offset = t - idx / 2560.0
    want_t0 = float(np.median(offset))
    resid = offset - want_t0
    assert t0 == want_t0
    assert stats["jitter_s"] == float(1.4826 * np.median(np.abs(resid - np.median(resid))))
    assert stats["max_abs_residual_s"] == float(np.max(np.abs(resid)))


@given(n=st.integers(1, 3000), seed=st.integers(0, 2**32 - 1), levels=st.sampled_from([0, 3, 50]))
@settings(max_examples=300, deadline=None)
def test_median_elements_are_the_partition_middle(n, seed, levels):
    """The elements ``np.partition`` puts at ranks k-1 and k (or k), ties and all."""
    rng = np.random.default_rng(seed)
    x = rng.normal(0, 1, n) if not levels else rng.integers(0, levels, n).astype(np.float64)
    k = n // 2
    want = np.partition(x, k)[k : k + 1] if n % 2 else np.partition(x, [k - 1, k])[k - 1 : k + 1]
    got = median_elements(x)
    assert np.array_equal(got, want)
    assert np.mean(got) == np.median(x)

"""Random sample-counter sequences: gaps, duplicates, wraps, late frames, restarts, flipped bits.

The sequences are built from a true tick series (what the sensor counted) and logger stamps
``tick / rate + jitter`` (jitter below a fifth of a tick), then the counter is derived from
the ticks the way a logger sees it: modulo ``2**bits``, with frames lost (gaps, some longer
than a wrap), repeated (a duplicate with its stamp), swapped with a neighbour (late), and the
sensor restarting from an arbitrary value (the ticks go on, the counter jumps back). Events
are at least :data:`rigtools.ingest.timebase.RESTART_RUN` + 2 usual steps apart: closer than
that, a restart and a late frame are not told apart by anyone.

Expected from :func:`rigtools.ingest.timebase.unwrap_counter` (stamps given): the kept ticks,
relative to the first, are the true ticks; the duplicates (and only they) are dropped; every
restart is reported where it happened. A corrupted counter value (one flipped bit, the
stamp intact) costs that element only (``n_outlier``), never the alignment of the rest.
The same sequences, as reference-layout frames in a candump log, come back through
``rigtools.ingest.read`` with every sample at its true index.
"""

from __future__ import annotations

import atexit
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rigtools.demo.can_writer import encode_reference_frames, quantise_reference, write_can_log
from rigtools.ingest import read
from rigtools.ingest.can.frames import CanFrameBatch
from rigtools.ingest.timebase import RESTART_RUN, unwrap_counter

FAST = settings(
    max_examples=40,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)
FAST_READ = settings(
    max_examples=10,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)
LONG = settings(
    max_examples=1000, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow]
)

_TMP = Path(tempfile.mkdtemp(prefix="rigtools-fuzz-counters-"))
atexit.register(shutil.rmtree, _TMP, True)

RATE = 8533.0  # frames per second (25.6 kHz / 3)
EVENTS = ("gap", "long_gap", "duplicate", "late", "restart", "flip")


@st.composite
def sequences(draw):
    """(counter, stamps, true ticks, expected keep, restart positions, flipped positions, bits)."""
    bits = draw(st.sampled_from([8, 12, 16]))
    m = 1 << bits
    tick = draw(st.integers(0, 10 * m))
    offset = draw(st.integers(0, m - 1))  # counter = tick + offset (mod m), until a restart
    events = draw(st.lists(st.sampled_from(EVENTS), max_size=6))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    ticks, counter, keep, restarts, flipped = [], [], [], [], []

    def emit(n):
        nonlocal tick
        for _ in range(n):
            ticks.append(tick)
            counter.append((tick + offset) % m)
            keep.append(True)
            tick += 1

    emit(RESTART_RUN + 3)
    for ev in events:
        if ev == "gap":
            tick += draw(st.integers(1, m // 4))
        elif ev == "long_gap":  # whole wraps lost: only the clock can count them
            g = draw(st.integers(m, 3 * m))
            tick += g + (g % m == 0)  # a multiple of the wrap looks like a clock jump (ignored)
        elif ev == "duplicate":
            ticks.append(ticks[-1])
            counter.append(counter[-1])
            keep.append(False)
        elif ev == "late":  # the last two frames swapped
            ticks[-1], ticks[-2] = ticks[-2], ticks[-1]
            counter[-1], counter[-2] = counter[-2], counter[-1]
        elif ev == "restart":  # the counter steps back (a step forward reads as a gap)
            new = (counter[-1] - draw(st.integers(1, m // 2 - 1))) % m
            offset = (new - tick) % m
            restarts.append(len(ticks))
        elif ev == "flip":
            emit(1)
            flipped.append(len(ticks) - 1)
            bit = draw(st.integers(0, bits - 1))
            counter[-1] ^= 1 << bit
            keep[-1] = False
        emit(RESTART_RUN + 3)
    t = np.asarray(ticks, np.float64) / RATE + rng.uniform(0, 0.2 / RATE, len(ticks))
    for i in range(1, len(keep)):  # a duplicate carries the stamp of the frame it repeats
        if not keep[i] and i not in flipped:
            t[i] = t[i - 1]
    return (np.asarray(counter), t, np.asarray(ticks), np.asarray(keep), restarts, flipped, bits)


def _check_unwrap(seq) -> None:
    counter, t, ticks, keep, restarts, flipped, bits = seq
    un = unwrap_counter(counter, 1 << bits, t, RATE)
    got = un.ticks[un.keep]
    assert np.array_equal(un.keep, keep), np.flatnonzero(un.keep != keep)[:5]
    assert np.array_equal(got - got[0], ticks[keep] - ticks[keep][0])
    assert un.n_outlier == len(flipped)
    assert un.n_duplicate == int((~keep).sum()) - len(flipped)
    assert set(un.restarts.tolist()) <= set(restarts)


@FAST
@given(seq=sequences())
def test_unwrap_recovers_the_true_ticks(seq):
    _check_unwrap(seq)


@pytest.mark.slow
@LONG
@given(seq=sequences())
def test_unwrap_long_profile(seq):
    _check_unwrap(seq)


def _frames_for(seq):
    """Reference-layout frames of channel accel_1 carrying the sequence, and the truth."""
    counter, t, _ticks, _keep, _restarts, _flipped, bits = seq
    n = len(counter)
    rng = np.random.default_rng(0)
    x = rng.normal(0, 30, 3 * n)
    base = encode_reference_frames([x], None, rng=0)
    data = base.data.copy()
    if bits != 16:
        counter = counter % (1 << bits)  # the reference counter is 16 bits: only 16 is exact
    data[:, 0] = counter & 0xFF
    data[:, 1] = (counter >> 8) & 0xFF
    frames = CanFrameBatch(
        1_700_000_000.0 + t,
        base.arbitration_id,
        base.is_extended,
        base.is_fd,
        base.length,
        data,
        base.channel,
        base.position,
        "line",
    )
    want = quantise_reference([x])["accel_1"].reshape(n, 3)
    return frames, want


@FAST_READ
@given(seq=sequences().filter(lambda s: s[6] == 16))
def test_counter_sequences_through_read_put_every_sample_at_its_tick(seq):
    _, _, ticks, keep, _, flipped, _ = seq
    frames, want = _frames_for(seq)
    p = write_can_log(_TMP / "seq.log", frames, "log")
    rec = read(p)
    ch = rec.channels["accel_1"]
    # The first frame is always kept and the earliest tick: it is sample index 0 of the channel.
    rel = (ticks[keep] - ticks[0]) * 3
    for r, row in zip(rel, want[keep], strict=True):
        np.testing.assert_array_equal(ch.values[r : r + 3], row)
    assert ch.valid.sum() == 3 * int(keep.sum())
    assert rec.report.rejected.get("counter_outlier", 0) == len(flipped)

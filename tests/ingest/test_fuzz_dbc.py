"""Random DBC layouts through the whole CAN path, and damaged DBC text.

hypothesis draws a DBC: one uniform-channel message (a sample counter of 4 to 16 bits and
1 to 4 samples, each of its own size, signedness, byte order, scale and offset, placed at
random bit positions inside their own bytes) and one multiplexed slow message (an 8-bit
multiplexer selecting one of two signals). Frames are encoded by cantools (the independent
implementation: ``Message.encode``), written as a candump log by python-can's
``CanutilsLogWriter``, and read back through ``rigtools.ingest.read(path, dbc=...)``.
Expected: every sample equals cantools' ``Message.decode`` of its frame, bit for bit, at index
``counter * k + j`` (counter unwrapped); every slow value equals the decoded value of the
signal its multiplexer selects, in frame order.

Damaged DBC text (cuts, flipped bytes) must load or raise :class:`rigtools.errors.DbcError`;
reading a log with it must return or raise a :class:`rigtools.errors.RigtoolsError`.
"""

from __future__ import annotations

import atexit
import shutil
import tempfile
from pathlib import Path

import can
import cantools
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rigtools.errors import DbcError, RigtoolsError
from rigtools.ingest import read
from rigtools.ingest.can.dbc import load_dbc

FAST = settings(
    max_examples=25,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
LONG = settings(
    max_examples=300,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)

_TMP = Path(tempfile.mkdtemp(prefix="rigtools-fuzz-dbc-"))
atexit.register(shutil.rmtree, _TMP, True)

FS = 1000.0
SCALES = [1, 0.5, 0.015, 0.001, 2.5, -0.25, 1e-6, 3.0517578125e-05]


@st.composite
def signal_spec(draw, max_bits: int):
    bits = draw(st.integers(2, max_bits))
    return {
        "bits": bits,
        "signed": draw(st.booleans()),
        "big": draw(st.booleans()),
        "scale": draw(st.sampled_from(SCALES)),
        "offset": draw(st.sampled_from([0, 0, -40, 12.5, 1000])),
        "shift": draw(st.integers(0, 7)),  # spare bits of its bytes placed before it
    }


@st.composite
def layouts(draw):
    counter = {
        "bits": draw(st.integers(4, 16)),
        "signed": False,
        "big": draw(st.booleans()),
        "scale": 1,
        "offset": 0,
        "shift": draw(st.integers(0, 7)),
    }
    samples = draw(st.lists(signal_spec(16), min_size=1, max_size=4))
    nbytes = sum(-(-s["bits"] // 8) for s in [counter, *samples])
    if nbytes > 8:  # keep what fits in 8 bytes
        kept = []
        used = -(-counter["bits"] // 8)
        for s in samples:
            if used + -(-s["bits"] // 8) <= 8:
                kept.append(s)
                used += -(-s["bits"] // 8)
        samples = kept or [
            {"bits": 8, "signed": True, "big": False, "scale": 1, "offset": 0, "shift": 0}
        ]
    slow = [draw(signal_spec(16)) for _ in range(2)]
    return counter, samples, slow


def _place(spec: dict, byte0: int) -> tuple[int, int]:
    """DBC start bit of a signal put in the bytes from ``byte0``; returns (start, next byte)."""
    nbytes = -(-spec["bits"] // 8)
    spare = nbytes * 8 - spec["bits"]
    shift = min(spec["shift"], spare)
    if spec["big"]:
        p = byte0 * 8 + shift  # position in the big-endian bit stream of its MSB
        start = (p // 8) * 8 + (7 - p % 8)
    else:
        start = byte0 * 8 + shift
    return start, byte0 + nbytes


def _sg(name: str, spec: dict, start: int, mux: str = "") -> str:
    lo = -(1 << (spec["bits"] - 1)) if spec["signed"] else 0
    hi = (1 << (spec["bits"] - 1)) - 1 if spec["signed"] else (1 << spec["bits"]) - 1
    order = "0" if spec["big"] else "1"
    sign = "-" if spec["signed"] else "+"
    a, b = sorted((lo * spec["scale"] + spec["offset"], hi * spec["scale"] + spec["offset"]))
    return (
        f" SG_ {name} {mux}: {start}|{spec['bits']}@{order}{sign} ({spec['scale']!r},"
        f'{spec["offset"]!r}) [{a!r}|{b!r}] "u" Node\n'
    )


def dbc_text(counter: dict, samples: list[dict], slow: list[dict]) -> str:
    text = 'VERSION ""\n\nNS_ :\n\nBS_:\n\nBU_: Node\n\nBO_ 291 RAND: 8 Node\n'
    start, nxt = _place(counter, 0)
    text += _sg("Cnt", counter, start)
    for j, s in enumerate(samples):
        start, nxt = _place(s, nxt)
        text += _sg(f"S{j}", s, start)
    text += "\nBO_ 1110 SLOW: 8 Node\n"
    text += ' SG_ Mux M : 0|8@1+ (1,0) [0|255] "" Node\n'
    for j, s in enumerate(slow):
        start, _ = _place(s, 1 + 2 * 0)  # both multiplexed signals share bytes 1..
        text += _sg(f"Slow{j}", s, start, mux=f"m{j} ")
    text += (
        '\nBA_DEF_ BO_ "RigChannel" STRING ;\nBA_DEF_ BO_ "RigSampleRate" FLOAT 0 1e7;\n'
        'BA_DEF_ BO_ "RigCounter" STRING ;\nBA_DEF_DEF_ "RigChannel" "";\n'
        'BA_DEF_DEF_ "RigSampleRate" 0;\nBA_DEF_DEF_ "RigCounter" "";\n'
        'BA_ "RigChannel" BO_ 291 "rand";\nBA_ "RigSampleRate" BO_ 291 1000;\n'
        'BA_ "RigCounter" BO_ 291 "Cnt";\n'
    )
    return text


def _random_raw(rng, spec: dict, n: int) -> np.ndarray:
    if spec["signed"]:
        return rng.integers(-(1 << (spec["bits"] - 1)), 1 << (spec["bits"] - 1), n)
    return rng.integers(0, 1 << spec["bits"], n)


def _check_layout(layout, seed: int) -> None:
    counter, samples, slow = layout
    text = dbc_text(counter, samples, slow)
    dbc = _TMP / "rand.dbc"
    dbc.write_text(text)
    db = cantools.database.load_string(text, database_format="dbc", strict=True)
    msg, smsg = db.get_message_by_name("RAND"), db.get_message_by_name("SLOW")
    rng = np.random.default_rng(seed)
    k = len(samples)
    n = 40
    c0 = int(rng.integers(0, 1 << counter["bits"]))
    raws = [_random_raw(rng, s, n) for s in samples]
    msgs, want_slow = [], {0: [], 1: []}
    t0 = 1_700_000_000.0
    for i in range(n):
        values = {"Cnt": (c0 + i) % (1 << counter["bits"])}
        for j, s in enumerate(samples):
            values[f"S{j}"] = int(raws[j][i]) * s["scale"] + s["offset"]
        data = msg.encode(values, scaling=True, strict=False)
        msgs.append(
            can.Message(
                timestamp=t0 + ((i + 1) * k - 1) / FS,
                arbitration_id=291,
                is_extended_id=False,
                data=data,
                channel=0,
            )
        )
        if i % 10 == 0:
            m = (i // 10) % 2
            raw = int(_random_raw(rng, slow[m], 1)[0])
            sdata = smsg.encode(
                {"Mux": m, f"Slow{m}": raw * slow[m]["scale"] + slow[m]["offset"]},
                scaling=True,
                strict=False,
            )
            msgs.append(
                can.Message(
                    timestamp=t0 + i * k / FS + 1e-4,
                    arbitration_id=1110,
                    is_extended_id=False,
                    data=sdata,
                    channel=0,
                )
            )
            want_slow[m].append(smsg.decode(sdata)[f"Slow{m}"])
    msgs.sort(key=lambda m: m.timestamp)
    log = _TMP / "rand.log"
    with can.CanutilsLogWriter(str(log)) as w:
        for m in msgs:
            w.on_message_received(m)
    rec = read(log, dbc=dbc)
    ch = rec.channels["rand"]
    assert ch.valid.all() and len(ch) == n * k
    assert ch.first_index == c0 * k
    decoded = [msg.decode(m.data) for m in msgs if m.arbitration_id == 291]
    want = np.array([[float(d[f"S{j}"]) for j in range(k)] for d in decoded]).ravel()
    np.testing.assert_array_equal(ch.values, want)
    for m in (0, 1):
        got = rec.slow[f"Slow{m}"].values
        np.testing.assert_array_equal(got, np.array(want_slow[m], float))
    assert rec.report.n_rejected == 0


@FAST
@given(layout=layouts(), seed=st.integers(0, 2**32 - 1))
def test_random_layouts_decode_exactly_as_cantools(layout, seed):
    _check_layout(layout, seed)


@pytest.mark.slow
@LONG
@given(layout=layouts(), seed=st.integers(0, 2**32 - 1))
def test_random_layouts_long_profile(layout, seed):
    _check_layout(layout, seed)


# --- damaged DBC text --------------------------------------------------------------------------

_REFERENCE = Path(__file__).resolve().parents[2] / "data_schemas" / "rig_reference.dbc"


def _check_damaged_dbc(cut: float, flips: list[tuple[float, int]], strict: bool) -> None:
    text = bytearray(_REFERENCE.read_bytes())
    for frac, value in flips:
        text[min(int(frac * len(text)), len(text) - 1)] = value
    text = text[: max(1, int(cut * len(text)))]
    dbc = _TMP / "damaged.dbc"
    dbc.write_bytes(bytes(text))
    try:
        load_dbc(dbc, strict=strict)
    except DbcError as exc:
        assert str(dbc) in str(exc)
    log = _TMP / "one.log"
    log.write_text(
        "(1700000000.000100) can0 100#0100020003000400\n"
        "(1700000000.000200) can0 200#1027000000000000\n"
    )
    try:
        read(log, dbc=dbc, strict_dbc=strict)
    except RigtoolsError:
        pass


_DBC_FLIPS = st.lists(st.tuples(st.floats(0.0, 1.0), st.integers(0, 255)), max_size=4)


@FAST
@given(cut=st.floats(0.0, 1.0), flips=_DBC_FLIPS, strict=st.booleans())
def test_damaged_dbc_loads_or_raises_dbc_error(cut, flips, strict):
    _check_damaged_dbc(cut, flips, strict)


@pytest.mark.slow
@LONG
@given(cut=st.floats(0.0, 1.0), flips=_DBC_FLIPS, strict=st.booleans())
def test_damaged_dbc_long_profile(cut, flips, strict):
    _check_damaged_dbc(cut, flips, strict)

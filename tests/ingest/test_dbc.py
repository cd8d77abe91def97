"""Vectorised DBC decoding against cantools and against a bit-by-bit reference."""

import cantools
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rigtools.errors import DbcError
from rigtools.ingest.can.dbc import decode_signal, load_dbc, raw_signal, signal_raw
from rigtools.schemas import schema_path


def _bits_reference(payload: bytes, start: int, length: int, byte_order: str) -> int:
    """Slow reference: walk the signal bit by bit as the DBC convention defines it."""
    value = 0
    if byte_order == "little_endian":
        for i in range(length):  # LSB first, bit k of the payload = byte k//8, bit k%8
            pos = start + i
            bit = (payload[pos // 8] >> (pos % 8)) & 1
            value |= bit << i
        return value
    pos = start  # MSB first, walking the DBC "sawtooth": 7..0 of byte 0, then 15..8, ...
    for _ in range(length):
        bit = (payload[pos // 8] >> (pos % 8)) & 1
        value = (value << 1) | bit
        pos = pos - 1 if pos % 8 else pos + 15
    return value


@settings(max_examples=300, deadline=None)
@given(data=st.data())
def test_raw_signal_matches_bitwise_reference_for_any_layout(data):
    width = data.draw(st.sampled_from([8, 12, 16, 32, 64]))
    byte_order = data.draw(st.sampled_from(["little_endian", "big_endian"]))
    length = data.draw(st.integers(1, 64))
    if byte_order == "little_endian":
        start = data.draw(st.integers(0, width * 8 - length))
    else:
        # MSB position in sawtooth numbering such that the signal fits the payload.
        msb_linear = data.draw(st.integers(0, width * 8 - length))
        start = (msb_linear // 8) * 8 + (7 - msb_linear % 8)
    rng = np.random.default_rng(data.draw(st.integers(0, 2**32 - 1)))
    payload = rng.integers(0, 256, (5, width), dtype=np.uint8)
    got = raw_signal(payload, start, length, byte_order)
    want = [_bits_reference(bytes(row), start, length, byte_order) for row in payload]
    assert got.tolist() == want


def test_reference_dbc_decodes_like_cantools():
    db = load_dbc(schema_path("rig_reference.dbc"))
    rng = np.random.default_rng(7)
    for msg in db.messages:
        payload = rng.integers(0, 256, (200, msg.length), dtype=np.uint8)
        for sig in msg.signals:
            got = decode_signal(payload, sig)
            want = [msg.decode(bytes(r), decode_choices=False)[sig.name] for r in payload]
            assert np.array_equal(got, np.asarray(want, float)), (msg.name, sig.name)


def test_reference_dbc_carries_the_layout_attributes():
    db = load_dbc(schema_path("rig_reference.dbc"))
    acc = [m for m in db.messages if "RigSampleRate" in m.dbc.attributes]
    assert len(acc) == 4
    for m in acc:
        assert m.dbc.attributes["RigSampleRate"].value == 25600
        assert m.get_signal_by_name(m.dbc.attributes["RigCounter"].value).length == 16


def test_dbc_that_does_not_parse_names_file_and_line(tmp_path):
    bad = tmp_path / "broken.dbc"
    bad.write_text('VERSION ""\nBO_ 100 M: 8 X\n SG_ S : 0|16@1+ (1,0) [0|1 "" X\n')
    expected = r"broken\.dbc at line 3 column 29: expected a valid DBC file"
    with pytest.raises(DbcError, match=expected):
        load_dbc(bad)


def test_missing_dbc_is_a_clear_error(tmp_path):
    with pytest.raises(DbcError, match="no such file"):
        load_dbc(tmp_path / "nope.dbc")


@pytest.mark.parametrize("byte_order", ["little_endian", "big_endian"])
@pytest.mark.parametrize("signed", [False, True])
@pytest.mark.parametrize("length", [8, 16, 32, 64])
def test_byte_aligned_signals_read_as_their_bytes(byte_order: str, signed: bool,
                                                  length: int) -> None:
    """Whole-byte signals (read as a view of their bytes) against the bit-by-bit reference.

    Every byte position the signal fits at, both byte orders, signed and unsigned: the raw
    values and their dtype are those of the general shift-and-mask path.
    """
    rng = np.random.default_rng(length)
    nb = length // 8
    # rows of 8 and 12 bytes (12: not a multiple of 8-byte signals), contiguous or a view
    for data in (rng.integers(0, 256, (64, 8), dtype=np.uint8),
                 rng.integers(0, 256, (64, 12), dtype=np.uint8),
                 rng.integers(0, 256, (64, 16), dtype=np.uint8)[:, 3:11]):
        data[0] = 0xFF  # all ones: the most negative and the largest values
        data[1] = 0x80
        for first in range(0, data.shape[1] + 1 - nb):
            start = 8 * first if byte_order == "little_endian" else 8 * first + 7
            sig = cantools.database.can.Signal("S", start, length, byte_order, signed)
            raw, _ = signal_raw(data, sig)
            want = [_bits_reference(bytes(row), start, length, byte_order) for row in data]
            if signed:
                want = [v - (1 << length) if v >> (length - 1) else v for v in want]
            assert raw.tolist() == want, (first, byte_order, data.shape)
            assert raw.dtype == np.dtype(f"{'i' if signed else 'u'}{nb}")

"""Random and damaged channel mappings (TOML), loaded and used on a CAN log.

Three properties:

* a random well-formed mapping of reference-DBC signals (any channel names, any of the four
  accelerometer messages, the samples in order, with or without the counter, any finite
  scale and offset) reads a log with every value equal to ``DBC value * scale + offset``
  computed in float64 as the builder computes it (``(raw * dbc_scale + dbc_offset) * scale +
  offset``), the DBC values being those the writer was given (``quantise_reference``);
* a random TOML document over the mapping keys (known and unknown keys, values of every
  TOML type, NaN and infinities) loads into a ``ChannelMapping`` or raises
  :class:`rigtools.errors.MappingError`, and reading a log with what loads returns a
  Recording or raises a :class:`rigtools.errors.RigtoolsError`;
* a valid mapping file cut short or with bytes replaced does the same.
"""

from __future__ import annotations

import atexit
import json
import math
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rigtools.demo.can_writer import encode_reference_frames, quantise_reference, write_can_log
from rigtools.errors import MappingError, RigtoolsError
from rigtools.ingest import load_mapping, read
from rigtools.ingest.layout import ChannelMapping

FAST = settings(
    max_examples=15,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)
LONG = settings(
    max_examples=300, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow]
)

_TMP = Path(tempfile.mkdtemp(prefix="rigtools-fuzz-mapping-"))
atexit.register(shutil.rmtree, _TMP, True)

_RNG = np.random.default_rng(9)
_CHANS = [_RNG.normal(0, 30, 3 * 40) for _ in range(4)]
_LOG = write_can_log(
    _TMP / "run.log", encode_reference_frames(_CHANS, {"Torque_Nm": 25.0}, rng=9), "log"
)
_TRUTH = quantise_reference(_CHANS)


def _toml_value(v: object) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, int):
        return str(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)  # a JSON string is a TOML basic string
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_toml_value(k)} = {_toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(type(v))


def to_toml(doc: dict[str, list[dict[str, object]]]) -> str:
    out = []
    for table, entries in doc.items():
        for e in entries:
            out.append(f"[[{table}]]")
            out += [f"{_toml_value(k)} = {_toml_value(v)}" for k, v in e.items()]
            out.append("")
    return "\n".join(out)


FINITE = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False).filter(lambda x: x != 0)


@st.composite
def valid_mappings(draw):
    n = draw(st.integers(1, 4))
    accs = draw(st.lists(st.integers(1, 4), min_size=n, max_size=n, unique=True))
    names = draw(
        st.lists(
            st.text("abcdefgh_0123456789", min_size=1, max_size=12),
            min_size=n,
            max_size=n,
            unique=True,
        )
    )
    entries = []
    for a, name in zip(accs, names, strict=True):
        e: dict[str, object] = {
            "channel": name,
            "message": draw(st.sampled_from([f"ACC{a}", 255 + a])),
            "samples": [f"Acc{a}_S{j}" for j in range(3)],
            "sample_rate_Hz": 25600.0,
            "scale": draw(FINITE),
            "offset": draw(st.floats(-1e3, 1e3, allow_nan=False)),
        }
        if draw(st.booleans()):
            e["counter"] = f"Acc{a}_Counter"
        if draw(st.booleans()):
            e["unit"] = draw(st.text(st.characters(blacklist_categories=("Cc", "Cs")), max_size=5))
        entries.append((a, e))
    return entries


def _check_valid(entries) -> None:
    p = _TMP / "valid.toml"
    p.write_text(to_toml({"uniform": [e for _, e in entries]}), encoding="utf-8")
    mapping = load_mapping(p)
    rec = read(_LOG, mapping=mapping)
    assert sorted(rec.channels) == sorted(e["channel"] for _, e in entries)
    for a, e in entries:
        ch = rec.channels[str(e["channel"])]
        want = _TRUTH[f"accel_{a}"] * float(e["scale"]) + float(e["offset"])  # type: ignore[arg-type]
        assert ch.valid.all()
        np.testing.assert_array_equal(ch.values, want)
        if "counter" not in e:
            assert any("no sample counter" in w for w in rec.report.warnings)


@FAST
@given(entries=valid_mappings())
def test_valid_random_mappings_scale_the_dbc_values_exactly(entries):
    _check_valid(entries)


# --- random and damaged documents --------------------------------------------------------------

KEYS = [
    "channel",
    "name",
    "message",
    "samples",
    "signal",
    "counter",
    "topic",
    "field",
    "sample_rate_Hz",
    "unit",
    "scale",
    "offset",
    "colour",
    "",
]
VALUES = st.one_of(
    st.text(max_size=8),
    st.integers(-(2**63), 2**63 - 1),
    st.floats(),
    st.booleans(),
    st.sampled_from(["ACC1", "Acc1_S0", "Acc1_Counter", "SPEED", "PinionSpeed_rpm", "256"]),
    st.lists(st.sampled_from(["Acc1_S0", "Acc1_S1", "Acc2_S2", "nope"]), max_size=4),
    st.dictionaries(st.text(max_size=4), st.integers(), max_size=2),
)
DOCS = st.dictionaries(
    st.sampled_from(["uniform", "slow"]),
    st.lists(st.dictionaries(st.sampled_from(KEYS), VALUES, max_size=8), max_size=3),
    max_size=2,
)


def _load_and_read(p: Path) -> None:
    try:
        mapping = load_mapping(p)
    except MappingError as exc:
        assert str(p) in str(exc)
        return
    assert isinstance(mapping, ChannelMapping)
    try:
        read(_LOG, mapping=mapping)
    except RigtoolsError:
        pass


@FAST
@given(doc=DOCS)
def test_random_documents_load_or_raise_mapping_error(doc):
    p = _TMP / "random.toml"
    p.write_text(to_toml(doc), encoding="utf-8")
    _load_and_read(p)


_GOOD = to_toml(
    {
        "uniform": [
            {
                "channel": "x",
                "message": "ACC1",
                "samples": ["Acc1_S0", "Acc1_S1", "Acc1_S2"],
                "counter": "Acc1_Counter",
                "sample_rate_Hz": 25600.0,
                "scale": 2.0,
            }
        ],
        "slow": [{"name": "torque", "message": 513, "signal": "Torque_Nm", "unit": "N.m"}],
    }
).encode()


@FAST
@given(
    cut=st.integers(0, len(_GOOD)),
    subs=st.lists(st.tuples(st.integers(0, len(_GOOD) - 1), st.integers(0, 255)), max_size=3),
)
def test_damaged_mapping_files_load_or_raise_mapping_error(cut, subs):
    b = bytearray(_GOOD)
    for at, value in subs:
        b[at] = value
    p = _TMP / "damaged.toml"
    p.write_bytes(bytes(b[:cut]))
    _load_and_read(p)


@pytest.mark.slow
@LONG
@given(entries=valid_mappings(), doc=DOCS)
def test_long_profile(entries, doc):
    _check_valid(entries)
    p = _TMP / "random.toml"
    p.write_text(to_toml(doc), encoding="utf-8")
    _load_and_read(p)

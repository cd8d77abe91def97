"""The compiled raw-to-physical conversion against NumPy's cast, product and sum, bit for bit."""

from __future__ import annotations

import zlib

import numpy as np
import pytest

from rigtools.ingest.conversion import convert_into


def _numpy_reference(raw: np.ndarray, conversion: tuple[tuple[float, float], ...]) -> np.ndarray:
    """The builder's former conversion: a cast, then ``*= scale; += offset`` per stage."""
    out = np.empty(raw.shape, np.float64)
    with np.errstate(invalid="ignore", over="ignore"):  # inf * 0, 1e300 * 1e300
        np.copyto(out, raw, casting="unsafe")
        for scale, offset in conversion:
            if scale == 1.0 and offset == 0.0:
                continue
            np.multiply(out, scale, out=out)
            np.add(out, offset, out=out)
    return out


def _raw(rng: np.random.Generator, dtype: str, n: int) -> np.ndarray:
    dt = np.dtype(dtype)
    if dt.kind in "iu":
        info = np.iinfo(dt)
        edges = np.array([info.min, info.max, 0, 1, info.max - 1], dt)
        return np.concatenate([edges, rng.integers(info.min, info.max, n, dtype=dt,
                                                   endpoint=True)])
    vals = rng.normal(0, 1e3, n).astype(dt)
    special = np.array([np.nan, np.inf, -np.inf, -0.0, 0.0, np.finfo(dt).max,
                        np.finfo(dt).tiny], dt)
    out = np.concatenate([special, vals])
    if dt == np.float32:  # a signalling NaN (quiet bit clear)
        out = np.concatenate([out, np.array([0x7F800001], np.uint32).view(np.float32)])
    return out


CONVERSIONS = [
    (),
    ((1.0, 0.0),),
    ((0.001, 0.0),),
    ((1.0, -3.5),),
    ((-0.0123, 7.0), (1.0, 0.0), (9.81, -0.25)),
    ((1e300, 1e300),),
    ((-1.0, 0.0),),
]


@pytest.mark.parametrize("dtype", ["int8", "int16", "int32", "int64", "uint8", "uint16",
                                   "uint32", "uint64", "float32", "float64"])
@pytest.mark.parametrize("conversion", CONVERSIONS)
def test_compiled_conversion_equals_numpy_bit_for_bit(dtype, conversion):
    rng = np.random.default_rng(zlib.crc32(repr((dtype, conversion)).encode()))
    raw = _raw(rng, dtype, 5000)
    out = np.empty(raw.shape, np.float64)
    convert_into(raw, conversion, out)
    ref = _numpy_reference(raw, conversion)
    assert np.array_equal(out.view(np.uint64), ref.view(np.uint64))


def test_two_dimensional_and_strided_rows():
    """Rows of samples (contiguous: compiled; a strided view: NumPy) convert alike."""
    rng = np.random.default_rng(3)
    raw = rng.integers(-32768, 32767, (300, 6), dtype=np.int16)
    conversion = ((0.0005, 0.1),)
    for view in (raw, raw[:, ::2], raw[::3]):
        out = np.empty(view.shape, np.float64)
        convert_into(view, conversion, out)
        assert np.array_equal(out, _numpy_reference(view, conversion))


def test_identity_stage_keeps_negative_zero():
    raw = np.array([-0.0, 0.0, 1.5], np.float64)
    out = np.empty(3)
    convert_into(raw, ((1.0, 0.0),), out)
    assert np.signbit(out[0]) and not np.signbit(out[1])


def test_booleans_go_through_numpy():
    raw = np.array([True, False, True])
    out = np.empty(3)
    convert_into(raw, ((2.0, 1.0),), out)
    assert out.tolist() == [3.0, 1.0, 3.0]


@pytest.mark.parametrize(("values", "finite"), [
    ([1.0, -2.5, 0.0], True),
    ([1.0, np.nan], False),
    ([np.inf, 1.0], False),
    ([-np.inf], False),
])
def test_finiteness_reported_on_the_way(values, finite):
    for dtype in (np.float32, np.float64):
        raw = np.array(values, dtype)
        out = np.empty(raw.shape)
        assert convert_into(raw, (), out) is finite
    assert convert_into(np.array([1, 2], np.int16), ((1e308, 1e308),), np.empty(2)) is False
    assert convert_into(np.array([True]), (), np.empty(1)) is None  # the NumPy path: unknown


def test_a_channel_with_a_non_finite_sample_is_counted_whatever_path():
    """The builder's non-finite count with the compiled conversion's verdict and without."""
    from rigtools.ingest import IngestReport, Provenance, RunMetadata
    from rigtools.ingest.builder import RecordingBuilder

    raw = np.arange(1000, dtype=np.float32)
    raw[123] = np.inf
    raw[500] = np.nan
    # one contiguous block (compiled), rows of a strided view (NumPy), float64 (adopted)
    for block in (raw.reshape(1, -1), raw.reshape(-1, 4)[:, ::3],
                  raw.astype(np.float64).reshape(1, -1)):
        report = IngestReport()
        b = RecordingBuilder("mem", report)
        b.add_samples("a", "g", 100.0, np.arange(block.shape[0]) * block.shape[1], block)
        prov = Provenance("mem", "0" * 64, 0, "test", {}, report)
        ch = b.build(RunMetadata(run_id="r"), prov).channels["a"]
        bad = ~np.isfinite(ch.values)
        assert report.rejected["non_finite_sample"] == int((~np.isfinite(block)).sum()) == 2
        assert bad.sum() == 2 and not ch.valid[bad].any() and ch.valid[~bad].all()


@pytest.mark.parametrize("dtype", [">i2", ">u4", ">f4", ">f8", "<f2"])
def test_big_endian_and_half_floats_go_through_numpy(dtype):
    """Big-endian payload fields (CDR_BE) and float16, which numba cannot compile.

    They convert alike through NumPy (the finiteness then unknown: None).
    """
    raw = np.array([1, 2, 3, 0, 7]).astype(dtype)
    out = np.empty(raw.shape)
    assert convert_into(raw, ((0.5, 1.0),), out) is None
    assert np.array_equal(out, _numpy_reference(raw, ((0.5, 1.0),)))

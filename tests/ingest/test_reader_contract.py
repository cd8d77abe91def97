"""The reader contract, once for every entry of the registry.

Every format in :data:`rigtools.ingest.registry.READERS` is one reader object satisfying
:class:`rigtools.ingest.contract.RecordingReader`. What every reader promises is checked here,
each test parametrised over the registry entries (or, for the promises of the CAN log parsers,
over :data:`~rigtools.ingest.registry.CAN_READERS`), on sample files its writers produce:

* the registry names each reader by its own ``name``, and every suffix by a registered format;
* ``sniff`` claims the files of its format and no other reader's (nor content of no format);
* a file is detected by its content whatever its suffix says, gzipped or not, and a gzipped
  file reads as the plain one;
* a reader forced on an empty file refuses it at its start, naming the file;
* a CAN log parser yields batches of ``batch_frames`` frames that join to the whole read,
  refuses a ``batch_frames`` below 1, and its files read end to end through the DBC;
* the fuzz harness (``tests/fuzz/harness.py``) runs over every family of the registry and
  reads intact and damaged files without any exception but rigtools' own.

What is particular to one format (dialects, damage, python-can's quirks) stays in its own
``test_<format>.py``.
"""

from __future__ import annotations

import atexit
import functools
import gzip
import shutil
import tempfile
from pathlib import Path

import can
import numpy as np
import pytest
from can.io.trc import TRCFileVersion
from fuzz.harness import FAMILIES, one_input

from rigtools.demo.can_writer import encode_reference_frames, quantise_reference, write_can_log
from rigtools.demo.mcap_writer import write_accel_mcap
from rigtools.errors import RecordingFormatError
from rigtools.ingest import read, write_parquet
from rigtools.ingest.can.frames import CanFrameBatch, concat
from rigtools.ingest.can.reader import CanLogReader
from rigtools.ingest.files import open_source
from rigtools.ingest.recording import IngestReport
from rigtools.ingest.registry import CAN_READERS, READERS, SUFFIXES, detect_format
from rigtools.ingest.stream_reader import StreamReader

#: Sample files per format: the variants its writers produce.
VARIANTS = {
    "mcap": ("protobuf", "json"),
    "parquet": ("normalized",),
    "blf": ("python-can", "rigtools"),
    "trc": ("v2.1", "v1.0"),
    "asc": ("python-can",),
    "candump": ("python-can", "rigtools"),
    "csv": ("python-can",),
}
SAMPLES = [(fmt, v) for fmt in READERS for v in VARIANTS[fmt]]
N_FRAMES = 30  # per channel of the reference layout: 90 samples each

_DIR = Path(tempfile.mkdtemp(prefix="rigtools-contract-"))
atexit.register(shutil.rmtree, _DIR, True)


def _frames() -> tuple[CanFrameBatch, dict[str, np.ndarray]]:
    accel = {"accel_1": 10 * np.sin(np.arange(3 * N_FRAMES) * 0.1)}
    frames = encode_reference_frames(accel, {"Torque_Nm": 100.0})
    return frames, quantise_reference(accel)


def _trc_v10(path: Path, frames: CanFrameBatch) -> Path:
    """TRC version 1.0 of the frames, by python-can's TRCWriter (write_can_log writes 2.1)."""
    w = can.TRCWriter(str(path))
    w.file_version = TRCFileVersion.V1_0
    for i in range(len(frames)):
        n = int(frames.length[i])
        w.on_message_received(can.Message(
            timestamp=float(frames.timestamp_s[i]), arbitration_id=int(frames.arbitration_id[i]),
            is_extended_id=bool(frames.is_extended[i]), data=bytes(frames.data[i, :n]),
            channel=int(frames.channel[i])))
    w.stop()
    return path


@functools.cache
def sample(fmt: str, variant: str) -> Path:
    """A small file of the format (written once per session)."""
    frames, _ = _frames()
    path = _DIR / f"{fmt}-{variant}.sample"
    if fmt == "mcap":
        rng = np.random.default_rng(1)
        chans = {"accel_1": (rng.standard_normal(500).astype(np.float32), 1000.0, "m/s^2", 0,
                             1_700_000_000.0)}
        return write_accel_mcap(path, chans, encoding=variant, batch=100)  # type: ignore[arg-type]
    if fmt == "parquet":
        return write_parquet(read(sample("blf", "python-can")), path)
    if fmt == "trc" and variant == "v1.0":
        return _trc_v10(path, frames)
    engine = "rigtools" if variant == "rigtools" else "python-can"
    return write_can_log(path, frames, fmt, engine=engine)


def _frames_of(reader: CanLogReader, path: Path, **kw: object) -> list[CanFrameBatch]:
    with open_source(path) as stream:
        return list(reader.iter_batches(stream, str(path), IngestReport(), **kw))  # type: ignore[call-arg]


# --- the registry ----------------------------------------------------------------------------


@pytest.mark.parametrize("fmt", READERS)
def test_registry_names_each_reader_by_its_name(fmt: str) -> None:
    reader = READERS[fmt]
    assert reader.name == fmt
    assert callable(reader.sniff) and callable(reader.read)
    assert fmt in SUFFIXES.values()
    assert isinstance(reader, CanLogReader) == (fmt in CAN_READERS)


def test_every_suffix_names_a_registered_format() -> None:
    assert set(SUFFIXES.values()) == set(READERS)
    assert all(s == s.lower() and s.startswith(".") for s in SUFFIXES)
    assert all(CAN_READERS[n] is READERS[n] for n in CAN_READERS)


# --- sniffing ----------------------------------------------------------------------------------

HEADER = b"timestamp,arbitration_id,extended,remote,error,dlc,data"
#: Heads by the format that must claim them (None: no format may).
HEADS: dict[str, tuple[str | None, bytes]] = {
    "blf": ("blf", b"LOGG" + (144).to_bytes(4, "little") + bytes(136)),
    "blf-signature-only": ("blf", b"LOGG"),
    "mcap": ("mcap", b"\x89MCAP0\r\n" + bytes(40)),
    "parquet": ("parquet", b"PAR1" + bytes(20)),
    "asc": ("asc", b"date Sam Sep 30 15:06:13.191 2017\nbase hex\n"),
    "asc-absolute": ("asc", b"date Mon Jan 1 2024\nbase hex timestamps absolute\n"),
    "trc": ("trc", b";$FILEVERSION=2.1\n"),
    "candump": ("candump", b"(1700000000.000000) can0 123#11\n"),
    "csv": ("csv", HEADER + b"\n"),
    "random-1": (None, np.random.default_rng(20240517).integers(0, 256, 4096, np.uint8).tobytes()),
    "random-2": (None, np.random.default_rng(7).integers(0, 256, 4096, np.uint8).tobytes()),
    "random-3": (None, np.random.default_rng(11).integers(0, 256, 4096, np.uint8).tobytes()),
    "empty": (None, b""),
    "blank": (None, b"\n  \r\n\t\n"),
    "plain-comment": (None, b"; a comment\n"),
    "other-csv": (None, b"a,b,c\n1,2,3\n"),
    "csv-header-not-first": (None, b"1.0,0x10,0,0,0,1,AQ==\n" + HEADER + b"\n"),
    "csv-header-capitalised": (None, b"Timestamp" + HEADER[9:] + b"\n"),
}


@pytest.mark.parametrize("head", HEADS)
@pytest.mark.parametrize("fmt", READERS)
def test_sniff_claims_its_format_only(fmt: str, head: str) -> None:
    owner, data = HEADS[head]
    assert READERS[fmt].sniff(data) is (owner == fmt)


@pytest.mark.parametrize(("fmt", "variant"), SAMPLES)
def test_sniff_claims_the_files_of_its_format_and_no_other_reader_does(
    fmt: str, variant: str
) -> None:
    head = sample(fmt, variant).read_bytes()[:8192]
    assert [name for name, r in READERS.items() if r.sniff(head)] == [fmt]


@pytest.mark.parametrize(("fmt", "variant"), SAMPLES)
def test_content_decides_the_format_whatever_the_suffix(fmt: str, variant: str) -> None:
    """A file is read as its format whatever its suffix says (another's, none, upper case)."""
    data = sample(fmt, variant).read_bytes()
    names = [f"run{s}" for s in sorted(SUFFIXES)] + ["run", "run.dat"]
    names += [f"RUN{s.upper()}" for s, f in SUFFIXES.items() if f == fmt]
    where = _DIR / f"named-{fmt}-{variant}"
    where.mkdir(exist_ok=True)
    for name in names:
        path = where / name
        path.write_bytes(data)
        assert detect_format(path) == fmt, name
        gz = where / (name + ".gz")
        gz.write_bytes(gzip.compress(data))
        assert detect_format(gz) == fmt, name + ".gz"


@pytest.mark.parametrize(
    ("fmt", "variant"), [(f, v) for f, v in SAMPLES if isinstance(READERS[f], StreamReader)]
)
def test_gzipped_file_reads_as_the_plain_one(fmt: str, variant: str) -> None:
    path = sample(fmt, variant)
    gz = path.with_name(path.name + ".gz")
    gz.write_bytes(gzip.compress(path.read_bytes()))
    plain, packed = read(path), read(gz)
    assert packed.provenance.reader == plain.provenance.reader == fmt
    assert packed.channels.keys() == plain.channels.keys()
    assert all(packed.channels[k].equals(plain.channels[k]) for k in plain.channels)
    assert packed.report.to_dict() == plain.report.to_dict()


# --- refusals ----------------------------------------------------------------------------------


@pytest.mark.parametrize("fmt", READERS)
def test_a_forced_reader_refuses_an_empty_file_at_its_start(tmp_path: Path, fmt: str) -> None:
    path = tmp_path / f"empty_run.{fmt}"
    path.write_bytes(b"")
    with pytest.raises(RecordingFormatError, match=rf"empty_run\.{fmt} at (byte 0|line 1): ") as e:
        read(path, fmt=fmt)
    assert e.value.position in (0, "line 1")
    if isinstance(READERS[fmt], StreamReader):
        assert "an empty file" in str(e.value)
    with pytest.raises(RecordingFormatError, match=r"at byte 0: expected a non-empty recording"):
        read(path)


# --- the CAN log parsers -----------------------------------------------------------------------


@pytest.mark.parametrize("batch_frames", [1, 4, 7])
@pytest.mark.parametrize("fmt", CAN_READERS)
def test_batches_hold_batch_frames_and_join_to_the_whole(fmt: str, batch_frames: int) -> None:
    path = sample(fmt, VARIANTS[fmt][0])
    whole = concat(_frames_of(CAN_READERS[fmt], path))
    parts = _frames_of(CAN_READERS[fmt], path, batch_frames=batch_frames)
    q, r = divmod(len(whole), batch_frames)
    assert [len(b) for b in parts] == [batch_frames] * q + ([r] if r else [])
    assert concat(parts).equals(whole, compare_position=True)


@pytest.mark.parametrize("bad", [0, -3])
@pytest.mark.parametrize("fmt", CAN_READERS)
def test_batch_frames_below_one_is_refused(fmt: str, bad: int) -> None:
    with pytest.raises(ValueError, match=r"`batch_frames` must be (an integer )?>= 1"):
        _frames_of(CAN_READERS[fmt], sample(fmt, VARIANTS[fmt][0]), batch_frames=bad)


@pytest.mark.parametrize(("fmt", "variant"), [(f, v) for f, v in SAMPLES if f in CAN_READERS])
def test_a_log_of_the_reference_layout_reads_end_to_end(fmt: str, variant: str) -> None:
    """rigtools.ingest.read over a log python-can (or rigtools) wrote from reference frames."""
    frames, want = _frames()
    rec = read(sample(fmt, variant), fmt=fmt)
    assert rec.provenance.reader == fmt
    assert rec.report.decoded == len(frames)
    assert rec.report.n_rejected == 0
    np.testing.assert_array_equal(rec.channels["accel_1"].values, want["accel_1"])
    assert rec.channels["accel_1"].valid.all()
    assert "Torque_Nm" in rec.slow


# --- the fuzz harness --------------------------------------------------------------------------


def test_every_format_is_in_a_fuzz_family() -> None:
    assert set().union(*FAMILIES.values()) == set(READERS)
    assert FAMILIES["can"] == tuple(CAN_READERS)


@pytest.mark.parametrize("family", FAMILIES)
def test_fuzz_harness_reads_intact_and_damaged_files_of_its_family(family: str) -> None:
    """The atheris harness's one execution, on seeds of every format of the family."""
    run = one_input(family)
    rng = np.random.default_rng(5)
    for fmt, variant in [(f, v) for f, v in SAMPLES if f in FAMILIES[family]]:
        data = sample(fmt, variant).read_bytes()
        damaged = [data, data[: len(data) // 3], data[: 2 * len(data) // 3]]
        for _ in range(3):
            flipped = bytearray(data)
            flipped[int(rng.integers(len(data)))] ^= 1 << int(rng.integers(8))
            damaged.append(bytes(flipped))
        for d in damaged:
            run(d)


"""Every reader over the corpus of damaged files that ``tests/make_damaged_corpus.py`` builds.

The corpus (built once per session into a temporary directory) holds small intact recordings
written by the real writers (python-can's BLF, ASC, TRC, candump and CSV writers; mcap's
``Writer`` with zstd, lz4 and uncompressed chunks, unchunked, unindexed and JSON-encoded) and,
for each, every damage of the script: cuts at 18 points, wrong magic, corrupted CRCs and
compressed data, zero-length and oversized chunk / container / record lengths, gzip wrappers
cut short or with a wrong CRC, garbage, Latin-1 and NUL bytes, BOMs, mixed line ends,
over-long lines, UTF-16 and duplicated, dropped and shuffled lines or containers.

The oracle is ``make_damaged_corpus.check_against_truth`` against the samples the writers
were given: ``read`` returns a Recording whose valid samples all equal the written ones at
their absolute index, that holds every sample of every record the damage did not touch
(``touched`` in the manifest, :func:`make_damaged_corpus.touched_records`), whose missing
samples inside a channel are counted, and whose slow values were all written; or it raises
a :class:`rigtools.errors.RigtoolsError`. No damage in
the corpus changes a sample silently (every flip lands in CRC-checked or compressed data, or
in a line that no longer parses), so no wrong sample is tolerated. The intact files must read
back complete with nothing counted. Each read stays within the time bound of the other
``test_fuzz_*`` modules.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
import pytest
from make_damaged_corpus import (
    MAX_CPU_S_FIXED,
    MAX_CPU_S_PER_MB,
    build_corpus,
    can_frames,
    can_row_samples,
    check_against_truth,
    mcap_required,
    required_samples,
)

from rigtools.errors import RigtoolsError
from rigtools.ingest import read

#: Damages after which the reader must still return data (not refuse the file): the intact
#: part is large and the damage local. Everything else may also be refused with a
#: RigtoolsError (a cut before the first record, a wrong magic, UTF-16, ...).
MUST_READ = {
    "garbage_lines",
    "latin1_line",
    "crlf_mixed",
    "overlong_line",
    "lines_duplicated",
    "lines_dropped",
    "lines_shuffled",
    "line_cut_in_middle",
    "nul_bytes",
    "utf8_bom",
    "chunk_crc_wrong",
    "chunk_data_flipped",
    "record_opcode_unknown",
    "tail_magic_missing",
    "footer_summary_start_wrong",
    "gzip_cut",
    "gzip_crc_wrong",
}


@pytest.fixture(scope="session")
def corpus(tmp_path_factory) -> tuple[Path, list[dict[str, str]], dict[str, np.ndarray]]:
    root = tmp_path_factory.mktemp("damaged_corpus")
    manifest = build_corpus(root)
    truth = dict(np.load(root / "truth.npz"))
    assert json.loads((root / "manifest.json").read_text()) == manifest
    return root, manifest, truth


@pytest.fixture(scope="session")
def intact(corpus) -> dict[str, object]:
    root, _, _ = corpus
    return {p.name: read(p) for p in sorted((root / "intact").iterdir())}


def test_intact_files_read_back_exactly_with_nothing_counted(corpus, intact):
    _, _, truth = corpus
    assert len(intact) == 14
    for name, rec in intact.items():
        family = "mcap" if name.endswith(".mcap") else "can"
        got = check_against_truth(rec, truth, family, intact=rec)
        n_written = sum(v.size for k, v in truth.items() if k.startswith(f"{family}:accel"))
        assert got.matched == n_written and got.missing == 0, name
        assert not rec.report.has_losses, (name, rec.report.to_dict())  # type: ignore[attr-defined]
        for sig in ("PinionSpeed_rpm",):
            np.testing.assert_array_equal(
                rec.slow[sig].values,  # type: ignore[attr-defined]
                truth[f"{family}:{sig}"],
                err_msg=name,
            )


def test_corpus_covers_every_reader_and_damage(corpus):
    _, manifest, _ = corpus
    sources = {m["source"] for m in manifest}
    assert {s.rsplit(".", 1)[1] for s in sources} == {"blf", "asc", "trc", "log", "csv", "mcap"}
    damages = {m["damage"] for m in manifest}
    assert MUST_READ <= damages
    assert len(manifest) > 400


def test_every_reader_over_every_damaged_file(corpus, intact):
    root, manifest, truth = corpus
    names, start, k = can_row_samples(can_frames())
    outcome: dict[str, list[str]] = {"read": [], "refused": []}
    failures = []
    for m in manifest:
        path = root / m["file"]
        size = path.stat().st_size
        t0 = time.process_time()
        try:
            rec = read(path)
        except RigtoolsError as exc:
            outcome["refused"].append(m["file"])
            if m["damage"] in MUST_READ:
                failures.append(f"{m['file']}: refused ({exc})")
            continue
        except Exception as exc:  # the guarantee: never any other exception
            failures.append(f"{m['file']}: {type(exc).__name__}: {exc}")
            continue
        cpu = time.process_time() - t0
        if cpu > MAX_CPU_S_FIXED + MAX_CPU_S_PER_MB * size / 1e6:
            failures.append(f"{m['file']}: {cpu:.2f} s CPU for {size} bytes")
        outcome["read"].append(m["file"])
        required = None
        if m["touched"] is not None:
            if m["family"] == "can":
                keep = sorted(set(range(len(names))) - set(m["touched"]))
                required = required_samples(names, start, k, keep, truth)
            else:
                required = mcap_required(m["touched"], truth)
        try:
            # Every sample of a record the damage did not touch comes back, equal: no lost
            # intact sample is tolerated (no damage of the corpus makes a twin of a record).
            got = check_against_truth(
                rec,
                truth,
                m["family"],
                intact=intact[m["source"]],
                required=required,
                tolerance_lost=0,
            )
        except AssertionError as exc:
            failures.append(f"{m['file']}: {exc}")
            continue
        if (
            got.missing
            and not rec.report.has_losses
            and m["damage"] != "header_lost"
            and not m["damage"].startswith("cut_at")
        ):
            # Losses at the edges of a file are invisible to any reader (a cut at a record
            # boundary, records removed cleanly at the start); everything else is counted.
            failures.append(f"{m['file']}: {got.missing} samples missing, nothing counted")
    assert not failures, "\n".join(failures)
    # Most damaged files still give data: damage costs the damaged part, not the file.
    assert len(outcome["read"]) > 0.75 * len(manifest), len(outcome["read"])


# --- the time bound per megabyte, on files large enough for it to matter (review r5, 6) --------


@pytest.fixture(scope="module")
def large_frames():
    """160,000 reference frames (40,000 per channel at 3 samples a frame, counter wrapping)."""
    from rigtools.demo.can_writer import encode_reference_frames, quantise_reference

    rng = np.random.default_rng(21)
    chans = {f"accel_{i + 1}": rng.normal(0, 30, 3 * 40_000) for i in range(4)}
    frames = encode_reference_frames(chans, {"Torque_Nm": 1.0}, first_counter=0, rng=21)
    truth = {f"can:{k}": v for k, v in quantise_reference(chans).items()}
    truth["can:first_index"] = np.array([0])
    return frames, truth


def _damage_large(data: bytes) -> bytes:
    """Three flipped bytes spread over the file and the last 5 % cut away."""
    b = bytearray(data[: len(data) * 19 // 20])
    for frac in (0.3, 0.5, 0.7):
        b[int(frac * len(b))] ^= 0x10
    return bytes(b)


def _read_within_bound(path: Path, min_bytes: int = 5_000_000):
    size = path.stat().st_size
    assert size >= min_bytes, size  # the per-MB term must dominate the fixed one
    t0 = time.process_time()
    try:
        rec = read(path)
    except RigtoolsError as exc:  # pragma: no cover - the damage is local: must read
        pytest.fail(f"refused: {exc}")
    cpu = time.process_time() - t0
    assert cpu <= MAX_CPU_S_FIXED + MAX_CPU_S_PER_MB * size / 1e6, f"{cpu:.2f} s for {size} B"
    return rec


@pytest.mark.parametrize("fmt", ["blf", "log"])
def test_time_bound_on_a_large_damaged_can_log(tmp_path, large_frames, fmt):
    """A 5-8 MB BLF (stored containers) or candump log, flipped in three places and cut short.

    The files of the corpus are 10-80 kB, where the fixed 0.5 s dominates the bound; here the
    5 s/MB term does (a walker quadratic in the file size would not make it). The read must
    also keep the data: at least 90 % of the samples come back, equal.
    """
    from rigtools.demo.can_writer import blf_bytes, write_can_log

    frames, truth = large_frames
    if fmt == "blf":
        data = blf_bytes(frames, compression_level=0)
    else:
        data = write_can_log(tmp_path / "big_intact.log", frames, "log").read_bytes()
    p = tmp_path / f"big.{fmt}"
    p.write_bytes(_damage_large(data))
    rec = _read_within_bound(p)
    got = check_against_truth(rec, truth, "can", tolerance_samples=3 * 3)
    assert got.matched >= 0.9 * sum(v.size for k, v in truth.items() if "accel" in k)


def test_time_bound_on_a_large_damaged_mcap(tmp_path):
    """A 6 MB zstd MCAP (two channels of 800,000 float32 samples), damaged as above."""
    from rigtools.demo.mcap_writer import write_accel_mcap

    rng = np.random.default_rng(22)
    chans = {k: rng.standard_normal(800_000).astype(np.float32) for k in ("accel_1", "accel_2")}
    spec = {k: (v, 10_000.0, "g", 0, 1.7e9) for k, v in chans.items()}
    src = write_accel_mcap(tmp_path / "big_intact.mcap", spec, None, batch=1000, chunk_size=1 << 18)
    p = tmp_path / "big.mcap"
    p.write_bytes(_damage_large(src.read_bytes()))
    rec = _read_within_bound(p)
    truth = {f"mcap:{k}": v.astype(np.float64) for k, v in chans.items()}
    truth["mcap:first_index"] = np.array([0])
    got = check_against_truth(rec, truth, "mcap")
    assert got.matched >= 0.8 * 1_600_000

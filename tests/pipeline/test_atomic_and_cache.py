"""Atomic writes leave a whole file or none; keys say what an output was made from."""

from __future__ import annotations

import errno
import hashlib
import os
import subprocess
import sys
from pathlib import Path

import pytest

from rigtools.pipeline.atomic import (
    TMP_MARKER,
    atomic_output,
    atomic_write_json,
    atomic_write_text,
    remove_stale_temporaries,
)
from rigtools.pipeline.cache import (
    CHUNK_BYTES,
    file_sha256,
    invalidate,
    is_current,
    key_path,
    read_key,
    stage_key,
    write_key,
)


def test_atomic_write_replaces_the_file_and_leaves_no_temporary(tmp_path: Path) -> None:
    p = tmp_path / "a.json"
    atomic_write_json(p, {"x": 1})
    atomic_write_json(p, {"x": 2})
    assert p.read_text(encoding="utf-8") == '{\n  "x": 2\n}\n'
    assert sorted(f.name for f in tmp_path.iterdir()) == ["a.json"]


def test_a_full_disk_leaves_the_old_file_and_names_the_final_one(tmp_path: Path) -> None:
    p = tmp_path / "run.parquet"
    atomic_write_text(p, "old")
    with pytest.raises(OSError, match=r"run\.parquet") as info, atomic_output(p) as tmp:
        tmp.write_bytes(b"half a fi")
        raise OSError(errno.ENOSPC, "No space left on device")
    assert info.value.errno == errno.ENOSPC
    assert info.value.filename == str(p)
    assert p.read_text() == "old"
    assert sorted(f.name for f in tmp_path.iterdir()) == ["run.parquet"]


def test_a_writer_that_wrote_nothing_is_an_error(tmp_path: Path) -> None:
    with pytest.raises(OSError, match="did not write the file"), atomic_output(tmp_path / "x"):
        pass
    assert not (tmp_path / "x").exists()


def test_an_exception_in_the_writer_removes_the_temporary(tmp_path: Path) -> None:
    with pytest.raises(KeyError), atomic_output(tmp_path / "x") as tmp:
        tmp.write_text("partial")
        raise KeyError("bug")
    assert list(tmp_path.iterdir()) == []


def test_temporaries_of_dead_writers_are_removed(tmp_path: Path) -> None:
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    stale = tmp_path / f"a.json{TMP_MARKER}{int(dead.stdout)}"
    mine = tmp_path / f"b.json{TMP_MARKER}{os.getpid()}"
    stale.write_text("x")
    mine.write_text("y")
    assert remove_stale_temporaries(tmp_path) == 1
    assert not stale.exists() and mine.exists()


def test_file_hash_over_chunks_is_the_hash_of_the_bytes(tmp_path: Path) -> None:
    data = os.urandom(2 * CHUNK_BYTES + 123)
    p = tmp_path / "rec.bin"
    p.write_bytes(data)
    assert file_sha256(p) == hashlib.sha256(data).hexdigest()


def test_stage_keys_follow_their_inputs() -> None:
    a = stage_key("ingest", {"sha": "1", "dbc": None})
    assert a == stage_key("ingest", {"dbc": None, "sha": "1"})  # order does not matter
    assert a != stage_key("ingest", {"sha": "2", "dbc": None})
    assert a != stage_key("observe", {"sha": "1", "dbc": None})


def test_an_output_is_current_only_with_its_key_and_files(tmp_path: Path) -> None:
    out = tmp_path / "x.parquet"
    k = key_path(tmp_path, "x")
    assert not is_current(k, "abc", (out,))
    out.write_text("data")
    assert not is_current(k, "abc", (out,))  # no key: never trusted
    write_key(k, "abc")
    assert read_key(k) == "abc" and is_current(k, "abc", (out,))
    assert not is_current(k, "abd", (out,))
    invalidate(k)
    invalidate(k)  # absent: nothing to do
    assert not is_current(k, "abc", (out,))

"""Report files are written atomically: an interrupted write leaves no page that looks complete."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

import rigtools.report.build as build_module
from rigtools.report import build_report
from rigtools.report.atomic import write_atomic


def test_write_atomic_replaces_and_cleans_up(tmp_path: Path) -> None:
    target = tmp_path / "report.html"
    write_atomic(target, "old")
    write_atomic(target, "new")
    assert target.read_text(encoding="utf-8") == "new"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.html"]


def test_failed_write_leaves_the_old_file_and_no_temporary(tmp_path: Path,
                                                           monkeypatch: pytest.MonkeyPatch) -> None:
    target = tmp_path / "report.json"
    write_atomic(target, "old")

    def broken_fsync(fd: int) -> None:
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(os, "fsync", broken_fsync)
    with pytest.raises(OSError, match="No space left on device"):
        write_atomic(target, "new")
    assert target.read_text(encoding="utf-8") == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.json"]


def test_interrupted_report_leaves_no_html(bare_outdir: Path,
                                           monkeypatch: pytest.MonkeyPatch) -> None:
    build_report(bare_outdir)
    assert (bare_outdir / "report.html").is_file()
    real = build_module.write_atomic

    def writer(path: str | Path, data: str | bytes) -> Path:
        if Path(path).name == "report.html":
            with open(Path(path).with_name("report.html.tmp-99999"), "w") as fh:
                fh.write(str(data)[:100])  # half-written, then the disk fills up
            raise OSError(28, "No space left on device")
        return real(path, data)
    monkeypatch.setattr(build_module, "write_atomic", writer)
    with pytest.raises(OSError, match="No space left"):
        build_report(bare_outdir)
    assert not (bare_outdir / "report.html").exists()
    monkeypatch.undo()
    paths = build_report(bare_outdir)  # the next build clears the leftover temporary
    assert paths.html.read_text(encoding="utf-8").rstrip().endswith("</html>")
    assert sorted(p.name for p in bare_outdir.iterdir()) == ["pipeline.json", "report.html",
                                                             "report.json"]


def test_interrupted_json_write_leaves_no_html(bare_outdir: Path,
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    build_report(bare_outdir)

    def writer(path: str | Path, data: str | bytes) -> Path:
        raise OSError(5, "Input/output error")
    monkeypatch.setattr(build_module, "write_atomic", writer)
    with pytest.raises(OSError, match="Input/output error"):
        build_report(bare_outdir)
    assert not (bare_outdir / "report.html").exists()
